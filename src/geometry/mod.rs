//! Shapes and the acceleration structure: triangles, spheres and the BVH.

pub mod bvh;
pub mod sphere;
pub mod triangle;

pub use bvh::{Bvh, BvhStats};
pub use sphere::Sphere;
pub use triangle::{Triangle, TriangleTest};
