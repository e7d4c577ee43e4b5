//! Culling triangles for a packet of rays from one point: the lines of a camera tile.
//!
//! A packet's frustum ([`Frustum`]) prunes boxes, but a leaf whose box it enters is then tested
//! triangle by triangle against every ray, and in a small scene of large triangles (the Cornell
//! box's walls) most of those triangles lie nowhere near the tile. When the rays share their
//! origin `o` (camera rays), a triangle `abc` can be culled for the whole packet in a few
//! operations:
//!
//! - Each edge spans a plane through `o`, with normal `n = (p − o) × (q − o)` for the edge `pq`.
//!   The line `o + t·d` passes through the triangle (in front of `o` or behind it) only if the
//!   three edge functions `nᵢ·d` have one sign (zeros count as either): the watertight test
//!   decides exactly this, up to rounding, before its range test on `t`.
//! - Over the packet's directions, bounded by a box `[d_lo, d_hi]`, each `nᵢ·d` lies in an
//!   interval (interval arithmetic). If one edge function is below zero for every direction and
//!   another above zero for every direction, no ray of the packet can hit the triangle.
//!
//! The same holds for rays from many origins whose lines meet in one point: shadow rays toward a
//! point light all pass through the light ([`LineBundle::through_ends`]), with a margin for how
//! far from it each line may pass.
//!
//! Both tests are made with a margin far above any rounding: `10⁻⁴·‖p − o‖₁·‖q − o‖₁·max|d|`
//! for the edge `pq` (distances from the rays' origins, which the watertight test computes
//! from, bounded through the apex), where rounding in the edge normals, in the direction bound (taken from the
//! rays' `1/d`) and in the watertight test's own edge functions errs by some `10⁻⁷` of the same
//! products. So a culled triangle is one no ray of the packet would have hit, and the answers
//! stay exactly those of single rays (the tests check every packet against them).

use glam::Vec3;

use crate::bvh::bounds::{Bounds, Frustum};
use crate::bvh::leaf::{RECORD_TRIANGLES, RECORD_VERTICES, Record};

/// The relative margin of the cull (see the module documentation).
const MARGIN: f32 = 1e-4;

/// A leaf's size beside a packet's footprint ([`LineBundle::size_of`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum LeafSize {
    /// At most twice the footprint: in a fine mesh the lines cross nearly every triangle of a
    /// leaf they reach, so the cull would only cost.
    Small,
    /// Over twice the footprint (a scene of large triangles): the triangles no line crosses
    /// are culled, for the rays that enter the box.
    Large,
    /// Over sixteen times the footprint (the Cornell box's walls and boxes before a tile):
    /// culled, and the rest tested against every open ray without the per-ray box test, which
    /// would keep most of them.
    Covering,
}

/// The lines of a packet's rays: all through one point (within `spread`), a box of directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LineBundle {
    apex: Vec3,
    dir_lo: Vec3,
    dir_hi: Vec3,
    /// `MARGIN` times the largest direction component's magnitude `D`.
    margin_scale: f32,
    /// `δ·D`, `δ` a bound on each line's distance from `apex` (0 for a shared origin).
    apex_scale: f32,
    /// The rays' origins' greatest distance from `apex` (`‖o − apex‖₁`; 0 for a shared origin).
    origin_reach: f32,
    /// The directions' spread: the direction box's largest edge over `D`.
    spread: f32,
}

impl LineBundle {
    /// The bundle of a packet whose frustum is `frustum`, if its rays share their origin (bit
    /// for bit). The frustum's `1/d` are finite, non-zero and of one sign per axis.
    #[inline(always)]
    pub fn of(frustum: &Frustum) -> Option<LineBundle> {
        if frustum.origin_lo != frustum.origin_hi {
            return None;
        }
        Self::with_apex(frustum, frustum.origin_lo, 0.0)
    }

    /// The bundle of a packet whose rays' points at `t = 1`, `o + d` (the light, for shadow
    /// rays toward a point light), all lie in the box `[end_lo, end_hi]` of edge at most
    /// `10⁻³·max|d|`; `None` if they spread further.
    ///
    /// Each line then passes within `δ = 2·(s + 10⁻⁶·(max|end| + max|d|))` of the box's low
    /// corner, `s` the box's largest edge: `√3·s` from the box, and the ends, computed from
    /// `o` and the rounded `1/(1/d)`, are within a few units of rounding (well under `10⁻⁶`)
    /// of the exact ones. Moving a line's point by `δ` changes the edge function of edge `pq`
    /// by at most `δ·(‖p − apex‖ + ‖q − apex‖)·|d|`, which the cull's margin adds.
    #[inline(always)]
    pub fn through_ends(frustum: &Frustum, end_lo: Vec3, end_hi: Vec3) -> Option<LineBundle> {
        let spread = (end_hi - end_lo).max_element();
        let largest = Self::directions(frustum).1;
        // Also `None` for a NaN spread.
        if spread.partial_cmp(&(1e-3 * largest)).is_none_or(|o| o.is_gt()) {
            return None;
        }
        let magnitude = end_lo.abs().max(end_hi.abs()).max_element();
        let delta = 2.0 * (spread + 1e-6 * (magnitude + largest));
        Self::with_apex(frustum, end_lo, delta)
    }

    /// The box of directions, from the frustum's `1/d`, and its largest component's magnitude.
    #[inline(always)]
    fn directions(frustum: &Frustum) -> ((Vec3, Vec3), f32) {
        // `1/(1/d)` is `d` within two roundings; the margin covers far more.
        let (a, b) = (frustum.inv_lo.recip(), frustum.inv_hi.recip());
        let (lo, hi) = (a.min(b), a.max(b));
        ((lo, hi), lo.abs().max(hi.abs()).max_element())
    }

    #[inline(always)]
    fn with_apex(frustum: &Frustum, apex: Vec3, delta: f32) -> Option<LineBundle> {
        let ((dir_lo, dir_hi), largest) = Self::directions(frustum);
        let reach = (frustum.origin_lo - apex).abs().max((frustum.origin_hi - apex).abs());
        let bundle = LineBundle {
            apex,
            dir_lo,
            dir_hi,
            margin_scale: MARGIN * largest,
            apex_scale: delta * largest,
            // Rounded up a little: a bound, not an estimate.
            origin_reach: reach.element_sum() * (1.0 + 1e-6),
            spread: (dir_hi - dir_lo).max_element() / largest,
        };
        let finite = apex.is_finite() && dir_lo.is_finite() && dir_hi.is_finite();
        let finite = finite && bundle.origin_reach.is_finite();
        (finite && bundle.margin_scale.is_finite() && bundle.apex_scale.is_finite())
            .then_some(bundle)
    }

    /// How large a leaf's box is beside the packet's footprint at the box's distance (its
    /// largest edge against the spread of the directions times the distance to the apex),
    /// which decides what the packet leaf kernel does with it. A size heuristic for speed: it
    /// never changes an answer (`packet/lanes.rs` says why). Compared squared, without a
    /// square root, since it is asked for every leaf a packet with a bundle reaches.
    #[inline(always)]
    pub fn size_of(&self, bounds: &Bounds) -> LeafSize {
        let extent = (bounds.max - bounds.min).max_element();
        let footprint =
            (bounds.centroid() - self.apex).length_squared() * self.spread * self.spread;
        let extent = extent * extent;
        if extent > 256.0 * footprint {
            LeafSize::Covering
        } else if extent > 4.0 * footprint {
            LeafSize::Large
        } else {
            LeafSize::Small
        }
    }

    /// The margin of the edge `pq` whose corners are `lp = ‖p − apex‖₁` and `lq` from the apex.
    ///
    /// The watertight test computes each edge function from the ray's own origin, so its
    /// rounding grows with the corners' distances from the origin, `‖p − o‖ ≤ lp + origin_reach`,
    /// not from the apex: for shadow rays toward a light, a triangle near the light has small
    /// edge functions about the apex that the test, from the far origin, rounds coarsely.
    #[inline(always)]
    fn margin(&self, lp: f32, lq: f32) -> f32 {
        let reach = self.origin_reach;
        self.margin_scale * (lp + reach) * (lq + reach) + self.apex_scale * (lp + lq)
    }

    /// [`may_cross`](Self::may_cross) for the triangles of a leaf record at once: bit `t` set
    /// where triangle `t` is kept. Each vertex is taken relative to the apex once, then the
    /// edges are tested lane by lane in arrays (the compiler vectorizes it), by the same
    /// operations in the same order as `may_cross`, so with the same answers (the tests compare
    /// them).
    #[inline(always)]
    pub fn may_cross_record(&self, record: &Record) -> u32 {
        let (nv, nt) = (record.vertices(), record.triangles());
        let [x, y, z] = record.rows();
        let mut relative = [Vec3::ZERO; RECORD_VERTICES];
        for (v, relative) in relative.iter_mut().enumerate().take(nv) {
            *relative = Vec3::new(x[v], y[v], z[v]) - self.apex;
        }
        // `corner[j][axis][t]`: corner `j` of triangle `t` relative to the apex (zero past `nt`:
        // kept, and masked off below).
        let mut corner = [[[0.0f32; RECORD_TRIANGLES]; 3]; 3];
        for (corner, indices) in corner.iter_mut().zip(record.corner_rows()) {
            for (t, &v) in indices.iter().enumerate() {
                let p = relative[v as usize];
                corner[0][t] = p.x;
                corner[1][t] = p.y;
                corner[2][t] = p.z;
            }
        }
        let (dir_lo, dir_hi) = (self.dir_lo.to_array(), self.dir_hi.to_array());
        let mut below = [false; RECORD_TRIANGLES];
        let mut above = [false; RECORD_TRIANGLES];
        for (p, q) in [(1, 2), (2, 0), (0, 1)] {
            let (p, q) = (&corner[p], &corner[q]);
            for lane in 0..RECORD_TRIANGLES {
                let p = Vec3::new(p[0][lane], p[1][lane], p[2][lane]);
                let q = Vec3::new(q[0][lane], q[1][lane], q[2][lane]);
                let n = p.cross(q);
                let (x, y) = (n * Vec3::from(dir_lo), n * Vec3::from(dir_hi));
                let lo = x.min(y).element_sum();
                let hi = x.max(y).element_sum();
                let (lp, lq) = (l1(p), l1(q));
                let margin = self.margin(lp, lq);
                below[lane] |= hi < -margin;
                above[lane] |= lo > margin;
            }
        }
        let kept = (0..RECORD_TRIANGLES)
            .fold(0, |mask, lane| mask | ((!(below[lane] & above[lane])) as u32) << lane);
        kept & ((1 << nt) - 1)
    }

    /// Whether some line of the bundle may pass through the triangle: `false` only where none
    /// does, by the margin of the module documentation. Triangles with a NaN vertex are kept
    /// (no comparison with NaN culls).
    /// The scalar twin of [`may_cross_record`](Self::may_cross_record).
    #[cfg_attr(not(test), expect(dead_code, reason = "the scalar twin of `may_cross_record`"))]
    pub fn may_cross(&self, [a, b, c]: [Vec3; 3]) -> bool {
        let (a, b, c) = (a - self.apex, b - self.apex, c - self.apex);
        let mut below = false;
        let mut above = false;
        for (p, q) in [(b, c), (c, a), (a, b)] {
            let n = p.cross(q);
            let (x, y) = (n * self.dir_lo, n * self.dir_hi);
            let lo = x.min(y).element_sum();
            let hi = x.max(y).element_sum();
            let (lp, lq) = (l1(p), l1(q));
            let margin = self.margin(lp, lq);
            below |= hi < -margin;
            above |= lo > margin;
        }
        !(below && above)
    }
}

/// `|x| + |y| + |z|`.
#[inline(always)]
fn l1(v: Vec3) -> f32 {
    v.abs().element_sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::RayBoxTest;
    use crate::bvh::leaf::Leaves;
    use crate::bvh::tests::Lcg;
    use crate::ray::Ray;
    use crate::triangle::WatertightRay;

    fn bundle_of(rays: &[Ray]) -> Option<LineBundle> {
        LineBundle::of(&Frustum::of(rays.iter().map(RayBoxTest::new))?)
    }

    /// A triangle of random size around `target`, its corners snapped by `snap`.
    fn triangle_around(rng: &mut Lcg, target: Vec3, snap: impl Fn(Vec3) -> Vec3) -> [Vec3; 3] {
        let size = [1e-3, 0.05, 0.5, 3.0][(rng.next() * 4.0) as usize % 4];
        [(); 3].map(|_| snap(target + (rng.vec() - 0.5) * size))
    }

    /// Triangles checked against a bundle: hit by some ray, or missed by all (and then culled
    /// or not).
    #[derive(Default)]
    struct Tally {
        hit: u32,
        missed: u32,
        culled: u32,
    }

    impl Tally {
        /// Checks that `triangle` is kept if a ray of `rays` hits it (below its `t_max`), and
        /// that the record test agrees with the one-triangle test (the triangle in a record
        /// with another that shares two of its corners).
        fn check(&mut self, bundle: &LineBundle, rays: &[Ray], triangle: [Vec3; 3]) {
            if crate::triangle::is_degenerate(triangle) {
                return;
            }
            let [v0, v1, v2] = triangle;
            let any_hit = rays
                .iter()
                .any(|ray| WatertightRay::new(ray).intersect(v0, v1, v2, ray.t_max).is_some());
            let kept = bundle.may_cross(triangle);
            let other = [v2, v1, v0 + (v1 - v0) * 2.0];
            let mut leaves = Leaves::default();
            let offset = leaves.push_leaf(&[(0, other), (1, triangle)]);
            let record = leaves.record(offset);
            assert_eq!(record.triangles(), 2);
            let kept_in_record = bundle.may_cross_record(&record);
            assert_eq!(kept_in_record & 2 != 0, kept, "{triangle:?}");
            assert_eq!(kept_in_record & 1 != 0, bundle.may_cross(other), "{other:?}");
            if any_hit {
                self.hit += 1;
                assert!(kept, "culled {triangle:?}, hit by a ray of {rays:?}");
            } else {
                self.missed += 1;
                self.culled += !kept as u32;
            }
        }

        /// Enough of both kinds were seen, and more than one in `fraction` of the missed ones
        /// culled.
        fn assert_culls(&self, fraction: u32) {
            let Tally { hit, missed, culled } = *self;
            assert!(hit > 3000 && missed > 3000, "{hit} hit, {missed} missed");
            assert!(
                culled * fraction > missed,
                "only {culled} of {missed} missed triangles culled"
            );
        }
    }

    /// Packets of camera-like rays from one origin, against triangles near and across them (on
    /// a coarse grid half of the time, so that rays pass exactly through edges and vertices):
    /// a triangle that any ray hits is never culled, and most of those no ray hits are.
    #[test]
    fn no_triangle_a_ray_hits_is_culled() {
        let mut rng = Lcg(7);
        let mut tally = Tally::default();
        for case in 0..4000 {
            let snap = |v: Vec3| if case % 2 == 0 { (v * 4.0).round() / 4.0 } else { v };
            let origin = snap(rng.vec() * 2.0 - 1.0);
            // A tile of directions around a central one, all with positive components.
            let centre = Vec3::new(0.2, 0.2, 1.0) + rng.vec() * 0.5;
            let spread = [0.01, 0.1, 0.5][case % 3];
            let rays: Vec<Ray> = (0..16)
                .map(|k| {
                    let (i, j) = ((k % 4) as f32 / 3.0, (k / 4) as f32 / 3.0);
                    Ray::new(origin, centre + Vec3::new(i - 0.5, j - 0.5, 0.0) * spread)
                })
                .collect();
            let Some(bundle) = bundle_of(&rays) else { continue };
            for _ in 0..8 {
                // Around a point one of the rays passes through, or anywhere ahead.
                let target = if rng.next() < 0.5 {
                    rays[(rng.next() * 16.0) as usize % 16].at(1.0 + 3.0 * rng.next())
                } else {
                    origin + rng.vec() * 6.0 - Vec3::new(3.0, 3.0, 0.0)
                };
                tally.check(&bundle, &rays, triangle_around(&mut rng, target, snap));
            }
        }
        tally.assert_culls(2);
    }

    /// The bundle of segments from many points to one (as shadow rays to a light are made).
    fn bundle_of_segments(rays: &[Ray]) -> Option<LineBundle> {
        let frustum = Frustum::of(rays.iter().map(RayBoxTest::new))?;
        let ends = rays.iter().map(|r| {
            let inv = RayBoxTest::new(r).inv_direction;
            r.origin + inv.recip()
        });
        let (lo, hi) =
            ends.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), e| (lo.min(e), hi.max(e)));
        LineBundle::through_ends(&frustum, lo, hi)
    }

    /// Shadow rays from points of a patch toward one light (the segment `o → light`, `t_max`
    /// 1), against triangles between them and elsewhere, some on a grid through the light: no
    /// triangle a segment hits is culled, and most of those none hits are.
    #[test]
    fn no_triangle_a_shadow_ray_hits_is_culled() {
        let mut rng = Lcg(17);
        let mut tally = Tally::default();
        for case in 0..4000 {
            let snap = |v: Vec3| if case % 2 == 0 { (v * 4.0).round() / 4.0 } else { v };
            let light = snap(Vec3::new(0.0, 4.0, 0.0) + rng.vec() * 2.0 - 1.0);
            let corner = Vec3::new(rng.next() * 4.0 - 2.0, 0.0, rng.next() * 4.0 - 2.0);
            let spread = [0.05, 0.3, 1.5][case % 3];
            let rays: Vec<Ray> = (0..16)
                .map(|k| {
                    let (i, j) = ((k % 4) as f32 / 3.0, (k / 4) as f32 / 3.0);
                    let origin = corner + Vec3::new(i, 1e-3 * rng.next(), j) * spread;
                    Ray::segment(origin, light - origin, 1.0)
                })
                .collect();
            let Some(bundle) = bundle_of_segments(&rays) else { continue };
            for _ in 0..8 {
                let ray = rays[(rng.next() * 16.0) as usize % 16];
                let u = rng.next();
                let target = if u < 0.3 {
                    ray.at(rng.next())
                } else if u < 0.6 {
                    // Near the light, where the edge functions about it are small.
                    ray.at(1.0 - 1e-2 * rng.next())
                } else {
                    corner + rng.vec() * 6.0 - 3.0
                };
                tally.check(&bundle, &rays, triangle_around(&mut rng, target, snap));
            }
        }
        tally.assert_culls(3);
    }

    /// A leaf is sized by its largest edge against the footprint `distance·spread` of the
    /// packet at the leaf's centre: above twice it `Large`, above sixteen times `Covering`.
    #[test]
    fn leaves_are_sized_against_the_packet_footprint() {
        // A 9×9 tile from the origin, directions over [0.01, 0.03] in x and y (one octant) and 1
        // in z: the footprint at distance 10 is about 10·0.02 = 0.2 (the spread is the
        // direction box's largest edge over the largest component).
        let rays: Vec<Ray> = (0..81)
            .map(|i| {
                let (x, y) = ((i % 9) as f32 - 4.0, (i / 9) as f32 - 4.0);
                Ray::new(Vec3::ZERO, Vec3::new(0.02 + x * 0.0025, 0.02 + y * 0.0025, 1.0))
            })
            .collect();
        let bundle = bundle_of(&rays).expect("a bundle");
        let leaf = |edge: f32| {
            let centre = Vec3::new(0.2, 0.2, 10.0);
            Bounds {
                min: centre - Vec3::new(edge / 2.0, 0.0, 0.0),
                max: centre + Vec3::new(edge / 2.0, 0.0, 0.0),
            }
        };
        for (edge, size) in [
            (0.1, LeafSize::Small),
            (0.39, LeafSize::Small),
            (0.41, LeafSize::Large),
            (3.1, LeafSize::Large),
            (3.3, LeafSize::Covering),
            (100.0, LeafSize::Covering),
        ] {
            assert_eq!(bundle.size_of(&leaf(edge)), size, "edge {edge}");
        }
    }

    #[test]
    fn packets_from_several_origins_have_no_bundle() {
        let rays = [Ray::new(Vec3::ZERO, Vec3::ONE), Ray::new(Vec3::X, Vec3::ONE)];
        assert_eq!(bundle_of(&rays), None);
        assert!(bundle_of(&rays[..1]).is_some());
        // Parallel lines meet nowhere near.
        assert_eq!(bundle_of_segments(&rays), None);
    }
}
