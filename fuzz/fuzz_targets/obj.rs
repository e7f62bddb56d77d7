//! Wavefront OBJ (and, after a NUL byte, its MTL library) through the loader
//! and into a built scene.

#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use raytracer::scene::mesh::{parse_mesh, MeshFormat};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let (obj, mtl) = common::split_mtl(data);
    let mut files = std::collections::BTreeMap::new();
    if let Some(mtl) = mtl {
        for name in ["m.mtl", "a.mtl", "mesh.mtl"] {
            files.insert(Path::new("virtual").join(name), mtl.to_vec());
        }
    }
    let files = common::Files(files);
    if let Ok(mesh) = parse_mesh(Path::new("virtual/mesh.obj"), obj, MeshFormat::Obj, &files) {
        common::place_and_build(&mesh);
    }
});
