//! Shapes and the acceleration structures: triangles, spheres, disks,
//! curves, the triangle BVH and the BVH over the other shapes' boxes, and
//! the motion of shapes that move while the shutter is open.

pub mod bvh;
pub mod curve;
pub mod disk;
pub mod motion;
pub mod sphere;
pub mod subdivision;
pub mod triangle;

pub use bvh::{BoxBvh, Bvh, BvhStats};
pub use curve::{Curve, CurveKind};
pub use disk::Disk;
pub use sphere::{sphere_uv, Sphere};
pub use triangle::{Triangle, TriangleTest};
