//! The canonical scenes (`../shared/SCENES.md`). They are the scene files in
//! `scenes/`, compiled in so that the default render needs no file; the
//! bunny scenes draw the Stanford bunny, which the project does not ship, so
//! its path comes from `--mesh`. A built-in scene's `[settings]` are its
//! preset: values a scene file (through `preset = "NAME"`) or the command
//! line override, and errors in them are reported as `preset NAME: ...`.

use super::{file, LoadOptions, LoadedScene, SceneDesc};
use crate::error::{Error, Result};
use crate::settings::{Layer, Origin, SceneSettings};
use std::path::Path;

/// The built-in scenes: name, file name in `scenes/`, text.
const SCENES: &[(&str, &str, &str)] = &[
    ("cornell", "cornell.toml", include_str!("../../scenes/cornell.toml")),
    (
        "cornell-bunny",
        "cornell-bunny.toml",
        include_str!("../../scenes/cornell-bunny.toml"),
    ),
    (
        "cornell-final",
        "cornell-final.toml",
        include_str!("../../scenes/cornell-final.toml"),
    ),
    (
        "cornell-specular",
        "cornell-specular.toml",
        include_str!("../../scenes/cornell-specular.toml"),
    ),
];

/// Names accepted by `--scene`.
pub const NAMES: &[&str] = &["cornell", "cornell-bunny", "cornell-final", "cornell-specular"];

/// Scenes that draw a mesh (the bunny), which `--mesh` must supply.
const WITH_MESH: &[&str] = &["cornell-bunny", "cornell-final"];

fn text_of(name: &str) -> Option<(&'static str, &'static str)> {
    SCENES.iter().find(|(n, _, _)| *n == name).map(|(_, f, t)| (*f, *t))
}

/// The settings of built-in scene `name` as a preset layer.
pub fn preset(name: &str) -> std::result::Result<Layer, String> {
    let (file_name, text) =
        text_of(name).ok_or_else(|| format!("no built-in scene '{name}' (known: {})", NAMES.join(", ")))?;
    let s = file::settings_of(Path::new(file_name), text).map_err(|e| e.to_string())?;
    Ok(as_preset(name, s))
}

/// A built-in scene's own settings are its preset, over the preset it names.
fn as_preset(name: &str, s: SceneSettings) -> Layer {
    let mut layer = s.preset;
    for (key, (value, _)) in s.scene_file.values {
        layer.values.insert(key, (value, Origin::Preset(name.to_string())));
    }
    layer
}

/// Looks a built-in scene up by name, loading its mesh when it has one.
/// `Ok(None)` for an unknown name.
pub fn by_name(name: &str, opts: &LoadOptions) -> Result<Option<LoadedScene>> {
    let Some((file_name, text)) = text_of(name) else {
        return Ok(None);
    };
    match (&opts.mesh, WITH_MESH.contains(&name)) {
        (None, true) => return Err(Error::MeshRequired { scene: name.into() }),
        (Some(p), false) => {
            return Err(Error::InvalidSetting(format!(
                "--mesh {}: scene '{name}' has no mesh",
                p.display()
            )))
        }
        _ => {}
    }
    let mut loaded = file::parse(Path::new(file_name), text, opts)?;
    let settings = std::mem::take(&mut loaded.desc.settings);
    loaded.desc.settings.preset = as_preset(name, settings);
    Ok(Some(loaded))
}

/// The built-in scene `name` without meshes (`cornell`, `cornell-specular`),
/// for tests and benchmarks.
///
/// # Panics
/// On a scene that needs a mesh or an unknown name: the texts are ours, and
/// a test parses every one.
pub fn desc(name: &str) -> SceneDesc {
    match by_name(name, &LoadOptions::default()) {
        Ok(Some(l)) => l.desc,
        Ok(None) => panic!("no built-in scene '{name}'"),
        Err(e) => panic!("built-in scene '{name}': {e}"),
    }
}

/// Scene `cornell`: the room, both blocks and the sphere light.
pub fn cornell() -> SceneDesc {
    desc("cornell")
}

/// Scene `cornell-specular`: `cornell` with a mirror block and a glass sphere.
pub fn cornell_specular() -> SceneDesc {
    desc("cornell-specular")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::scene::mesh::Mesh;
    use crate::scene::transform::{Fit, Transform};

    #[test]
    fn every_builtin_scene_parses_and_names_itself() {
        for name in NAMES {
            let opts = LoadOptions {
                mesh: WITH_MESH.contains(name).then(|| "unused.obj".into()),
                smooth: false,
                lenient: false,
            };
            match by_name(name, &opts) {
                Ok(Some(l)) => assert_eq!(l.desc.name, *name),
                // The bunny scenes get as far as their mesh.
                Err(Error::Io { path, .. }) if WITH_MESH.contains(name) => {
                    assert_eq!(path, std::path::Path::new("unused.obj"), "{name}")
                }
                other => panic!("{name}: {other:?}"),
            }
            assert!(!preset(name).unwrap().is_empty(), "{name} has settings");
        }
        assert_eq!(SCENES.len(), NAMES.len());
    }

    #[test]
    fn room_spans_the_unit_cube_with_y_down() {
        let d = cornell();
        assert_eq!(d.triangles.len(), 30);
        // Floor triangles lie on y = +1, the left (purple) wall on x = -1.
        let floor = d.materials.iter().position(|(n, _)| n == "floor").unwrap() as u32;
        let left = d.materials.iter().position(|(n, _)| n == "left_wall").unwrap() as u32;
        for t in d.triangles.iter() {
            if t.material == floor {
                assert!(t.vertices.iter().all(|v| (v.y - 1.0).abs() < 1e-6));
            }
            if t.material == left {
                assert!(t.vertices.iter().all(|v| (v.x + 1.0).abs() < 1e-6));
            }
        }
        // Blocks stand on the floor.
        let max_y = d
            .triangles
            .range(10..d.triangles.len())
            .flat_map(|t| t.vertices)
            .map(|v| v.y)
            .fold(f32::MIN, f32::max);
        assert!((max_y - 1.0).abs() < 1e-6);
    }

    /// Whether the segment from `p` to `q` meets the box.
    fn segment_meets(p: Vec3, q: Vec3, b: &crate::math::Aabb) -> bool {
        let d = q - p;
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        for k in 0..3 {
            if d[k] == 0.0 {
                if p[k] < b.min[k] || p[k] > b.max[k] {
                    return false;
                }
                continue;
            }
            let (a, c) = ((b.min[k] - p[k]) / d[k], (b.max[k] - p[k]) / d[k]);
            t0 = t0.max(a.min(c));
            t1 = t1.min(a.max(c));
        }
        t0 <= t1
    }

    #[test]
    fn bunny_shows_where_its_bounding_box_projects_and_nowhere_else() {
        use crate::integrator::{render, RenderSettings};
        use crate::scene::Scene;
        let Some(path) = crate::scene::mesh::tests::bunny_path() else {
            return;
        };
        let opts = LoadOptions {
            mesh: Some(path),
            smooth: false,
            lenient: false,
        };
        let mut desc = by_name("cornell-bunny", &opts).unwrap().unwrap().desc;
        let n = 64;
        desc.camera.width = n;
        desc.camera.height = n;
        let bunny = desc.materials.iter().position(|(name, _)| name == "bunny").unwrap() as u32;
        let mut room = desc.clone();
        room.triangles = room.triangles.iter().filter(|t| t.material != bunny).collect();
        assert_eq!(desc.triangles.len() - room.triangles.len(), 69_451);
        let mut bounds = crate::math::Aabb::EMPTY;
        for t in desc.triangles.iter().filter(|t| t.material == bunny) {
            t.vertices.iter().for_each(|&v| bounds.grow(v));
        }
        // It stands on the floor where the short block stood, about 0.62 high.
        assert!((bounds.max.y - 1.0).abs() < 1e-5 && (bounds.extent().y - 0.617336).abs() < 1e-5);

        let settings = RenderSettings {
            ssaa: 2,
            shadow_samples: 2,
            ..Default::default()
        };
        let with = Scene::build(desc).unwrap();
        let without = Scene::build(room).unwrap();
        let a = render(&with, &settings, &|| {}).unwrap().film;
        let b = render(&without, &settings, &|| {}).unwrap().film;

        // The bunny's box on the image.
        let (mut x0, mut y0, mut x1, mut y1) = (f32::MAX, f32::MAX, f32::MIN, f32::MIN);
        for i in 0..8 {
            let c = Vec3::select(
                glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
                bounds.max,
                bounds.min,
            );
            let (x, y) = with.camera.project(c).unwrap();
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
        }
        // Shadows fall outside that box; a pixel is safe from them when no
        // segment from what it sees to the light can cross the bunny's box
        // (grown by the light's radius, plus a margin).
        let light = with.lights[0].position();
        let mut grown = bounds;
        grown.min -= Vec3::splat(0.15);
        grown.max += Vec3::splat(0.15);
        let (mut inside, mut inside_changed, mut outside) = (0, 0, 0);
        for py in 0..n {
            for px in 0..n {
                let changed = a.get(px, py) != b.get(px, py);
                let (fx, fy) = (px as f32, py as f32);
                if fx >= x0 && fx + 1.0 <= x1 && fy >= y0 && fy + 1.0 <= y1 {
                    inside += 1;
                    inside_changed += changed as u32;
                    continue;
                }
                if fx + 2.0 < x0 || fx - 1.0 > x1 || fy + 2.0 < y0 || fy - 1.0 > y1 {
                    let shadowed = (0..9).any(|k| {
                        let ray = without
                            .camera
                            .generate_ray(fx + 0.5 * (k % 3) as f32, fy + 0.5 * (k / 3) as f32);
                        without
                            .intersect(&ray, 0.0, f32::INFINITY)
                            .is_some_and(|h| segment_meets(h.p, light, &grown))
                    });
                    if !shadowed {
                        outside += 1;
                        assert!(
                            !changed,
                            "pixel ({px}, {py}) changed, far from the bunny and its shadow"
                        );
                    }
                }
            }
        }
        println!("{inside_changed} of {inside} pixels inside the bunny's box changed; {outside} far pixels did not");
        assert!(inside > 50, "the bunny's box covers only {inside} pixels");
        assert!(
            inside_changed * 2 > inside,
            "only {inside_changed} of {inside} pixels show the bunny"
        );
        assert!(outside > n * n / 2, "only {outside} pixels were far enough to check");
    }

    /// SCENES.md's explicit formulas for the two bunny scenes, in f64.
    fn explicit_bunny(p: Vec3) -> Vec3 {
        let c = glam::DVec3::new(-0.0168405, 0.032987, -0.001537);
        let q = (p.as_dvec3() - c) * 4.0;
        glam::DVec3::new(-q.x + 0.33, -q.y + 1.0, q.z - 0.39).as_vec3()
    }

    fn explicit_final(p: Vec3) -> Vec3 {
        let c = glam::DVec3::new(-0.0168405, 0.032987, -0.001537);
        let q = (p.as_dvec3() - c) * 2.70102;
        glam::DVec3::new(q.x + 0.27183, -q.y + 0.40672, -q.z - 0.48132).as_vec3()
    }

    /// The transform of the mesh shape in built-in scene `name`'s file.
    fn mesh_transform(name: &str) -> Transform {
        let (_, text) = text_of(name).unwrap();
        let doc: toml::Table = toml::from_str(text).unwrap();
        let shapes = doc["shapes"].as_array().unwrap();
        let mesh = shapes.iter().find(|s| s["type"].as_str() == Some("mesh")).unwrap();
        let v3 = |v: &toml::Value| {
            let a = v.as_array().unwrap();
            let f = |i: usize| a[i].as_float().or(a[i].as_integer().map(|x| x as f64)).unwrap() as f32;
            Vec3::new(f(0), f(1), f(2))
        };
        Transform {
            rotate_deg: v3(&mesh["rotate"]),
            fit: Some(Fit {
                height: mesh["fit"]["height"].as_float().unwrap() as f32,
                bottom_centre: v3(&mesh["fit"]["bottom_centre"]),
            }),
            ..Default::default()
        }
    }

    /// Largest distance between the fit transform's and the explicit formula's result.
    fn fit_error(m: &Mesh, t: &Transform, explicit: fn(Vec3) -> Vec3) -> f32 {
        let placed = t.apply(m).unwrap();
        m.positions
            .iter()
            .zip(&placed.positions)
            .map(|(p, q)| (explicit(*p) - *q).abs().max_element())
            .fold(0.0, f32::max)
    }

    #[test]
    fn fit_agrees_with_the_explicit_bunny_formulas() {
        // A stand-in with the bunny's bounding box (its corners and centre).
        let (lo, hi) = (
            Vec3::new(-0.094690, 0.032987, -0.061874),
            Vec3::new(0.061009, 0.187321, 0.058800),
        );
        let mut pts: Vec<Vec3> = (0..8)
            .map(|i| Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), hi, lo))
            .collect();
        pts.push((lo + hi) * 0.5);
        let stand_in = Mesh {
            path: "box.obj".into(),
            triangles: vec![[0, 3, 5], [6, 7, 8], [1, 2, 4]],
            positions: pts,
            normals: None,
            uvs: None,
            parts: vec![],
            warnings: vec![],
        };
        let mut meshes = vec![stand_in];
        if let Some(p) = crate::scene::mesh::tests::bunny_path() {
            meshes.push(crate::scene::mesh::load_mesh(&p).unwrap());
        }
        for m in &meshes {
            let e = fit_error(m, &mesh_transform("cornell-bunny"), explicit_bunny);
            assert!(e < 1e-5, "cornell-bunny: {e}");
            let e = fit_error(m, &mesh_transform("cornell-final"), explicit_final);
            assert!(e < 1e-5, "cornell-final: {e}");
        }
    }
}
