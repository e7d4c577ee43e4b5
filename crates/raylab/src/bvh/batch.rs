//! Large batches of independent ray queries: one answer per ray, computed on every thread of the
//! current rayon pool, in the tree's order where that pays.
//!
//! [`Batch`] takes its rays from a [`RaySource`] (a slice of [`Ray`]s, or a caller's own arrays,
//! checked ray by ray as they are traced) and answers closest hits, occlusion, crossing counts,
//! or any function of a ray. A batch of at least [`Batch::ORDER_MIN_RAYS`] rays against a tree
//! of at least [`Batch::ORDER_MIN_TREE_BYTES`] is traced in the order of [`order::segment_key`]
//! (neighbours run through the same part of the tree, which then stays in the cache), each
//! chunk asking the cache for the rays a few places ahead; smaller ones are traced as they come.
//! The work is cut into chunks of [`Batch::CHUNK`] rays; a batch of one chunk traced as it comes
//! runs on the calling thread (waking a pool's thread costs more than such a batch).
//!
//! The answers are each ray's own query's, bit for bit, whatever the order, the chunking and
//! the threads: the tests check them against single rays in any order.
//!
//! A bad ray (what [`RaySource::ray`] refuses) stops the batch with the error of **the first**
//! bad ray, even where a thread met a later one first (or with the error met, if no ray is bad
//! when the batch looks again: a source that changed during the batch).
//!
//! ```
//! use raylab::bvh::{Batch, Bvh};
//! use raylab::{Accelerator, Ray, Scene};
//! use glam::Vec3;
//!
//! let scene = Scene::built_in("cornell")?;
//! let bvh = Bvh::new(&scene.vertices());
//! let rays: Vec<Ray> = (0..1000)
//!     .map(|i| Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::new(i as f32 * 1e-3 - 0.5, 0.1, 1.0)))
//!     .collect();
//! let hits = Batch::new(&bvh).closest_hits(&rays[..]).unwrap();
//! assert_eq!(hits[7], bvh.closest_hit(&rays[7]));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use rayon::prelude::*;

use super::{Bvh, order};
use crate::accel::{Accelerator, Hit};
use crate::ray::Ray;

/// Where a batch's rays come from.
pub trait RaySource: Sync {
    /// What a bad ray is.
    type Error: Send;

    /// How many rays.
    fn len(&self) -> usize;

    /// Whether there are none.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Ray `i` (`i < len()`), or why it cannot be traced.
    fn ray(&self, i: usize) -> Result<Ray, Self::Error>;

    /// Ray `i` as it is, maybe bad: only its ordering key is computed from it
    /// ([`order::segment_key`] takes any ray).
    fn ray_unchecked(&self, i: usize) -> Ray;

    /// Asks the cache for ray `i`'s data, a few rays before it is traced (a hint; by default
    /// nothing).
    #[inline(always)]
    fn prefetch(&self, _i: usize) {}
}

/// Rays given as they are: every ray is traced (one that can hit nothing answers a miss).
impl RaySource for [Ray] {
    type Error = std::convert::Infallible;

    #[inline(always)]
    fn len(&self) -> usize {
        <[Ray]>::len(self)
    }

    #[inline(always)]
    fn ray(&self, i: usize) -> Result<Ray, Self::Error> {
        Ok(self[i])
    }

    #[inline(always)]
    fn ray_unchecked(&self, i: usize) -> Ray {
        self[i]
    }

    #[inline(always)]
    fn prefetch(&self, i: usize) {
        prefetch(self.as_ptr().wrapping_add(i).cast());
    }
}

pub use crate::memory::prefetch;

/// A tree's batch queries (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct Batch<'a> {
    bvh: &'a Bvh,
    ordered: Option<bool>,
}

impl<'a> Batch<'a> {
    /// Rays per chunk of work.
    pub const CHUNK: usize = 2048;
    /// The fewest rays a batch is put in the tree's order for: below it the sort costs about
    /// what the cache gives back.
    pub const ORDER_MIN_RAYS: usize = 1 << 14;
    /// The smallest tree (`BvhStats::bytes`) a batch is put in its order for: smaller ones stay
    /// in the caches in any order.
    pub const ORDER_MIN_TREE_BYTES: usize = 4 << 20;
    /// How many rays ahead a chunk asks the cache for in the tree's order.
    const AHEAD: usize = 8;

    /// `bvh`'s batch queries, ordered by the rule of the module documentation.
    pub fn new(bvh: &'a Bvh) -> Batch<'a> {
        Batch { bvh, ordered: None }
    }

    /// The same, always in the tree's order (`true`) or never (`false`): to measure.
    pub fn ordered(self, ordered: bool) -> Batch<'a> {
        Batch { ordered: Some(ordered), ..self }
    }

    /// The closest hit of every ray.
    pub fn closest_hits<S: RaySource + ?Sized>(
        &self,
        rays: &S,
    ) -> Result<Vec<Option<Hit>>, S::Error> {
        let bvh = self.bvh;
        self.answers(rays, |ray| bvh.closest_hit(ray))
    }

    /// Whether each ray is blocked between its `t_min` and `t_max`.
    pub fn occluded<S: RaySource + ?Sized>(&self, rays: &S) -> Result<Vec<bool>, S::Error> {
        let bvh = self.bvh;
        self.answers(rays, |ray| bvh.occluded(ray))
    }

    /// How often each ray crosses the surface ([`Bvh::count_crossings`]).
    pub fn crossing_counts<S: RaySource + ?Sized>(&self, rays: &S) -> Result<Vec<u32>, S::Error> {
        let bvh = self.bvh;
        self.answers(rays, |ray| bvh.count_crossings(ray))
    }

    /// `answer` of every ray, in the rays' order.
    pub fn answers<S: RaySource + ?Sized, T: Send + Copy + Default>(
        &self,
        rays: &S,
        answer: impl Fn(&Ray) -> T + Sync,
    ) -> Result<Vec<T>, S::Error> {
        let mut out = vec![T::default(); rays.len()];
        self.answers_into(rays, &mut out, answer)?;
        Ok(out)
    }

    /// `answer` of every ray into `out` (one slot per ray, in the rays' order): no allocation
    /// where the rays are traced as they come. On a bad ray, `out` is partly written.
    pub fn answers_into<S: RaySource + ?Sized, T: Send + Copy + Default>(
        &self,
        rays: &S,
        out: &mut [T],
        answer: impl Fn(&Ray) -> T + Sync,
    ) -> Result<(), S::Error> {
        assert_eq!(rays.len(), out.len(), "one slot per ray");
        match self.trace_order(rays) {
            Some(order) => {
                let sorted = self.in_order(rays, &order, answer)?;
                for (&i, &x) in order.iter().zip(&sorted) {
                    out[i as usize] = x;
                }
                Ok(())
            }
            None => each_chunk(rays, out, |slot, ray| *slot = answer(ray)),
        }
    }

    /// The order to trace `rays` in, or `None` to trace them as they come.
    fn trace_order<S: RaySource + ?Sized>(&self, rays: &S) -> Option<Vec<u32>> {
        let n = rays.len();
        let wanted = self.ordered.unwrap_or(
            n >= Self::ORDER_MIN_RAYS && self.bvh.stats().bytes() >= Self::ORDER_MIN_TREE_BYTES,
        );
        if !wanted || u32::try_from(n).is_err() {
            return None;
        }
        let bounds = self.bvh.bounds();
        let mut keys = vec![0u32; n];
        keys.par_chunks_mut(Self::CHUNK).enumerate().for_each(|(c, keys)| {
            for (k, key) in keys.iter_mut().enumerate() {
                *key = order::segment_key(&bounds, &rays.ray_unchecked(c * Self::CHUNK + k));
            }
        });
        Some(order::order_by_key(&keys))
    }

    /// `answer` for the rays `order` names, in that order, in parallel chunks, each asking the
    /// cache for the rays a few places ahead.
    fn in_order<S: RaySource + ?Sized, T: Send + Copy + Default>(
        &self,
        rays: &S,
        order: &[u32],
        answer: impl Fn(&Ray) -> T + Sync,
    ) -> Result<Vec<T>, S::Error> {
        let mut sorted = vec![T::default(); order.len()];
        let found = sorted
            .par_chunks_mut(Self::CHUNK)
            .zip(order.par_chunks(Self::CHUNK))
            .try_for_each(|(out, indices)| {
                for (k, &i) in indices.iter().enumerate() {
                    if let Some(&ahead) = indices.get(k + Self::AHEAD) {
                        rays.prefetch(ahead as usize);
                    }
                    out[k] = answer(&rays.ray(i as usize)?);
                }
                Ok(())
            });
        // The threads may have met a later bad ray first: name the first one.
        found.map_err(|e| first_error(rays).unwrap_or(e))?;
        Ok(sorted)
    }
}

/// Runs `answer` on every ray and its slot of `out` (one per ray) in parallel chunks of
/// [`Batch::CHUNK`], in the rays' order within each; a batch of one chunk on the calling thread.
/// On a bad ray, the first bad ray's error (`out` then partly written).
pub fn each_chunk<S: RaySource + ?Sized, T: Send>(
    rays: &S,
    out: &mut [T],
    answer: impl Fn(&mut T, &Ray) + Sync,
) -> Result<(), S::Error> {
    assert_eq!(rays.len(), out.len(), "one slot per ray");
    let chunk = |(c, out): (usize, &mut [T])| {
        for (k, slot) in out.iter_mut().enumerate() {
            answer(slot, &rays.ray(c * Batch::CHUNK + k)?);
        }
        Ok(())
    };
    let found = if out.len() <= Batch::CHUNK {
        out.chunks_mut(Batch::CHUNK).enumerate().try_for_each(chunk)
    } else {
        out.par_chunks_mut(Batch::CHUNK).enumerate().try_for_each(chunk)
    };
    // The threads may have met a later bad ray first: name the first one.
    found.map_err(|e| first_error(rays).unwrap_or(e))
}

/// The first bad ray's error, after a parallel pass met some bad ray (`None` if none is bad
/// now: the source changed during the batch; the error met is then kept).
#[cold]
fn first_error<S: RaySource + ?Sized>(rays: &S) -> Option<S::Error> {
    (0..rays.len()).find_map(|i| rays.ray(i).err())
}
