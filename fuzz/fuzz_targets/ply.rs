//! Stanford PLY (ASCII and both binary encodings) through the loader and into
//! a built scene.

#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use raytracer::scene::mesh::{parse_mesh, MeshFormat};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let files = common::Files(Default::default());
    if let Ok(mesh) = parse_mesh(Path::new("virtual/mesh.ply"), data, MeshFormat::Ply, &files) {
        common::place_and_build(&mesh);
    }
});
