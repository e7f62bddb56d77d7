//! RGL measured BRDF tensor files (`.bsdf`) through the reader, and the
//! BRDF of any file it accepts evaluated and sampled: values and densities
//! finite and never negative.

#![no_main]

use libfuzzer_sys::fuzz_target;
use raytracer::bsdf::{MeasuredBxdf, MeasuredData, TransportMode};
use raytracer::math::{Vec2, Vec3};

fuzz_target!(|data: &[u8]| {
    let grey = |l: &[f32]| vec![Vec3::splat(1.0 / l.len().max(1) as f32); l.len()];
    let Ok(m) = MeasuredData::from_bytes(data, "fuzz.bsdf", grey) else {
        return;
    };
    // The renderer keeps measured data for the process's life; here it is
    // freed at the end, so that the leak check still sees the reader's.
    let data = Box::into_raw(Box::new(m));
    // SAFETY: `data` is a live allocation until the `from_raw` below, and
    // no BxDF of it outlives that.
    let plain = MeasuredBxdf::new(unsafe { &*data });
    let dirs = [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.6, 0.0, 0.8),
        Vec3::new(-0.3, 0.5, 0.812404),
        Vec3::new(0.0, -0.99, 0.141067),
    ];
    for (b, mode) in [
        (plain, TransportMode::Radiance),
        (
            MeasuredBxdf {
                mirrored: true,
                ..plain
            },
            TransportMode::Importance,
        ),
    ] {
        for wo in dirs {
            for wi in dirs {
                let f = b.f(wo, wi, mode);
                let pdf = b.pdf(wo, wi);
                assert!(f.is_finite() && f.min_element() >= 0.0, "{f}");
                assert!(pdf.is_finite() && pdf >= 0.0, "{pdf}");
            }
            for u in [Vec2::new(0.1, 0.2), Vec2::new(0.5, 0.5), Vec2::new(0.97, 0.01)] {
                if let Some(s) = b.sample_f(wo, u, mode) {
                    assert!(s.f.is_finite() && s.f.min_element() >= 0.0 && s.pdf > 0.0 && s.pdf.is_finite());
                    assert!(s.wi.is_finite() && s.wi.z * wo.z > 0.0);
                }
            }
        }
    }
    // SAFETY: made by `into_raw` above; no BxDF of it is used again.
    drop(unsafe { Box::from_raw(data) });
});
