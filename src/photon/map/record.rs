//! The packed photon record, apart from the kd-tree so that its encoding
//! (and the photon map file format, which is this record) can change without
//! touching the queries.
//!
//! A photon takes 32 bytes, index included: position 3 x f32, power 3 x f16
//! (relative to the map's `unit`, so that f16's range is not wasted on tiny
//! absolute powers), flags (split axis, direct bit), incoming direction and
//! surface normal octahedral-encoded in 2 x u16 each (Cigolle et al. 2014),
//! object id u32.

use crate::math::Vec3;
use half::f16;

const AXIS_MASK: u8 = 0b11;
const DIRECT: u8 = 0b100;
const CAUSTIC: u8 = 0b1000;
const MOVING: u8 = 0b1_0000;

/// One stored photon: where it landed, what it carried, where it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Photon {
    pub p: Vec3,
    /// f16 bits of power / map unit.
    power: [u16; 3],
    /// Bits 0-1: split axis of the kd-tree node; bit 2: a first-hit (direct)
    /// photon; bit 3: a caustic photon (first diffuse hit after specular ones);
    /// bit 4: on a moving shape, kept where the shape is at its motion's start.
    flags: u8,
    _pad: u8,
    /// Octahedral code of the unit direction the photon came from.
    wi: u32,
    /// Octahedral code of the surface normal, on the side the photon arrived from.
    n: u32,
    /// Object id of the surface (the scene's `Hit::object`).
    pub object: u32,
}

const _: () = assert!(std::mem::size_of::<Photon>() as u64 == crate::settings::PHOTON_RECORD_BYTES);

impl Photon {
    /// Packs a photon; `power` is relative to the map's unit.
    pub fn new(p: Vec3, wi: Vec3, n: Vec3, power: Vec3, object: u32, direct: bool) -> Photon {
        Photon {
            p,
            power: power
                .to_array()
                .map(|c| f16::from_f32(c.min(f16::MAX.to_f32())).to_bits()),
            flags: if direct { DIRECT } else { 0 },
            _pad: 0,
            wi: oct_encode(wi),
            n: oct_encode(n),
            object,
        }
    }

    /// Power relative to the map's unit.
    pub fn power(&self) -> Vec3 {
        Vec3::from_array(self.power.map(half_to_f32))
    }

    /// Unit direction towards where the photon came from.
    pub fn wi(&self) -> Vec3 {
        oct_decode(self.wi)
    }

    /// Whether the photon arrived from the side of the plane with normal `n`
    /// (a sign test, so the direction need not be normalised).
    pub fn arrived_from(&self, n: Vec3) -> bool {
        oct_unnormalised(self.wi).dot(n) > 0.0
    }

    /// Unit surface normal on the side the photon arrived from.
    pub fn normal(&self) -> Vec3 {
        oct_decode(self.n)
    }

    /// Whether this photon is a first hit from a light (direct illumination).
    pub fn is_direct(&self) -> bool {
        self.flags & DIRECT != 0
    }

    /// The 32-byte little-endian record of photon map files: position 3 x
    /// f32, power 3 x f16 bits, flags, a zero byte, wi, n, object (u32 each).
    pub fn to_le_bytes(&self) -> [u8; 32] {
        let mut b = [0u8; 32];
        for (i, c) in self.p.to_array().into_iter().enumerate() {
            b[4 * i..4 * i + 4].copy_from_slice(&c.to_le_bytes());
        }
        for (i, c) in self.power.into_iter().enumerate() {
            b[12 + 2 * i..14 + 2 * i].copy_from_slice(&c.to_le_bytes());
        }
        b[18] = self.flags;
        b[19] = 0;
        b[20..24].copy_from_slice(&self.wi.to_le_bytes());
        b[24..28].copy_from_slice(&self.n.to_le_bytes());
        b[28..32].copy_from_slice(&self.object.to_le_bytes());
        b
    }

    /// The photon of a record, or `None` for one no map holds (non-finite
    /// position, an axis beyond z, unknown flag bits): queries index a
    /// position by the axis bits, so these are checked, whatever the checksum.
    pub fn from_le_bytes(b: &[u8; 32]) -> Option<Photon> {
        let u32_at = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        let u16_at = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
        let p = Vec3::new(
            f32::from_bits(u32_at(0)),
            f32::from_bits(u32_at(4)),
            f32::from_bits(u32_at(8)),
        );
        let flags = b[18];
        if !p.is_finite()
            || flags & AXIS_MASK > 2
            || flags & !(AXIS_MASK | DIRECT | CAUSTIC | MOVING) != 0
            || b[19] != 0
        {
            return None;
        }
        Some(Photon {
            p,
            power: [u16_at(12), u16_at(14), u16_at(16)],
            flags,
            _pad: 0,
            wi: u32_at(20),
            n: u32_at(24),
            object: u32_at(28),
        })
    }

    /// Marks the photon as a caustic one: it reached its first diffuse surface
    /// through mirrors or glass only (a path light -> specular+ -> here).
    pub fn caustic(mut self) -> Photon {
        self.flags |= CAUSTIC;
        self
    }

    /// Whether the photon came from the light through specular surfaces only.
    pub fn is_caustic(&self) -> bool {
        self.flags & CAUSTIC != 0
    }

    /// Marks the photon as one on a moving shape, its position, direction
    /// and normal given where the shape is at its motion's start
    /// (`Scene::rest_frame`).
    pub fn moving(mut self) -> Photon {
        self.flags |= MOVING;
        self
    }

    pub fn is_moving(&self) -> bool {
        self.flags & MOVING != 0
    }

    pub(super) fn axis(&self) -> usize {
        (self.flags & AXIS_MASK) as usize
    }

    pub(super) fn set_axis(&mut self, axis: usize) {
        self.flags = (self.flags & !AXIS_MASK) | axis as u8;
    }
}

/// f16 bits to f32 for finite values (we store no infinities): shift the
/// exponent and mantissa into place and rebias the exponent by a multiply by
/// 2^112, which also turns subnormals into the right normal values (Giesen,
/// "half to float done quic"). Branch-free and much faster than a call per
/// value through a runtime CPU-feature check.
#[inline]
fn half_to_f32(h: u16) -> f32 {
    let magnitude = f32::from_bits(((h & 0x7fff) as u32) << 13) * f32::from_bits(0x7780_0000);
    f32::from_bits(magnitude.to_bits() | (((h & 0x8000) as u32) << 16))
}

/// Octahedral encoding of a unit vector into two 16-bit fixed-point coordinates.
pub fn oct_encode(v: Vec3) -> u32 {
    let l1 = v.x.abs() + v.y.abs() + v.z.abs();
    if !(l1 > 0.0 && l1.is_finite()) {
        return oct_encode(Vec3::Z);
    }
    let (mut x, mut y) = (v.x / l1, v.y / l1);
    if v.z < 0.0 {
        (x, y) = ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y));
    }
    // 65534 steps, so that 0 and +-1 are exact (the axes round-trip exactly).
    let q = |f: f32| ((f.clamp(-1.0, 1.0) * 0.5 + 0.5) * 65534.0).round() as u32;
    q(x) | (q(y) << 16)
}

pub fn oct_decode(e: u32) -> Vec3 {
    oct_unnormalised(e).normalize()
}

/// The decoded direction before normalisation (length in [1/sqrt(3), 1]).
fn oct_unnormalised(e: u32) -> Vec3 {
    let d = |b: u32| b.min(65534) as f32 * (2.0 / 65534.0) - 1.0;
    let (mut x, mut y) = (d(e & 0xffff), d(e >> 16));
    let z = 1.0 - x.abs() - y.abs();
    if z < 0.0 {
        (x, y) = ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y));
    }
    Vec3::new(x, y, z)
}

fn sign(f: f32) -> f32 {
    if f >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{uniform_sphere, Rng};

    #[test]
    fn packing_keeps_directions_and_power() {
        let mut rng = Rng::new(9, 2);
        for _ in 0..10_000 {
            let v = uniform_sphere(rng.next_2d());
            let d = oct_decode(oct_encode(v));
            // 16-bit octahedral codes: error below 1e-4 radians.
            assert!((d - v).length() < 1e-4, "{v:?} -> {d:?}");
        }
        for v in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            assert!((oct_decode(oct_encode(v)) - v).length() < 1e-6);
        }
        let p = Photon::new(Vec3::ONE, Vec3::Y, -Vec3::Z, Vec3::new(1.0, 0.2, 1e-3), 7, true);
        let e = (p.power() - Vec3::new(1.0, 0.2, 1e-3)) / Vec3::new(1.0, 0.2, 1e-3);
        assert!(e.abs().max_element() < 1e-3, "{:?}", p.power());
        assert!(p.is_direct() && !p.is_caustic() && p.object == 7);
        let c = p.caustic();
        assert!(c.is_caustic() && c.is_direct() && c.power() == p.power() && !c.is_moving());
        // The moving bit survives a file's record, apart from the others.
        let m = Photon::from_le_bytes(&p.moving().to_le_bytes()).unwrap();
        assert!(m.is_moving() && m.is_direct() && !m.is_caustic() && m.object == 7);
        assert!((p.wi() - Vec3::Y).length() < 1e-6 && (p.normal() + Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn half_decoding_matches_the_half_crate() {
        for h in 0..=u16::MAX {
            let want = f16::from_bits(h);
            if want.is_finite() {
                assert_eq!(half_to_f32(h).to_bits(), want.to_f32().to_bits(), "{h:#x}");
            }
        }
    }
}
