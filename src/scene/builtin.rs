//! The canonical scenes, with the numbers of the project's scene definitions
//! built in so that the default render needs no file.

use super::{CameraDesc, SceneDesc, SceneSettings, TriangleDesc};
use crate::geometry::Sphere;
use crate::light::Light;
use crate::material::Material;
use crate::math::Vec3;
use std::f32::consts::PI;

/// Names accepted by `--scene`.
pub const NAMES: &[&str] = &["cornell"];

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
    SceneDesc {
        name: name.into(),
        camera,
        materials: vec![],
        triangles: vec![],
        spheres: vec![],
        lights: vec![],
        settings: SceneSettings::default(),
    }
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
    d
}

/// Looks a built-in scene up by name.
pub fn by_name(name: &str) -> Option<SceneDesc> {
    match name {
        "cornell" => Some(cornell()),
        _ => None,
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
}
