//! The integration tests in one binary, each file a module: with link-time
//! optimisation every test binary costs a whole-program link. Only
//! `tests/ply_alloc.rs` stays apart, since it installs its own global allocator.

mod bvh;
mod cli;
mod fuzz_regressions;
mod layout;
mod materials;
mod mesh_cli;
mod pbrt;
mod persist;
mod photon_cli;
mod radiometry;
mod shapes;
mod specular;
mod textures;
mod tiles;
mod view;
