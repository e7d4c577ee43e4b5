//! The build's boxes and bins, and the leaf cost unit its surface area heuristic counts in.
//!
//! [`Aabb`] is a box in SIMD-friendly form; a node's centroids are sorted into [`Bin`]s, at most
//! [`MAX_BINS`] per axis, and [`records`] is the cost of a leaf in record tests (the unit
//! [`unit_shift`] chooses), shared by the binned split ([`sweep`](super::sweep)) and the
//! optimal collapse.

use glam::Vec3A;

use crate::bvh::bounds::Bounds;
use crate::bvh::leaf::RECORD_TRIANGLES;

/// The most bins a build uses ([`BuildSettings::bins`](super::BuildSettings::bins) is clamped to it).
pub(super) const MAX_BINS: usize = 256;
/// A box in SIMD-friendly form, for the build only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Aabb {
    pub(super) min: Vec3A,
    pub(super) max: Vec3A,
}

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    pub(super) const EMPTY: Aabb = Aabb { min: Vec3A::INFINITY, max: Vec3A::NEG_INFINITY };

    #[inline]
    pub(super) fn union(self, other: Aabb) -> Aabb {
        Aabb { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    #[inline]
    pub(super) fn grow(self, p: Vec3A) -> Aabb {
        Aabb { min: self.min.min(p), max: self.max.max(p) }
    }

    #[inline]
    pub(super) fn half_area(&self) -> f32 {
        self.bounds().half_area()
    }

    /// [`half_area`](Self::half_area) of a box known not to be empty (it holds a primitive):
    /// no emptiness test.
    #[cfg(any(test, not(target_arch = "x86_64")))]
    #[inline]
    pub(super) fn half_area_nonempty(&self) -> f32 {
        let d = self.max - self.min;
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    #[inline]
    pub(super) fn bounds(&self) -> Bounds {
        Bounds { min: self.min.into(), max: self.max.into() }
    }
}

/// Per-bin bounds of primitives, and counts.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Bin {
    pub(super) bounds: Aabb,
    pub(super) count: u32,
}

/// How many leaf tests `n` triangles take at least, in leaves of up to `2^unit` triangles:
/// `⌈n / 2^unit⌉` ([`unit_shift`]).
#[inline]
pub(super) fn records(n: u32, unit: u32) -> f32 {
    ((n + (1 << unit) - 1) >> unit) as f32
}

/// The leaf cost unit of a build with leaves of up to `max_leaf` triangles, as a shift: a record
/// of eight (one test pass) where leaves hold eight or more, four otherwise (the small scenes'
/// leaves of four: then a subtree of `n` triangles needs `⌈n/4⌉` leaves, each a test).
pub(super) fn unit_shift(max_leaf: usize) -> u32 {
    if max_leaf >= RECORD_TRIANGLES { RECORD_TRIANGLES.trailing_zeros() } else { 2 }
}
