//! TOML scene files, with a virtual directory holding one small mesh of each
//! format, parsed and built into a scene (BVH included).

#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use raytracer::scene::file::parse_with;
use raytracer::scene::{LoadOptions, Scene};
use std::path::Path;

const OBJ: &[u8] = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nusemtl red\nf 1 2 3\nf 1 3 4\n";
const MTL: &[u8] = b"newmtl red\nKd 0.8 0.1 0.1\n";
const PLY: &[u8] = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let dir = Path::new("virtual");
    let files = common::Files(
        [("a.obj", OBJ), ("m.mtl", MTL), ("a.ply", PLY)]
            .into_iter()
            .map(|(n, b)| (dir.join(n), b.to_vec()))
            .collect(),
    );
    let opts = LoadOptions::default();
    if let Ok(loaded) = parse_with(&dir.join("scene.toml"), text, &opts, &files) {
        let _ = Scene::build(loaded.desc);
    }
});
