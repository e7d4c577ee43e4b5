//! Triangles and the watertight ray/triangle test.
//!
//! The test is Woop, Benthin & Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013,
//! with the conservative `t > 0` bound of PBR 4th ed. §6.8.4. It transforms the triangle into a
//! space where the ray is the +z axis from the origin, then evaluates three 2D edge functions.
//! Because an edge shared by two triangles gives the same edge function (with opposite sign) to
//! both, and because edges are *inclusive* (a value of exactly 0 counts as inside), no ray can slip
//! between two triangles that share an edge or a vertex: no black seams along a quad's diagonal.
//!
//! The edge functions are plain `a·b − c·d` on purpose: a fused multiply-add would round the two
//! orderings of a shared edge differently and reopen the crack.

use glam::Vec3;

use crate::float::gamma;
use crate::ray::{Ray, SurfacePoint};

/// A triangle of the lab's scene: three vertices, a normal and a diffuse colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// First vertex.
    pub v0: Vec3,
    /// Second vertex.
    pub v1: Vec3,
    /// Third vertex.
    pub v2: Vec3,
    /// Unit normal, `normalize((v2 − v0) × (v1 − v0))` as in the lab.
    pub normal: Vec3,
    /// Diffuse reflectance ρ per channel (the lab's `color`).
    pub albedo: Vec3,
}

impl Triangle {
    /// A triangle with the lab's normal `normalize((v2 − v0) × (v1 − v0))`.
    ///
    /// A zero-area triangle gets a zero normal; [`WatertightRay::intersect`] never hits it.
    pub fn new(v0: Vec3, v1: Vec3, v2: Vec3, albedo: Vec3) -> Self {
        let normal = (v2 - v0).cross(v1 - v0).normalize_or_zero();
        Triangle { v0, v1, v2, normal, albedo }
    }

    /// The three vertices.
    #[inline]
    pub fn corners(&self) -> [Vec3; 3] {
        [self.v0, self.v1, self.v2]
    }

    /// The point with barycentric coordinates `(b0, b1, b2)` and its rounding-error bound
    /// (PBR 4th ed. §6.8.5: interpolating the vertices errs by at most `γ₇ Σ|bᵢ·pᵢ|`).
    pub fn surface_point(&self, b0: f32, b1: f32, b2: f32) -> SurfacePoint {
        let (a, b, c) = (b0 * self.v0, b1 * self.v1, b2 * self.v2);
        SurfacePoint {
            p: a + b + c,
            error: gamma(7) * (a.abs() + b.abs() + c.abs()),
            normal: self.normal,
        }
    }
}

/// Where a ray meets a triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weight of `v0`.
    pub b0: f32,
    /// Barycentric weight of `v1`.
    pub b1: f32,
    /// Barycentric weight of `v2`.
    pub b2: f32,
}

/// Triangles per [`TriangleBlock`]: the width of the batched pre-test.
pub const LANES: usize = 8;

/// Up to `N` triangles stored coordinate by coordinate, so that one ray can be tested against all
/// of them with straight-line, vectorizable code ([`WatertightRay::block_candidates`]).
/// Unused lanes hold NaN vertices, which are never hit.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct TriangleBlock<const N: usize = LANES> {
    /// `vertices[j][axis][lane]`: coordinate `axis` of vertex `j` of the triangle in `lane`.
    pub(crate) vertices: [[[f32; N]; 3]; 3],
}

impl<const N: usize> TriangleBlock<N> {
    /// A block with every lane unused.
    pub const EMPTY: Self = TriangleBlock { vertices: [[[f32::NAN; N]; 3]; 3] };

    /// Packs triangles, in order, into blocks; the last block is padded.
    pub fn pack(triangles: impl IntoIterator<Item = [Vec3; 3]>) -> Vec<Self> {
        let mut blocks = Vec::new();
        for (i, triangle) in triangles.into_iter().enumerate() {
            let lane = i % N;
            if lane == 0 {
                blocks.push(Self::EMPTY);
            }
            blocks.last_mut().expect("pushed above").set(lane, triangle);
        }
        blocks
    }

    /// Puts a triangle in `lane`.
    #[inline]
    pub fn set(&mut self, lane: usize, triangle: [Vec3; 3]) {
        for (j, vertex) in triangle.iter().enumerate() {
            for axis in 0..3 {
                self.vertices[j][axis][lane] = vertex[axis];
            }
        }
    }

    /// The vertices of the triangle in `lane`.
    #[inline]
    pub fn triangle(&self, lane: usize) -> [Vec3; 3] {
        let vertex = |j: usize| {
            let v = &self.vertices[j];
            Vec3::new(v[0][lane], v[1][lane], v[2][lane])
        };
        [vertex(0), vertex(1), vertex(2)]
    }
}

/// Widens `t_max · det` by more than the relative rounding of that product and of
/// `t = t_scaled · (1/det)` (a few units in the last place).
pub(crate) const T_LIMIT_SLACK: f32 = 1.0 + 8.0 * f32::EPSILON;

/// `px·qy − py·qx` in double precision, where the products are exact.
#[inline(never)]
#[cold]
fn edge_function_f64(px: f32, py: f32, qx: f32, qy: f32) -> f32 {
    (px as f64 * qy as f64 - py as f64 * qx as f64) as f32
}

/// Whether a triangle has exactly zero area (its edge cross product is the zero vector), so that
/// no ray ever hits it. Compares the cross product itself rather than its squared length, which
/// underflows for tiny triangles.
#[inline]
pub fn is_degenerate([v0, v1, v2]: [Vec3; 3]) -> bool {
    (v2 - v0).cross(v1 - v0) == Vec3::ZERO
}

/// The axis along which `d` is longest, which the watertight test maps to z; ties go to the
/// lowest axis, so any ray gets one answer.
#[inline]
pub fn dominant_axis(d: Vec3) -> usize {
    let abs = d.abs();
    // Without branches (a ray's axis is as good as random: a branch on it mispredicts often):
    // 0 where x is the longest, else 1 where y is at least z, else 2.
    let x_longest = (abs.x >= abs.y) & (abs.x >= abs.z);
    let y_over_z = abs.y >= abs.z;
    usize::from(!x_longest) * (2 - usize::from(y_over_z))
}

/// Coordinate `k` (0, 1 or 2; a larger `k` reads `z`) of `v`, by an indexed load rather than
/// the branches of `Vec3`'s `Index`: the per-ray setup reads the coordinates of an axis picked
/// by the ray's direction, which branches would mispredict.
#[inline(always)]
pub(crate) fn coordinate(v: Vec3, k: usize) -> f32 {
    [v.x, v.y, v.z][k.min(2)]
}

/// The per-ray part of the watertight test: which axis the ray is mostly along, and the shear that
/// maps the ray onto +z. Computed once per ray and reused for every triangle.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    pub(crate) origin: Vec3,
    pub(crate) t_min: f32,
    pub(crate) kx: usize,
    pub(crate) ky: usize,
    pub(crate) kz: usize,
    pub(crate) shear_x: f32,
    pub(crate) shear_y: f32,
    pub(crate) shear_z: f32,
}

impl WatertightRay {
    /// Prepares `ray` for triangle tests.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let kz = dominant_axis(ray.direction);
        Self::with_shear_z(ray, 1.0 / ray.direction[kz])
    }

    /// [`new`](Self::new) for a ray whose `1/d` is already computed (`inv_direction` must be
    /// exactly `1.0 / ray.direction`, per axis): no division.
    #[inline]
    pub(crate) fn with_inverse(ray: &Ray, inv_direction: Vec3) -> Self {
        let kz = dominant_axis(ray.direction);
        let shear_z = coordinate(inv_direction, kz);
        // The answers must be exactly those of `new`, which divides.
        debug_assert!(
            shear_z.to_bits() == (1.0 / ray.direction[kz]).to_bits() || shear_z.is_nan(),
            "inv_direction is not 1/d"
        );
        Self::with_shear_z(ray, shear_z)
    }

    /// The test's setup given `shear_z = 1/d[kz]`.
    #[inline(always)]
    fn with_shear_z(ray: &Ray, shear_z: f32) -> Self {
        let d = ray.direction;
        let kz = dominant_axis(d);
        let (next, after) = ((kz + 1) % 3, (kz + 2) % 3);
        // Swapping x and y keeps the triangles' winding when the ray points along −z.
        let (kx, ky) = if coordinate(d, kz) < 0.0 { (after, next) } else { (next, after) };
        WatertightRay {
            origin: ray.origin,
            // A NaN range start admits no hit.
            t_min: if ray.t_min.is_nan() { f32::INFINITY } else { ray.t_min },
            kx,
            ky,
            kz,
            shear_x: coordinate(d, kx) * shear_z,
            shear_y: coordinate(d, ky) * shear_z,
            shear_z,
        }
    }

    /// [`intersect`](Self::intersect) out of line, for the rare triangles a vector test leaves
    /// undecided (see [`any_lane_hits`](Self::any_lane_hits)). The ray is taken by value, so
    /// that a traversal need not keep it in memory for this call: the copy is made only here.
    #[cold]
    #[inline(never)]
    pub(crate) fn intersect_rarely(
        self,
        v0: Vec3,
        v1: Vec3,
        v2: Vec3,
        t_max: f32,
    ) -> Option<TriangleHit> {
        self.intersect(v0, v1, v2, t_max)
    }

    /// Intersects the ray with triangle `(v0, v1, v2)`, counting hits on edges and vertices,
    /// for `0 < t < t_max` and `t >= ray.t_min`. Both sides of the triangle are hit.
    #[inline(always)]
    pub fn intersect(&self, v0: Vec3, v1: Vec3, v2: Vec3, t_max: f32) -> Option<TriangleHit> {
        self.intersect_with::<false>(v0, v1, v2, t_max)
    }

    /// [`intersect`](Self::intersect) with half-open edges: a ray through an edge or a vertex
    /// that triangles share crosses exactly one of them where the surface goes on across it
    /// (and none or two where it folds back), so counting these hits along a ray counts how
    /// often it crosses a closed surface, whose parity says inside or outside.
    ///
    /// Where an edge function is exactly zero (the ray meets the edge's line: the test decides
    /// that exactly), the edge counts as inside only if it is the triangle's "owned" edge: its
    /// direction in the ray's frame, turned by the sign of the triangle's winding as seen from
    /// the ray, points to `+y` (or along `+x` if level). Two triangles that share an edge with
    /// a consistent winding run along it in opposite directions, so one owns it and the other
    /// does not; the differences are exactly opposite in floating point too. At a shared vertex
    /// both of a triangle's edges through it must be owned: of a fan around the vertex, exactly
    /// one triangle is (the half-open rule of rasterisers, e.g. Direct3D's top-left rule).
    #[inline(always)]
    pub fn crossing(&self, v0: Vec3, v1: Vec3, v2: Vec3, t_max: f32) -> Option<TriangleHit> {
        self.intersect_with::<true>(v0, v1, v2, t_max)
    }

    /// [`intersect`](Self::intersect), or [`crossing`](Self::crossing) if `HALF_OPEN`.
    #[inline(always)]
    fn intersect_with<const HALF_OPEN: bool>(
        &self,
        v0: Vec3,
        v1: Vec3,
        v2: Vec3,
        t_max: f32,
    ) -> Option<TriangleHit> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        // Translate to the ray's origin, then shear so the ray runs along +z.
        let a = v0 - self.origin;
        let b = v1 - self.origin;
        let c = v2 - self.origin;
        let ax = a[kx] - self.shear_x * a[kz];
        let ay = a[ky] - self.shear_y * a[kz];
        let bx = b[kx] - self.shear_x * b[kz];
        let by = b[ky] - self.shear_y * b[kz];
        let cx = c[kx] - self.shear_x * c[kz];
        let cy = c[ky] - self.shear_y * c[kz];

        // Edge functions: twice the signed areas of the sub-triangles seen from the ray.
        let mut e0 = bx * cy - by * cx;
        let mut e1 = cx * ay - cy * ax;
        let mut e2 = ax * by - ay * bx;
        // A zero in single precision may be a rounding artefact: decide it exactly. Products of
        // two f32 are exact in f64, so the sign below is the true sign. Only the edges that are
        // zero are redone (Woop et al. redo all three): then every edge function is the same
        // function of its two vertices in both triangles that share it, whatever their other
        // edges, so the two can never disagree about which side of the edge the ray passes.
        if e0 == 0.0 {
            e0 = edge_function_f64(bx, by, cx, cy);
        }
        if e1 == 0.0 {
            e1 = edge_function_f64(cx, cy, ax, ay);
        }
        if e2 == 0.0 {
            e2 = edge_function_f64(ax, ay, bx, by);
        }
        // Inclusive edges: only a strict sign disagreement means outside.
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        // A zero-area triangle is never hit (as in PBR 4th ed.; comparing the cross product itself
        // rather than its squared length, which underflows for tiny triangles).
        if is_degenerate([v0, v1, v2]) {
            return None;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 || det.is_nan() {
            return None; // Edge-on or degenerate triangle, or a NaN ray.
        }
        if HALF_OPEN && (e0 == 0.0 || e1 == 0.0 || e2 == 0.0) {
            // The edge from `p` to `q` (e0: b to c, e1: c to a, e2: a to b), its direction
            // turned by the winding's sign.
            let owned = |e: f32, (px, py): (f32, f32), (qx, qy): (f32, f32)| {
                let (dx, dy) = if det > 0.0 { (qx - px, qy - py) } else { (px - qx, py - qy) };
                e != 0.0 || dy > 0.0 || (dy == 0.0 && dx > 0.0)
            };
            let (a2, b2, c2) = ((ax, ay), (bx, by), (cx, cy));
            if !(owned(e0, b2, c2) && owned(e1, c2, a2) && owned(e2, a2, b2)) {
                return None;
            }
        }

        // Scaled distance along the ray, compared against the range without dividing. The
        // comparison with `t_max` is widened past the rounding of `t_max · det` and of the division
        // below, so that it only ever rejects hits that the exact `t >= t_max` test further down
        // would reject too: then whether a hit counts depends on its own `t` alone, never on which
        // triangle tightened `t_max` first (so every accelerator and every order agree).
        let az = self.shear_z * a[kz];
        let bz = self.shear_z * b[kz];
        let cz = self.shear_z * c[kz];
        let t_scaled = e0 * az + e1 * bz + e2 * cz;
        let t_limit = t_max * det * T_LIMIT_SLACK;
        if det < 0.0 && (t_scaled >= 0.0 || t_scaled <= t_limit) {
            return None;
        }
        if det > 0.0 && (t_scaled <= 0.0 || t_scaled >= t_limit) {
            return None;
        }

        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        // Also rejects a NaN `t` or a NaN `t_max`.
        if t.is_nan() || t_max.is_nan() || t >= t_max {
            return None; // `t_max · det` may have rounded; decide on t itself.
        }

        // A caller that sets `t_min > 0` brings its own epsilon (as Embree's `tnear`): hits
        // from `t_min` on count. Otherwise reject hits whose t is not conservatively greater than
        // zero (PBR 4th ed. §6.8.4): together with the offset of spawned rays this rules out
        // self-intersection. The bound is loose for small triangles seen at grazing angles, so it
        // is not applied on top of an explicit `t_min` (where it would reject real hits that are
        // well past the caller's epsilon).
        if self.t_min > 0.0 {
            if t < self.t_min {
                return None;
            }
        } else if t
            <= self.conservative_delta_t(
                [a, b, c],
                [ax, bx, cx],
                [ay, by, cy],
                [e0, e1, e2],
                inv_det,
            )
        {
            return None;
        }

        Some(TriangleHit { t, b0: e0 * inv_det, b1: e1 * inv_det, b2: e2 * inv_det })
    }

    /// PBR 4th ed. §6.8.4's bound on the rounding error of `t`, for vertices relative to the
    /// origin `v`, their sheared coordinates `x`, `y`, the edge functions `e` and `1/det`.
    #[inline]
    fn conservative_delta_t(
        &self,
        v: [Vec3; 3],
        x: [f32; 3],
        y: [f32; 3],
        e: [f32; 3],
        inv_det: f32,
    ) -> f32 {
        let kz = self.kz;
        let max3 = |p: [f32; 3]| p[0].abs().max(p[1].abs()).max(p[2].abs());
        let max_zt =
            max3([self.shear_z * v[0][kz], self.shear_z * v[1][kz], self.shear_z * v[2][kz]]);
        let delta_z = gamma(3) * max_zt;
        let max_xt = max3(x);
        let max_yt = max3(y);
        // The error of `a[kx] − shear_x·a[kz]` is relative to both terms. PBR bounds the second
        // by the sheared z, which is too loose for short directions (it rejects real hits, e.g.
        // of a 10⁻⁶-sized scene's rays) and too tight for long ones; bounding it directly keeps
        // the bound conservative and tight for directions of any length.
        let max_unsheared_z = max3([v[0][kz], v[1][kz], v[2][kz]]);
        let delta_x = gamma(5) * (max_xt + self.shear_x.abs() * max_unsheared_z);
        let delta_y = gamma(5) * (max_yt + self.shear_y.abs() * max_unsheared_z);
        let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let max_e = max3(e);
        3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs()
    }
}

impl WatertightRay {
    /// A bit mask of the triangles in `block` that [`intersect`](Self::intersect) may hit for
    /// `t < t_max`: the same arithmetic, lane by lane, without the final conservative `t` bound.
    ///
    /// It never leaves out a triangle that `intersect` hits, because every value it compares is
    /// computed by the same operations in the same order; lanes whose edge functions round to
    /// exactly zero are passed on for `intersect` to decide in double precision. Written as
    /// straight-line code over fixed-size arrays so that the compiler vectorizes it; `intersect`
    /// is its scalar twin, and the tests check that the two agree.
    #[inline]
    pub fn block_candidates<const N: usize>(&self, block: &TriangleBlock<N>, t_max: f32) -> u32 {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let (ox, oy, oz) = (self.origin[kx], self.origin[ky], self.origin[kz]);
        let (sx, sy, sz) = (self.shear_x, self.shear_y, self.shear_z);
        // Pick the permuted axes by reference once per block, so that the lane loop indexes only
        // by lane.
        let [p0, p1, p2] = &block.vertices;
        let (p0x, p0y, p0z) = (&p0[kx], &p0[ky], &p0[kz]);
        let (p1x, p1y, p1z) = (&p1[kx], &p1[ky], &p1[kz]);
        let (p2x, p2y, p2z) = (&p2[kx], &p2[ky], &p2[kz]);
        let mut pass = [false; N];
        for lane in 0..N {
            let (a_kx, a_ky, a_kz) = (p0x[lane] - ox, p0y[lane] - oy, p0z[lane] - oz);
            let (b_kx, b_ky, b_kz) = (p1x[lane] - ox, p1y[lane] - oy, p1z[lane] - oz);
            let (c_kx, c_ky, c_kz) = (p2x[lane] - ox, p2y[lane] - oy, p2z[lane] - oz);
            let (ax, ay) = (a_kx - sx * a_kz, a_ky - sy * a_kz);
            let (bx, by) = (b_kx - sx * b_kz, b_ky - sy * b_kz);
            let (cx, cy) = (c_kx - sx * c_kz, c_ky - sy * c_kz);
            let e0 = bx * cy - by * cx;
            let e1 = cx * ay - cy * ax;
            let e2 = ax * by - ay * bx;
            let any_zero = (e0 == 0.0) | (e1 == 0.0) | (e2 == 0.0);
            let inside = ((e0 >= 0.0) & (e1 >= 0.0) & (e2 >= 0.0))
                | ((e0 <= 0.0) & (e1 <= 0.0) & (e2 <= 0.0));
            let det = e0 + e1 + e2;
            let t_scaled = e0 * (sz * a_kz) + e1 * (sz * b_kz) + e2 * (sz * c_kz);
            let t_limit = t_max * det * T_LIMIT_SLACK;
            let in_range = ((det > 0.0) & (t_scaled > 0.0) & (t_scaled < t_limit))
                | ((det < 0.0) & (t_scaled < 0.0) & (t_scaled > t_limit));
            pass[lane] = any_zero | (inside & in_range);
        }
        pass.iter().enumerate().fold(0, |mask, (lane, &p)| mask | (p as u32) << lane)
    }

    /// Whether [`intersect`](Self::intersect) hits any of the triangles in lanes `first + k` of
    /// `block` for the bits `k` set in `lanes` (the lanes a vector test left to the
    /// double-precision path).
    #[inline(always)]
    pub(crate) fn any_lane_hits<const N: usize>(
        &self,
        block: &TriangleBlock<N>,
        first: usize,
        lanes: u32,
        t_max: f32,
    ) -> bool {
        lanes != 0 && self.any_lane_hits_rarely(block, first, lanes, t_max)
    }

    /// [`any_lane_hits`](Self::any_lane_hits) for some lanes: rare (an edge function rounded to
    /// zero), so out of the traversal loops, which then keep their registers (a call in a loop
    /// makes the compiler keep every vector value on the stack).
    #[cold]
    #[inline(never)]
    fn any_lane_hits_rarely<const N: usize>(
        &self,
        block: &TriangleBlock<N>,
        first: usize,
        mut lanes: u32,
        t_max: f32,
    ) -> bool {
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let [v0, v1, v2] = block.triangle(first + lane);
            if self.intersect(v0, v1, v2, t_max).is_some() {
                return true;
            }
        }
        false
    }
}

/// The unit normal `(v1 − v0) × (v2 − v0)` of the counter-clockwise side, zero for zero area.
#[inline]
pub fn geometric_normal([v0, v1, v2]: [Vec3; 3]) -> Vec3 {
    (v1 - v0).cross(v2 - v0).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(origin: Vec3, direction: Vec3, tri: [Vec3; 3]) -> Option<TriangleHit> {
        WatertightRay::new(&Ray::new(origin, direction)).intersect(
            tri[0],
            tri[1],
            tri[2],
            f32::INFINITY,
        )
    }

    const UNIT: [Vec3; 3] = [Vec3::ZERO, Vec3::X, Vec3::Y];

    /// The branch-free axis and coordinate picks give what the plain branches and `Vec3`'s
    /// index give: ties to the lowest axis, NaN and zero components, every sign.
    #[test]
    fn axis_picks_are_the_branching_ones() {
        let reference = |d: Vec3| {
            let abs = d.abs();
            if abs.x >= abs.y && abs.x >= abs.z {
                0
            } else if abs.y >= abs.z {
                1
            } else {
                2
            }
        };
        let values = [0.0f32, -0.0, 1.0, -1.0, 2.0, -3.0, f32::NAN, f32::INFINITY, 1e-40];
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    let d = Vec3::new(x, y, z);
                    assert_eq!(dominant_axis(d), reference(d), "{d}");
                    for k in 0..3 {
                        assert_eq!(coordinate(d, k).to_bits(), d[k].to_bits(), "{d}[{k}]");
                    }
                }
            }
        }
    }

    #[test]
    fn hits_the_interior_with_correct_t_and_barycentrics() {
        let h = hit(Vec3::new(0.25, 0.5, -2.0), Vec3::Z, UNIT).unwrap();
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!((h.b1 - 0.25).abs() < 1e-6 && (h.b2 - 0.5).abs() < 1e-6);
        assert!((h.b0 + h.b1 + h.b2 - 1.0).abs() < 1e-6);
    }

    #[test]
    fn both_sides_are_hit() {
        assert!(hit(Vec3::new(0.2, 0.2, -1.0), Vec3::Z, UNIT).is_some());
        assert!(hit(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, UNIT).is_some());
    }

    #[test]
    fn misses_outside_and_behind() {
        assert!(hit(Vec3::new(0.6, 0.6, -1.0), Vec3::Z, UNIT).is_none());
        assert!(hit(Vec3::new(0.2, 0.2, 1.0), Vec3::Z, UNIT).is_none());
    }

    #[test]
    fn edges_and_vertices_are_inclusive() {
        for target in [Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.5, 0.0, 0.0), Vec3::ZERO, Vec3::X] {
            // Dyadic coordinates: the ray passes exactly through the edge or vertex. (Rays that
            // only nearly do are the business of the crack tests, with two triangles.)
            let origin = Vec3::new(0.125, 0.375, -1.0);
            assert!(hit(origin, target - origin, UNIT).is_some(), "missed {target}");
        }
    }

    #[test]
    fn t_max_is_exclusive() {
        let origin = Vec3::new(0.2, 0.2, -1.0);
        let tri = WatertightRay::new(&Ray::new(origin, Vec3::Z));
        assert!(tri.intersect(UNIT[0], UNIT[1], UNIT[2], 1.0).is_none());
        assert!(tri.intersect(UNIT[0], UNIT[1], UNIT[2], 1.0001).is_some());
    }

    #[test]
    fn negative_zero_direction_components_hit() {
        for direction in
            [Vec3::new(-0.0, -0.0, 1.0), Vec3::new(0.0, -0.0, 1.0), Vec3::new(-0.0, 0.0, -1.0)]
        {
            let origin = Vec3::new(0.2, 0.2, -direction.z);
            assert!(hit(origin, direction, UNIT).is_some(), "{direction:?}");
        }
    }

    #[test]
    fn degenerate_triangles_are_never_hit() {
        let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let point = [Vec3::ONE; 3];
        for tri in [line, point] {
            let origin = Vec3::new(1.0, 0.0, -1.0);
            assert!(hit(origin, Vec3::Z, tri).is_none());
            assert!(hit(Vec3::ONE - Vec3::Z, Vec3::Z, tri).is_none());
        }
    }

    #[test]
    fn zero_direction_and_nan_never_hit_or_panic() {
        let origin = Vec3::new(0.2, 0.2, -1.0);
        assert!(hit(origin, Vec3::ZERO, UNIT).is_none());
        assert!(hit(origin, Vec3::new(f32::NAN, 0.0, 1.0), UNIT).is_none());
        assert!(hit(Vec3::NAN, Vec3::Z, UNIT).is_none());
    }

    #[test]
    fn the_lab_normal_follows_the_lab_winding() {
        let tri = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE);
        // (v2 − v0) × (v1 − v0) = Y × X = −Z.
        assert_eq!(tri.normal, -Vec3::Z);
    }

    #[test]
    fn surface_point_error_bounds_the_true_point() {
        let tri = Triangle::new(
            Vec3::new(1000.1, 0.3, 7.0),
            Vec3::new(1001.7, 2.9, 7.5),
            Vec3::new(999.2, 1.1, 8.25),
            Vec3::ONE,
        );
        let (b0, b1, b2) = (0.2f32, 0.3f32, 0.5f32);
        let sp = tri.surface_point(b0, b1, b2);
        let exact = [tri.v0, tri.v1, tri.v2]
            .iter()
            .zip([b0, b1, b2])
            .map(|(v, b)| v.as_dvec3() * b as f64)
            .fold(glam::DVec3::ZERO, |acc, v| acc + v);
        let diff = (sp.p.as_dvec3() - exact).abs();
        assert!(diff.cmple(sp.error.as_dvec3()).all(), "{diff} > {}", sp.error);
    }
}
