//! The rays of a packet, lane by lane, with their search state: what packet traversal
//! (`packet`) and the packet kernels (`packet/leaf.rs`, `packet/lanes.rs`) share.

use glam::Vec3;

use super::bundle::LineBundle;
use crate::accel::Hit;
use crate::bvh::bounds::{FAR_SCALE, Frustum, RayBoxTest};
#[cfg(target_arch = "x86_64")]
use crate::bvh::simd::Lanes;
use crate::bvh::traverse::can_hit;
use crate::float::next_float_up;
use crate::ray::Ray;
use crate::triangle::WatertightRay;

/// What the rays of a group share: their direction signs and the watertight test's
/// `kx, ky, kz`.
pub(super) type Shared = ([bool; 3], [usize; 3]);

/// The most rays traced together: an 8×8 tile of camera rays.
pub(crate) const PACKET: usize = 64;

/// The rays of one packet, lane by lane (structure of arrays), with their search state.
/// Lanes from `len` on hold stale values and are never counted.
#[derive(Clone)]
#[repr(C, align(64))]
pub(crate) struct PacketRays {
    /// Origins, per world axis.
    pub origin: [[f32; PACKET]; 3],
    /// `1/d`, per world axis.
    pub inv_direction: [[f32; PACKET]; 3],
    /// The slab test's `t_min` ([`RayBoxTest::t_min`]).
    pub box_t_min: [f32; PACKET],
    /// The watertight test's shear, `shear_x`, `shear_y`, `shear_z`.
    pub shear: [[f32; PACKET]; 3],
    /// The watertight test's `t_min` ([`WatertightRay`]).
    pub triangle_t_min: [f32; PACKET],
    /// Triangles are accepted below this (see [`Closest`](crate::bvh::traverse::Closest)).
    pub triangle_limit: [f32; PACKET],
    /// Boxes are entered up to this.
    pub box_limit: [f32; PACKET],
    /// The closest hit so far (`+∞` for none), its triangle (`u32::MAX` for none) and
    /// barycentrics.
    pub best_t: [f32; PACKET],
    pub best_triangle: [u32; PACKET],
    pub best_b1: [f32; PACKET],
    pub best_b2: [f32; PACKET],
    /// The rays in the packet.
    pub len: usize,
    /// Shared by all rays: the direction's signs, and the watertight test's `kx, ky, kz`
    /// (whose `kz` is the dominant axis).
    pub negative: [bool; 3],
    pub k: [usize; 3],
    /// The rays' lines, when they meet in one point (a shared origin, or the light that shadow
    /// rays end at): culls a leaf's triangles for all of them, and sizes leaves against the
    /// packet's footprint ([`LineBundle::size_of`]).
    pub bundle: Option<LineBundle>,
}

impl PacketRays {
    /// An empty packet, to be filled.
    pub(super) fn new() -> PacketRays {
        PacketRays {
            origin: [[0.0; PACKET]; 3],
            inv_direction: [[0.0; PACKET]; 3],
            box_t_min: [0.0; PACKET],
            shear: [[0.0; PACKET]; 3],
            triangle_t_min: [0.0; PACKET],
            triangle_limit: [0.0; PACKET],
            box_limit: [0.0; PACKET],
            best_t: [0.0; PACKET],
            best_triangle: [0; PACKET],
            best_b1: [0.0; PACKET],
            best_b2: [0.0; PACKET],
            len: 0,
            negative: [false; 3],
            k: [0, 1, 2],
            bundle: None,
        }
    }

    /// Prepares `ray` in lane `i`, and returns its group (direction octant and dominant axis,
    /// `0..24`) with what the group's rays share, or `None` if it cannot join a packet.
    ///
    /// The scalar twin of [`fill`](super::setup::fill), which fills every lane at once.
    #[cfg_attr(not(test), expect(dead_code, reason = "the scalar twin of `fill`"))]
    pub(super) fn set_lane(&mut self, i: usize, ray: &Ray) -> Option<(usize, Shared)> {
        let box_ray = RayBoxTest::new(ray);
        if !can_hit(ray) || !Frustum::can_join(&box_ray) {
            return None;
        }
        let triangle_ray = WatertightRay::with_inverse(ray, box_ray.inv_direction);
        for axis in 0..3 {
            self.origin[axis][i] = box_ray.origin[axis];
            self.inv_direction[axis][i] = box_ray.inv_direction[axis];
        }
        self.box_t_min[i] = box_ray.t_min;
        self.shear[0][i] = triangle_ray.shear_x;
        self.shear[1][i] = triangle_ray.shear_y;
        self.shear[2][i] = triangle_ray.shear_z;
        self.triangle_t_min[i] = triangle_ray.t_min;
        self.triangle_limit[i] = ray.t_max;
        self.box_limit[i] = ray.t_max * FAR_SCALE;
        self.best_t[i] = f32::INFINITY;
        self.best_triangle[i] = u32::MAX;
        let n = box_ray.negative;
        let group = (n[0] as usize | (n[1] as usize) << 1 | (n[2] as usize) << 2) * 3
            + box_ray.dominant_axis;
        Some((group, (n, [triangle_ray.kx, triangle_ray.ky, triangle_ray.kz])))
    }

    /// Copies lane `j` of `from` (before tracing) into lane `i`.
    #[inline(always)]
    pub(super) fn copy_lane(&mut self, i: usize, from: &PacketRays, j: usize) {
        for axis in 0..3 {
            self.origin[axis][i] = from.origin[axis][j];
            self.inv_direction[axis][i] = from.inv_direction[axis][j];
            self.shear[axis][i] = from.shear[axis][j];
        }
        self.box_t_min[i] = from.box_t_min[j];
        self.triangle_t_min[i] = from.triangle_t_min[j];
        self.triangle_limit[i] = from.triangle_limit[j];
        self.box_limit[i] = from.box_limit[j];
        self.best_t[i] = from.best_t[j];
        self.best_triangle[i] = from.best_triangle[j];
    }

    /// Ray `i`'s slab test.
    #[inline(always)]
    pub fn box_ray(&self, i: usize) -> RayBoxTest {
        RayBoxTest {
            origin: Vec3::new(self.origin[0][i], self.origin[1][i], self.origin[2][i]),
            inv_direction: Vec3::new(
                self.inv_direction[0][i],
                self.inv_direction[1][i],
                self.inv_direction[2][i],
            ),
            negative: self.negative,
            t_min: self.box_t_min[i],
            dominant_axis: self.k[2],
        }
    }

    /// Ray `i`'s watertight test.
    #[inline(always)]
    pub fn triangle_ray(&self, i: usize) -> WatertightRay {
        WatertightRay {
            origin: Vec3::new(self.origin[0][i], self.origin[1][i], self.origin[2][i]),
            t_min: self.triangle_t_min[i],
            kx: self.k[0],
            ky: self.k[1],
            kz: self.k[2],
            shear_x: self.shear[0][i],
            shear_y: self.shear[1][i],
            shear_z: self.shear[2][i],
        }
    }

    /// Ray `i`'s closest hit so far.
    #[inline(always)]
    pub(super) fn best(&self, i: usize) -> Option<Hit> {
        (self.best_triangle[i] != u32::MAX).then(|| Hit {
            t: self.best_t[i],
            triangle: self.best_triangle[i],
            b1: self.best_b1[i],
            b2: self.best_b2[i],
        })
    }

    /// Offers ray `i` a hit: kept if nearer than its best, or as near with a lower index.
    #[inline(always)]
    pub fn offer(&mut self, i: usize, t: f32, triangle: u32, b1: f32, b2: f32) {
        if t < self.best_t[i] || (t == self.best_t[i] && triangle < self.best_triangle[i]) {
            self.best_t[i] = t;
            self.best_triangle[i] = triangle;
            self.best_b1[i] = b1;
            self.best_b2[i] = b2;
            self.triangle_limit[i] = next_float_up(t);
            self.box_limit[i] = t * FAR_SCALE;
        }
    }

    /// [`offer`](Self::offer) of hits on `triangle` to the rays `base..` (as many as `V`
    /// has lanes) in `nearer`, whose `t` are below their best: each is kept, as `offer` keeps
    /// it, with the same values, a register at a time.
    ///
    /// # Safety
    /// The CPU must support `V`'s instruction set, and `base` plus `V`'s lanes must not pass
    /// [`PACKET`]; the lanes of `t` in `nearer` are finite.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub unsafe fn take_nearer<V: Lanes>(
        &mut self,
        base: usize,
        nearer: u32,
        triangle: u32,
        [t, b1, b2]: [V; 3],
    ) {
        // SAFETY: the caller's guarantee: every load and store is of `V`'s lanes from `base`.
        // (Written out row by row: a closure would not inherit the target features.)
        unsafe {
            let keep = V::mask_of(nearer);
            let row = self.best_t.as_mut_ptr().add(base);
            V::select(keep, t, V::loadu(row)).store(row);
            let row = self.best_b1.as_mut_ptr().add(base);
            V::select(keep, b1, V::loadu(row)).store(row);
            let row = self.best_b2.as_mut_ptr().add(base);
            V::select(keep, b2, V::loadu(row)).store(row);
            // The index's bits, moved as a float's (blends and moves keep every bit).
            let row = self.best_triangle.as_mut_ptr().add(base).cast::<f32>();
            V::select(keep, V::splat(f32::from_bits(triangle)), V::loadu(row)).store(row);
            let row = self.triangle_limit.as_mut_ptr().add(base);
            V::select(keep, t.next_up_finite(), V::loadu(row)).store(row);
            let row = self.box_limit.as_mut_ptr().add(base);
            V::select(keep, t.mul(V::splat(FAR_SCALE)), V::loadu(row)).store(row);
        }
    }

    /// The greatest box limit of the rays: the packet's. (Rays that are done have their limit
    /// set to `-∞` by [`close`](Self::close).)
    #[inline(always)]
    pub(super) fn limit(&self) -> f32 {
        highest(&self.box_limit[..self.len])
    }

    /// Takes the rays in `done` out of the packet's limit.
    #[inline(always)]
    pub(super) fn close(&mut self, mut done: u64) {
        while done != 0 {
            self.box_limit[done.trailing_zeros() as usize] = f32::NEG_INFINITY;
            done &= done - 1;
        }
    }

    /// The packet's frustum: what [`Frustum::of`] gives for its rays, computed from the lanes
    /// (the rays were checked by [`Frustum::can_join`] and share their octant and dominant axis).
    #[inline(always)]
    pub(super) fn frustum(&self) -> Frustum {
        let n = self.len;
        let mut pad_axes = [false; 3];
        pad_axes[self.k[2]] = true;
        // Written out axis by axis: `[0, 1, 2].map(..)` is not inlined into the instruction
        // set's entry point (its closure is compiled without the entry's target features).
        let (o, inv) = (&self.origin, &self.inv_direction);
        Frustum {
            origin_lo: Vec3::new(lowest(&o[0][..n]), lowest(&o[1][..n]), lowest(&o[2][..n])),
            origin_hi: Vec3::new(highest(&o[0][..n]), highest(&o[1][..n]), highest(&o[2][..n])),
            inv_lo: Vec3::new(lowest(&inv[0][..n]), lowest(&inv[1][..n]), lowest(&inv[2][..n])),
            inv_hi: Vec3::new(highest(&inv[0][..n]), highest(&inv[1][..n]), highest(&inv[2][..n])),
            negative: self.negative,
            t_min: lowest(&self.box_t_min[..n]),
            pad_axes,
        }
    }

    /// The lines of the packet, if they meet in one point: the shared origin, or the rays'
    /// common point at `t = 1` (shadow rays toward a point light).
    #[inline(always)]
    pub(super) fn bundle(&self, frustum: &Frustum) -> Option<LineBundle> {
        if let Some(bundle) = LineBundle::of(frustum) {
            return Some(bundle);
        }
        let n = self.len;
        let mut end = [[0.0f32; PACKET]; 3];
        for (axis, end) in end.iter_mut().enumerate() {
            let lanes = self.origin[axis].iter().zip(&self.inv_direction[axis]);
            for (end, (&o, &inv)) in end.iter_mut().zip(lanes) {
                *end = o + 1.0 / inv;
            }
        }
        let lo = Vec3::new(lowest(&end[0][..n]), lowest(&end[1][..n]), lowest(&end[2][..n]));
        let hi = Vec3::new(highest(&end[0][..n]), highest(&end[1][..n]), highest(&end[2][..n]));
        LineBundle::through_ends(frustum, lo, hi)
    }

    /// The mask of all rays of the packet.
    #[inline(always)]
    pub(super) fn all(&self) -> u64 {
        if self.len == PACKET { u64::MAX } else { (1 << self.len) - 1 }
    }
}

/// The least of finite values, eight lanes at a time (a form the compiler vectorizes).
#[inline(always)]
fn lowest(values: &[f32]) -> f32 {
    reduce(values, f32::INFINITY, |a, b| if b < a { b } else { a })
}

/// The greatest of finite values.
#[inline(always)]
fn highest(values: &[f32]) -> f32 {
    reduce(values, f32::NEG_INFINITY, |a, b| if b > a { b } else { a })
}

/// Folds `values` by `pick` in eight columns, then the columns and the rest.
#[inline(always)]
fn reduce(values: &[f32], start: f32, pick: impl Fn(f32, f32) -> f32 + Copy) -> f32 {
    let mut columns = [start; 8];
    let chunks = values.chunks_exact(8);
    let rest = chunks.remainder();
    for chunk in chunks {
        for (c, &v) in columns.iter_mut().zip(chunk) {
            *c = pick(*c, v);
        }
    }
    columns.into_iter().chain(rest.iter().copied()).fold(start, pick)
}
