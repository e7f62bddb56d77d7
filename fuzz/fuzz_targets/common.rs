//! What the fuzz targets share: in-memory files, so that no input can make a
//! loader read the machine's files, and the steps after a successful load
//! that must not panic on anything a loader accepts.

#![allow(dead_code)]

use raytracer::material::Material;
use raytracer::math::Vec3;
use raytracer::scene::mesh::{FileSource, Mesh};
use raytracer::scene::transform::Transform;
use raytracer::scene::{CameraDesc, Scene, SceneDesc};
use std::collections::BTreeMap;
use std::io::{Error, ErrorKind};
use std::path::{Path, PathBuf};

/// A fixed set of files; every other path is not found.
pub struct Files(pub BTreeMap<PathBuf, Vec<u8>>);

impl FileSource for Files {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        self.0
            .get(path)
            .cloned()
            .ok_or_else(|| Error::new(ErrorKind::NotFound, "not among the fuzz target's files"))
    }
}

/// Splits an input at its first NUL: the mesh before, the material library
/// (served for any `.mtl` name) after.
pub fn split_mtl(data: &[u8]) -> (&[u8], Option<&[u8]>) {
    match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], Some(&data[i + 1..])),
        None => (data, None),
    }
}

/// Places a loaded mesh in a scene and builds its BVH, as a render would.
pub fn place_and_build(mesh: &Mesh) {
    let _ = mesh.bounds();
    // Built by the library's own constructor, so that a field added to the
    // description cannot leave this crate behind.
    let mut desc = SceneDesc::empty(
        "fuzz",
        CameraDesc {
            position: Vec3::new(0.0, 0.0, -5.0),
            look_at: Vec3::ZERO,
            up: Vec3::new(0.0, -1.0, 0.0),
            fov_y_deg: 40.0,
            width: 8,
            height: 8,
            window: None,
            lens: None,
            orthographic: None,
            spherical: None,
            realistic: None,
        },
    );
    let m = desc.material("grey", Material::diffuse(0.5, 0.5, 0.5));
    if mesh
        .add_to_scene(&mut desc, &Transform::default(), Some(m), true)
        .is_ok()
    {
        let _ = Scene::build(desc);
    }
}
