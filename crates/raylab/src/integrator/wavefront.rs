//! `path` as a wavefront: the paths of a tile advanced together, stage by stage, with their rays
//! traced as batches.
//!
//! The estimator, the random numbers and the arithmetic are those of [`Path`]: each stage is
//! the scalar path's own code ([`Path`]'s vertex, light-sampling and BSDF-sampling steps) run
//! over the lanes that are still alive, and each lane draws from its own [`Sampler`] in the
//! scalar order (light, then BSDF, then roulette), so every sample is the scalar path's to the
//! bit (`tests/wavefront.rs`). What changes is the order of the work:
//!
//! 1. **closest hits** of every live path's ray: the camera rays as packets
//!    ([`Accelerator::closest_hits`]), the later rays one by one;
//! 2. **emission and misses**: light found by the camera or by BSDF sampling, weighted by MIS;
//!    paths that leave the scene or reach `max_depth` end;
//! 3. **light sampling** at every live vertex: a shadow ray and the contribution it carries;
//! 4. **occlusion** of the shadow rays, one by one;
//! 5. **BSDF sampling and Russian roulette**: the next ray, or the end of the path.
//!
//! Packets pay only where rays are coherent. Measured (`cargo bench -p raylab --bench path`, one
//! thread, 128×96): packets for every bounce made `showcase.toml` 16 times slower (216 ms a
//! pass against 13.5), packets for the shadow rays 3.8 times (51.7 ms; occlusion 3,100 ns a
//! sample against 121), and even on the Cornell box shadow packets doubled the occlusion time;
//! packets for the camera rays alone gain a few per cent there (10.6 and 10.0 ms against 10.9 and
//! 10.6 without).
//!
//! Scenes with cut-out (alpha-masked) materials trace each ray through its holes one at a time,
//! as the scalar path does.
//!
//! This is the structure that the SIMD stages (issue 27) fill in: a stage that runs over lanes
//! can run sixteen of them per instruction. The sampler's draws already do: the light's
//! choice and point, the BSDF's lobe and direction, and the roulette's number are each drawn for
//! all of a stage's paths at once ([`Sampler::next_1d_each`], [`Sampler::next_2d_each`],
//! sixteen lanes per loop). The rest is the scalar code, lane
//! by lane: the twin the vector stages will be tested against.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use glam::{Vec2, Vec3};

use super::Integrator;
use super::path::{Path, PathSettings, PathState, Vertex};
use crate::accel::{Accelerator, Hit};
use crate::ray::Ray;
use crate::sampling::Sampler;
use crate::scene::Scene;

/// [`Path`] run as a wavefront (see the module documentation): the same samples, the work
/// ordered by stage.
pub struct PathWavefront<'a, A: ?Sized> {
    path: Path<'a, A>,
    /// Time per stage, when measured ([`with_stage_times`](Self::with_stage_times)).
    times: Option<StageClock>,
}

impl<'a, A: Accelerator + ?Sized> PathWavefront<'a, A> {
    /// A wavefront path tracer for `scene`, whose [`vertices`](Scene::vertices) `accel` holds.
    pub fn new(scene: &'a Scene, accel: &'a A, settings: PathSettings) -> Self {
        PathWavefront { path: Path::new(scene, accel, settings), times: None }
    }

    /// The same, measuring the time each stage takes (summed over threads): for the stage
    /// table of the benchmarks. Costs a clock reading per stage and tile.
    pub fn with_stage_times(mut self) -> Self {
        self.times = Some(StageClock::default());
        self
    }

    /// The time each stage took so far, if measured.
    pub fn stage_times(&self) -> Option<StageTimes> {
        self.times.as_ref().map(StageClock::read)
    }

    /// The scalar path tracer it runs the stages of.
    pub fn path(&self) -> &Path<'a, A> {
        &self.path
    }
}

impl<A: Accelerator + ?Sized> Integrator for PathWavefront<'_, A> {
    fn radiance(&self, ray: &Ray, sampler: &mut Sampler) -> Vec3 {
        self.path.radiance(ray, sampler)
    }

    fn radiance_each(&self, rays: &[Ray], samplers: &mut [Sampler], out: &mut [Vec3]) {
        assert_eq!(rays.len(), out.len(), "one colour per ray");
        assert_eq!(rays.len(), samplers.len(), "one sampler per ray");
        let path = &self.path;
        let max_depth = path.settings().max_depth.unwrap_or(u32::MAX);
        if max_depth == 0 {
            out.fill(Vec3::ZERO);
            return;
        }
        let (scene, accel) = (path.scene(), path.accel());
        // The stages' buffers, made per tile: a thread-local set reused from tile to tile was
        // measured slower (BENCHMARKS.md, "The wavefront").
        let mut states: Vec<PathState> = rays.iter().map(PathState::new).collect();
        // The paths still tracing, by index.
        let mut alive: Vec<usize> = (0..rays.len()).collect();
        let mut batch: Vec<Ray> = Vec::with_capacity(rays.len());
        let mut hits: Vec<Option<Hit>> = Vec::with_capacity(rays.len());
        let mut vertices: Vec<(usize, Vertex)> = Vec::with_capacity(rays.len());
        let mut shadowed: Vec<(usize, Vec3)> = Vec::with_capacity(rays.len());
        let mut occluded: Vec<bool> = Vec::with_capacity(rays.len());
        // A stage's paths, and the numbers drawn for them a batch at a time.
        let mut lanes: Vec<usize> = Vec::with_capacity(rays.len());
        let mut numbers: Vec<f32> = Vec::with_capacity(rays.len());
        let mut points: Vec<Vec2> = Vec::with_capacity(rays.len());
        let mut first = true;
        let mut lap = Lap::start(self.times.as_ref());
        while !alive.is_empty() {
            // 1. Closest hits, as a batch.
            batch.clear();
            batch.extend(alive.iter().map(|&i| states[i].ray));
            hits.clear();
            hits.resize(batch.len(), None);
            if scene.has_cut_outs() {
                for (ray, hit) in batch.iter().zip(&mut hits) {
                    *hit = super::closest_opaque_hit(scene, accel, ray);
                }
            } else if first {
                // Camera rays are coherent: packets pay (see the module documentation).
                accel.closest_hits(&batch, &mut hits);
            } else {
                for (ray, hit) in batch.iter().zip(&mut hits) {
                    *hit = accel.closest_hit(ray);
                }
            }
            first = false;
            lap.end(|t| &t.closest_hits);

            // 2. Light found; paths that leave the scene or reach the depth limit end.
            vertices.clear();
            for (&i, hit) in alive.iter().zip(&hits) {
                let state = &mut states[i];
                if let Some(interaction) = path.arrive(state, hit.as_ref())
                    && state.depth + 1 < max_depth
                {
                    vertices.push((i, path.vertex(&state.ray, &interaction)));
                }
            }

            lap.end(|t| &t.surfaces);

            // 3. Light sampling at every vertex: the shadow rays.
            batch.clear();
            shadowed.clear();
            lanes.clear();
            lanes.extend(vertices.iter().map(|(i, _)| *i));
            numbers.resize(lanes.len(), 0.0);
            points.resize(lanes.len(), Vec2::ZERO);
            Sampler::next_1d_each(samplers, &lanes, &mut numbers);
            Sampler::next_2d_each(samplers, &lanes, &mut points);
            for (((i, vertex), &u_light), &u_point) in vertices.iter().zip(&numbers).zip(&points) {
                if let Some((shadow_ray, contribution)) =
                    path.sample_light_with(vertex, u_light, u_point, states[*i].throughput)
                {
                    batch.push(shadow_ray);
                    shadowed.push((*i, contribution));
                }
            }

            lap.end(|t| &t.light_sampling);

            // 4. Occlusion, as a batch.
            occluded.clear();
            occluded.resize(batch.len(), false);
            for (ray, blocked) in batch.iter().zip(&mut occluded) {
                *blocked = super::occluded_opaque(scene, accel, ray);
            }
            for (&(i, contribution), &blocked) in shadowed.iter().zip(&occluded) {
                if !blocked {
                    states[i].radiance += contribution;
                }
            }

            lap.end(|t| &t.occlusion);

            // 5. BSDF sampling and Russian roulette: the paths that go on.
            // The lobes' numbers for every vertex, then the roulette's for the paths that
            // bounced, each drawn a batch at a time (`lanes` still holds the vertices' paths).
            Sampler::next_1d_each(samplers, &lanes, &mut numbers);
            Sampler::next_2d_each(samplers, &lanes, &mut points);
            let mut bounced = std::mem::take(&mut alive);
            bounced.clear();
            for (((i, vertex), &u_lobe), &u_direction) in vertices.iter().zip(&numbers).zip(&points)
            {
                if path.bounce(&mut states[*i], vertex, u_lobe, u_direction) {
                    bounced.push(*i);
                }
            }
            numbers.resize(bounced.len(), 0.0);
            Sampler::next_1d_each(samplers, &bounced, &mut numbers);
            alive = bounced;
            let mut kept = 0;
            for k in 0..alive.len() {
                let i = alive[k];
                if path.survives_roulette(&mut states[i], numbers[k]) {
                    alive[kept] = i;
                    kept += 1;
                }
            }
            alive.truncate(kept);
            if let Some(times) = &self.times {
                times.vertices.fetch_add(vertices.len() as u64, Ordering::Relaxed);
            }
            lap.end(|t| &t.scattering);
        }
        for (state, colour) in states.iter().zip(out) {
            *colour = path.finish(state.radiance);
        }
        if let Some(times) = &self.times {
            times.paths.fetch_add(rays.len() as u64, Ordering::Relaxed);
        }
    }
}

/// The time the wavefront's stages took, summed over threads, and how much work they did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StageTimes {
    /// Closest hits (1).
    pub closest_hits: Duration,
    /// Surface interactions, emission found with its MIS weight, and the vertices' materials
    /// and shading frames (2).
    pub surfaces: Duration,
    /// Light sampling: the light's choice, its point, the BSDF's value and MIS (3).
    pub light_sampling: Duration,
    /// Occlusion of the shadow rays (4).
    pub occlusion: Duration,
    /// BSDF sampling and Russian roulette (5).
    pub scattering: Duration,
    /// Paths traced (camera samples).
    pub paths: u64,
    /// Vertices scattered from.
    pub vertices: u64,
}

/// [`StageTimes`] as the threads add to it: nanoseconds.
#[derive(Debug, Default)]
struct StageClock {
    closest_hits: AtomicU64,
    surfaces: AtomicU64,
    light_sampling: AtomicU64,
    occlusion: AtomicU64,
    scattering: AtomicU64,
    paths: AtomicU64,
    vertices: AtomicU64,
}

impl StageClock {
    fn read(&self) -> StageTimes {
        let time = |t: &AtomicU64| Duration::from_nanos(t.load(Ordering::Relaxed));
        StageTimes {
            closest_hits: time(&self.closest_hits),
            surfaces: time(&self.surfaces),
            light_sampling: time(&self.light_sampling),
            occlusion: time(&self.occlusion),
            scattering: time(&self.scattering),
            paths: self.paths.load(Ordering::Relaxed),
            vertices: self.vertices.load(Ordering::Relaxed),
        }
    }
}

/// A stopwatch over the stages, reading the clock only when times are measured.
struct Lap<'c> {
    clock: Option<(&'c StageClock, Instant)>,
}

impl<'c> Lap<'c> {
    fn start(clock: Option<&'c StageClock>) -> Lap<'c> {
        Lap { clock: clock.map(|clock| (clock, Instant::now())) }
    }

    /// Adds the time since the last lap to the stage `slot` picks.
    #[inline]
    fn end(&mut self, slot: impl Fn(&StageClock) -> &AtomicU64) {
        if let Some((clock, last)) = &mut self.clock {
            let now = Instant::now();
            slot(clock).fetch_add((now - *last).as_nanos() as u64, Ordering::Relaxed);
            *last = now;
        }
    }
}
