//! The top level's box test for a packet of rays, all lanes at once.
//!
//! [`TwoLevel`](super::TwoLevel)'s packet walk asks, at every box, which of up to 64 rays enter
//! it. Asked ray by ray ([`RayBoxTest::enter`]) that was a quarter of the lab's time on an
//! instanced model. [`BoxLanes`] keeps the rays as arrays (one per coordinate) and makes the
//! same test over every lane in one straight loop that the compiler vectorizes; the arithmetic
//! is `enter`'s, operation for operation, so the masks are the same bit for bit (its scalar twin
//! is `enter` itself: `tests` compares them).

use glam::Vec3;

use super::top::{Margin, PACKET};
use crate::bvh::{Bounds, FAR_SCALE, RayBoxTest, SLAB_PAD};

/// Up to [`PACKET`] rays' box-test set-up, lane by lane (unused lanes hold zeros).
pub(super) struct BoxLanes {
    origin: [[f32; PACKET]; 3],
    inv_direction: [[f32; PACKET]; 3],
    negative: [[bool; PACKET]; 3],
    dominant: [[bool; PACKET]; 3],
    t_min: [f32; PACKET],
    /// `|o|∞`: what a box's margin grows with ([`Margin::pad`]).
    size: [f32; PACKET],
    /// Each lane's current `t_max` (the caller keeps it up to date).
    pub t_max: [f32; PACKET],
}

impl BoxLanes {
    /// The lanes of `tests` (`None`: a lane without a ray).
    pub fn new(tests: &[Option<RayBoxTest>]) -> BoxLanes {
        debug_assert!(tests.len() <= PACKET);
        let mut lanes = BoxLanes {
            origin: [[0.0; PACKET]; 3],
            inv_direction: [[0.0; PACKET]; 3],
            negative: [[false; PACKET]; 3],
            dominant: [[false; PACKET]; 3],
            t_min: [0.0; PACKET],
            size: [0.0; PACKET],
            t_max: [f32::NEG_INFINITY; PACKET],
        };
        for (i, test) in tests.iter().enumerate() {
            let Some(test) = test else { continue };
            for axis in 0..3 {
                lanes.origin[axis][i] = test.origin[axis];
                lanes.inv_direction[axis][i] = test.inv_direction[axis];
                lanes.negative[axis][i] = test.negative[axis];
                lanes.dominant[axis][i] = test.dominant_axis == axis;
            }
            lanes.t_min[i] = test.t_min;
            lanes.size[i] = test.origin.abs().max_element();
        }
        lanes
    }

    /// The largest `|o|∞` of the rays: what the packet's frustum grows a box's margin by.
    pub fn largest_size(&self) -> f32 {
        self.size.iter().fold(0.0, |a, &b| a.max(b))
    }

    /// The lanes of `mask` whose rays enter `bounds` grown by `margin` within their
    /// `[t_min, t_max]`: bit `i` as `RayBoxTest::enter(grown box, t_max[i]).is_some()`.
    #[inline]
    pub fn reaching(&self, bounds: &Bounds, margin: &Margin, mask: u64) -> u64 {
        let mut enters = [false; PACKET];
        for (i, enters) in enters.iter_mut().enumerate() {
            let pad = margin.pad(self.size[i]);
            let (lo, hi) = (bounds.min - Vec3::splat(pad), bounds.max + Vec3::splat(pad));
            let mut near = self.t_min[i];
            let mut far = self.t_max[i];
            let mut reach = 0.0f32;
            for axis in 0..3 {
                let (near_plane, far_plane) = if self.negative[axis][i] {
                    (hi[axis], lo[axis])
                } else {
                    (lo[axis], hi[axis])
                };
                let (o, inv) = (self.origin[axis][i], self.inv_direction[axis][i]);
                let t_near = (near_plane - o) * inv;
                let t_far = (far_plane - o) * inv;
                near = t_near.max(near);
                far = (t_far * FAR_SCALE).min(far);
                if self.dominant[axis][i] {
                    reach = t_near.abs().max(t_far.abs());
                }
            }
            let pad = reach * SLAB_PAD;
            *enters = near - pad <= far + pad;
        }
        let bits = enters.iter().enumerate().fold(0u64, |bits, (i, &e)| bits | (e as u64) << i);
        bits & mask
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests_uniform as uniform;
    use super::*;
    use crate::ray::Ray;

    /// Every lane's bit is what `enter` says of its ray, over hostile rays (axis-parallel
    /// directions with signed zeros, origins on the box's planes, empty and reversed ranges)
    /// and boxes with and without margins.
    #[test]
    fn the_lanes_agree_with_enter_bit_for_bit() {
        let mut state = 5u64;
        let mut agreed = (0, 0);
        for round in 0..400 {
            let mut r = || uniform(&mut state);
            let min = Vec3::new(r() * 4.0 - 2.0, r() * 4.0 - 2.0, r() * 4.0 - 2.0);
            let bounds = Bounds { min, max: min + Vec3::new(r(), r(), r()) * 2.0 };
            let margin = if round % 2 == 0 {
                Margin::default()
            } else {
                Margin { scale: 1e-3 * r(), reach: 10.0 * r() }
            };
            let count = 1 + (r() * PACKET as f32) as usize % PACKET;
            let mut rays = Vec::new();
            let mut t_max = Vec::new();
            for k in 0..count {
                let mut origin = Vec3::new(r() * 8.0 - 4.0, r() * 8.0 - 4.0, r() * 8.0 - 4.0);
                if k % 3 == 0 {
                    origin.x = bounds.min.x; // on a plane: 0 · ∞ is NaN
                }
                // Half of them aimed at a point of the box, some at its corners (where the
                // pads decide).
                let centre = bounds.centroid();
                let inside = match k % 7 {
                    // Just outside a corner: within the pads, beyond the box.
                    3 => bounds.max + (bounds.max - centre) * 2e-6,
                    6 => bounds.max + (bounds.max - centre) * 2e-3 * r(),
                    4 => Vec3::new(bounds.min.x, bounds.max.y, bounds.min.z),
                    _ => bounds.min + (bounds.max - bounds.min) * Vec3::new(r(), r(), r()),
                };
                let mut direction = if k % 2 == 0 {
                    inside - origin
                } else {
                    Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5)
                };
                match k % 5 {
                    0 => direction.x = 0.0,
                    1 => direction = Vec3::new(-0.0, direction.y, 0.0),
                    _ => {}
                }
                if direction == Vec3::ZERO {
                    direction = Vec3::Z;
                }
                let mut ray = Ray::new(origin, direction);
                ray.t_min = if k % 4 == 0 { r() * 2.0 } else { 0.0 };
                rays.push(ray);
                t_max.push(match k % 6 {
                    0 => f32::INFINITY,
                    1 => 0.0,
                    2 => f32::NEG_INFINITY,
                    _ => r() * 6.0,
                });
            }
            let tests: Vec<Option<RayBoxTest>> = rays
                .iter()
                .enumerate()
                .map(|(k, ray)| (k % 11 != 5).then(|| RayBoxTest::new(ray)))
                .collect();
            let mut lanes = BoxLanes::new(&tests);
            lanes.t_max[..count].copy_from_slice(&t_max);
            let mask = if count == PACKET { u64::MAX } else { (1u64 << count) - 1 };
            let got = lanes.reaching(&bounds, &margin, mask);
            for (i, test) in tests.iter().enumerate() {
                let expected = test.as_ref().is_some_and(|test| {
                    let pad = margin.pad(test.origin.abs().max_element());
                    let grown = Bounds {
                        min: bounds.min - Vec3::splat(pad),
                        max: bounds.max + Vec3::splat(pad),
                    };
                    test.enter(&grown, t_max[i]).is_some()
                });
                // A lane without a ray is the caller's to leave out of the mask.
                if test.is_some() {
                    assert_eq!(
                        got >> i & 1 == 1,
                        expected,
                        "round {round} lane {i}: {:?}",
                        rays[i]
                    );
                    agreed.0 += expected as u32;
                    agreed.1 += 1;
                }
            }
            assert_eq!(got & !mask, 0, "no bit outside the mask");
        }
        // Both answers occur often.
        assert!(agreed.0 > agreed.1 / 10 && agreed.0 < agreed.1 * 9 / 10, "{agreed:?}");
    }
}
