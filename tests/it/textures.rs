//! Textures and materials in TOML scene files: a checkerboard floor seen by
//! rays and in a render, image textures from files beside the scene, every
//! material type, and the errors bad values give.

use raytracer::integrator::{render, IntegratorKind, RenderSettings};
use raytracer::material::{ConductorFresnel, Material, Roughness};
use raytracer::math::{Ray, Vec2, Vec3};
use raytracer::scene::{load, LoadOptions};
use raytracer::texture::{TexCoord, Texture};
use raytracer::Scene;
use std::path::Path;
use std::sync::Arc;

const CAMERA: &str =
    "[camera]\nposition = [0, -3, 0]\nlook_at = [0, 0, 0]\nup = [0, 0, 1]\nfov_y = 40\nwidth = 32\nheight = 32\n";

/// A 2 x 2 floor in y = 0 with texture coordinates (x + 1) / 2, (z + 1) / 2,
/// its material's reflectance a checkerboard of 2 x 2 squares.
const FLOOR: &str = r#"
[textures.checks]
type = "checkerboard"
tex1 = 0.8
tex2 = [0.1, 0.1, 0.1]
uscale = 2
vscale = 2

[materials.floor]
type = "diffuse"
reflectance = "checks"

[[lights]]
type = "point"
position = [0, -2, 0]
power = 50

[[shapes]]
type = "quad"
material = "floor"
vertices = [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]]
uvs = [[0, 0], [1, 0], [1, 1], [0, 1]]
"#;

fn write_scene(dir: &Path, text: &str) -> String {
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

#[test]
fn a_checkerboard_floor_is_bright_and_dark_where_its_squares_are() {
    let dir = tempfile::tempdir().unwrap();
    let scene = load(
        &write_scene(dir.path(), &format!("{CAMERA}{FLOOR}")),
        &LoadOptions::default(),
    )
    .unwrap();
    let scene = Scene::build(scene.desc).unwrap();
    // Rays straight down onto each square: the hit's uv and the reflectance there.
    for (x, z, want) in [(-0.5, -0.5, 0.8), (0.5, -0.5, 0.1), (-0.5, 0.5, 0.1), (0.5, 0.5, 0.8)] {
        let hit = scene
            .intersect(&Ray::new(Vec3::new(x, -1.0, z), Vec3::Y), 1e-4, f32::INFINITY)
            .unwrap();
        let uv = Vec2::new((x + 1.0) / 2.0, (z + 1.0) / 2.0);
        assert!((hit.uv - uv).abs().max_element() < 1e-5, "({x}, {z}): {}", hit.uv);
        let Material::Diffuse { reflectance } = scene.material(hit.material) else {
            panic!("not diffuse");
        };
        let r = reflectance.evaluate(&TexCoord::at(hit.uv, hit.p, hit.ng));
        assert_eq!(r, Vec3::splat(want), "({x}, {z})");
    }
    // The render: image x grows with world x, image y with -z. The light
    // above the centre lights the four quarters alike, so they differ by the
    // reflectances' ratio, 8.
    let settings = RenderSettings {
        ssaa: 1,
        integrator: IntegratorKind::Direct,
        ..Default::default()
    };
    let film = render(&scene, &settings, &|| {}).unwrap().film;
    // Means over mirror-image 6 x 6 blocks (samples are jittered within pixels).
    let block = |x0: u32, y0: u32| {
        let mut sum = 0.0;
        for y in y0..y0 + 6 {
            for x in x0..x0 + 6 {
                sum += film.get(x, y).x;
            }
        }
        sum / 36.0
    };
    let (top_left, top_right) = (block(5, 5), block(21, 5));
    let (bottom_left, bottom_right) = (block(5, 21), block(21, 21));
    // Top left is x < 0, z > 0: the dark square; bottom left (z < 0) the bright one.
    assert!((bottom_left / top_left - 8.0).abs() < 0.25, "{bottom_left} {top_left}");
    assert!((top_right / top_left - 8.0).abs() < 0.25, "{top_right} {top_left}");
    assert!(
        (bottom_right / top_left - 1.0).abs() < 0.03,
        "{bottom_right} {top_left}"
    );
}

#[test]
fn image_textures_load_beside_the_scene_and_are_shared() {
    let dir = tempfile::tempdir().unwrap();
    // 2 x 1: sRGB 128 on the left, white on the right.
    image::save_buffer(
        dir.path().join("tex.png"),
        &[128, 128, 128, 255, 255, 255],
        2,
        1,
        image::ColorType::Rgb8,
    )
    .unwrap();
    let text = format!(
        "{CAMERA}\n[textures.a]\ntype = \"image\"\nfile = \"tex.png\"\nwrap = \"clamp\"\n\
         [textures.b]\ntype = \"image\"\nfile = \"tex.png\"\nscale = 0.5\n\
         [textures.lin]\ntype = \"image\"\nfile = \"tex.png\"\nencoding = \"linear\"\n\
         [textures.m]\ntype = \"mix\"\ntex1 = \"a\"\ntex2 = \"b\"\namount = 0.25\n\
         [materials.x]\nreflectance = \"m\"\n[materials.y]\nreflectance = \"lin\"\n"
    );
    let d = load(&write_scene(dir.path(), &text), &LoadOptions::default())
        .unwrap()
        .desc;
    let get = |n: &str| d.materials.iter().find(|(k, _)| k == n).unwrap().1.clone();
    let Material::Diffuse {
        reflectance: Texture::Mix { a, b, .. },
    } = get("x")
    else {
        panic!("{:?}", get("x"));
    };
    let (Texture::Image(a), Texture::Image(b)) = (&*a, &*b) else {
        panic!("not images");
    };
    assert!(Arc::ptr_eq(&a.image, &b.image), "one file, one decoded image");
    let left = TexCoord::at(Vec2::new(0.0, 0.5), Vec3::ZERO, Vec3::Z);
    assert!((a.evaluate(left.uv).x - 0.2158605).abs() < 1e-5);
    let Material::Diffuse { reflectance: lin } = get("y") else {
        panic!()
    };
    let Texture::Image(lin) = lin else { panic!() };
    assert!(!Arc::ptr_eq(&a.image, &lin.image), "another encoding, another image");
    // The fingerprint's Debug form names the file, not its pixels.
    let dbg = format!("{:?}", get("x"));
    assert!(dbg.contains("tex.png") && !dbg.contains("0.2158"), "{dbg}");
}

#[test]
fn every_material_type_is_read_with_pbrt_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "{CAMERA}\n[materials.d]\n\
         [materials.cu]\ntype = \"conductor\"\n\
         [materials.au]\ntype = \"conductor\"\nmetal = \"Au\"\nroughness = 0.2\n\
         [materials.ek]\ntype = \"conductor\"\neta = [0.2, 0.9, 1.1]\nk = 3\nuroughness = 0.1\nvroughness = 0.3\nremap_roughness = false\n\
         [materials.r]\ntype = \"conductor\"\nreflectance = [0.9, 0.5, 0.2]\n\
         [materials.g]\ntype = \"dielectric\"\n\
         [materials.rg]\ntype = \"dielectric\"\neta = 1.33\nroughness = 0.1\n\
         [materials.t]\ntype = \"thindielectric\"\n\
         [materials.c]\ntype = \"coateddiffuse\"\nreflectance = [0.2, 0.3, 0.4]\nroughness = 0.05\n\
         [materials.dt]\ntype = \"diffusetransmission\"\n\
         [materials.m]\ntype = \"mirror\"\n[materials.gl]\ntype = \"glass\"\n"
    );
    let d = load(&write_scene(dir.path(), &text), &LoadOptions::default())
        .unwrap()
        .desc;
    let get = |n: &str| d.materials.iter().find(|(k, _)| k == n).unwrap().1.clone();
    let c = |v: f32| Texture::Constant(Vec3::splat(v));
    let metal = |name| {
        let (eta, k) = raytracer::bsdf::named_metal(name).unwrap();
        ConductorFresnel::Ior { eta, k }
    };
    assert_eq!(get("d"), Material::Diffuse { reflectance: c(0.5) });
    assert_eq!(
        get("cu"),
        Material::Conductor {
            fresnel: metal("Cu"),
            roughness: Roughness::SMOOTH.into()
        }
    );
    assert_eq!(
        get("au"),
        Material::Conductor {
            fresnel: metal("Au"),
            roughness: Roughness::isotropic(0.2, true).into()
        }
    );
    assert_eq!(
        get("ek"),
        Material::Conductor {
            fresnel: ConductorFresnel::Ior {
                eta: Vec3::new(0.2, 0.9, 1.1),
                k: Vec3::splat(3.0)
            },
            roughness: Roughness {
                u: 0.1,
                v: 0.3,
                remap: false
            }
            .into()
        }
    );
    assert_eq!(get("r"), Material::mirror(Vec3::new(0.9, 0.5, 0.2)));
    assert_eq!(get("g"), Material::glass(1.5));
    assert_eq!(
        get("rg"),
        Material::Dielectric {
            eta: 1.33,
            roughness: Roughness::isotropic(0.1, true).into()
        }
    );
    assert_eq!(get("t"), Material::ThinDielectric { eta: 1.5 });
    assert_eq!(
        get("c"),
        Material::CoatedDiffuse {
            reflectance: Texture::Constant(Vec3::new(0.2, 0.3, 0.4)),
            roughness: Roughness::isotropic(0.05, true).into(),
            eta: 1.5,
            thickness: 0.01,
            medium: None,
        }
    );
    assert_eq!(
        get("dt"),
        Material::DiffuseTransmission {
            reflectance: c(0.25),
            transmittance: c(0.25)
        }
    );
    assert_eq!(get("m"), Material::mirror(Vec3::ONE));
    assert_eq!(get("gl"), Material::glass(1.5));
}

#[test]
fn bad_materials_and_textures_are_one_line_errors_at_their_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("notes.png"), "not an image").unwrap();
    // CAMERA is 7 lines; each case's first line is line 8.
    let cases: [(&str, usize, &str); 13] = [
        (
            "[materials.x]\ntype = \"conductor\"\nroughness = -0.1\n",
            10,
            "roughness -0.1 must be >= 0",
        ),
        (
            "[materials.x]\ntype = \"dielectric\"\neta = 0\n",
            10,
            "eta 0 must be > 0",
        ),
        (
            "[materials.x]\ntype = \"conductor\"\neta = [1, -1, 1]\nk = 1\n",
            10,
            "eta",
        ),
        (
            "[textures.t]\ntype = \"image\"\nfile = \"absent.png\"\n",
            10,
            "absent.png not found",
        ),
        (
            "[textures.t]\ntype = \"image\"\nfile = \"notes.png\"\n",
            10,
            "notes.png",
        ),
        (
            "[materials.x]\nreflectance = \"nothing\"\n",
            9,
            "unknown texture 'nothing'",
        ),
        (
            "[textures.a]\ntype = \"scale\"\ntex = \"b\"\n[textures.b]\ntype = \"mix\"\namount = \"a\"\n",
            13,
            "cycle: a -> b -> a",
        ),
        (
            "[materials.x]\ntype = \"diffuse\"\neta = 1.5\n",
            10,
            "`eta` does not apply",
        ),
        ("[textures.t]\ntype = \"noise\"\n", 9, "unknown texture type 'noise'"),
        (
            "[textures.t]\ntype = \"image\"\nfile = \"notes.png\"\nwrap = \"mirror\"\n",
            11,
            "wrap 'mirror'",
        ),
        (
            "[textures.t]\ntype = \"image\"\nfile = \"notes.png\"\nfilter = \"sharp\"\n",
            11,
            "filter 'sharp'",
        ),
        (
            "[materials.x]\ntype = \"coateddiffuse\"\nthickness = 0\n",
            10,
            "thickness",
        ),
        ("[materials.x]\ntype = \"metal\"\n", 9, "unknown material type 'metal'"),
    ];
    for (case, line, what) in cases {
        let path = write_scene(dir.path(), &format!("{CAMERA}{case}"));
        let e = match load(&path, &LoadOptions::default()) {
            Ok(_) => panic!("{case}: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.starts_with(&format!("{path}:{line}: ")),
            "wrong line in '{e}' for\n{case}"
        );
        assert!(e.contains(what), "'{e}' does not say '{what}'");
        assert!(!e.contains('\n'), "'{e}' is not one line");
    }
}

#[test]
fn a_normal_map_beside_the_scene_tilts_the_shading_normal_of_any_material() {
    let dir = tempfile::tempdir().unwrap();
    // One texel (255, 128, 128): the normal tilted all the way along +dp/du.
    image::save_buffer(dir.path().join("n.png"), &[255, 128, 128], 1, 1, image::ColorType::Rgb8).unwrap();
    let text = format!(
        "{CAMERA}\n[materials.tilted]\nnormal_map = \"n.png\"\n\
         [materials.shiny]\ntype = \"conductor\"\nroughness = 0.2\nnormal_map = \"n.png\"\n\
         [[shapes]]\ntype = \"quad\"\nmaterial = \"tilted\"\n\
         vertices = [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]]\nuvs = [[0, 0], [1, 0], [1, 1], [0, 1]]\n"
    );
    let loaded = load(&write_scene(dir.path(), &text), &LoadOptions::default()).unwrap();
    let get = |n: &str| loaded.desc.materials.iter().find(|(k, _)| k == n).unwrap().1.clone();
    let Material::NormalMapped { base, map, .. } = get("shiny") else {
        panic!("{:?}", get("shiny"))
    };
    assert!(matches!(*base, Material::Conductor { .. }));
    // Read as linear values, not decoded as sRGB.
    assert_eq!(map.pixel(0), Vec3::new(1.0, 128.0 / 255.0, 128.0 / 255.0));
    // Seen by a ray, the quad's shading normal leans along dp/du (+x) as far
    // as the map says: (2 x 1 - 1, 2 x 128/255 - 1, 2 x 128/255 - 1) normalised.
    let scene = Scene::build(loaded.desc.clone()).unwrap();
    let hit = scene
        .intersect(&Ray::new(Vec3::new(0.2, -1.0, 0.3), Vec3::Y), 0.0, f32::INFINITY)
        .unwrap();
    let m = scene.material(hit.material);
    let frame = m.bsdf(&scene.surface(&hit), -Vec3::Y).frame;
    let e = 2.0 * 128.0 / 255.0 - 1.0;
    let n = hit.ng * e + Vec3::new(1.0, 0.0, 0.0) + hit.ng.cross(Vec3::X) * e;
    assert!(
        (frame.z - n.normalize()).length() < 1e-4,
        "{} against {}",
        frame.z,
        n.normalize()
    );
    // Errors at the key's line: a missing file, and a displacement as well.
    for (extra, what) in [
        ("[materials.bad]\nnormal_map = \"none.png\"\n", "image file"),
        (
            "[materials.bad]\nnormal_map = \"n.png\"\ndisplacement = 0.1\n",
            "not both",
        ),
    ] {
        let path = write_scene(dir.path(), &format!("{text}{extra}"));
        let e = load(&path, &LoadOptions::default()).unwrap_err().to_string();
        assert!(
            e.contains("scene.toml:") && e.contains("normal_map") && e.contains(what),
            "{e}"
        );
    }
}
