use super::*;
use crate::integrator::{render, RenderSettings};
use crate::material::{CoatMedium, ConductorFresnel, Roughness};
use crate::scene::builtin;
use crate::scene::mesh::tests::bunny_path;
use crate::Scene;
use std::path::PathBuf;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn parse_str(text: &str) -> Result<LoadedScene> {
    parse(Path::new("test.toml"), text, &LoadOptions::default())
}

/// Renders a small, quick PFM of the scene and returns its bytes.
fn small_pfm(mut desc: SceneDesc, dir: &Path, name: &str) -> Vec<u8> {
    desc.camera.width = 64;
    desc.camera.height = 64;
    let scene = Scene::build(desc).unwrap();
    let settings = RenderSettings {
        ssaa: 2,
        shadow_samples: 2,
        ..Default::default()
    };
    let out = render(&scene, &settings, &|| {}).unwrap();
    let p = dir.join(name);
    crate::image_io::write_image(&out.film, &p, 0.0).unwrap();
    std::fs::read(p).unwrap()
}

/// The settings a scene resolves to with nothing on the command line.
fn same_settings(d: &SceneDesc) -> crate::settings::RenderSettings {
    let none = crate::settings::Layer::default();
    let layers = crate::settings::Layers {
        command_line: &none,
        scene_file: &d.settings.scene_file,
        preset: &d.settings.preset,
    };
    crate::settings::resolve(layers, Default::default()).unwrap()
}

fn without_settings(d: &SceneDesc) -> SceneDesc {
    SceneDesc {
        settings: Default::default(),
        ..d.clone()
    }
}

#[test]
fn a_spherical_camera_needs_no_field_of_view() {
    let text = "[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nspherical = \"equirectangular\"\nwidth = 64\nheight = 32\n";
    let desc = parse_str(text).unwrap().desc;
    assert_eq!(
        desc.camera.spherical,
        Some(crate::camera::SphericalMapping::Equirectangular)
    );
    let cam = desc.camera.camera().unwrap();
    // A quarter across the middle row: along the view, +z.
    assert!((cam.generate_ray(16.0, 16.0).d - Vec3::Z).length() < 1e-5);
}

#[test]
fn cornell_toml_is_the_builtin_scene_bit_for_bit() {
    let file = load(&scenes_dir().join("cornell.toml"), &LoadOptions::default()).unwrap();
    let embedded = builtin::cornell();
    assert!(file.meshes.is_empty());
    // Same numbers, in the same order, down to the last bit; the built-in
    // scene's settings are its preset, the file's its own, and resolve alike.
    assert_eq!(same_settings(&file.desc), same_settings(&embedded));
    assert_eq!(without_settings(&file.desc), without_settings(&embedded));
    let dir = tempfile::tempdir().unwrap();
    let a = small_pfm(file.desc, dir.path(), "file.pfm");
    let b = small_pfm(embedded, dir.path(), "builtin.pfm");
    assert_eq!(a.len(), 64 * 64 * 12 + "PF\n64 64\n-1.0\n".len());
    assert!(a == b, "the PFM files differ");
}

#[test]
fn every_shape_and_light_type_is_read() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.mtl"), "newmtl red\nKd 0.8 0.1 0.1\n").unwrap();
    std::fs::write(
        dir.path().join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 2 0 0\nv 0 2 0\nusemtl red\nf 1 2 3\n",
    )
    .unwrap();
    let text = r#"
        [camera]
        position = [0, 0, -3]
        look_at = [0, 0, 0]
        fov_y = 40
        width = 32

        [settings]
        ssaa = 3

        [materials.grey]
        albedo = [0.5, 0.5, 0.5]
        [materials.spare]
        type = "diffuse"
        albedo = [0, 0, 0]

        [[lights]]
        type = "point"
        position = [0, -1, 0]
        power = 10
        colour = [1, 0.5, 0]
        [[lights]]
        type = "sphere"
        centre = [0, -1, 1]
        radius = 0.25
        power = 2

        [[shapes]]
        type = "triangle"
        material = "grey"
        vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
        normals = [[0, 0, 1], [0, 0, 1], [0, 0, 1]]
        [[shapes]]
        type = "quad"
        material = "grey"
        vertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
        [[shapes]]
        type = "box"
        material = "grey"
        min = [-1, -1, -1]
        max = [1, 2, 3]
        [[shapes]]
        type = "sphere"
        material = "grey"
        centre = [0, 0, 5]
        radius = 0.5
        [[shapes]]
        type = "mesh"
        path = "m.obj"
        scale = 0.5
        translate = [0, 0, 1]
    "#;
    let path = dir.path().join("s.toml");
    let s = parse(&path, text, &LoadOptions::default()).unwrap();
    let d = &s.desc;
    assert_eq!(d.name, "s");
    assert_eq!((d.camera.width, d.camera.height), (32, 512));
    assert_eq!(d.camera.up, Vec3::new(0.0, -1.0, 0.0));
    let origin = crate::settings::Origin::SceneFile {
        path: path.clone(),
        line: 9,
    };
    let ssaa = d.settings.scene_file.get("ssaa");
    assert_eq!(ssaa, Some(&(crate::settings::Value::Int(3), origin)));
    assert_eq!(d.settings.scene_file.get("shadow_samples"), None);
    assert_eq!(
        d.lights[0],
        Light::Point {
            position: Vec3::new(0.0, -1.0, 0.0),
            power: Vec3::new(10.0, 5.0, 0.0),
        }
    );
    assert!(matches!(d.lights[1], Light::Sphere { sphere, .. } if sphere.radius == 0.25));
    // 1 triangle + 2 for the quad + 12 for the box + 1 from the mesh.
    assert_eq!(d.triangles.len(), 16);
    assert_eq!(d.triangles.normals(0), Some([Vec3::Z; 3]));
    assert_eq!(
        d.triangles.vertices(2).unwrap(),
        [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)]
    );
    let mut b = crate::math::Aabb::EMPTY;
    for t in d.triangles.range(3..15) {
        t.vertices.iter().for_each(|&v| b.grow(v));
        // Every box face lies in one of the box's planes.
        let n = crate::geometry::Triangle::new(t.vertices[0], t.vertices[1], t.vertices[2]).normal_raw();
        assert_eq!(n.abs().cmpgt(Vec3::ZERO).bitmask().count_ones(), 1, "{t:?}");
    }
    assert_eq!((b.min, b.max), (Vec3::splat(-1.0), Vec3::new(1.0, 2.0, 3.0)));
    assert_eq!(d.spheres.len(), 1);
    // The mesh, scaled then moved, takes its MTL colour as a material.
    let m = &d.triangles.get(15).unwrap();
    assert_eq!(
        m.vertices,
        [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0)
        ]
    );
    assert_eq!(
        d.materials[m.material as usize],
        ("m/red".into(), Material::diffuse(0.8, 0.1, 0.1))
    );
    // Unused materials still belong to the scene.
    assert!(d.materials.iter().any(|(n, _)| n == "spare"));
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.meshes[0].triangles, 1);
    Scene::build(s.desc).unwrap();
}

const CAMERA: &str = "[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nfov_y = 40\n";

#[test]
fn errors_name_the_file_and_line() {
    let m = "[materials.grey]\nalbedo = [0.5, 0.5, 0.5]\n";
    let cases: Vec<(String, usize, &str)> = vec![
        (format!("{CAMERA}fov = 3\n"), 5, "unknown field `fov`"),
        ("[camera]\nposition = [0, 0]\n".into(), 2, "three numbers, found 2"),
        ("[camera]\nposition = [0, 0, -3, 7]\n".into(), 2, "three numbers, found 4"),
        ("[camera]\nposition = [0, 0, 0, \"junk\"]\n".into(), 2, "invalid type: string"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"triangle\"\nmaterial = \"grey\"\nvertices = [[0, 0, 0, 9], [1, 0, 0], [0, 1, 0]]\n"), 10, "three numbers, found 4"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"triangle\"\nmaterial = \"grey\"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nuvs = [[0, 0, 1], [1, 0], [0, 1]]\n"), 11, "two numbers, found 3"),
        ("[camera\n".into(), 1, ""),
        (format!("{CAMERA}[settings]\nssaa = -1\n"), 6, "ssaa = -1: expected a whole number"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"sphere\"\nmaterial = \"grey\"\ncentre = [0, 0, 0]\n"), 7, "missing `radius`"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"cone\"\n"), 8, "unknown variant `cone`"),
        (format!("{CAMERA}{m}\n[[shapes]]\ntype = \"sphere\"\nmaterial = \"gray\"\ncentre = [0, 0, 0]\nradius = 1\n"), 10, "unknown material 'gray'"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"quad\"\nmaterial = \"grey\"\nradius = 1\nvertices = []\n"), 7, "`radius` does not apply to a quad"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"quad\"\nmaterial = \"grey\"\nvertices = [[0, 0, 0]]\n"), 7, "needs 4 points"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"triangle\"\nmaterial = \"grey\"\nvertices = [[0, 0, nan], [1, 0, 0], [0, 1, 0]]\n"), 10, "finite"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"mesh\"\npath = \"a.obj\"\nscale = [1, 2]\n"), 10, "a number or an array of three numbers"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"mesh\"\npath = \"a.obj\"\nscale = 0\n"), 7, "non-zero"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"mesh\"\npath = \"a.obj\"\nfit = {{ height = 1 }}\n"), 10, "bottom_centre"),
        (format!("{CAMERA}{m}[[shapes]]\ntype = \"mesh\"\npath = \"no-such.obj\"\n"), 7, "no-such.obj not found (pass --mesh PATH"),
        (format!("{CAMERA}[materials.a]\nalbedo = [2, 0, 0]\n"), 6, "[0, 1]"),
        (format!("{CAMERA}[[lights]]\ntype = \"sphere\"\ncentre = [0, 0, 0]\npower = 1\n"), 5, "missing `radius`"),
        (format!("{CAMERA}[[lights]]\ntype = \"point\"\nposition = [0, 0, 0]\nradius = 1\npower = 1\n"), 5, "`radius` does not apply to a point light"),
        (format!("{CAMERA}[[lights]]\ntype = \"quad\"\nvertices = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]\nradiance = [1, 1, 1]\n"), 5, "area is zero"),
        (format!("{CAMERA}[[lights]]\ntype = \"quad\"\nvertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]\n"), 5, "give `radiance` or `power`"),
        (format!("{CAMERA}[[lights]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0]]\nradiance = [1, -1, 1]\n"), 5, "radiance must be >= 0"),
        ("[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nfov_y = 180\n".into(), 1, "fov_y"),
        ("[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, -3]\nfov_y = 40\n".into(), 1, "the camera looks at its own position [0, 0, -3]"),
        ("[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nup = [0, 0, 1]\nfov_y = 40\n".into(), 1, "the camera's up [0, 0, 1] is zero or along its viewing direction"),
        (format!("{CAMERA}[[lights]]\ntype = \"point\"\nposition = [0, 0, 0]\npower = 1e25\n"), 5, "point light: its power is 1e25, beyond the limit of 1e15"),
        (format!("{CAMERA}[[lights]]\ntype = \"sphere\"\ncentre = [0, 0, 0]\nradius = 1e-20\npower = 10\n"), 5, "sphere light: its radiance is inf"),
        (format!("{CAMERA}lens_radius = 0.1\n"), 1, "a lens needs both lens_radius and focal_distance"),
        ("[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\n".into(), 1, "missing `fov_y`"),
        ("[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nspherical = \"cube\"\n".into(), 1, "spherical 'cube': use equalarea or equirectangular"),
        ("[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nspherical = \"equalarea\"\nlens_radius = 0.1\nfocal_distance = 1\n".into(), 1, "a spherical camera has no lens"),
        (format!("{CAMERA}lens_radius = 0.1\nfocal_distance = -1\n"), 1, "must be positive (lens_radius 0: a pinhole)"),
        (format!("{CAMERA}\n[settings]\nssaa = 0\n"), 7, "ssaa = 0: must be between 1 and 64"),
        (format!("{CAMERA}\n[settings]\nssaa = 2\nthreads = 2\n"), 8, "unknown key `threads`"),
        (format!("{CAMERA}\n[settings]\npreset = \"nowhere\"\n"), 7, "no built-in scene 'nowhere'"),
    ];
    for (text, line, what) in cases {
        let e = parse_str(&text).expect_err(&text).to_string();
        assert!(
            e.starts_with(&format!("test.toml:{line}: ")),
            "wrong line in '{e}' for\n{text}"
        );
        assert!(e.contains(what), "'{e}' does not say '{what}'");
        assert!(!e.contains('\n'), "'{e}' is not one line");
    }
}

#[test]
fn mesh_option_replaces_the_one_mesh_path() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("real.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let text = format!(
        "{CAMERA}[materials.grey]\nalbedo = [0.5, 0.5, 0.5]\n[[shapes]]\ntype = \"mesh\"\npath = \"absent.obj\"\nmaterial = \"grey\"\n"
    );
    let opts = LoadOptions {
        mesh: Some(obj.clone()),
        smooth: false,
        lenient: false,
    };
    let s = parse(Path::new("x.toml"), &text, &opts).unwrap();
    assert_eq!(s.desc.triangles.len(), 1);
    assert_eq!(s.meshes[0].path, obj);
    // A scene without a mesh has nothing for --mesh to replace.
    let e = parse(Path::new("x.toml"), CAMERA, &opts).unwrap_err().to_string();
    assert!(e.contains("--mesh") && e.contains("0 mesh shapes"), "{e}");
}

#[test]
fn cornell_bunny_toml_is_the_builtin_scene() {
    let Some(bunny) = bunny_path() else { return };
    let opts = LoadOptions {
        mesh: Some(bunny),
        smooth: false,
        lenient: false,
    };
    let file = load(&scenes_dir().join("cornell-bunny.toml"), &opts).unwrap();
    let embedded = builtin::by_name("cornell-bunny", &opts).unwrap().unwrap();
    assert_eq!(same_settings(&file.desc), same_settings(&embedded.desc));
    assert_eq!(without_settings(&file.desc), without_settings(&embedded.desc));
}

#[test]
fn smooth_passes_vertex_normals_on_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("n.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nelement face 1\n\
         property list uchar int vertex_indices\nend_header\n0 0 0 0 0 2\n1 0 0 0 0 1\n0 1 0 0 1 1\n3 0 1 2\n",
    )
    .unwrap();
    let scene = |smooth_key: &str, smooth_opt: bool| {
        let text = format!(
            "{CAMERA}[materials.grey]\nalbedo = [0.5, 0.5, 0.5]\n\
             [[shapes]]\ntype = \"mesh\"\npath = \"n.ply\"\nmaterial = \"grey\"\nrotate = [0, 0, 90]\n{smooth_key}"
        );
        let opts = LoadOptions {
            mesh: None,
            smooth: smooth_opt,
            lenient: false,
        };
        parse(&dir.path().join("s.toml"), &text, &opts)
            .unwrap()
            .desc
            .triangles
            .normals(0)
    };
    assert_eq!(scene("", false), None);
    assert_eq!(scene("smooth = false\n", false), None);
    // Normalised and turned with the mesh: z stays, y turns into -x.
    let want = Some([Vec3::Z, Vec3::Z, Vec3::new(-1.0, 0.0, 1.0).normalize()]);
    assert_eq!(scene("smooth = true\n", false), want);
    assert_eq!(scene("", true), want);
}

#[test]
fn mirror_and_glass_materials_are_read_and_checked() {
    let base = r#"
        [camera]
        position = [0, 0, -3]
        look_at = [0, 0, 0]
        fov_y = 40
        [materials.m]
        type = "mirror"
        reflectance = [0.9, 0.8, 0.7]
        [materials.g]
        type = "glass"
        ior = 1.33
        [materials.plain_glass]
        type = "glass"
    "#;
    let d = parse_str(base).unwrap().desc;
    let get = |n: &str| d.materials.iter().find(|(k, _)| k == n).map(|(_, m)| m.clone());
    assert_eq!(get("m"), Some(Material::mirror(Vec3::new(0.9, 0.8, 0.7))));
    assert_eq!(get("g"), Some(Material::glass(1.33)));
    assert_eq!(get("plain_glass"), Some(Material::glass(1.5)));
    for (bad, what) in [
        ("[materials.x]\ntype = \"glass\"\nalbedo = [1, 1, 1]\n", "albedo"),
        ("[materials.x]\ntype = \"glass\"\nior = 0.5\n", "ior"),
        (
            "[materials.x]\ntype = \"mirror\"\nreflectance = [2, 0, 0]\n",
            "reflectance",
        ),
        (
            "[materials.x]\ntype = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\nior = 1.5\n",
            "ior",
        ),
        ("[materials.x]\ntype = \"metal\"\n", "metal"),
    ] {
        let text = format!("[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nfov_y = 40\n{bad}");
        let e = parse_str(&text).unwrap_err().to_string();
        assert!(e.contains("test.toml:") && e.contains(what), "{bad}: {e}");
    }
}

#[test]
fn any_material_may_be_bump_mapped_by_a_displacement() {
    let text = r#"
        [camera]
        position = [0, 0, -3]
        look_at = [0, 0, 0]
        fov_y = 40
        [textures.bumps]
        type = "checkerboard"
        tex1 = 0.02
        tex2 = 0
        [materials.tiles]
        displacement = "bumps"
        [materials.metal]
        type = "conductor"
        roughness = 0.1
        displacement = 0.5
        [materials.plain]
        type = "mirror"
    "#;
    let d = parse_str(text).unwrap().desc;
    let get = |n: &str| {
        d.materials
            .iter()
            .find(|(k, _)| k == n)
            .map(|(_, m)| m.clone())
            .unwrap()
    };
    let Material::Bumped { base, displacement } = get("tiles") else {
        panic!("{:?}", get("tiles"))
    };
    assert_eq!(*base, Material::diffuse(0.5, 0.5, 0.5));
    assert!(
        matches!(displacement, crate::texture::Texture::Checkerboard { .. }),
        "{displacement:?}"
    );
    let Material::Bumped { base, displacement } = get("metal") else {
        panic!("{:?}", get("metal"))
    };
    assert!(matches!(*base, Material::Conductor { .. }) && displacement.as_constant() == Some(Vec3::splat(0.5)));
    assert!(!get("plain").is_bumped());
    // A displacement that is no number, colour or texture is refused at its line.
    let bad = text.replace("displacement = 0.5", "displacement = \"nothing\"");
    let e = parse_str(&bad).unwrap_err().to_string();
    assert!(
        e.starts_with("test.toml:15:") && e.contains("unknown texture 'nothing'"),
        "{e}"
    );
    // Textures do not take one.
    let bad = text.replace("tex2 = 0", "tex2 = 0\ndisplacement = 1");
    let e = parse_str(&bad).unwrap_err().to_string();
    assert!(e.contains("`displacement` does not apply"), "{e}");
}

#[test]
fn any_shape_may_be_cut_out_by_an_alpha() {
    let text = r#"
        [camera]
        position = [0, 0, -3]
        look_at = [0, 0, 0]
        fov_y = 40
        [textures.leaf]
        type = "checkerboard"
        tex1 = 1
        tex2 = 0
        [materials.grey]
        [[shapes]]
        type = "quad"
        material = "grey"
        vertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
        [[shapes]]
        type = "quad"
        material = "grey"
        vertices = [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
        alpha = "leaf"
        [[shapes]]
        type = "sphere"
        material = "grey"
        centre = [0, 0, 3]
        radius = 1
        alpha = 0.25
        [[shapes]]
        type = "box"
        material = "grey"
        min = [0, 0, 0]
        max = [1, 1, 1]
        alpha = 1
    "#;
    let d = parse_str(text).unwrap().desc;
    let leaf = match &d.cutouts[0].alpha {
        crate::texture::Texture::Checkerboard { .. } => true,
        other => panic!("{other:?}"),
    };
    assert!(leaf);
    assert_eq!(d.cutouts[0].shapes, crate::scene::CutShapes::Triangles(2..4));
    assert_eq!(d.cutouts[1].shapes, crate::scene::CutShapes::Sphere(0));
    assert_eq!(d.cutouts[1].alpha.as_constant(), Some(Vec3::splat(0.25)));
    // An alpha of 1 cuts nothing out.
    assert_eq!(d.cutouts.len(), 2);
    let e = parse_str(&text.replace("alpha = \"leaf\"", "alpha = \"stem\""))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("test.toml:19:") && e.contains("unknown texture 'stem' for `alpha`"),
        "{e}"
    );
    let e = parse_str(&text.replace("alpha = 0.25", "alpha = [1, 2]"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("a number or the name of a texture"), "{e}");
}

#[test]
fn shapes_move_by_their_motion_and_bad_motions_are_refused() {
    let text = r#"
        [camera]
        position = [0, 0, -3]
        look_at = [0, 0, 0]
        fov_y = 40
        shutter = [0.25, 0.75]
        [materials.grey]
        [[shapes]]
        type = "quad"
        material = "grey"
        vertices = [[-3, -3, 2], [3, -3, 2], [3, 3, 2], [-3, 3, 2]]
        [[shapes]]
        type = "box"
        material = "grey"
        min = [0, 0, 0]
        max = [1, 2, 1]
        motion = { translate = [1, 0, 0], rotate = [0, 90, 0] }
        [[shapes]]
        type = "sphere"
        material = "grey"
        centre = [0, 0, 3]
        radius = 1
    "#;
    let d = parse_str(text).unwrap().desc;
    assert_eq!(d.shutter, [0.25, 0.75]);
    assert_eq!(d.moving.len(), 1);
    assert_eq!(d.moving[0].triangles, 2..14);
    // The box turns a quarter about its centre (0.5, 1, 0.5) while it
    // slides one unit along x: its corner (0, 0, 0) ends at (1, 0, 1).
    let m = &d.moving[0].motion;
    let centre = Vec3::new(0.5, 1.0, 0.5);
    for (t, at) in [
        (0.0, centre),
        (0.5, centre + Vec3::new(0.5, 0.0, 0.0)),
        (1.0, centre + Vec3::X),
    ] {
        assert!((m.relative(t).transform_point3(centre) - at).length() < 1e-5, "{t}");
    }
    let corner = m.relative(1.0).transform_point3(Vec3::ZERO);
    assert!((corner - Vec3::new(1.0, 0.0, 1.0)).length() < 1e-5, "{corner}");
    // About a point of its own, the box swings around it.
    let about = parse_str(&text.replace("rotate = [0, 90, 0] }", "rotate = [0, 90, 0], about = [0, 0, 0] }"))
        .unwrap()
        .desc;
    let swung = about.moving[0].motion.relative(1.0).transform_point3(centre);
    assert!((swung - Vec3::new(1.5, 1.0, -0.5)).length() < 1e-5, "{swung}");
    // Rays at the shutter's times meet it where it is then.
    let scene = Scene::build(d).unwrap();
    assert!(scene.has_motion() && scene.camera.shutter == Some([0.25, 0.75]));
    let down = |x: f32, time: f32| crate::math::Ray::timed(Vec3::new(x, 1.0, -5.0), Vec3::Z, time);
    let hit = |x: f32, time: f32| scene.intersect(&down(x, time), 0.0, f32::INFINITY).map(|h| h.p.z);
    assert_eq!(hit(1.7, 0.0).map(|z| (z * 1e4).round()), Some(2e4));
    assert!(
        hit(1.7, 1.0).is_some_and(|z| (z - 0.0).abs() < 1e-4),
        "{:?}",
        hit(1.7, 1.0)
    );
    assert!(hit(0.3, 0.0).is_some_and(|z| z.abs() < 1e-4));
    // A sphere moves about its centre.
    let ball = parse_str(&text.replace(
        "radius = 1",
        "radius = 1\n        motion = { translate = [1, 0, 0], scale = 2 }",
    ))
    .unwrap()
    .desc;
    assert_eq!(ball.moving_shapes.len(), 1);
    assert_eq!(ball.moving_shapes[0].shape, crate::scene::CutShapes::Sphere(0));
    let m = ball.moving_shapes[0].motion.relative(1.0);
    let centre = Vec3::new(0.0, 0.0, 3.0);
    assert!((m.transform_point3(centre) - (centre + Vec3::X)).length() < 1e-5);
    assert!((m.transform_point3(centre + Vec3::Y) - (centre + Vec3::new(1.0, 2.0, 0.0))).length() < 1e-5);
    for (from, to, line, why) in [
        (
            "rotate = [0, 90, 0] }",
            "rotate = [0, 90, 0] }\n        alpha = 0.5",
            17,
            "an `alpha` cut-out on a moving shape is not supported",
        ),
        (
            "rotate = [0, 90, 0] }",
            "scale = 0 }",
            17,
            "scale [0.0, 0.0, 0.0] must be positive",
        ),
        ("rotate = [0, 90, 0] }", "speed = 2 }", 17, "unknown field `speed`"),
        (
            "shutter = [0.25, 0.75]",
            "shutter = [0.75, 0.25]",
            6,
            "closes at 0.25, before it opens at 0.75",
        ),
        ("shutter = [0.25, 0.75]", "shutter = [1]", 6, "needs two numbers"),
    ] {
        let e = parse_str(&text.replace(from, to)).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("test.toml:{line}:")) && e.contains(why),
            "{why}: {e}"
        );
    }
    // A medium the camera is in.
    let e = parse_str(
        &text
            .replace("fov_y = 40", "fov_y = 40\n        medium = \"fog\"")
            .replace(
                "[materials.grey]",
                "[materials.grey]\n        [media.fog]\n        sigma_s = 0.1",
            ),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("test.toml:20:") && e.contains("`motion` in a scene with participating media"),
        "{e}"
    );
}

#[test]
fn the_camera_may_move_turning_about_its_position() {
    let text = "[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
                motion = { translate = [1, 0, 0], rotate = [0, 90, 0] }\n";
    let d = parse_str(text).unwrap().desc;
    let m = d.camera_motion.as_ref().unwrap();
    let p = Vec3::new(0.0, 0.0, -3.0);
    // Its position slides straight along x while the view turns a quarter
    // about it: what it looked at, 3 ahead, is 3 along x from it at time 1.
    assert!((m.relative(0.5).transform_point3(p) - Vec3::new(0.5, 0.0, -3.0)).length() < 1e-5);
    let target = m.relative(1.0).transform_point3(Vec3::ZERO);
    assert!((target - Vec3::new(4.0, 0.0, -3.0)).length() < 1e-4, "{target}");
    assert!(Scene::build(d).unwrap().has_motion());
    // A camera in fog; one that would grow; one turning half round a point
    // so far away that it would leave f32's range.
    let fog = format!("{text}[media.fog]\nsigma_s = 0.1\n").replace("fov_y = 40", "fov_y = 40\nmedium = \"fog\"");
    let grows = text.replace("rotate = [0, 90, 0]", "scale = 2");
    let far = text.replace("rotate = [0, 90, 0]", "rotate = [0, 180, 0], about = [3e38, 0, 0]");
    for (bad, line, why) in [
        (fog, 6, "`motion` in a scene with participating media"),
        (grows, 5, "camera: `motion`: a camera does not scale"),
        (far, 5, "beyond finite coordinates"),
    ] {
        let e = parse_str(&bad).unwrap_err().to_string();
        assert!(e.starts_with(&format!("test.toml:{line}:")) && e.contains(why), "{e}");
    }
}

#[test]
fn coated_conductor_materials_are_read_and_checked() {
    let text = format!(
        "{CAMERA}[materials.rims]\ntype = \"coatedconductor\"\nroughness = 0.1\nmetal = \"Al\"\n\
         metal_uroughness = 0.2\nmetal_vroughness = 0.3\nthickness = 0\nmax_depth = 20\n\
         [materials.plain]\ntype = \"coatedconductor\"\nmetal_eta = [0.2, 0.3, 0.4]\nmetal_k = 3\n"
    );
    let d = parse_str(&text).unwrap().desc;
    let get = |n: &str| d.materials.iter().find(|(k, _)| k == n).map(|(_, m)| m.clone());
    let (al_eta, al_k) = crate::bsdf::named_metal("Al").unwrap();
    let rough = |u: f32, v: f32| Roughness { u, v, remap: true }.into();
    assert_eq!(
        get("rims"),
        Some(Material::CoatedConductor {
            interface_roughness: rough(0.1, 0.1),
            eta: 1.5,
            thickness: 0.0,
            conductor: ConductorFresnel::Ior { eta: al_eta, k: al_k },
            conductor_roughness: rough(0.2, 0.3),
            max_depth: 20,
            samples: 1,
            medium: None,
        })
    );
    let Some(Material::CoatedConductor {
        conductor, thickness, ..
    }) = get("plain")
    else {
        panic!("{:?}", get("plain"))
    };
    assert_eq!(thickness, 0.01);
    assert_eq!(
        conductor,
        ConductorFresnel::Ior {
            eta: Vec3::new(0.2, 0.3, 0.4),
            k: Vec3::splat(3.0)
        }
    );
    for (bad, what) in [
        ("metal_eta = 1.2\n", "`metal_eta` needs `metal_k` too"),
        ("metal = \"Au\"\nmetal_k = 2\n", "give `metal` or `metal_k`"),
        (
            "metal_roughness = 0.1\nmetal_uroughness = 0.2\n",
            "give `metal_roughness`",
        ),
        ("metal_roughness = -1\n", "metal_roughness -1 must be >= 0"),
        ("samples = 0\n", "samples 0 must be a whole number"),
        ("eta = 1.5\nior = 1.5\n", "ior"),
    ] {
        let text = format!("{CAMERA}[materials.x]\ntype = \"coatedconductor\"\n{bad}");
        let e = parse_str(&text).unwrap_err().to_string();
        assert!(e.contains("test.toml:") && e.contains(what), "{bad}: {e}");
    }
}

#[test]
fn dielectrics_disperse_with_an_index_per_channel_or_a_named_glass() {
    let text = format!(
        "{CAMERA}[materials.prism]\ntype = \"dielectric\"\neta = [1.5, 1.52, 1.55]\n\
         [materials.lens]\ntype = \"dielectric\"\nglass = \"BK7\"\nroughness = 0.1\n\
         [materials.plain]\ntype = \"dielectric\"\neta = [1.4, 1.4, 1.4]\n"
    );
    let d = parse_str(&text).unwrap().desc;
    let get = |n: &str| d.materials.iter().find(|(k, _)| k == n).map(|(_, m)| m.clone());
    assert_eq!(
        get("prism"),
        Some(Material::Dispersive {
            eta: Vec3::new(1.5, 1.52, 1.55),
            roughness: Roughness::SMOOTH.into(),
        })
    );
    let Some(Material::Dispersive { eta, roughness }) = get("lens") else {
        panic!("{:?}", get("lens"))
    };
    assert!(eta.x < eta.y && eta.y < eta.z && eta.x > 1.51 && eta.z < 1.53, "{eta}");
    assert_eq!(
        roughness,
        Roughness {
            u: 0.1,
            v: 0.1,
            remap: true
        }
        .into()
    );
    // The same index in every channel is a plain dielectric.
    assert!(matches!(get("plain"), Some(Material::Dielectric { eta, .. }) if eta == 1.4));
    for (bad, what) in [
        (
            "glass = \"BK8\"\n",
            "unknown glass 'BK8' (known: BK7, BAF10, FK51A, LASF9, F5, F10, F11)",
        ),
        ("glass = \"BK7\"\neta = 1.5\n", "give `glass` or `eta`"),
        ("eta = [1.5, 0, 1.5]\n", "must be > 0"),
        ("eta = [1.5, 1.6]\n", "`eta` must be a number or [r, g, b]"),
    ] {
        let text = format!("{CAMERA}[materials.x]\ntype = \"dielectric\"\n{bad}");
        let e = parse_str(&text).unwrap_err().to_string();
        assert!(e.contains("test.toml:") && e.contains(what), "{bad}: {e}");
    }
}

#[test]
fn cornell_specular_toml_is_the_builtin_scene() {
    let file = load(&scenes_dir().join("cornell-specular.toml"), &LoadOptions::default()).unwrap();
    let embedded = builtin::cornell_specular();
    assert_eq!(same_settings(&file.desc), same_settings(&embedded));
    assert_eq!(without_settings(&file.desc), without_settings(&embedded));
}

#[test]
fn quad_lights_become_two_triangle_lights_of_the_given_radiance_or_power() {
    let text = format!(
        "{CAMERA}[[lights]]\ntype = \"quad\"\nvertices = [[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]]\n\
         power = 10\ncolour = [1, 0.5, 0]\ntwo_sided = true\n\
         [[lights]]\ntype = \"triangle\"\nvertices = [[0, 0, 1], [1, 0, 1], [0, 1, 1]]\nradiance = [3, 3, 3]\n"
    );
    let d = parse_str(&text).unwrap().desc;
    assert_eq!(d.lights.len(), 3);
    // Power over both sides of a 2 x 1 quad: L = 10 / (pi 2 2).
    let l = 10.0 / (std::f32::consts::PI * 4.0);
    for light in &d.lights[..2] {
        match light {
            Light::Triangle {
                radiance, two_sided, ..
            } => {
                assert!((radiance.x - l).abs() < 1e-5 && (radiance.y - 0.5 * l).abs() < 1e-5 && radiance.z == 0.0);
                assert!(*two_sided);
            }
            other => panic!("{other:?}"),
        }
    }
    let total: f32 = d.lights[..2].iter().map(|l| l.power().x).sum();
    assert!((total - 10.0).abs() < 1e-4, "{total}");
    assert!(matches!(d.lights[2], Light::Triangle { two_sided: false, radiance, .. } if radiance == Vec3::splat(3.0)));
}

#[test]
fn spot_distant_and_infinite_lights_are_read() {
    let text = format!(
        "{CAMERA}[[lights]]\ntype = \"spot\"\nposition = [0, -1, 0]\ndirection = [0, 2, 0]\nintensity = [2, 2, 2]\n\
         scale = 1.5\ncone_angle = 25\ncone_delta = 10\n\
         [[lights]]\ntype = \"spot\"\nposition = [1, -1, 0]\ndirection = [0, 1, 0]\npower = 12\ncolour = [1, 0.5, 0]\n\
         [[lights]]\ntype = \"distant\"\ndirection = [0, 0, -3]\nradiance = [1, 2, 3]\nscale = 2\n\
         [[lights]]\ntype = \"infinite\"\nradiance = [0.5, 0.5, 1]\n\
         [[lights]]\ntype = \"infinite\"\n"
    );
    let d = parse_str(&text).unwrap().desc;
    assert_eq!(d.lights.len(), 5);
    let Light::Spot {
        position,
        direction,
        intensity,
        cos_falloff_start,
        cos_falloff_end,
    } = d.lights[0]
    else {
        panic!("{:?}", d.lights[0])
    };
    assert_eq!(
        (position, direction, intensity),
        (Vec3::new(0.0, -1.0, 0.0), Vec3::Y, Vec3::splat(3.0))
    );
    assert!((cos_falloff_start - 15f32.to_radians().cos()).abs() < 1e-6);
    assert!((cos_falloff_end - 25f32.to_radians().cos()).abs() < 1e-6);
    // Given power, the spot emits it (30 and 5 degrees by default).
    let p = d.lights[1].power();
    assert!((p - Vec3::new(12.0, 6.0, 0.0)).abs().max_element() < 1e-4, "{p}");
    assert!(
        matches!(&d.lights[1], Light::Spot { cos_falloff_end, .. } if (cos_falloff_end - 30f32.to_radians().cos()).abs() < 1e-6)
    );
    assert!(
        matches!(&d.lights[2], Light::Distant { direction, radiance, .. } if *direction == -Vec3::Z && *radiance == Vec3::new(2.0, 4.0, 6.0))
    );
    assert!(
        matches!(&d.lights[3], Light::Infinite { radiance, map: None, .. } if *radiance == Vec3::new(0.5, 0.5, 1.0))
    );
    assert!(matches!(&d.lights[4], Light::Infinite { radiance, map: None, .. } if *radiance == Vec3::ONE));

    // Built, the lights at infinity know the scene's size; only the infinite ones are seen by escaping rays.
    let mut desc = d;
    desc.material("grey", Material::diffuse(0.5, 0.5, 0.5));
    desc.triangles.push(TriangleDesc {
        vertices: [
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
        ],
        normals: None,
        uvs: None,
        material: 0,
    });
    let scene = Scene::build(desc).unwrap();
    assert_eq!(scene.infinite_lights(), &[3, 4]);
    // The bounding box spans the triangle and the spots: [-1, 1] x [-1, 0] x [-1, 1].
    let r = 0.5 * Vec3::new(2.0, 1.0, 2.0).length();
    let expected = Vec3::new(2.0, 4.0, 6.0) * std::f32::consts::PI * r * r;
    assert!(
        (scene.lights[2].power() - expected).abs().max_element() < 1e-3,
        "{:?}",
        scene.lights[2]
    );
    assert!((scene.lights[4].power().x - 4.0 * std::f32::consts::PI.powi(2) * r * r).abs() < 1e-3);
}

/// Writes a `w` x `h` image whose texel (x, y) is `f(x, y)`.
fn write_env(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> Vec3) {
    let mut film = crate::film::Film::new(w, h);
    for y in 0..h {
        for x in 0..w {
            film.set(x, y, f(x, y));
        }
    }
    crate::image_io::write_image(&film, path, 0.0).unwrap();
}

#[test]
fn environment_maps_may_be_hdr_or_8_bit_images_as_pbrt_reads_them() {
    let dir = tempfile::tempdir().unwrap();
    // The same 4 x 2 map as PFM, Radiance HDR and 8-bit PNG.
    let value = |x: u32, y: u32| Vec3::new(0.5 + x as f32, 0.25, 1.0 + y as f32) * 0.25;
    write_env(&dir.path().join("sky.pfm"), 4, 2, value);
    let pixels: Vec<::image::Rgb<f32>> = (0..2)
        .flat_map(|y| (0..4).map(move |x| ::image::Rgb(value(x, y).to_array())))
        .collect();
    let file = std::fs::File::create(dir.path().join("sky.hdr")).unwrap();
    ::image::codecs::hdr::HdrEncoder::new(file)
        .encode(&pixels, 4, 2)
        .unwrap();
    // 8-bit: 188 is 0.5029 in linear sRGB, 0 is 0.
    let mut png = ::image::RgbImage::new(4, 2);
    png.pixels_mut().for_each(|p| *p = ::image::Rgb([188, 0, 188]));
    png.save(dir.path().join("sky.png")).unwrap();
    let map = |name: &str| {
        let path = dir.path().join(format!("{name}.toml"));
        std::fs::write(
            &path,
            format!("{CAMERA}[[lights]]\ntype = \"infinite\"\nfile = \"{name}\"\n"),
        )
        .unwrap();
        let d = load(&path, &LoadOptions::default()).unwrap().desc;
        let Light::Infinite { map: Some(m), .. } = &d.lights[0] else {
            panic!("{:?}", d.lights[0])
        };
        m.texels().to_vec()
    };
    let (pfm, hdr) = (map("sky.pfm"), map("sky.hdr"));
    assert_eq!(pfm.len(), 8);
    for (a, b) in pfm.iter().zip(&hdr) {
        // RGBE keeps 8 bits of mantissa a texel.
        assert!((*a - *b).abs().max_element() <= 0.01 * a.max_element(), "{a} {b}");
    }
    for t in map("sky.png") {
        assert!((t - Vec3::new(0.5029, 0.0, 0.5029)).abs().max_element() < 1e-3, "{t}");
    }
}

#[test]
fn environment_maps_are_read_beside_the_scene_file() {
    use crate::light::EnvMapping;
    let dir = tempfile::tempdir().unwrap();
    // Lat-long: the top row (+z) bright, the rest dim.
    write_env(&dir.path().join("sky.pfm"), 8, 4, |_, y| {
        Vec3::splat(if y == 0 { 5.0 } else { 0.1 })
    });
    write_env(&dir.path().join("oct.exr"), 4, 4, |x, y| {
        Vec3::new(x as f32, y as f32, 1.0)
    });
    let scene = dir.path().join("env.toml");
    std::fs::write(
        &scene,
        format!(
            "{CAMERA}[[lights]]\ntype = \"infinite\"\nfile = \"sky.pfm\"\nscale = 2\nrotate = [90, 0, 0]\n\
             [[lights]]\ntype = \"infinite\"\nfile = \"oct.exr\"\nmapping = \"octahedral\"\n"
        ),
    )
    .unwrap();
    let d = load(&scene, &LoadOptions::default()).unwrap().desc;
    let Light::Infinite { map: Some(m), .. } = &d.lights[0] else {
        panic!("{:?}", d.lights[0])
    };
    assert_eq!((m.width(), m.height(), m.mapping()), (8, 4, EnvMapping::LatLong));
    // Turned by 90 degrees about x, the map's +z (its top row) is the world's up, -y.
    assert_eq!(d.lights[0].le_escaped(Vec3::ZERO, -Vec3::Y), Vec3::splat(10.0));
    assert_eq!(d.lights[0].le_escaped(Vec3::ZERO, Vec3::Y), Vec3::splat(0.2));
    let Light::Infinite { map: Some(m), .. } = &d.lights[1] else {
        panic!("{:?}", d.lights[1])
    };
    assert_eq!(m.mapping(), EnvMapping::Octahedral);
    // The octahedral map's centre is +z: texel (2, 2) of 4 x 4.
    assert_eq!(d.lights[1].le_escaped(Vec3::ZERO, Vec3::Z), Vec3::new(2.0, 2.0, 1.0));
    // The corners are -z.
    assert_eq!(d.lights[1].le_escaped(Vec3::ZERO, -Vec3::Z).z, 1.0);
}

#[test]
fn an_infinite_light_may_enter_through_a_portal() {
    let text = format!(
        "{CAMERA}[[lights]]\ntype = \"infinite\"\nradiance = [1, 2, 3]\n\
         portal = [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]\n"
    );
    let d = parse_str(&text).unwrap().desc;
    let Light::Infinite { portal: Some(p), .. } = &d.lights[0] else {
        panic!("{:?}", d.lights[0])
    };
    assert_eq!(p.corners()[2], Vec3::new(1.0, 1.0, 1.0));
    // Seen through the portal from below, and past it.
    assert_eq!(
        d.lights[0].le_escaped(Vec3::new(0.5, 0.5, 0.0), Vec3::Z),
        Vec3::new(1.0, 2.0, 3.0)
    );
    assert_eq!(d.lights[0].le_escaped(Vec3::new(1.5, 0.5, 0.0), Vec3::Z), Vec3::ZERO);
}

#[test]
fn a_quad_light_may_emit_an_image_spanning_it_from_its_first_vertex() {
    let dir = tempfile::tempdir().unwrap();
    // 2 x 1: left texel 1, right texel 3 (mean luminance 2).
    write_env(&dir.path().join("screen.pfm"), 2, 1, |x, _| {
        Vec3::splat(1.0 + 2.0 * x as f32)
    });
    let path = dir.path().join("screen.toml");
    let light = |extra: &str| {
        format!(
            "{CAMERA}[[lights]]\ntype = \"quad\"\nvertices = [[0, 0, 1], [2, 0, 1], [2, 1, 1], [0, 1, 1]]\n\
             file = \"screen.pfm\"\n{extra}\n"
        )
    };
    std::fs::write(&path, light("radiance = [1, 1, 2]")).unwrap();
    let d = load(&path, &LoadOptions::default()).unwrap().desc;
    assert_eq!(d.lights.len(), 2);
    // u runs along the first edge (x), v along the last (y): the image's
    // left texel at x < 1, its right one at x > 1, whatever y.
    let le = |l: &Light, uv: Vec2| l.le(Vec3::ZERO, Vec3::Z, uv);
    for l in &d.lights {
        let Light::Triangle { image: Some(t), .. } = l else {
            panic!("{l:?}")
        };
        for (b0, b1) in [(0.6, 0.3), (0.2, 0.2), (0.1, 0.7)] {
            let uv = t.uv[0] * b0 + t.uv[1] * b1 + t.uv[2] * (1.0 - b0 - b1);
            let [v0, v1, v2] = match l {
                Light::Triangle { vertices, .. } => *vertices,
                _ => unreachable!(),
            };
            let x = (v0 * b0 + v1 * b1 + v2 * (1.0 - b0 - b1)).x;
            assert!((uv.x - x / 2.0).abs() < 1e-6, "{uv} at x {x}");
            let want = if x < 0.5 {
                1.0
            } else if x > 1.5 {
                3.0
            } else {
                le(l, uv).x
            };
            assert_eq!(le(l, uv), Vec3::new(want, want, 2.0 * want), "at x {x}");
        }
    }
    // `power` is the flux: over the area, pi and the image's mean luminance.
    std::fs::write(&path, light("power = 10")).unwrap();
    let d = load(&path, &LoadOptions::default()).unwrap().desc;
    let flux: f32 = d.lights.iter().map(|l| crate::math::luminance(l.power())).sum();
    assert!((flux / 10.0 - 1.0).abs() < 1e-5, "{flux}");
    // A missing image is named.
    std::fs::write(&path, light("power = 10").replace("screen.pfm", "nothing.pfm")).unwrap();
    let e = load(&path, &LoadOptions::default()).unwrap_err().to_string();
    assert!(
        e.contains("quad light: emission image") && e.contains("nothing.pfm: file not found"),
        "{e}"
    );
}

#[test]
fn bad_lights_are_one_line_errors_at_their_line() {
    let dir = tempfile::tempdir().unwrap();
    write_env(&dir.path().join("wide.exr"), 4, 2, |_, _| Vec3::ONE);
    write_env(&dir.path().join("nan.pfm"), 2, 1, |x, _| {
        Vec3::splat(if x == 1 { f32::NAN } else { 1.0 })
    });
    std::fs::write(dir.path().join("junk.exr"), "not an image").unwrap();
    std::fs::write(dir.path().join("notes.txt"), "not an image").unwrap();
    let cases = [
        (
            "type = \"infinite\"\nfile = \"missing.exr\"",
            "missing.exr: file not found",
        ),
        ("type = \"infinite\"\nfile = \"junk.exr\"", "junk.exr"),
        ("type = \"infinite\"\nfile = \"notes.txt\"", "not an image file of a known format"),
        (
            "type = \"infinite\"\nfile = \"nan.pfm\"",
            "texel (1, 0) is not a finite number",
        ),
        (
            "type = \"infinite\"\nfile = \"wide.exr\"\nmapping = \"octahedral\"",
            "must be square",
        ),
        (
            "type = \"infinite\"\nfile = \"wide.exr\"\nmapping = \"cube\"",
            "unknown mapping 'cube'",
        ),
        ("type = \"infinite\"\nmapping = \"latlong\"", "`mapping` needs `file`"),
        (
            "type = \"infinite\"\nfile = \"wide.exr\"\nradiance = [1, 1, 1]",
            "not both",
        ),
        (
            "type = \"infinite\"\nradiance = [1, -1, 1]",
            "radiance [1.0, -1.0, 1.0] must be >= 0",
        ),
        ("type = \"infinite\"\nscale = -2", "scale -2 must be >= 0"),
        (
            "type = \"infinite\"\ndirection = [0, 0, 1]",
            "`direction` does not apply to an infinite light",
        ),
        (
            "type = \"distant\"\nradiance = [1, 1, 1]",
            "distant light: missing `direction`",
        ),
        ("type = \"distant\"\ndirection = [0, 0, 0]", "has no length"),
        (
            "type = \"distant\"\ndirection = [0, 0, 1]\npower = 3",
            "`power` does not apply",
        ),
        (
            "type = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 0, 1]",
            "give `intensity` or `power`",
        ),
        (
            "type = \"spot\"\ndirection = [0, 0, 1]\npower = 1",
            "spot light: missing `position`",
        ),
        (
            "type = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 0, 1]\npower = 1\ncone_angle = 0",
            "cone_angle 0 must be in (0, 180]",
        ),
        (
            "type = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 0, 1]\npower = 1\ncone_angle = 10\ncone_delta = 12",
            "cone_delta 12 must be in [0, cone_angle = 10]",
        ),
        (
            "type = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 0, 1]\nintensity = [nan, 1, 1]",
            "not a finite",
        ),
        (
            "type = \"spot\"\nposition = [0, 0, 0]\ndirection = [0, 0, 1]\nintensity = [1, 1, 1]\nfile = \"a.exr\"",
            "`file` does not apply",
        ),
        (
            "type = \"infinite\"\nportal = [[0, 0, 1], [1, 0, 1], [1, 1, 1]]",
            "`portal` needs 4 corners, not 3",
        ),
        (
            "type = \"point\"\nposition = [0, 0, 0]\npower = 1\nfile = \"wide.exr\"",
            "`file` does not apply to a point light",
        ),
        (
            "type = \"quad\"\nvertices = [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]\nradiance = [1, 1, 1]\nfile = \"notes.txt\"",
            "quad light: emission image",
        ),
        (
            "type = \"infinite\"\nportal = [[0, 0, 1], [1, 0, 1], [2, 1, 1], [0, 1, 1]]",
            "must make a rectangle",
        ),
        (
            "type = \"point\"\nposition = [0, 0, 0]\npower = 1\nportal = [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]",
            "`portal` does not apply to a point light",
        ),
    ];
    for (i, (light, what)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("bad{i}.toml"));
        // The light's table starts at line 6, after the camera and a blank line.
        std::fs::write(&path, format!("{CAMERA}\n[[lights]]\n{light}\n")).unwrap();
        let e = load(&path, &LoadOptions::default()).unwrap_err().to_string();
        assert!(!e.contains('\n'), "'{e}' is not one line");
        assert!(e.contains(what), "{light}: '{e}' does not say '{what}'");
        let at = format!("{}:", path.display());
        let line: usize = e[at.len()..].split(':').next().unwrap().parse().unwrap_or(0);
        assert!(
            e.starts_with(&at) && (6..=7 + light.lines().count()).contains(&line),
            "{light}: '{e}'"
        );
        // Exit status 2 is the binary's for every such error (tests/it/cli.rs).
    }
}

#[test]
fn disk_lights_are_read_and_bad_ones_refused() {
    let base = "[camera]\nposition = [0, 0, -3]\nlook_at = [0, 0, 0]\nfov_y = 40\n[[lights]]\ntype = \"disk\"\n";
    let ok = parse_str(&format!(
        "{base}centre = [0, -1, 0]\nnormal = [0, 2, 0]\nradius = 0.5\npower = 10\n"
    ))
    .unwrap();
    match &ok.desc.lights[..] {
        [Light::Disk {
            disk,
            radiance,
            two_sided: false,
            ..
        }] => {
            assert_eq!(disk.normal, Vec3::Y);
            // L = Phi / (pi A) for one side.
            let want = 10.0 / (std::f32::consts::PI * std::f32::consts::PI * 0.25);
            assert!((radiance.x - want).abs() < 1e-4 * want, "{radiance}");
        }
        other => panic!("{other:?}"),
    }
    for (bad, what) in [
        (
            "centre = [0, 0, 0]\nnormal = [0, 0, 0]\nradius = 1\npower = 1\n",
            "normal",
        ),
        (
            "centre = [0, 0, 0]\nnormal = [0, 1, 0]\nradius = 0\npower = 1\n",
            "radius",
        ),
        (
            "centre = [0, 0, 0]\nnormal = [0, 1, 0]\nradius = 1\ninner_radius = 1\npower = 1\n",
            "inner_radius",
        ),
        ("centre = [0, 0, 0]\nnormal = [0, 1, 0]\nradius = 1\n", "power"),
        (
            "centre = [0, 0, 0]\nnormal = [0, 1, 0]\nradius = 1\npower = 1\nvertices = [[0, 0, 0]]\n",
            "vertices",
        ),
    ] {
        let e = parse_str(&format!("{base}{bad}")).unwrap_err().to_string();
        assert!(e.contains(":5") && e.contains(what) && !e.contains('\n'), "{what}: {e}");
    }
}

#[test]
fn a_camera_may_have_a_thin_lens() {
    let text = format!("{CAMERA}lens_radius = 0.05\nfocal_distance = 3\n");
    let scene = parse_str(&text).unwrap();
    let lens = scene.desc.camera.lens.unwrap();
    assert_eq!((lens.radius, lens.focal_distance), (0.05, 3.0));
    let built = crate::Scene::build(scene.desc).unwrap();
    assert!(built.camera.has_lens());
    // A radius of 0 is the pinhole.
    let text = format!("{CAMERA}lens_radius = 0\nfocal_distance = 3\n");
    assert_eq!(parse_str(&text).unwrap().desc.camera.lens, None);
}

#[test]
fn media_bound_by_shapes_and_the_camera_in_one() {
    use crate::medium::{Medium, MediumInterface};
    use crate::scene::{Boundary, CutShapes};
    let text = r#"
        [camera]
        position = [0, 0, 0]
        look_at = [0, 0, 1]
        fov_y = 2
        width = 3
        height = 3
        medium = "air"
        [media.air]
        sigma_s = 0.0
        sigma_a = [0.0, 0.0, 0.0]
        [media.ink]
        sigma_a = [0.1, 0.3, 0.6]
        le = [2, 1, 0]
        [media.unused]
        sigma_s = 1
        [materials.none]
        type = "interface"
        [materials.grey]
        [[shapes]]
        type = "sphere"
        material = "none"
        centre = [0, 0, 5]
        radius = 1
        medium_inside = "ink"
        medium_outside = "air"
        [[shapes]]
        type = "box"
        material = "none"
        min = [-1, -1, 20]
        max = [1, 1, 21]
        medium_inside = "ink"
        medium_outside = "air"
        [[shapes]]
        type = "quad"
        material = "grey"
        vertices = [[-1, -1, 30], [1, -1, 30], [1, 1, 30], [-1, 1, 30]]
        medium_outside = "air"
        medium_inside = "air"
    "#;
    let d = parse_str(text).unwrap().desc;
    let (air, ink) = (
        Medium {
            sigma_a: Vec3::ZERO,
            sigma_s: Vec3::ZERO,
            g: 0.0,
            density: None,
            emission: None,
        },
        Medium {
            sigma_a: Vec3::new(0.1, 0.3, 0.6),
            sigma_s: Vec3::ZERO,
            g: 0.0,
            density: None,
            emission: Some(std::sync::Arc::new(crate::medium::Emission::uniform(Vec3::new(
                2.0, 1.0, 0.0,
            )))),
        },
    );
    // Media in order of first use; the one nobody names is left out.
    assert_eq!(d.media, [("air".to_string(), air), ("ink".to_string(), ink)]);
    assert_eq!(d.camera_medium, Some(0));
    let mi = MediumInterface {
        inside: Some(1),
        outside: Some(0),
    };
    // The box's faces wind inwards: its interface is turned so that its
    // interior is inside; a shape between one medium and itself bounds none.
    assert_eq!(
        d.boundaries,
        [
            Boundary {
                interface: mi,
                shapes: CutShapes::Sphere(0),
            },
            Boundary {
                interface: mi.flipped(),
                shapes: CutShapes::Triangles(0..12),
            },
        ]
    );
    assert_eq!(d.materials[d.spheres[0].material as usize].1, Material::Interface);
    // Only the path tracer renders media: it is what the scene recommends
    // unless the file names an integrator, whatever its preset says.
    let integrator = |d: &crate::scene::SceneDesc| {
        let layers = [&d.settings.scene_file, &d.settings.preset];
        layers.iter().find_map(|l| l.get("integrator").map(|v| v.0))
    };
    assert_eq!(integrator(&d), Some(Value::Name("path")));
    assert!(Scene::build(d).unwrap().has_media());
    let preset = parse_str(&format!("[settings]\npreset = \"cornell\"\n{text}"))
        .unwrap()
        .desc;
    assert_eq!(integrator(&preset), Some(Value::Name("path")));
    let chosen = parse_str(&format!("[settings]\nintegrator = \"sppm\"\n{text}"))
        .unwrap()
        .desc;
    assert_eq!(integrator(&chosen), Some(Value::Name("sppm")));
    // Without media, nothing is recommended.
    assert_eq!(integrator(&parse_str(CAMERA).unwrap().desc), None);
    let e = parse_str(&text.replacen("medium_inside = \"ink\"", "medium_inside = \"inc\"", 1))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("test.toml:25: unknown medium 'inc' (defined: air, ink, unused)"),
        "{e}"
    );
    let e = parse_str(&text.replace("sigma_a = [0.1, 0.3, 0.6]", "sigma_a = [0.1, -0.3, 0.6]"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("test.toml:12: medium 'ink': sigma_a"), "{e}");
    let e = parse_str(&text.replace("le = [2, 1, 0]", "le = [2, -1, 0]"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("test.toml:12: medium 'ink': le [2, -1, 0] must be finite"),
        "{e}"
    );
    let e = parse_str(&text.replace(
        "type = \"interface\"",
        "type = \"interface\"\n        displacement = 0.1",
    ))
    .unwrap_err()
    .to_string();
    assert!(e.contains("material 'none': `displacement` does not apply"), "{e}");
    // A shape of no surface that bounds nothing would only be a hole.
    let e = parse_str(&text.replacen("medium_inside = \"ink\"\n        medium_outside = \"air\"\n", "", 1))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("test.toml:20: sphere shape: its material is an `interface`, no surface, so it must bound media"),
        "{e}"
    );
}

#[test]
fn subsurface_materials_are_read_and_checked() {
    use crate::material::SubsurfaceScattering;
    let text = format!(
        "{CAMERA}[materials.skin]\ntype = \"subsurface\"\nname = \"Skin1\"\nscale = 1000\n\
         [materials.wax]\ntype = \"subsurface\"\nreflectance = [0.8, 0.6, 0.3]\nmfp = 0.01\neta = 1.5\nroughness = 0.2\n\
         [materials.jade]\ntype = \"subsurface\"\nsigma_a = [4, 0.5, 3]\nsigma_s = 40\ng = 0.4\n"
    );
    let d = parse_str(&text).unwrap().desc;
    let get = |n: &str| match d.materials.iter().find(|(k, _)| k == n).map(|(_, m)| m) {
        Some(Material::Subsurface(s)) => s.as_ref().clone(),
        other => panic!("{other:?}"),
    };
    let skin = get("skin");
    assert_eq!(skin.eta, 1.33);
    assert_eq!(*skin.table, crate::bssrdf::BssrdfTable::new(0.0, 1.33));
    let constant = |t: &crate::texture::Texture| match t {
        crate::texture::Texture::Constant(c) => *c,
        other => panic!("{other:?}"),
    };
    let SubsurfaceScattering::Coefficients { sigma_a, sigma_s } = &skin.scattering else {
        panic!()
    };
    assert!((constant(sigma_a) - Vec3::new(32.0, 170.0, 480.0)).abs().max_element() < 1e-3);
    assert!(
        (constant(sigma_s) - Vec3::new(740.0, 880.0, 1010.0))
            .abs()
            .max_element()
            < 1e-3
    );
    let wax = get("wax");
    assert_eq!(wax.eta, 1.5);
    assert!(!wax.roughness.is_smooth());
    assert!(
        matches!(&wax.scattering, SubsurfaceScattering::Reflectance { mfp, .. } if constant(mfp) == Vec3::splat(0.01))
    );
    let jade = get("jade");
    assert_eq!(*jade.table, crate::bssrdf::BssrdfTable::new(0.4, 1.33));
    assert_eq!(
        jade.scattering,
        SubsurfaceScattering::Coefficients {
            sigma_a: Vec3::new(4.0, 0.5, 3.0).into(),
            sigma_s: Vec3::splat(40.0).into()
        }
    );
    for (bad, what) in [
        ("name = \"Skin3\"\n", "unknown measured medium 'Skin3'"),
        ("name = \"Skin1\"\ng = 0.5\n", "takes no `g`"),
        ("sigma_a = 1\n", "`sigma_s` is missing"),
        (
            "sigma_a = 1\nsigma_s = 1\nreflectance = 0.5\n",
            "give the medium one way",
        ),
        ("reflectance = 0.5\nmfp = 0\n", "mfp [0.0, 0.0, 0.0] must be > 0"),
        ("g = 1\n", "g 1 must lie strictly between -1 and 1"),
        ("ior = 1.5\n", "`ior` does not apply"),
    ] {
        let text = format!("{CAMERA}[materials.x]\ntype = \"subsurface\"\n{bad}");
        let e = parse_str(&text).unwrap_err().to_string();
        assert!(e.contains("test.toml:") && e.contains(what), "{bad}: {e}");
    }
}

#[test]
fn noise_dots_and_ramps_are_textures_of_their_own_space() {
    let text = r#"
        [camera]
        position = [0, 0, -3]
        look_at = [0, 0, 0]
        fov_y = 40
        [textures.clouds]
        type = "fbm"
        frequency = 4
        octaves = 5
        roughness = 0.6
        [textures.sky]
        type = "mix"
        tex1 = [0.2, 0.3, 0.8]
        tex2 = 1
        amount = "clouds"
        [textures.stone]
        type = "marble"
        variation = 0.5
        [textures.spots]
        type = "dots"
        inside = "stone"
        outside = [0.9, 0.9, 0.8]
        uscale = 8
        vscale = 8
        [textures.ramp]
        type = "bilerp"
        v11 = [1, 0, 0]
        [materials.a]
        reflectance = "sky"
        [materials.b]
        reflectance = "spots"
        [materials.c]
        reflectance = "ramp"
        displacement = "bumps"
        [textures.bumps]
        type = "wrinkled"
    "#;
    let d = parse_str(text).unwrap().desc;
    let reflectance = |n: &str| {
        let m = d
            .materials
            .iter()
            .find(|(k, _)| k == n)
            .map(|(_, m)| m.clone())
            .unwrap();
        match m {
            Material::Diffuse { reflectance } => reflectance,
            Material::Bumped { base, .. } => match *base {
                Material::Diffuse { reflectance } => reflectance,
                other => panic!("{other:?}"),
            },
            other => panic!("{other:?}"),
        }
    };
    // The fBm is read at the point times the frequency.
    let p = Vec3::new(0.3, -0.2, 0.7);
    let tc = crate::texture::TexCoord::at(crate::math::Vec2::new(0.25, 0.5), p, Vec3::Z);
    let amount = crate::texture::noise::fbm(p * 4.0, Vec3::ZERO, Vec3::ZERO, 0.6, 5);
    let want = Vec3::new(0.2, 0.3, 0.8) * (1.0 - amount) + Vec3::ONE * amount;
    assert!((reflectance("a").evaluate(&tc) - want).abs().max_element() < 1e-6);
    assert!(matches!(reflectance("b"), crate::texture::Texture::Dots { .. }));
    // The ramp: v00 = v10 = 0, v01 = 1, v11 red, at (u, v) = (0.25, 0.5).
    let ramp = reflectance("c").evaluate(&tc);
    let want = Vec3::ONE * (0.75 * 0.5) + Vec3::X * (0.25 * 0.5);
    assert!((ramp - want).abs().max_element() < 1e-6, "{ramp}");
    // Refusals at their key's line.
    for (from, to, what) in [
        ("octaves = 5", "octaves = 40", "octaves 40: a whole number in 0..=32"),
        ("frequency = 4", "frequency = 0", "frequency 0 must be positive"),
        ("v11 = [1, 0, 0]", "v11 = \"sky\"", "`v11` must be a number or a colour"),
        ("variation = 0.5", "variation = 0.5\nwidth = 1", "width"),
        ("type = \"dots\"", "type = \"ptex\"", "unknown texture type 'ptex'"),
    ] {
        let e = parse_str(&text.replace(from, to)).unwrap_err().to_string();
        assert!(e.starts_with("test.toml:") && e.contains(what), "{to}: {e}");
    }
}

#[test]
fn textures_may_be_placed_by_the_point_rather_than_by_uv() {
    let text = r#"
        [camera]
        position = [0, 0, -3]
        look_at = [0, 0, 0]
        fov_y = 40
        [textures.planks]
        type = "checkerboard"
        mapping = "planar"
        v1 = [2, 0, 0]
        v2 = [0, 0, 2]
        udelta = 0.5
        [textures.globe]
        type = "bilerp"
        mapping = "spherical"
        centre = [1, 2, 3]
        axis = [0, -1, 0]
        v01 = 0
        v10 = 1
        v11 = 1
        [textures.barrel]
        type = "bilerp"
        mapping = "cylindrical"
        centre = [1, 2, 3]
        axis = [0, -1, 0]
        v01 = 0
        v11 = 0
        v10 = 1
        [textures.cubes]
        type = "checkerboard"
        dimension = 3
        frequency = 2
        [materials.a]
        reflectance = "planks"
        [materials.b]
        reflectance = "globe"
        [materials.c]
        reflectance = "barrel"
        [materials.d]
        reflectance = "cubes"
    "#;
    let d = parse_str(text).unwrap().desc;
    let reflectance = |n: &str| match d.materials.iter().find(|(k, _)| k == n).map(|(_, m)| m.clone()) {
        Some(Material::Diffuse { reflectance }) => reflectance,
        other => panic!("{other:?}"),
    };
    // (u, v) is the same everywhere: only the point places these.
    let at = |p: Vec3| crate::texture::TexCoord::at(crate::math::Vec2::new(0.5, 0.5), p, Vec3::Z);
    // Planar: s = 0.5 + 2 x, t = 2 z; white where floor(s) + floor(t) is even.
    let planks = reflectance("a");
    assert_eq!(planks.evaluate(&at(Vec3::new(0.1, 5.0, 0.1))), Vec3::ONE);
    assert_eq!(planks.evaluate(&at(Vec3::new(0.3, 5.0, 0.1))), Vec3::ZERO);
    assert_eq!(planks.evaluate(&at(Vec3::new(0.3, -5.0, 0.6))), Vec3::ONE);
    // Spherical about (1, 2, 3) with its pole along -y: s = theta / pi is 0
    // at the pole and 1 at the other; the ramp is s alone (v10 = v11 = 1).
    let globe = reflectance("b");
    let centre = Vec3::new(1.0, 2.0, 3.0);
    for (p, s) in [
        (centre - Vec3::Y, 0.0),
        (centre + Vec3::Y * 5.0, 1.0),
        (centre + Vec3::X, 0.5),
    ] {
        assert!(
            (globe.evaluate(&at(p)) - Vec3::splat(s)).abs().max_element() < 1e-5,
            "{p}"
        );
    }
    // Cylindrical: t is the height along the axis, the ramp (1 - t) s, so
    // zero a unit up the axis and s (half a turn round: 0.5 or so) on it.
    let barrel = reflectance("c");
    assert!(barrel.evaluate(&at(centre - Vec3::Y + Vec3::X)).max_element().abs() < 1e-5);
    let side = barrel.evaluate(&at(centre + Vec3::X)).x;
    assert!(side > 0.0 && side < 1.0, "{side}");
    // A checkerboard of space: cubes half a unit wide.
    let cubes = reflectance("d");
    assert_eq!(cubes.evaluate(&at(Vec3::new(0.25, 0.25, 0.25))), Vec3::ONE);
    assert_eq!(cubes.evaluate(&at(Vec3::new(0.75, 0.25, 0.25))), Vec3::ZERO);
    // Keys of another mapping, an unknown mapping or dimension, no axis.
    for (from, to, what) in [
        (
            "udelta = 0.5",
            "uscale = 2",
            "`uscale` does not apply to mapping 'planar'",
        ),
        ("mapping = \"planar\"", "mapping = \"cubic\"", "mapping 'cubic'"),
        ("dimension = 3", "dimension = 4", "dimension 4: use 2 or 3"),
        (
            "axis = [0, -1, 0]\n        v01",
            "axis = [0, 0, 0]\n        v01",
            "`axis` must not be zero",
        ),
        (
            "frequency = 2",
            "frequency = 2\n        uscale = 1",
            "`uscale` does not apply",
        ),
    ] {
        let e = parse_str(&text.replacen(from, to, 1)).unwrap_err().to_string();
        assert!(e.starts_with("test.toml:") && e.contains(what), "{to}: {e}");
    }
}

#[test]
fn an_area_light_may_reflect_by_a_material() {
    // A quad light facing away from the camera, lit by a sphere light
    // behind the camera: its back is dark unless it reflects.
    let scene = |material: &str| {
        format!(
            "{CAMERA}width = 8\nheight = 8\n[materials.white]\nalbedo = [0.8, 0.8, 0.8]\n\
             [[lights]]\ntype = \"sphere\"\ncentre = [0, 0, -4]\nradius = 0.5\npower = 100\n\
             [[lights]]\ntype = \"quad\"\nradiance = [5, 5, 5]\n{material}\
             vertices = [[-2, -2, 1], [2, -2, 1], [2, 2, 1], [-2, 2, 1]]\n"
        )
    };
    let centre = |text: &str| {
        let d = parse_str(text).unwrap().desc;
        let s = crate::integrator::analytic::path_settings(16, None);
        render(&Scene::build(d).unwrap(), &s, &|| {}).unwrap().film.get(4, 4)
    };
    let d = parse_str(&scene("material = \"white\"\n")).unwrap().desc;
    let Some(Some(surface)) = d.light_surfaces.get(1) else {
        panic!("{:?}", d.light_surfaces)
    };
    assert_eq!(d.materials[surface.material as usize].0, "white");
    assert_eq!(surface.uvs, Some(AREA_LIGHT_UVS[0]));
    assert_eq!(d.light_surfaces.first(), Some(&None));
    // The quad faces +z, away from the camera at z = -3.
    assert_eq!(centre(&scene("")), Vec3::ZERO);
    let lit = centre(&scene("material = \"white\"\n"));
    assert!(lit.x > 0.05 && lit.x < 5.0, "{lit}");
    // An unknown material is named at its line; a light without a surface
    // takes none.
    let e = parse_str(&scene("material = \"chalk\"\n")).unwrap_err().to_string();
    assert!(
        e.contains("test.toml:17") && e.contains("unknown material 'chalk'"),
        "{e}"
    );
    let point = format!("{CAMERA}[materials.white]\nalbedo = [1, 1, 1]\n[[lights]]\ntype = \"point\"\nposition = [0, 0, 0]\npower = 1\nmaterial = \"white\"\n");
    let e = parse_str(&point).unwrap_err().to_string();
    assert!(e.contains("`material` does not apply to a point light"), "{e}");
}

#[test]
fn a_two_sided_sphere_light_glows_inside_too_with_its_power_over_both_sides() {
    let light = |extra: &str| {
        let text = format!("{CAMERA}[[lights]]\ntype = \"sphere\"\ncentre = [0, 0, 0]\nradius = 1\npower = 8\n{extra}");
        parse_str(&text).unwrap().desc.lights[0].clone()
    };
    let (one, both) = (light(""), light("two_sided = true\n"));
    assert!(matches!(
        one,
        Light::Sphere {
            emits: crate::light::Emits::Outwards,
            ..
        }
    ));
    assert!(matches!(
        both,
        Light::Sphere {
            emits: crate::light::Emits::Both,
            ..
        }
    ));
    assert_eq!(both.radiance() * 2.0, one.radiance());
    assert_eq!(both.power(), one.power());
    // Seen from inside, towards the centre: dark unless two-sided.
    let p = Vec3::new(0.0, 0.0, 1.0);
    assert_eq!(one.le(p, -Vec3::Z, Vec2::ZERO), Vec3::ZERO);
    assert_eq!(both.le(p, -Vec3::Z, Vec2::ZERO), both.radiance());
    // `--light-radius` keeps the sides a sphere emits from, and so its
    // radiance; a light it turns into a sphere keeps no surface.
    let text = format!(
        "{CAMERA}[materials.m]\nalbedo = [1, 1, 1]\n[[lights]]\ntype = \"sphere\"\ncentre = [0, 0, 0]\nradius = 1\npower = 8\ntwo_sided = true\nmaterial = \"m\"\n\
         [[lights]]\ntype = \"triangle\"\nradiance = [1, 1, 1]\nvertices = [[0, 0, 2], [1, 0, 2], [0, 1, 2]]\nmaterial = \"m\"\n"
    );
    let mut d = parse_str(&text).unwrap().desc;
    d.set_light_radius(0.5);
    let Light::Sphere { emits, sphere, .. } = &d.lights[0] else {
        panic!("{:?}", d.lights[0])
    };
    assert_eq!((*emits, sphere.radius), (crate::light::Emits::Both, 0.5));
    assert_eq!(d.lights[0].power(), both.power());
    assert!(d.light_surfaces[0].is_some() && d.light_surfaces[1].is_none());
}

#[test]
fn a_sphere_light_wraps_its_emission_image_with_z_up() {
    // A 2 x 2 image: blue top row, red bottom row. The sphere's top (+z)
    // reads blue, its bottom red; `power` sets the flux by the image's
    // mean luminance.
    let dir = tempfile::tempdir().unwrap();
    write_env(&dir.path().join("glow.pfm"), 2, 2, |_, y| {
        if y == 0 {
            Vec3::new(0.0, 0.0, 1.0)
        } else {
            Vec3::new(1.0, 0.0, 0.0)
        }
    });
    let path = dir.path().join("s.toml");
    std::fs::write(
        &path,
        format!(
            "{CAMERA}[[lights]]\ntype = \"sphere\"\ncentre = [0, 0, 0]\nradius = 1\npower = 10\nfile = \"glow.pfm\"\n"
        ),
    )
    .unwrap();
    let d = load(&path, &LoadOptions::default()).unwrap().desc;
    let l = &d.lights[0];
    let up = l.sample_li(Vec3::new(0.0, 0.0, 5.0), Vec2::new(0.5, 0.5)).unwrap();
    let down = l.sample_li(Vec3::new(0.0, 0.0, -5.0), Vec2::new(0.5, 0.5)).unwrap();
    assert!(up.weight.z > 0.0 && up.weight.x == 0.0, "{:?}", up.weight);
    assert!(down.weight.x > 0.0 && down.weight.z == 0.0, "{:?}", down.weight);
    assert!((crate::math::luminance(l.power()) - 10.0).abs() < 1e-3, "{}", l.power());
}

#[test]
fn measured_materials_read_their_file_beside_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("brdfs")).unwrap();
    std::fs::write(dir.path().join("brdfs/ggx.bsdf"), crate::bsdf::measured_test_file()).unwrap();
    std::fs::write(dir.path().join("brdfs/bad.bsdf"), b"tensor_file\0\x02\x00").unwrap();
    let text = r#"
        [camera]
        position = [0, 0, -3]
        look_at = [0, 0, 0]
        fov_y = 40
        [materials.paint]
        type = "measured"
        file = "brdfs/ggx.bsdf"
        displacement = 0.1
    "#;
    let scene = dir.path().join("scene.toml");
    let d = parse(&scene, text, &LoadOptions::default()).unwrap().desc;
    let m = d.materials.iter().find(|(k, _)| k == "paint").map(|(_, m)| m).unwrap();
    let Material::Bumped { base, .. } = m else {
        panic!("{m:?}")
    };
    assert!(matches!(**base, Material::Measured(_)), "{base:?}");
    // A missing file, a broken one, no file, and a key it does not take:
    // each at its line.
    for (from, to, line, what) in [
        ("ggx.bsdf", "nope.bsdf", 8, "nope.bsdf:"),
        ("ggx.bsdf", "bad.bsdf", 8, "version 2.0"),
        ("file = \"brdfs/ggx.bsdf\"", "", 6, "missing `file`"),
        ("displacement = 0.1", "roughness = 0.1", 9, "`roughness` does not apply"),
    ] {
        let e = parse(&scene, &text.replace(from, to), &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("scene.toml:{line}:")) && e.contains(what), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }
}

#[test]
fn a_lens_file_makes_a_realistic_camera_focused_at_what_it_looks_at() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("lenses")).unwrap();
    // A singlet (f 50.85 mm) with its stop behind it.
    std::fs::write(
        dir.path().join("lenses/singlet.dat"),
        "50 5 1.5 40\n-50 2 1 40\n0 40 0 8\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("lenses/bad.dat"), "50 5 1.5 40\n-50 2 1\n").unwrap();
    let text = r#"
        [camera]
        position = [0, 0, -3]
        look_at = [0, 0, 0]
        lens_file = "lenses/singlet.dat"
        aperture = 4
        aperture_shape = "pentagon"
        width = 48
        height = 32
    "#;
    let scene = dir.path().join("scene.toml");
    let d = parse(&scene, text, &LoadOptions::default()).unwrap().desc;
    let lens = d.camera.realistic.clone().expect("a lens");
    assert!((lens.focal_length - 0.05085).abs() < 5e-5);
    assert_eq!(lens.summary(), (3, Some(4.0)));
    // Focused at look_at: rays from the film's centre meet there.
    let cam = d.camera.camera().unwrap();
    let hits: Vec<Vec3> = [(0.3, 0.5), (0.7, 0.5), (0.5, 0.3), (0.5, 0.7)]
        .iter()
        .filter_map(|&(u, v)| {
            let (r, w) = cam.sample_ray(24.0, 16.0, Vec2::new(u, v));
            (w > 0.0).then(|| r.o + r.d * (-r.o.z / r.d.z))
        })
        .collect();
    assert!(hits.len() >= 3);
    for h in &hits {
        assert!(h.truncate().length() < 2e-3, "{h}");
    }
    for (from, to, line, what) in [
        ("singlet.dat", "nope.dat", 5, "nope.dat:"),
        ("singlet.dat", "bad.dat", 5, "line 2: 7 numbers"),
        ("\"pentagon\"", "\"hexagon\"", 5, "unknown aperture_shape 'hexagon'"),
        ("aperture = 4", "fov_y = 40", 2, "has no `fov_y`"),
        ("aperture = 4", "focus_distance = 0.01", 5, "too close"),
        (
            "lens_file = \"lenses/singlet.dat\"",
            "fov_y = 40",
            2,
            "`aperture` needs a `lens_file`",
        ),
    ] {
        let e = parse(&scene, &text.replace(from, to), &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("scene.toml:{line}:")) && e.contains(what), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }
}

#[test]
fn coats_that_scatter_are_read_and_checked() {
    let text = format!(
        "{CAMERA}[materials.milk]\ntype = \"coateddiffuse\"\nreflectance = [0.5, 0.1, 0.1]\nalbedo = 0.9\ng = 0.3\n\
         thickness = 0.2\nmax_depth = 30\n\
         [materials.gold]\ntype = \"coatedconductor\"\nmetal = \"Au\"\nalbedo = [0.5, 0.4, 0.3]\n\
         [materials.clear]\ntype = \"coateddiffuse\"\ng = 0.5\n"
    );
    let d = parse_str(&text).unwrap().desc;
    let get = |n: &str| d.materials.iter().find(|(k, _)| k == n).map(|(_, m)| m.clone());
    let medium = |n: &str| match get(n) {
        Some(Material::CoatedDiffuse { medium, .. } | Material::CoatedConductor { medium, .. }) => medium,
        m => panic!("{m:?}"),
    };
    assert_eq!(
        medium("milk"),
        Some(CoatMedium {
            albedo: crate::texture::Texture::from(Vec3::splat(0.9)),
            g: 0.3,
            max_depth: 30,
            samples: 1
        })
    );
    assert_eq!(
        medium("gold").map(|m| (m.albedo.as_constant(), m.g, m.max_depth)),
        Some((Some(Vec3::new(0.5, 0.4, 0.3)), 0.0, 10))
    );
    // No albedo: a coat that only absorbs, whatever its g.
    assert_eq!(medium("clear"), None);
    for (bad, why) in [
        ("g = 1", "g 1 must lie in (-1, 1)"),
        ("albedo = 1.5", "must lie in [0, 1]"),
    ] {
        let t = format!("{CAMERA}[materials.m]\ntype = \"coateddiffuse\"\n{bad}\n");
        let e = parse_str(&t).unwrap_err().to_string();
        assert!(e.contains(why), "{e}");
    }
}
