//! The photon map: compact photon records and the balanced kd-tree over them.
//!
//! Two parts that change for different reasons: the packed record
//! (`record`) is what a photon costs in memory and in photon map files, the
//! kd-tree (`kdtree`) is how the photons near a point are found again. The
//! tree reads a record only through its position and the split axis the
//! record keeps in its flags.

mod kdtree;
mod record;

pub use kdtree::{Neighbour, PhotonMap, LEAF};
pub use record::{oct_decode, oct_encode, Photon};
