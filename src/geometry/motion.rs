//! Shapes that move while the shutter is open: pbrt-v4's
//! `AnimatedTransform`.
//!
//! A moving shape has two object-to-world transformations, at the start and
//! end of its transformation times (pbrt-v4's `TransformTimes`, 0 and 1 by
//! default). Each is decomposed into a translation, a rotation and a
//! stretch (the polar decomposition M = T R S, S symmetric), and in between
//! the translation and stretch are interpolated linearly and the rotation
//! by spherical interpolation, so that a turning shape turns rather than
//! shrinking through the interpolated matrix; before the start and after
//! the end the transformation holds still.
//!
//! The shape's triangles are stored as placed at the start time, so
//! [`Motion::relative`] gives the transformation from there to the place at
//! a ray's time.

use crate::math::Vec3;
use glam::{Mat3, Mat4, Quat};

/// One end of a motion, decomposed.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Decomposed {
    translation: Vec3,
    rotation: Quat,
    stretch: Mat3,
}

/// Samples of the motion taken to bound a moving box: consecutive samples
/// of a point's path are at most 360 / 64 degrees of turn apart, where an
/// arc exceeds its chord by less than 0.1%.
const BOUND_STEPS: usize = 64;

#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    ends: [Decomposed; 2],
    times: [f32; 2],
    /// The inverse of the start transformation.
    start_inverse: Mat4,
    /// The frame the motion is given in (`in_frame`), with its inverse:
    /// identity unless the motion was given about a pivot or the scene was
    /// reflected after it was given.
    frame: Mat4,
    frame_inverse: Mat4,
}

impl Motion {
    /// The motion between object-to-world transformations `start` at time
    /// `times[0]` and `end` at `times[1]`; an error when either cannot be
    /// decomposed (a projective or singular matrix), when they differ in
    /// handedness, or when the times are not finite and increasing.
    pub fn new(start: Mat4, end: Mat4, times: [f32; 2]) -> Result<Motion, String> {
        if !(times[0].is_finite() && times[1].is_finite() && times[0] < times[1]) {
            return Err(format!(
                "transformation times {} and {} must be finite and increasing",
                times[0], times[1]
            ));
        }
        let (a, b) = (decompose(start)?, decompose(end)?);
        if (a.stretch.determinant() > 0.0) != (b.stretch.determinant() > 0.0) {
            return Err("the start and end transformations differ in handedness".into());
        }
        // The shorter way round, as pbrt-v4 takes it.
        let b = if a.rotation.dot(b.rotation) < 0.0 {
            Decomposed {
                rotation: -b.rotation,
                ..b
            }
        } else {
            b
        };
        let start_inverse = start.inverse();
        if !start_inverse.is_finite() {
            return Err("the start transformation cannot be inverted".into());
        }
        Ok(Motion {
            ends: [a, b],
            times,
            start_inverse,
            frame: Mat4::IDENTITY,
            frame_inverse: Mat4::IDENTITY,
        })
    }

    /// The object-to-world transformation at `time`.
    pub fn at(&self, time: f32) -> Mat4 {
        let [a, b] = &self.ends;
        let s = ((time - self.times[0]) / (self.times[1] - self.times[0])).clamp(0.0, 1.0);
        if s.is_nan() || s <= 0.0 {
            return compose(a);
        }
        if s >= 1.0 {
            return compose(b);
        }
        compose(&Decomposed {
            translation: a.translation.lerp(b.translation, s),
            rotation: a.rotation.slerp(b.rotation, s).normalize(),
            stretch: a.stretch * (1.0 - s) + b.stretch * s,
        })
    }

    /// The transformation from the shape as placed at the start time to its
    /// place at `time`.
    pub fn relative(&self, time: f32) -> Mat4 {
        let m = self.at(time) * self.start_inverse;
        if self.frame == Mat4::IDENTITY {
            m
        } else {
            self.frame * m * self.frame_inverse
        }
    }

    /// The same motion seen in a scene reflected by `mirror` (a reflection:
    /// its own inverse).
    pub fn mirrored(&self, mirror: Mat4) -> Motion {
        self.in_frame(mirror, mirror)
    }

    /// The motion given in a frame whose origin is `pivot`: what it turns
    /// and stretches about stays on the straight line its translation
    /// takes, where about the world's origin it would swing along an arc.
    pub fn about(&self, pivot: Vec3) -> Motion {
        self.in_frame(Mat4::from_translation(pivot), Mat4::from_translation(-pivot))
    }

    /// Conjugated by `frame` (with its inverse): relative(t) becomes
    /// frame * relative(t) * frame^-1.
    fn in_frame(&self, frame: Mat4, inverse: Mat4) -> Motion {
        Motion {
            frame: frame * self.frame,
            frame_inverse: self.frame_inverse * inverse,
            ..self.clone()
        }
    }

    /// A box holding `b` (placed at the start time) wherever it moves.
    pub fn bounds(&self, min: Vec3, max: Vec3) -> (Vec3, Vec3) {
        let corners: Vec<Vec3> = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                )
            })
            .collect();
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        // A point between two samples of its path is within half the path's
        // length between them of one of them; the chord stands for that
        // length (see BOUND_STEPS), doubled for safety.
        let mut pad = 0.0f32;
        let mut last: Option<Vec<Vec3>> = None;
        for k in 0..=BOUND_STEPS {
            let t = self.times[0] + (self.times[1] - self.times[0]) * k as f32 / BOUND_STEPS as f32;
            let m = self.relative(t);
            let placed: Vec<Vec3> = corners.iter().map(|&c| m.transform_point3(c)).collect();
            for &p in &placed {
                lo = lo.min(p);
                hi = hi.max(p);
            }
            if let Some(prev) = &last {
                for (p, q) in placed.iter().zip(prev) {
                    pad = pad.max(p.distance(*q));
                }
            }
            last = Some(placed);
        }
        // Corners bound the box's points since each sample is affine.
        let pad = Vec3::splat(pad + 1e-5 * (hi - lo).max_element());
        (lo - pad, hi + pad)
    }
}

/// M = T R S with R a rotation and S symmetric (S's determinant carries a
/// reflection's sign), by the iteration pbrt-v4 uses: R <- (R + R^-T) / 2.
fn decompose(m: Mat4) -> Result<Decomposed, String> {
    if !m.is_finite() || m.row(3) != glam::Vec4::new(0.0, 0.0, 0.0, 1.0) {
        return Err("a moving shape's transformation must be affine".into());
    }
    let translation = m.w_axis.truncate();
    let m3 = Mat3::from_mat4(m);
    let det = m3.determinant();
    if det.abs() <= 1e-12 || !det.is_finite() {
        return Err("a moving shape's transformation is singular".into());
    }
    // A reflection is moved into the stretch, so that R is a rotation.
    let mut r = if det < 0.0 { -m3 } else { m3 };
    for _ in 0..100 {
        let next = (r + r.inverse().transpose()) * 0.5;
        let change = (0..3)
            .map(|i| (next.col(i) - r.col(i)).abs().max_element())
            .fold(0.0f32, f32::max);
        r = next;
        if change < 1e-7 {
            break;
        }
    }
    let stretch = r.inverse() * m3;
    let rotation = Quat::from_mat3(&r).normalize();
    if !rotation.is_finite() || !stretch.is_finite() {
        return Err("a moving shape's transformation cannot be decomposed".into());
    }
    Ok(Decomposed {
        translation,
        rotation,
        stretch,
    })
}

fn compose(d: &Decomposed) -> Mat4 {
    let m3 = Mat3::from_quat(d.rotation) * d.stretch;
    Mat4::from_cols(
        m3.x_axis.extend(0.0),
        m3.y_axis.extend(0.0),
        m3.z_axis.extend(0.0),
        d.translation.extend(1.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    fn close(a: Mat4, b: Mat4) -> bool {
        (0..4).all(|i| (a.col(i) - b.col(i)).abs().max_element() < 1e-4)
    }

    #[test]
    fn ends_are_the_given_transformations() {
        let start = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
            * Mat4::from_rotation_y(0.3)
            * Mat4::from_scale(Vec3::new(2.0, -1.0, 0.5))
            * Mat4::from_rotation_x(0.7);
        let end = Mat4::from_translation(Vec3::new(-1.0, 0.0, 3.0))
            * Mat4::from_rotation_z(2.0)
            * Mat4::from_scale(Vec3::new(1.0, -3.0, 1.0));
        let m = Motion::new(start, end, [0.5, 2.0]).unwrap();
        assert!(close(m.at(0.5), start) && close(m.at(-3.0), start));
        assert!(close(m.at(2.0), end) && close(m.at(7.0), end));
        assert!(close(m.relative(0.5), Mat4::IDENTITY));
    }

    #[test]
    fn a_turn_is_interpolated_as_a_turn() {
        // Half-way through a quarter turn about z the point (1, 0, 0) is on
        // the unit circle at 45 degrees, not inside it as a matrix lerp gives.
        let m = Motion::new(Mat4::IDENTITY, Mat4::from_rotation_z(PI / 2.0), [0.0, 1.0]).unwrap();
        let p = m.at(0.5).transform_point3(Vec3::X);
        let h = std::f32::consts::FRAC_1_SQRT_2;
        assert!((p - Vec3::new(h, h, 0.0)).length() < 1e-5, "{p}");
        // Translation and scale are linear in time.
        let m = Motion::new(
            Mat4::from_scale(Vec3::splat(1.0)),
            Mat4::from_translation(Vec3::new(4.0, 0.0, 0.0)) * Mat4::from_scale(Vec3::splat(3.0)),
            [0.0, 1.0],
        )
        .unwrap();
        let p = m.at(0.25).transform_point3(Vec3::Y);
        assert!((p - Vec3::new(1.0, 1.5, 0.0)).length() < 1e-5, "{p}");
    }

    #[test]
    fn bounds_hold_the_moving_box_at_every_time() {
        let m = Motion::new(
            Mat4::from_translation(Vec3::new(0.0, 1.0, 0.0)),
            Mat4::from_translation(Vec3::new(3.0, 0.0, 0.0)) * Mat4::from_rotation_y(3.0),
            [0.0, 1.0],
        )
        .unwrap();
        let (min, max) = (Vec3::new(-1.0, 0.5, -0.5), Vec3::new(2.0, 1.5, 0.5));
        let (lo, hi) = m.bounds(min, max);
        for k in 0..=1000 {
            let r = m.relative(k as f32 / 1000.0);
            for i in 0..8 {
                let c = Vec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                );
                let p = r.transform_point3(c);
                assert!(p.cmpge(lo).all() && p.cmple(hi).all(), "{p} outside {lo} {hi}");
            }
        }
        // And not much more: the box turning about y through 3 radians
        // sweeps about a disk of its corner's radius.
        assert!((hi - lo).max_element() < 3.0 + 2.0 * 2.2);
    }

    #[test]
    fn a_mirrored_motion_moves_the_mirror_image() {
        let m = Motion::new(
            Mat4::IDENTITY,
            Mat4::from_translation(Vec3::new(1.0, 2.0, 0.0)) * Mat4::from_rotation_z(1.0),
            [0.0, 1.0],
        )
        .unwrap();
        let r = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let p = Vec3::new(0.3, -0.2, 0.5);
        let moved = m.relative(0.6).transform_point3(p);
        let seen = m.mirrored(r).relative(0.6).transform_point3(r.transform_point3(p));
        assert!((seen - r.transform_point3(moved)).length() < 1e-5, "{seen} {moved}");
    }

    #[test]
    fn undecomposable_motions_are_refused() {
        let mut projective = Mat4::IDENTITY;
        projective.x_axis.w = 0.5;
        assert!(Motion::new(Mat4::IDENTITY, projective, [0.0, 1.0]).is_err());
        assert!(Motion::new(Mat4::IDENTITY, Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)), [0.0, 1.0]).is_err());
        assert!(Motion::new(Mat4::IDENTITY, Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)), [0.0, 1.0]).is_err());
        assert!(Motion::new(Mat4::IDENTITY, Mat4::IDENTITY, [1.0, 1.0]).is_err());
    }
}
