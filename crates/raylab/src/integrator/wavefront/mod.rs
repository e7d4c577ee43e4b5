//! `path` as a wavefront: the paths of a tile advanced together, stage by stage, with their rays
//! traced as batches and their vertices shaded sixteen lanes per instruction, grouped by BSDF.
//!
//! The estimator, the random numbers and the arithmetic are those of [`PathScalar`]: every sample is
//! the scalar path's to the bit (`tests/wavefront.rs` compares whole renders of every scene).
//! Each lane draws from its own [`Sampler`] in the scalar order; what changes is the order of
//! the work:
//!
//! 1. **closest hits** of every live path's ray: the camera rays as packets
//!    ([`Accelerator::closest_hits`]), the later rays as one batch
//!    ([`Accelerator::closest_hits_incoherent`]: in lanes, against a small scene's flat list
//!    or through a tree);
//! 2. **surfaces**: emission found, weighted by MIS; paths that leave the scene or reach
//!    `max_depth` end; each vertex's material, shading normal and BSDF. The vertex goes
//!    straight into a lane of its BSDF's kind (its point, shading normal, tangent and the
//!    BSDF's parameters: [`PathScalar::lane_surface`]; the lanes make its frame). The commonest hits,
//!    on an unplaced triangle that is no light's, of a material without a normal map
//!    ([`PathScalar::plain_surface`]), go without building their whole interaction;
//! 3. **draws**: a chunk's numbers (the light's choice and point, the BSDF's lobe and
//!    direction, the roulette's) in one pass over their samplers
//!    ([`Sampler::next_vertex_each`], sixteen lanes per loop);
//! 4. **shading**: light sampling, BSDF sampling and Russian roulette. The lanes (`lanes/`:
//!    sixteen to a chunk in structure-of-arrays form, one BSDF kind to a chunk) get their
//!    lights and numbers and are shaded by one loop the compiler vectorizes, sixteen lanes per
//!    AVX-512 instruction; lights other than area-sampled triangles and the constant
//!    environment, and the rare lane whose offset point overflows, run the scalar path's steps
//!    ([`PathScalar::sample_light_with`], `bounce`, `survives_roulette`) one by one;
//! 5. **occlusion** of the shadow rays as one batch ([`Accelerator::occluded_incoherent`]: in
//!    lanes, against a small scene's flat list or through a tree), and the light they bring.
//!
//! Stages 2 to 4 run a chunk at a time: as soon as sixteen vertices of a kind are gathered,
//! their numbers are drawn and they are shaded, while their rows are still in the first-level
//! cache (a chunk and its results take about 5.5 KiB, a 1,024-path wavefront's some 350 KiB, more
//! than the 32 KiB of this machine's first-level cache). Each path draws from its own
//! sampler, so the order in which paths draw changes no number.
//!
//! Grouping by BSDF kind is what keeps the lanes full and each BSDF's code on whole vectors: a
//! chunk holds one kind's vertices, whichever paths they belong to. Every kind shades in lanes.
//!
//! Packets pay only where rays are coherent, so only the camera rays go as packets; the later
//! bounces and the shadow rays, incoherent, go in lanes one ray per lane
//! ([`Accelerator::closest_hits_incoherent`]).
//!
//! Scenes with cut-out (alpha-masked) materials trace each ray through its holes one at a time,
//! as the scalar path does.

mod lanes;

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3;

use lanes::{LaneDraws, LaneVertex, Lanes};

use super::Integrator;
use super::light_sampler::LaneRole;
use super::path::{LaneKind, PathScalar, PathSettings, PathState, Vertex};
use crate::accel::{Accelerator, Hit};
use crate::cpu::Isa;
use crate::material::lanes::LaneBsdf;
use crate::ray::Ray;
use crate::sampling::{Sampler, VertexNumbers};
use crate::scene::Scene;

/// [`PathScalar`] run as a wavefront (see the module documentation): the same samples, the work
/// ordered by stage.
pub struct Path<'a, A: ?Sized> {
    path: PathScalar<'a, A>,
    /// The instruction set the lanes run on.
    isa: Isa,
    /// Time per stage, when measured ([`with_stage_times`](Self::with_stage_times)).
    times: Option<StageClock>,
}

impl<'a, A: Accelerator + ?Sized> Path<'a, A> {
    /// A wavefront path tracer for `scene`, whose [`vertices`](Scene::vertices) `accel` holds.
    pub fn new(scene: &'a Scene, accel: &'a A, settings: PathSettings) -> Self {
        Path { path: PathScalar::new(scene, accel, settings), isa: Isa::detect(), times: None }
    }

    /// A wavefront path tracer with lights made before (`raylab view` keeps them from frame
    /// to frame).
    pub fn with_lights(
        scene: &'a Scene,
        accel: &'a A,
        lights: &'a super::LightSet,
        settings: PathSettings,
    ) -> Self {
        let path = PathScalar::with_lights(scene, accel, lights, settings);
        Path { path, isa: Isa::detect(), times: None }
    }

    /// The same, with its lanes run on the instruction set `isa` rather than the best this CPU
    /// has (the same samples, to the bit): for tests and benchmarks.
    ///
    /// # Panics
    /// If this CPU does not support `isa`.
    pub fn with_isa(mut self, isa: Isa) -> Self {
        assert!(isa.is_supported(), "{} is not supported by this CPU", isa.name());
        self.isa = isa;
        self
    }

    /// The same, measuring the time each stage takes (summed over threads): for the stage
    /// table of the benchmarks. Costs a clock reading per stage and tile, and three per chunk
    /// of lanes.
    pub fn with_stage_times(mut self) -> Self {
        self.times = Some(StageClock::default());
        self
    }

    /// The time each stage took so far, if measured.
    pub fn stage_times(&self) -> Option<StageTimes> {
        self.times.as_ref().map(StageClock::read)
    }

    /// The scalar path tracer it runs the stages of.
    pub fn path(&self) -> &PathScalar<'a, A> {
        &self.path
    }
}

impl<A: Accelerator + ?Sized> Integrator for Path<'_, A> {
    fn radiance(&self, ray: &Ray, sampler: &mut Sampler) -> Vec3 {
        self.path.radiance(ray, sampler)
    }

    fn discarded_samples(&self) -> u64 {
        self.path.discarded_samples()
    }

    /// 128×8 tiles: 1,024 paths advance together, which fills the lanes of the later bounces
    /// better than smaller tiles. (The lab's integrator keeps 8×8: its frame is slower in wider
    /// tiles.)
    fn tile_width(&self) -> u32 {
        128
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
        let rr_depth = path.settings().rr_depth;
        // The stages' buffers, made per tile (a thread-local set reused from tile to tile was
        // no faster).
        let mut states = PathState::starting(rays);
        // The paths still tracing, by index.
        let mut alive: Vec<usize> = (0..rays.len()).collect();
        let mut batch: Vec<Ray> = Vec::with_capacity(rays.len());
        let mut hits: Vec<Option<Hit>> = Vec::with_capacity(rays.len());
        let mut shadows = ShadowRays::with_capacity(rays.len());
        let mut numbers = Numbers::with_capacity(rays.len());
        // The vertices in lanes, a set for each BSDF kind, and their paths, made per tile (one
        // reused from tile to tile, thread-local, was slower).
        let mut sets: [(Lanes, Vec<usize>); LaneKind::ALL.len()] =
            std::array::from_fn(|_| (Lanes::default(), Vec::new()));
        // The paths that go on after this bounce.
        let mut bounced: Vec<usize> = Vec::with_capacity(rays.len());
        let mut first = true;
        let mut lap = Lap::start(self.times.as_ref());
        while !alive.is_empty() {
            // 1. Closest hits, as a batch: the camera rays as they came (every path, in order),
            // the later rays gathered from the paths still tracing.
            let batch = if first {
                rays
            } else {
                batch.clear();
                batch.extend(alive.iter().map(|&i| states[i].ray));
                &batch[..]
            };
            hits.clear();
            hits.resize(batch.len(), None);
            if scene.has_cut_outs() {
                for (ray, hit) in batch.iter().zip(&mut hits) {
                    *hit = super::closest_opaque_hit(scene, accel, ray);
                }
            } else if first {
                // Camera rays are coherent: packets pay (see the module documentation).
                accel.closest_hits(batch, &mut hits);
            } else {
                accel.closest_hits_incoherent(batch, &mut hits);
            }
            first = false;
            lap.end(|t| &t.closest_hits);

            // 2–4. Light found; paths that leave the scene or reach the depth limit end.
            // Vertices go straight into the lanes of their BSDF's kind and are shaded sixteen
            // at a time as soon as a chunk is full, while its rows are in the first-level
            // cache; the last chunks of each kind after.
            shadows.clear();
            bounced.clear();
            let mut chunk = Chunk {
                states: &mut states,
                samplers,
                numbers: &mut numbers,
                shadows: &mut shadows,
                bounced: &mut bounced,
                lap: &mut lap,
            };
            for (&i, hit) in alive.iter().zip(&hits) {
                let state = &mut chunk.states[i];
                let last = state.depth + 1 >= max_depth;
                // The commonest hits, an unplaced triangle of a material without a normal map,
                // by the shortcut:
                // nothing is emitted there, so at the depth limit it needs nothing at all. Any
                // other hit by the general steps.
                let plain =
                    if last { None } else { hit.as_ref().and_then(|hit| path.plain_surface(hit)) };
                let surface = match plain {
                    Some(plain) => plain,
                    None => {
                        let Some(interaction) = path.arrive(state, hit.as_ref()) else { continue };
                        if last {
                            continue;
                        }
                        path.lane_surface(&state.ray, &interaction)
                    }
                };
                let kind = LaneKind::kind(&surface.bsdf);
                let (set, paths) = &mut sets[kind as usize];
                set.push(
                    &surface,
                    &LaneVertex {
                        arrival: state.ray.direction,
                        throughput: state.throughput,
                        eta: state.eta,
                        roulette: state.depth + 1 >= rr_depth,
                    },
                );
                paths.push(i);
                if set.len() == lanes::LANES {
                    chunk.lap.end(|t| &t.surfaces);
                    self.shade_kind(kind, &mut chunk, set, paths);
                    set.clear();
                    paths.clear();
                }
            }
            chunk.lap.end(|t| &t.surfaces);
            for (kind, (set, paths)) in LaneKind::ALL.into_iter().zip(&mut sets) {
                if set.len() > 0 {
                    self.shade_kind(kind, &mut chunk, set, paths);
                    set.clear();
                    paths.clear();
                }
            }
            std::mem::swap(&mut alive, &mut bounced);

            // 5. Occlusion of the shadow rays, and the light they bring.
            shadows.trace(scene, accel);
            for (&blocked, &(i, contribution)) in shadows.blocked.iter().zip(&shadows.light) {
                if !blocked {
                    states[i].radiance += contribution;
                }
            }
            lap.end(|t| &t.occlusion);
        }
        for (state, colour) in states.iter().zip(out) {
            *colour = path.finish(state.radiance);
        }
        if let Some(times) = &self.times {
            times.paths.fetch_add(rays.len() as u64, Ordering::Relaxed);
        }
    }
}

/// What shading a chunk of lanes reads and adds to: the paths' states and samplers, the
/// numbers' buffer, and the stage's shadow rays and paths that go on.
struct Chunk<'s, 'c> {
    states: &'s mut [PathState],
    samplers: &'s mut [Sampler],
    numbers: &'s mut Numbers,
    shadows: &'s mut ShadowRays,
    bounced: &'s mut Vec<usize>,
    lap: &'s mut Lap<'c>,
}

impl<A: Accelerator + ?Sized> Path<'_, A> {
    /// [`shade_lanes`](Self::shade_lanes) with the code of `kind`'s BSDF.
    #[inline(never)]
    fn shade_kind(&self, kind: LaneKind, chunk: &mut Chunk, lanes: &mut Lanes, paths: &[usize]) {
        lanes::with_lane_bsdf!(kind, B => self.shade_lanes::<B>(chunk, lanes, paths))
    }

    /// Draws the numbers of `lanes` (the vertices of `paths`, whose BSDFs are `B`s), shades
    /// them, and takes their results: shadow rays, and the next rays of the paths that go on.
    #[inline(never)]
    fn shade_lanes<B: LaneBsdf>(&self, chunk: &mut Chunk, lanes: &mut Lanes, paths: &[usize]) {
        let path = &self.path;
        chunk.numbers.draw(chunk.samplers, paths);
        chunk.lap.end(|t| &t.draws);
        // The lanes the scalar steps decide in part or whole (for the stage table).
        debug_assert!(paths.len() <= lanes::LANES, "a chunk at a time");
        let mut scalar = 0u32;
        for (lane, &i) in paths.iter().enumerate() {
            let drawn = chunk.numbers.drawn[lane];
            let light = path.lights().pick_for_lanes(drawn.point);
            if light.role() == LaneRole::Other {
                scalar |= 1 << lane;
                let vertex = lanes.vertex::<B>(lane);
                chunk
                    .shadows
                    .add(i, chunk.numbers.sample_light(path, &chunk.states[i], &vertex, lane));
            }
            lanes.set_draws(
                lane,
                &LaneDraws {
                    light,
                    u_point: drawn.point,
                    u_lobe: drawn.lobe,
                    u_direction: drawn.direction,
                    u_roulette: drawn.roulette,
                },
            );
        }
        lanes.shade::<B>(self.isa);
        for (lane, &i) in paths.iter().enumerate() {
            let state = &mut chunk.states[i];
            let result = lanes.result(lane);
            if !result.exact {
                // An offset point was not finite: the scalar steps decide the lane.
                scalar |= 1 << lane;
                let vertex = lanes.vertex::<B>(lane);
                if result.light_in_lanes {
                    chunk.shadows.add(i, chunk.numbers.sample_light(path, state, &vertex, lane));
                }
                if chunk.numbers.bounce(path, state, &vertex, lane) {
                    chunk.bounced.push(i);
                }
                continue;
            }
            chunk.shadows.add(i, result.shadow);
            if let Some(next) = result.next {
                state.ray = next.ray;
                state.throughput = next.throughput;
                state.eta = next.eta;
                state.previous_pdf = next.pdf;
                state.previous_delta = next.delta;
                state.previous_point = lanes.point(lane);
                state.depth += 1;
                chunk.bounced.push(i);
            }
        }
        if let Some(times) = &self.times {
            let vertices = paths.len() as u64;
            times.vertices.fetch_add(vertices, Ordering::Relaxed);
            times.lanes.fetch_add(vertices - u64::from(scalar.count_ones()), Ordering::Relaxed);
            times.chunks.fetch_add(1, Ordering::Relaxed);
        }
        chunk.lap.end(|t| &t.shading);
    }
}

/// The shadow rays of a stage's vertices, and the light each brings to its path if nothing
/// blocks it.
struct ShadowRays {
    rays: Vec<Ray>,
    light: Vec<(usize, Vec3)>,
    /// Whether each ray is blocked, once [traced](Self::trace).
    blocked: Vec<bool>,
}

impl ShadowRays {
    fn with_capacity(n: usize) -> ShadowRays {
        ShadowRays {
            rays: Vec::with_capacity(n),
            light: Vec::with_capacity(n),
            blocked: Vec::with_capacity(n),
        }
    }

    /// Finds which rays are blocked: as a batch ([`Accelerator::occluded_incoherent`]), or one
    /// by one through their holes in a scene with cut-outs.
    fn trace<A: Accelerator + ?Sized>(&mut self, scene: &Scene, accel: &A) {
        self.blocked.clear();
        self.blocked.resize(self.rays.len(), false);
        if scene.has_cut_outs() {
            for (ray, blocked) in self.rays.iter().zip(&mut self.blocked) {
                *blocked = super::occluded_opaque(scene, accel, ray);
            }
        } else {
            accel.occluded_incoherent(&self.rays, &mut self.blocked);
        }
    }

    fn clear(&mut self) {
        self.rays.clear();
        self.light.clear();
    }

    /// Path `i`'s light sample, if it made one.
    #[inline]
    fn add(&mut self, i: usize, sample: Option<(Ray, Vec3)>) {
        if let Some((ray, contribution)) = sample {
            self.rays.push(ray);
            self.light.push((i, contribution));
        }
    }
}

/// The numbers a stage's vertices draw, in the scalar path's order: the light's choice and
/// point, the BSDF's lobe and direction, the roulette's number ([`VertexNumbers`]), vertex by
/// vertex.
struct Numbers {
    drawn: Vec<VertexNumbers>,
}

impl Numbers {
    fn with_capacity(n: usize) -> Numbers {
        Numbers { drawn: Vec::with_capacity(n) }
    }

    /// Draws each of `lanes`' numbers in one pass over their samplers.
    fn draw(&mut self, samplers: &mut [Sampler], lanes: &[usize]) {
        self.drawn.resize(lanes.len(), VertexNumbers::default());
        Sampler::next_vertex_each(samplers, lanes, &mut self.drawn);
    }

    /// The scalar path's light sample at vertex `v` (its numbers): the shadow ray and what it
    /// brings.
    #[inline]
    fn sample_light<A: Accelerator + ?Sized>(
        &self,
        path: &PathScalar<'_, A>,
        state: &PathState,
        vertex: &Vertex,
        v: usize,
    ) -> Option<(Ray, Vec3)> {
        let drawn = &self.drawn[v];
        path.sample_light_with(vertex, drawn.point, state.throughput)
    }

    /// The scalar path's BSDF sample and roulette at vertex `v` (its numbers): whether the path
    /// goes on.
    #[inline]
    fn bounce<A: Accelerator + ?Sized>(
        &self,
        path: &PathScalar<'_, A>,
        state: &mut PathState,
        vertex: &Vertex,
        v: usize,
    ) -> bool {
        let drawn = &self.drawn[v];
        path.bounce(state, vertex, drawn.lobe, drawn.direction)
            && path.survives_roulette(state, drawn.roulette)
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
    /// The sampler's numbers for every vertex (3).
    pub draws: Duration,
    /// Light sampling (the light's choice, its point, the BSDF's value and MIS), BSDF
    /// sampling and Russian roulette (4).
    pub shading: Duration,
    /// Occlusion of the shadow rays (5).
    pub occlusion: Duration,
    /// Paths traced (camera samples).
    pub paths: u64,
    /// Vertices scattered from.
    pub vertices: u64,
    /// Of those, the vertices whose light sample and bounce the lanes made whole: not left to
    /// the scalar steps for their light (a point light, a textured emitter) or an offset that
    /// overflowed.
    pub lanes: u64,
    /// Chunks of lanes shaded (each up to sixteen vertices of one BSDF kind): how full the
    /// vectors ran is `vertices / (16 · chunks)`.
    pub chunks: u64,
}

/// [`StageTimes`] as the threads add to it: nanoseconds.
#[derive(Debug, Default)]
struct StageClock {
    closest_hits: AtomicU64,
    surfaces: AtomicU64,
    draws: AtomicU64,
    shading: AtomicU64,
    occlusion: AtomicU64,
    paths: AtomicU64,
    vertices: AtomicU64,
    lanes: AtomicU64,
    chunks: AtomicU64,
}

impl StageClock {
    fn read(&self) -> StageTimes {
        let time = |t: &AtomicU64| Duration::from_nanos(t.load(Ordering::Relaxed));
        StageTimes {
            closest_hits: time(&self.closest_hits),
            surfaces: time(&self.surfaces),
            draws: time(&self.draws),
            shading: time(&self.shading),
            occlusion: time(&self.occlusion),
            paths: self.paths.load(Ordering::Relaxed),
            vertices: self.vertices.load(Ordering::Relaxed),
            lanes: self.lanes.load(Ordering::Relaxed),
            chunks: self.chunks.load(Ordering::Relaxed),
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
