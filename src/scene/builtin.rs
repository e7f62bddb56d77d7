//! The canonical scenes, with the numbers of the project's scene definitions
//! (`../shared/SCENES.md`) built in so that the default render needs no file.
//! The bunny scenes draw the Stanford bunny, which the project does not ship:
//! its path comes from `--mesh`.

use super::mesh::{load_mesh_timed, Mesh};
use super::transform::{Fit, Transform};
use super::{CameraDesc, LoadOptions, LoadedScene, SceneDesc, SceneSettings, TriangleDesc};
use crate::error::{Error, Result};
use crate::geometry::Sphere;
use crate::light::Light;
use crate::material::Material;
use crate::math::Vec3;
use std::f32::consts::PI;

/// Names accepted by `--scene`.
pub const NAMES: &[&str] = &["cornell", "cornell-bunny", "cornell-final", "cornell-specular"];

/// Cornell box data (side 555) to the coursework's [-1, 1]^3 with x and y negated.
pub fn cornell_point(x: f32, y: f32, z: f32) -> Vec3 {
    let s = 2.0 / 555.0;
    Vec3::new(-(x * s - 1.0), -(y * s - 1.0), z * s - 1.0)
}

/// Vertex order of a block's 10 triangles over its points A..H.
const BLOCK: [[usize; 3]; 10] = [
    [4, 1, 0],
    [4, 5, 1],
    [5, 3, 1],
    [5, 7, 3],
    [7, 2, 3],
    [7, 6, 2],
    [6, 4, 2],
    [4, 0, 2],
    [6, 5, 4],
    [6, 7, 5],
];

pub const SHORT_BLOCK: [[f32; 3]; 8] = [
    [290.0, 0.0, 114.0],
    [130.0, 0.0, 65.0],
    [240.0, 0.0, 272.0],
    [82.0, 0.0, 225.0],
    [290.0, 165.0, 114.0],
    [130.0, 165.0, 65.0],
    [240.0, 165.0, 272.0],
    [82.0, 165.0, 225.0],
];

pub const TALL_BLOCK: [[f32; 3]; 8] = [
    [423.0, 0.0, 247.0],
    [265.0, 0.0, 296.0],
    [472.0, 0.0, 406.0],
    [314.0, 0.0, 456.0],
    [423.0, 330.0, 247.0],
    [265.0, 330.0, 296.0],
    [472.0, 330.0, 406.0],
    [314.0, 330.0, 456.0],
];

/// Adds a block given by its eight corners (A..H, before scaling).
pub fn add_block(desc: &mut SceneDesc, corners: &[[f32; 3]; 8], material: u32) {
    let p: Vec<Vec3> = corners.iter().map(|c| cornell_point(c[0], c[1], c[2])).collect();
    for t in BLOCK {
        desc.triangles.push(TriangleDesc {
            vertices: [p[t[0]], p[t[1]], p[t[2]]],
            normals: None,
            material,
        });
    }
}

/// Albedos of the room's surfaces, in the order floor, left, right, ceiling, back.
pub struct RoomColours {
    pub floor: Vec3,
    pub left: Vec3,
    pub right: Vec3,
    pub ceiling: Vec3,
    pub back: Vec3,
}

/// Adds the room's ten triangles.
pub fn add_room(desc: &mut SceneDesc, colours: &RoomColours) {
    let l = 555.0;
    let a = cornell_point(l, 0.0, 0.0);
    let b = cornell_point(0.0, 0.0, 0.0);
    let c = cornell_point(l, 0.0, l);
    let d = cornell_point(0.0, 0.0, l);
    let e = cornell_point(l, l, 0.0);
    let f = cornell_point(0.0, l, 0.0);
    let g = cornell_point(l, l, l);
    let h = cornell_point(0.0, l, l);
    let walls: [(&str, Vec3, [[Vec3; 3]; 2]); 5] = [
        ("floor", colours.floor, [[c, b, a], [c, d, b]]),
        ("left_wall", colours.left, [[a, e, c], [c, e, g]]),
        ("right_wall", colours.right, [[f, b, d], [h, f, d]]),
        ("ceiling", colours.ceiling, [[e, f, g], [f, h, g]]),
        ("back_wall", colours.back, [[g, d, c], [g, h, d]]),
    ];
    for (name, albedo, tris) in walls {
        let m = desc.material(name, Material::Diffuse { albedo });
        for v in tris {
            desc.triangles.push(TriangleDesc {
                vertices: v,
                normals: None,
                material: m,
            });
        }
    }
}

/// The default light: radius 0.1, power 14 pi W, below the ceiling near the front.
pub fn cornell_light() -> Light {
    Light::Sphere {
        sphere: Sphere {
            centre: Vec3::new(0.0, -0.5, -0.7),
            radius: 0.1,
        },
        power: Vec3::splat(14.0 * PI),
    }
}

pub fn cornell_camera(width: u32, height: u32) -> CameraDesc {
    CameraDesc {
        position: Vec3::new(0.0, 0.0, -3.0),
        look_at: Vec3::ZERO,
        up: Vec3::new(0.0, -1.0, 0.0),
        fov_y_deg: (2.0 * 0.5f32.atan()).to_degrees(),
        width,
        height,
    }
}

fn empty(name: &str, camera: CameraDesc) -> SceneDesc {
    SceneDesc::empty(name, camera)
}

pub fn cornell_colours() -> RoomColours {
    RoomColours {
        floor: Vec3::new(0.15, 0.75, 0.15),
        left: Vec3::new(0.75, 0.15, 0.75),
        right: Vec3::new(0.75, 0.75, 0.15),
        ceiling: Vec3::new(0.15, 0.75, 0.75),
        back: Vec3::splat(0.75),
    }
}

/// Scene `cornell`: the room, both blocks and the sphere light.
pub fn cornell() -> SceneDesc {
    let mut d = empty("cornell", cornell_camera(512, 512));
    add_room(&mut d, &cornell_colours());
    let short = d.material("short_block", Material::diffuse(0.75, 0.15, 0.15));
    add_block(&mut d, &SHORT_BLOCK, short);
    let tall = d.material("tall_block", Material::diffuse(0.15, 0.15, 0.75));
    add_block(&mut d, &TALL_BLOCK, tall);
    d.lights.push(cornell_light());
    d.settings = cornell_photon_preset();
    d
}

/// Photon mapping by default in `cornell` and `cornell-bunny`, with the
/// settings measured best for time and error against the path tracer
/// (BENCHMARKS.md): a million photons, up to 10 hits each (5 loses 1% of the
/// light), radius 0.06, no gather filter (in this box of right angles it only
/// darkens the corners), irradiance precomputed at every 4th photon (3 times
/// faster at the same error).
fn cornell_photon_preset() -> SceneSettings {
    SceneSettings {
        integrator: Some(crate::integrator::IntegratorKind::Photon),
        photons: Some(1_000_000),
        max_bounces: Some(10),
        gather_radius: Some(0.06),
        precompute_irradiance: Some(true),
        ..SceneSettings::default()
    }
}

/// Scene `cornell-specular`: `cornell` with the tall block a perfect mirror,
/// no short block, a glass sphere (ior 1.5) on the floor, and the light moved
/// behind the sphere so that it focuses a caustic on the floor in front of it.
pub fn cornell_specular() -> SceneDesc {
    let mut d = empty("cornell-specular", cornell_camera(512, 512));
    add_room(&mut d, &cornell_colours());
    let tall = d.material("tall_block", Material::Mirror { reflectance: Vec3::ONE });
    add_block(&mut d, &TALL_BLOCK, tall);
    let glass = d.material("glass_sphere", Material::Glass { ior: 1.5 });
    d.spheres.push(super::SphereDesc {
        sphere: Sphere {
            centre: Vec3::new(0.33, 0.7, -0.39),
            radius: 0.3,
        },
        material: glass,
    });
    d.lights.push(Light::Sphere {
        sphere: Sphere {
            centre: Vec3::new(0.0, -0.6, 0.3),
            radius: 0.1,
        },
        power: Vec3::splat(14.0 * PI),
    });
    // Photon mapping with a caustic map by default: `cornell`'s global map
    // (hits through mirrors and glass count towards the 10, and fewer lose
    // about 4% of the light here), and 200k caustic photons gathered within
    // 0.02, a pixel or two at 512 x 512, so the caustic stays sharp.
    d.settings.integrator = Some(crate::integrator::IntegratorKind::Photon);
    d.settings.photons = Some(200_000);
    d.settings.max_bounces = Some(10);
    d.settings.gather_radius = Some(0.1);
    d.settings.caustic_photons = Some(200_000);
    d.settings.caustic_radius = Some(0.02);
    d
}

/// Where the bunny of `cornell-bunny` goes: turned 180 degrees about z,
/// 0.617336 high, standing on the floor where the short block stood.
pub fn bunny_transform() -> Transform {
    Transform {
        rotate_deg: Vec3::new(0.0, 0.0, 180.0),
        fit: Some(Fit {
            height: 0.617336,
            bottom_centre: Vec3::new(0.33, 1.0, -0.39),
        }),
        ..Default::default()
    }
}

/// Where the bunny of `cornell-final` goes: turned 180 degrees about x,
/// 0.41686 high, standing on the short block.
pub fn final_bunny_transform() -> Transform {
    Transform {
        rotate_deg: Vec3::new(180.0, 0.0, 0.0),
        fit: Some(Fit {
            height: 0.41686,
            bottom_centre: Vec3::new(0.27183, 0.40672, -0.48132),
        }),
        ..Default::default()
    }
}

/// Scene `cornell-bunny`: the room, the tall block and the light of
/// `cornell`, with the bunny (white, two-sided Lambertian) in place of the
/// short block. Flat-shaded unless `smooth` and the mesh has normals.
pub fn cornell_bunny(bunny: &Mesh, smooth: bool) -> Result<SceneDesc> {
    let mut d = empty("cornell-bunny", cornell_camera(512, 512));
    add_room(&mut d, &cornell_colours());
    let tall = d.material("tall_block", Material::diffuse(0.15, 0.15, 0.75));
    add_block(&mut d, &TALL_BLOCK, tall);
    let m = d.material("bunny", Material::diffuse(0.75, 0.75, 0.75));
    bunny.add_to_scene(&mut d, &bunny_transform(), Some(m), smooth)?;
    d.lights.push(cornell_light());
    d.settings = cornell_photon_preset();
    Ok(d)
}

/// Scene `cornell-final`: the report's final render made physically based
/// (SCENES.md): both blocks, the bunny on the short block, a small bright
/// light, a wide camera and the report's sample counts.
pub fn cornell_final(bunny: &Mesh, smooth: bool) -> Result<SceneDesc> {
    let mut d = empty(
        "cornell-final",
        CameraDesc {
            position: Vec3::new(0.0, 0.0, -2.0),
            look_at: Vec3::ZERO,
            up: Vec3::new(0.0, -1.0, 0.0),
            fov_y_deg: 90.0,
            width: 600,
            height: 600,
        },
    );
    let off_white = Vec3::new(0.86, 0.86, 0.76);
    let colours = RoomColours {
        floor: off_white,
        left: Vec3::new(0.239, 0.008, 0.031),
        right: Vec3::new(0.031, 0.239, 0.008),
        ceiling: off_white,
        back: off_white,
    };
    add_room(&mut d, &colours);
    let short = d.material("short_block", Material::Diffuse { albedo: off_white });
    add_block(&mut d, &SHORT_BLOCK, short);
    let tall = d.material("tall_block", Material::Diffuse { albedo: off_white });
    add_block(&mut d, &TALL_BLOCK, tall);
    let m = d.material("bunny", Material::diffuse(0.286, 0.18, 0.039));
    bunny.add_to_scene(&mut d, &final_bunny_transform(), Some(m), smooth)?;
    d.lights.push(Light::Sphere {
        sphere: Sphere {
            centre: Vec3::new(0.0, -0.5, -0.7),
            radius: 0.02,
        },
        power: Vec3::splat(16.0 * PI),
    });
    // The report's final settings: 8x8 supersampling, 400 shadow samples,
    // 750,000 photons of at most 5 bounces (first hits not stored), gathered
    // within 0.4 where the surface normals' cosine exceeds 0.25.
    d.settings = SceneSettings {
        ssaa: Some(8),
        shadow_samples: Some(400),
        integrator: Some(crate::integrator::IntegratorKind::Photon),
        photons: Some(750_000),
        max_bounces: Some(5),
        gather_radius: Some(0.4),
        gather_filter: Some(crate::photon::GatherFilter::Report),
        // Not the report's: a gather of radius 0.4 at each of 64 samples a pixel
        // would cost an hour; the precomputed estimate gives the same picture.
        precompute_irradiance: Some(true),
        ..SceneSettings::default()
    };
    Ok(d)
}

/// Looks a built-in scene up by name, loading its mesh when it has one.
/// `Ok(None)` for an unknown name.
pub fn by_name(name: &str, opts: &LoadOptions) -> Result<Option<LoadedScene>> {
    let with_bunny = |build: fn(&Mesh, bool) -> Result<SceneDesc>| -> Result<LoadedScene> {
        let path = opts
            .mesh
            .as_deref()
            .ok_or_else(|| Error::MeshRequired { scene: name.into() })?;
        let (mesh, report) = load_mesh_timed(path)?;
        Ok(LoadedScene {
            desc: build(&mesh, opts.smooth)?,
            meshes: vec![report],
        })
    };
    match name {
        "cornell" => {
            if let Some(p) = &opts.mesh {
                return Err(Error::InvalidSetting(format!(
                    "--mesh {}: scene 'cornell' has no mesh",
                    p.display()
                )));
            }
            Ok(Some(LoadedScene {
                desc: cornell(),
                meshes: vec![],
            }))
        }
        "cornell-specular" => {
            if let Some(p) = &opts.mesh {
                return Err(Error::InvalidSetting(format!(
                    "--mesh {}: scene 'cornell-specular' has no mesh",
                    p.display()
                )));
            }
            Ok(Some(LoadedScene {
                desc: cornell_specular(),
                meshes: vec![],
            }))
        }
        "cornell-bunny" => with_bunny(cornell_bunny).map(Some),
        "cornell-final" => with_bunny(cornell_final).map(Some),
        _ => Ok(None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn room_spans_the_unit_cube_with_y_down() {
        let d = cornell();
        assert_eq!(d.triangles.len(), 30);
        // Floor triangles lie on y = +1, the left (purple) wall on x = -1.
        let floor = d.materials.iter().position(|(n, _)| n == "floor").unwrap() as u32;
        let left = d.materials.iter().position(|(n, _)| n == "left_wall").unwrap() as u32;
        for t in &d.triangles {
            if t.material == floor {
                assert!(t.vertices.iter().all(|v| (v.y - 1.0).abs() < 1e-6));
            }
            if t.material == left {
                assert!(t.vertices.iter().all(|v| (v.x + 1.0).abs() < 1e-6));
            }
        }
        // Blocks stand on the floor.
        let max_y = d.triangles[10..]
            .iter()
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
        };
        let mut desc = by_name("cornell-bunny", &opts).unwrap().unwrap().desc;
        let n = 64;
        desc.camera.width = n;
        desc.camera.height = n;
        let bunny = desc.materials.iter().position(|(name, _)| name == "bunny").unwrap() as u32;
        let mut room = desc.clone();
        room.triangles.retain(|t| t.material != bunny);
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
            parts: vec![],
            warnings: vec![],
        };
        let mut meshes = vec![stand_in];
        if let Some(p) = crate::scene::mesh::tests::bunny_path() {
            meshes.push(crate::scene::mesh::load_mesh(&p).unwrap());
        }
        for m in &meshes {
            let e = fit_error(m, &bunny_transform(), explicit_bunny);
            assert!(e < 1e-5, "cornell-bunny: {e}");
            let e = fit_error(m, &final_bunny_transform(), explicit_final);
            assert!(e < 1e-5, "cornell-final: {e}");
        }
    }
}
