use raytracer::scene::{load, LoadOptions};
use raytracer::Scene;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut loaded = load(&args[1], &LoadOptions::default()).unwrap();
    let _ = &mut loaded;
    let scene = Scene::build(loaded.desc).unwrap();
    let (x, y): (f32, f32) = (args[2].parse().unwrap(), args[3].parse().unwrap());
    let ray = scene.camera.generate_ray(x, y);
    let mut r = ray;
    for _ in 0..6 {
        let Some(hit) = scene.intersect(&r, 0.0, f32::INFINITY) else {
            println!("escapes {}", r.d);
            break;
        };
        let m = scene.material(hit.material);
        let sp = scene.surface(&hit);
        println!(
            "hit t {} p {} ng {} ns {} spns {} mat {:?}",
            hit.t,
            hit.p,
            hit.ng,
            hit.ns,
            sp.ns,
            format!("{m:?}").chars().take(60).collect::<String>()
        );
        let wo = -r.d;
        let bsdf = m.bsdf(&sp, wo);
        // follow the transmission lobe (uc near 1)
        let Some(bs) = bsdf.sample_f(
            wo,
            0.999,
            raytracer::math::Vec2::new(0.5, 0.5),
            raytracer::bsdf::TransportMode::Radiance,
        ) else {
            println!("  no sample");
            break;
        };
        println!(
            "  sample flags {:?} wi {} f {} pdf {} keeps_side {}",
            bs.flags,
            bs.wi,
            bs.f,
            bs.pdf,
            hit.keeps_side(wo, bs.wi, bs.flags)
        );
        r = raytracer::math::Ray::new(raytracer::math::offset_origin(hit.p, hit.ng, bs.wi), bs.wi);
    }
}
