//! pbrt-v4's procedural textures and texture mappings (pbrt-v4 10.2 and
//! 10.6): where a surface point falls on a 2D pattern other than by its
//! (u, v) (spherical, cylindrical and planar mappings), checkerboards in the
//! plane and in space filtered over the pixel's footprint, polka dots,
//! bilinear ramps, and the noise patterns (fBm, wrinkles, wind-blown waves,
//! marble) in the texture's own space.

use super::noise::{fbm, noise, turbulence};
use super::{Footprint, TexCoord, UvMapping};
use crate::math::{Vec2, Vec3};
use glam::Affine3A;
use std::f32::consts::{FRAC_1_PI, PI};

/// How a surface point finds its place (s, t) on a 2D texture, and how far
/// that moves from pixel to pixel (pbrt-v4's `TextureMapping2D`).
#[derive(Clone, Debug, PartialEq)]
pub enum Mapping2D {
    /// The surface's (u, v), scaled and offset.
    Uv(UvMapping),
    /// The direction of the point from the texture space's origin:
    /// s = theta / pi from +z, t = phi / 2 pi about it.
    Spherical(Affine3A),
    /// The angle about texture space's z axis, s = (pi + phi) / 2 pi, and
    /// the height along it, t = z.
    Cylindrical(Affine3A),
    /// The point's components along two vectors of texture space, offset.
    Planar {
        to_texture: Affine3A,
        vs: Vec3,
        vt: Vec3,
        ds: f32,
        dt: f32,
    },
}

impl Mapping2D {
    /// `tc` with (s, t) in place of (u, v) and the footprint of (s, t) in
    /// place of that of (u, v): what the 2D texture under the mapping is
    /// looked up at.
    pub fn map(&self, tc: &TexCoord) -> TexCoord {
        let f = &tc.footprint;
        let (st, d) = match self {
            Mapping2D::Uv(m) => (
                Vec2::new(m.su * tc.uv.x + m.du, m.sv * tc.uv.y + m.dv),
                [m.su * f.dudx, m.su * f.dudy, m.sv * f.dvdx, m.sv * f.dvdy],
            ),
            Mapping2D::Spherical(to) => {
                let pt = to.transform_point3(tc.p);
                let x2y2 = pt.x * pt.x + pt.y * pt.y;
                let r = x2y2.sqrt();
                let dsdp = Vec3::new(-pt.y, pt.x, 0.0) / (2.0 * PI * x2y2);
                let dtdp = Vec3::new(pt.x * pt.z / r, pt.y * pt.z / r, -r) / (PI * (x2y2 + pt.z * pt.z));
                let v = pt.normalize_or_zero();
                let st = Vec2::new(v.z.clamp(-1.0, 1.0).acos() * FRAC_1_PI, phi(v.y, v.x) / (2.0 * PI));
                (st, derivatives(to, f, dsdp, dtdp))
            }
            Mapping2D::Cylindrical(to) => {
                let pt = to.transform_point3(tc.p);
                let x2y2 = pt.x * pt.x + pt.y * pt.y;
                let dsdp = Vec3::new(-pt.y, pt.x, 0.0) / (2.0 * PI * x2y2);
                let st = Vec2::new((PI + pt.y.atan2(pt.x)) / (2.0 * PI), pt.z);
                (st, derivatives(to, f, dsdp, Vec3::Z))
            }
            Mapping2D::Planar {
                to_texture,
                vs,
                vt,
                ds,
                dt,
            } => {
                let v = to_texture.transform_point3(tc.p);
                let st = Vec2::new(ds + v.dot(*vs), dt + v.dot(*vt));
                (st, derivatives(to_texture, f, *vs, *vt))
            }
        };
        // A point on the mapping's axis or at its centre has no direction:
        // its place is the origin, its footprint none.
        let finite = |x: f32| if x.is_finite() { x } else { 0.0 };
        TexCoord {
            uv: Vec2::new(finite(st.x), finite(st.y)),
            footprint: Footprint {
                dudx: finite(d[0]),
                dudy: finite(d[1]),
                dvdx: finite(d[2]),
                dvdy: finite(d[3]),
                ..*f
            },
            ..*tc
        }
    }

    /// The mapping of a scene reflected by `r` (its own inverse): the point
    /// is carried back before it is mapped.
    pub fn reflected(&self, r: &Affine3A) -> Mapping2D {
        let mut m = self.clone();
        match &mut m {
            Mapping2D::Uv(_) => {}
            Mapping2D::Spherical(t) | Mapping2D::Cylindrical(t) | Mapping2D::Planar { to_texture: t, .. } => *t *= *r,
        }
        m
    }
}

/// The azimuth of (x, y) in [0, 2 pi).
fn phi(y: f32, x: f32) -> f32 {
    let p = y.atan2(x);
    if p < 0.0 {
        p + 2.0 * PI
    } else {
        p
    }
}

/// [ds/dx, ds/dy, dt/dx, dt/dy] from the gradients of s and t in texture
/// space and the point's footprint in the world.
fn derivatives(to: &Affine3A, f: &Footprint, dsdp: Vec3, dtdp: Vec3) -> [f32; 4] {
    let (dpdx, dpdy) = (to.transform_vector3(f.dpdx), to.transform_vector3(f.dpdy));
    [dsdp.dot(dpdx), dsdp.dot(dpdy), dtdp.dot(dpdx), dtdp.dot(dpdy)]
}

/// The weight of a checkerboard's second texture at `tc`: 0 on squares
/// (cubes) whose cell indices sum to an even number, 1 on the others, and
/// between where the pixel's footprint straddles an edge: the checks
/// integrated against a filter 1.5 footprints wide (pbrt-v4's
/// `Checkerboard`, the same closed form).
pub fn checkerboard_weight(st: Vec2, f: &Footprint) -> f32 {
    let ds = 1.5 * f.dudx.abs().max(f.dudy.abs());
    let dt = 1.5 * f.dvdx.abs().max(f.dvdy.abs());
    0.5 - filtered_square_wave(st.x, ds) * filtered_square_wave(st.y, dt) / 2.0
}

/// `checkerboard_weight` of the cubes of texture space.
pub fn checkerboard_weight_3d(to: &Affine3A, tc: &TexCoord) -> f32 {
    let p = to.transform_point3(tc.p);
    let (dpdx, dpdy) = (
        to.transform_vector3(tc.footprint.dpdx),
        to.transform_vector3(tc.footprint.dpdy),
    );
    let d = dpdx.abs().max(dpdy.abs()) * 1.5;
    0.5 - 0.5 * filtered_square_wave(p.x, d.x) * filtered_square_wave(p.y, d.y) * filtered_square_wave(p.z, d.z)
}

/// The square wave +1 on [2k, 2k + 1), -1 on [2k + 1, 2k + 2), averaged
/// over [x - r, x + r] under a tent filter; the wave itself where that
/// interval holds no edge.
fn filtered_square_wave(x: f32, r: f32) -> f32 {
    if (x - r).floor() == (x + r).floor() {
        return 1.0 - 2.0 * ((x.floor() as i64) & 1) as f32;
    }
    // The wave's integral's integral, in closed form.
    let d = |x: f32| {
        let y = x / 2.0 - (x / 2.0).floor() - 0.5;
        x / 2.0 + y * (1.0 - 2.0 * y.abs())
    };
    (d(x + r) - 2.0 * d(x) + d(x - r)) / (r * r)
}

/// Whether (s, t) lies in a polka dot: cells one unit wide centred on the
/// integers, about half of them (where the noise is positive) holding a dot
/// of radius 0.35 shifted by the noise (pbrt-v4's `InsidePolkaDot`).
pub fn inside_polka_dot(st: Vec2) -> bool {
    let (s, t) = ((st.x + 0.5).floor(), (st.y + 0.5).floor());
    let n = |x: f32, y: f32| noise(Vec3::new(x, y, 0.5));
    if n(s + 0.5, t + 0.5) <= 0.0 {
        return false;
    }
    let radius = 0.35;
    let max_shift = 0.5 - radius;
    let centre = Vec2::new(s + max_shift * n(s + 1.5, t + 2.8), t + max_shift * n(s + 4.5, t + 9.8));
    (st - centre).length_squared() < radius * radius
}

/// A pattern of noise in the texture's own space (pbrt-v4's `fbm`,
/// `wrinkled`, `windy` and `marble` textures).
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseTexture {
    /// From the world to texture space: the inverse of the transformation
    /// in force where the texture was defined.
    pub to_texture: Affine3A,
    pub pattern: Pattern,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pattern {
    /// Fractional Brownian motion: `octaves` of noise, weights `omega` times
    /// the last's.
    Fbm { octaves: u32, omega: f32 },
    /// Turbulence: the same of the noise's magnitude.
    Wrinkled { octaves: u32, omega: f32 },
    /// Waves (six octaves of fBm) whose height follows a slower fBm.
    Windy,
    /// Veins of marble: the colour along pbrt-v4's spline of greys and a
    /// blue at 0.5 + 0.5 sin(y + variation fBm), the point scaled by `scale`.
    Marble {
        octaves: u32,
        omega: f32,
        scale: f32,
        variation: f32,
    },
}

/// The colours of marble's spline (pbrt-v4's).
const MARBLE: [Vec3; 9] = [
    Vec3::new(0.58, 0.58, 0.6),
    Vec3::new(0.58, 0.58, 0.6),
    Vec3::new(0.58, 0.58, 0.6),
    Vec3::new(0.5, 0.5, 0.5),
    Vec3::new(0.6, 0.59, 0.58),
    Vec3::new(0.58, 0.58, 0.6),
    Vec3::new(0.58, 0.58, 0.6),
    Vec3::new(0.2, 0.2, 0.33),
    Vec3::new(0.58, 0.58, 0.6),
];

impl NoiseTexture {
    /// The pattern's value at `tc`: a number for all but marble (all three
    /// channels), marble's colour.
    pub fn evaluate(&self, tc: &TexCoord) -> Vec3 {
        let to = &self.to_texture;
        let p = to.transform_point3(tc.p);
        let dpdx = to.transform_vector3(tc.footprint.dpdx);
        let dpdy = to.transform_vector3(tc.footprint.dpdy);
        match self.pattern {
            Pattern::Fbm { octaves, omega } => Vec3::splat(fbm(p, dpdx, dpdy, omega, octaves)),
            Pattern::Wrinkled { octaves, omega } => Vec3::splat(turbulence(p, dpdx, dpdy, omega, octaves)),
            Pattern::Windy => {
                let strength = fbm(0.1 * p, 0.1 * dpdx, 0.1 * dpdy, 0.5, 3);
                let height = fbm(p, dpdx, dpdy, 0.5, 6);
                Vec3::splat(strength.abs() * height)
            }
            Pattern::Marble {
                octaves,
                omega,
                scale,
                variation,
            } => {
                let p = p * scale;
                let marble = p.y + variation * fbm(p, scale * dpdx, scale * dpdy, omega, octaves);
                let t = 0.5 + 0.5 * marble.sin();
                let t = if t.is_finite() { t } else { 0.0 };
                let segments = MARBLE.len() - 3;
                let first = ((t * segments as f32).floor() as usize).min(segments - 1);
                let t = t * segments as f32 - first as f32;
                1.5 * cubic_bezier(&MARBLE[first..first + 4], t)
            }
        }
    }

    /// The largest value the pattern takes in any channel: the sum of its
    /// octaves' weights (the noise lies within [-1, 1]).
    pub fn max_value(&self) -> f32 {
        let weights = |octaves: u32, omega: f32| (0..=octaves).map(|i| omega.abs().powi(i as i32)).sum::<f32>();
        match self.pattern {
            Pattern::Fbm { octaves, omega } | Pattern::Wrinkled { octaves, omega } => weights(octaves, omega),
            Pattern::Windy => weights(3, 0.5) * weights(6, 0.5),
            Pattern::Marble { .. } => 1.5 * MARBLE.iter().map(|c| c.max_element()).fold(0.0, f32::max),
        }
    }
}

/// The cubic Bezier curve through control points `cp[0..4]` at `t`, by de
/// Casteljau's construction.
fn cubic_bezier(cp: &[Vec3], t: f32) -> Vec3 {
    let lerp = |a: Vec3, b: Vec3| a * (1.0 - t) + b * t;
    let (a, b, c) = (lerp(cp[0], cp[1]), lerp(cp[1], cp[2]), lerp(cp[2], cp[3]));
    let (d, e) = (lerp(a, b), lerp(b, c));
    lerp(d, e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat4;

    /// The transformation of pbrt-v4's texture space in the cases below:
    /// `Translate 0.5 -1 2`, `Rotate 30 1 1 0`, `Scale 2 2 2`.
    fn to_texture() -> Affine3A {
        let m = Mat4::from_translation(Vec3::new(0.5, -1.0, 2.0))
            * Mat4::from_axis_angle(Vec3::new(1.0, 1.0, 0.0).normalize(), 30f32.to_radians())
            * Mat4::from_scale(Vec3::splat(2.0));
        Affine3A::from_mat4(m.inverse())
    }

    fn lookup(p: Vec3, uv: Vec2, d: [f32; 4], dpdx: Vec3, dpdy: Vec3) -> TexCoord {
        TexCoord {
            uv,
            p,
            n: Vec3::Z,
            footprint: Footprint {
                dudx: d[0],
                dudy: d[1],
                dvdx: d[2],
                dvdy: d[3],
                dpdx,
                dpdy,
            },
        }
    }

    /// A lookup at `p` with the narrow footprint of the cases below: (u, v)
    /// (0.25, 0.75), the (u, v) derivatives (0.1, 0.2, 0.3, 0.4), dpdx
    /// (0.01, 0.02, 0) and dpdy (0, -0.01, 0.03).
    fn narrow(p: Vec3) -> TexCoord {
        lookup(
            p,
            Vec2::new(0.25, 0.75),
            [0.1, 0.2, 0.3, 0.4],
            Vec3::new(0.01, 0.02, 0.0),
            Vec3::new(0.0, -0.01, 0.03),
        )
    }

    const POINTS: [Vec3; 4] = [
        Vec3::new(0.3, 0.7, 0.1),
        Vec3::new(1.5, -2.25, 3.75),
        Vec3::new(12.34, 5.67, -8.9),
        Vec3::new(-0.6, 0.05, 0.95),
    ];

    #[test]
    #[allow(clippy::excessive_precision)] // as pbrt-v4 printed them
    fn mappings_are_pbrts_with_their_footprints() {
        // pbrt-v4's spherical, cylindrical and planar (v1 (1, 0.5, 0), v2
        // (0, 0.25, 1), udelta 0.3, vdelta -0.2) mappings at these points,
        // (s, t, ds/dx, ds/dy, dt/dx, dt/dy) each, printed by a program linked
        // against pbrt-v4, for dpdx (0.01, 0.02, 0) and dpdy (0, -0.01, 0.03).
        let want: [[[f32; 6]; 3]; 4] = [
            [
                [
                    0.860952318,
                    0.156614885,
                    0.000267302385,
                    0.00148530654,
                    -0.00229551038,
                    -0.000970054185,
                ],
                [
                    0.6566149,
                    -1.15859985,
                    0.000267302385,
                    0.00148530654,
                    -0.00176776689,
                    0.0147581473,
                ],
                [
                    0.824756801,
                    -1.24597836,
                    0.0101674674,
                    -0.0053191185,
                    0.000648498768,
                    0.0149177071,
                ],
            ],
            [
                [
                    0.0721515939,
                    0.821195722,
                    0.00536925672,
                    -0.00287094736,
                    -0.00156897865,
                    -0.00167869008,
                ],
                [
                    0.321195751,
                    1.15551984,
                    0.00536925672,
                    -0.00287094736,
                    -0.00176776689,
                    0.0147581473,
                ],
                [
                    0.295140028,
                    0.895449817,
                    0.0101674674,
                    -0.0053191185,
                    0.000648498768,
                    0.0149177071,
                ],
            ],
            [
                [
                    0.643936932,
                    0.0323438272,
                    0.000170418803,
                    3.5813664e-05,
                    -5.64705806e-05,
                    -0.000398992823,
                ],
                [
                    0.532343805,
                    -3.80590248,
                    0.000170418803,
                    3.5813664e-05,
                    -0.00176776689,
                    0.0147581473,
                ],
                [
                    8.76435184,
                    -3.6105783,
                    0.0101674674,
                    -0.0053191185,
                    0.000648498768,
                    0.0149177071,
                ],
            ],
            [
                [
                    0.858940423,
                    0.382103622,
                    -0.00431140047,
                    0.00133929262,
                    -0.000543549599,
                    -0.0036089737,
                ],
                [
                    0.882103562,
                    -0.834733248,
                    -0.00431140047,
                    0.00133929262,
                    -0.00176776689,
                    0.0147581473,
                ],
                [
                    0.141313449,
                    -0.967889965,
                    0.0101674674,
                    -0.0053191185,
                    0.000648498768,
                    0.0149177071,
                ],
            ],
        ];
        let t = to_texture();
        let mappings = [
            Mapping2D::Spherical(t),
            Mapping2D::Cylindrical(t),
            Mapping2D::Planar {
                to_texture: t,
                vs: Vec3::new(1.0, 0.5, 0.0),
                vt: Vec3::new(0.0, 0.25, 1.0),
                ds: 0.3,
                dt: -0.2,
            },
        ];
        for (p, want) in POINTS.into_iter().zip(want) {
            let tc = narrow(p);
            for (m, w) in mappings.iter().zip(want) {
                let st = m.map(&tc);
                let f = st.footprint;
                let got = [st.uv.x, st.uv.y, f.dudx, f.dudy, f.dvdx, f.dvdy];
                for (g, w) in got.iter().zip(w) {
                    assert!((g - w).abs() <= 1e-5 * w.abs().max(1.0), "{p} {m:?}: {got:?} vs {w:?}");
                }
                // The point's own footprint stays for what the texture holds.
                assert_eq!((f.dpdx, f.dpdy), (tc.footprint.dpdx, tc.footprint.dpdy));
                // In a scene reflected across x = 0 the mapping reads the
                // point carried back: the same (s, t) at the reflected point.
                let r = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
                let mirrored = TexCoord {
                    p: r.transform_point3(p),
                    ..tc
                };
                let back = m.reflected(&r).map(&mirrored).uv;
                assert!((back - st.uv).abs().max_element() < 1e-5, "{m:?}: {back} vs {}", st.uv);
            }
        }
    }

    #[test]
    #[allow(clippy::excessive_precision)] // as pbrt-v4 printed them
    fn checkerboards_are_filtered_as_pbrts() {
        // pbrt-v4's `Checkerboard` weights at the points above: a 2D board
        // (uscale 4, vscale 2, udelta 0.1) and a 3D one in the texture space
        // above, looked up with a narrow footprint and a wide one.
        let want = [
            [0.483362257, 0.0, 0.347222209, 0.184665561],
            [0.483362257, 0.0, 0.347222209, 0.302070141],
            [0.483362257, 0.0, 0.347222209, 0.13516295],
            [0.483362257, 0.0, 0.347222209, 0.17478025],
        ];
        let board = Mapping2D::Uv(UvMapping {
            su: 4.0,
            sv: 2.0,
            du: 0.1,
            dv: 0.0,
        });
        let t = to_texture();
        for (p, want) in POINTS.into_iter().zip(want) {
            let narrow = narrow(p);
            let wide = lookup(
                p,
                Vec2::new(0.25, 0.77),
                [0.1, 0.02, 0.03, 0.04],
                Vec3::new(0.4, 0.2, 0.0),
                Vec3::new(0.0, -0.3, 0.5),
            );
            let weight2 = |tc: &TexCoord| {
                let st = board.map(tc);
                checkerboard_weight(st.uv, &st.footprint)
            };
            let got = [
                weight2(&narrow),
                checkerboard_weight_3d(&t, &narrow),
                weight2(&wide),
                checkerboard_weight_3d(&t, &wide),
            ];
            for (g, w) in got.iter().zip(want) {
                assert!((g - w).abs() < 1e-5, "{p}: {got:?} vs {want:?}");
            }
        }
        // Without a footprint, the sharp board: even cells 0, odd cells 1.
        assert_eq!(checkerboard_weight(Vec2::new(0.5, 0.5), &Footprint::NONE), 0.0);
        assert_eq!(checkerboard_weight(Vec2::new(1.5, 0.5), &Footprint::NONE), 1.0);
        assert_eq!(checkerboard_weight(Vec2::new(-0.5, 0.5), &Footprint::NONE), 1.0);
    }

    #[test]
    fn polka_dots_are_pbrts() {
        // How many of a 10 x 10 grid of points 0.1 apart from each corner
        // lie in pbrt-v4's dots (`InsidePolkaDot`, printed by a program
        // linked against pbrt-v4).
        let cases = [
            ((0.1, 0.2), 15),
            ((3.3, -1.9), 0),
            ((10.05, 7.2), 0),
            ((-4.6, 2.4), 39),
            ((0.9, 0.1), 0),
            ((5.2, 5.1), 25),
            ((-2.0, -3.1), 5),
            ((7.7, -8.3), 37),
        ];
        for ((s, t), want) in cases {
            let corner = Vec2::new(s, t);
            let inside = (0..10)
                .flat_map(|i| (0..10).map(move |j| Vec2::new(i as f32 * 0.1, j as f32 * 0.1)))
                .filter(|&d| inside_polka_dot(corner + d))
                .count();
            assert_eq!(inside, want, "{corner}");
        }
    }

    #[test]
    fn marble_follows_pbrts_spline_and_noise_stays_within_its_bound() {
        let marble = NoiseTexture {
            to_texture: Affine3A::IDENTITY,
            pattern: Pattern::Marble {
                octaves: 8,
                omega: 0.5,
                scale: 1.0,
                variation: 0.0,
            },
        };
        // Without variation marble is a function of y alone: t = 0.5 +
        // 0.5 sin(y). At t = 1/2 (y = 0) the spline's fourth of six segments
        // starts, at its control point 0.5 grey; at t = 0 the first, at
        // (0.58, 0.58, 0.6); each times 1.5.
        let at = |y: f32| marble.evaluate(&TexCoord::at(Vec2::ZERO, Vec3::new(0.3, y, -2.0), Vec3::Z));
        assert!((at(0.0) - Vec3::splat(0.75)).abs().max_element() < 1e-5, "{}", at(0.0));
        let bottom = at(-std::f32::consts::FRAC_PI_2);
        assert!(
            (bottom - 1.5 * Vec3::new(0.58, 0.58, 0.6)).abs().max_element() < 1e-5,
            "{bottom}"
        );
        for pattern in [
            Pattern::Fbm { octaves: 8, omega: 0.5 },
            Pattern::Wrinkled { octaves: 3, omega: 0.9 },
            Pattern::Windy,
        ] {
            let n = NoiseTexture {
                to_texture: Affine3A::IDENTITY,
                pattern,
            };
            for i in 0..2000 {
                let p = Vec3::new(i as f32 * 0.137, (i % 37) as f32 * 0.71, (i % 11) as f32 * -0.39);
                let v = n.evaluate(&TexCoord::at(Vec2::ZERO, p, Vec3::Z)).x;
                assert!(
                    v.abs() <= n.max_value(),
                    "{pattern:?} at {p}: {v} beyond {}",
                    n.max_value()
                );
            }
        }
    }
}
