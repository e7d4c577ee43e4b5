//! The wavefront's stages over one tile of paths ([`Stages::run`]): closest hits, surfaces,
//! draws, shading and occlusion, as the module documentation of `wavefront` numbers them, with
//! the buffers they pass between them.

use std::sync::atomic::Ordering;

use glam::{Vec2, Vec3};

use super::clock::{Lap, StageClock};
use super::vertices::{self, LaneDraws, LaneVertex, VertexLanes};
use crate::accel::{Accelerator, Hit};
use crate::cpu::Isa;
use crate::integrator::path::{PathScalar, PathState, Vertex};
use crate::integrator::{closest_opaque_hit, occluded_opaque};
use crate::light::Emission;
use crate::light::lanes::LaneRole;
use crate::material::BsdfKind;
use crate::material::lanes::LaneBsdf;
use crate::ray::{Ray, SurfacePoint};
use crate::sampling::{Sampler, VertexNumbers};
use crate::scene::Scene;

/// The stages of one tile's paths (see the module documentation), run by [`run`](Self::run):
/// the scalar path tracer whose steps they are, the instruction set of the lanes, and the clock
/// when stage times are measured.
pub(super) struct Stages<'p, 'a, A: ?Sized> {
    pub(super) path: &'p PathScalar<'a, A>,
    pub(super) isa: Isa,
    pub(super) times: Option<&'p StageClock>,
}

/// A tile's paths and the stages' buffers, made per tile (a thread-local set reused from tile
/// to tile was no faster).
struct Tile {
    states: Vec<PathState>,
    /// The paths still tracing, by index.
    alive: Vec<usize>,
    /// The rays of the paths still tracing, after the camera rays.
    batch: Vec<Ray>,
    hits: Vec<Option<Hit>>,
    shadows: ShadowRays,
    numbers: Numbers,
    /// The vertices in lanes, a set for each BSDF kind, and their paths.
    sets: [(VertexLanes, Vec<usize>); BsdfKind::ALL.len()],
    /// The paths that go on after this bounce.
    bounced: Vec<usize>,
    /// The paths that left the scene at this bounce, their directions and what they find.
    escaped: Vec<usize>,
    directions: Vec<Vec3>,
    emissions: Vec<Emission>,
}

impl Tile {
    fn new(rays: &[Ray]) -> Tile {
        let n = rays.len();
        Tile {
            states: PathState::starting(rays),
            alive: (0..n).collect(),
            batch: Vec::with_capacity(n),
            hits: Vec::with_capacity(n),
            shadows: ShadowRays::with_capacity(n),
            numbers: Numbers::with_capacity(n),
            sets: std::array::from_fn(|_| (VertexLanes::default(), Vec::new())),
            bounced: Vec::with_capacity(n),
            escaped: Vec::with_capacity(n),
            directions: Vec::with_capacity(n),
            emissions: Vec::with_capacity(n),
        }
    }
}

impl<A: Accelerator + ?Sized> Stages<'_, '_, A> {
    /// The colours of `rays` (camera rays, each with its sampler), a tile's paths advanced
    /// together until every one has ended: stage 1, stages 2 to 4, stage 5, over again.
    pub(super) fn run(&self, rays: &[Ray], samplers: &mut [Sampler], out: &mut [Vec3]) {
        assert_eq!(rays.len(), out.len(), "one colour per ray");
        assert_eq!(rays.len(), samplers.len(), "one sampler per ray");
        let path = self.path;
        if path.settings().max_depth == Some(0) {
            out.fill(Vec3::ZERO);
            return;
        }
        let mut tile = Tile::new(rays);
        let mut first = true;
        let mut lap = Lap::start(self.times);
        while !tile.alive.is_empty() {
            self.closest_hits(&mut tile, rays, first);
            first = false;
            lap.end(|t| &t.closest_hits);
            self.surfaces(&mut tile, samplers, &mut lap);
            self.occlusion(&mut tile);
            lap.end(|t| &t.occlusion);
        }
        for (state, colour) in tile.states.iter().zip(out) {
            *colour = path.finish(state.radiance);
        }
        if let Some(times) = self.times {
            times.paths.fetch_add(rays.len() as u64, Ordering::Relaxed);
        }
    }

    /// Stage 1, closest hits, as a batch: the camera rays as they came (every path, in order),
    /// the later rays gathered from the paths still tracing.
    #[inline(always)]
    fn closest_hits(&self, tile: &mut Tile, rays: &[Ray], first: bool) {
        let (scene, accel) = (self.path.scene(), self.path.accel());
        let Tile { states, alive, batch, hits, .. } = tile;
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
            for (ray, hit) in batch.iter().zip(hits.iter_mut()) {
                *hit = closest_opaque_hit(scene, accel, ray);
            }
        } else if first {
            // Camera rays are coherent: packets pay (see the module documentation).
            accel.closest_hits(batch, hits);
        } else {
            accel.closest_hits_incoherent(batch, hits);
        }
    }

    /// Stages 2 to 4: light found; paths that leave the scene or reach the depth limit end. Vertices go
    /// straight into the lanes of their BSDF's kind and are shaded sixteen at a time
    /// ([`shade_kind`](Self::shade_kind): draws, then shading) as soon as a chunk is full,
    /// while its rows are in the first-level cache; the last chunks of each kind after. The
    /// paths that go on are the next stage's `alive`.
    #[inline(always)]
    fn surfaces(&self, tile: &mut Tile, samplers: &mut [Sampler], lap: &mut Lap) {
        let path = self.path;
        let max_depth = path.settings().max_depth.unwrap_or(u32::MAX);
        let rr_depth = path.settings().rr_depth;
        let Tile {
            states,
            alive,
            hits,
            shadows,
            numbers,
            sets,
            bounced,
            escaped,
            directions,
            emissions,
            ..
        } = tile;
        shadows.clear();
        bounced.clear();
        escaped.clear();
        let mut chunk = Chunk { states, samplers, numbers, shadows, bounced, lap };
        for (&i, hit) in alive.iter().zip(hits.iter()) {
            if hit.is_none() {
                // It left the scene: what it finds there, with the others' (below).
                escaped.push(i);
                continue;
            }
            let state = &mut chunk.states[i];
            let last = state.depth + 1 >= max_depth;
            // The commonest hits, an unplaced triangle of a material without a normal map, by
            // the shortcut: nothing is emitted there, so at the depth limit it needs nothing at
            // all. Any other hit by the general steps.
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
            let kind = surface.bsdf.kind();
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
            if set.len() == vertices::LANES {
                chunk.lap.end(|t| &t.surfaces);
                self.shade_kind(kind, &mut chunk, set, paths);
                set.clear();
                paths.clear();
            }
        }
        path.escape_each(chunk.states, escaped, directions, emissions);
        chunk.lap.end(|t| &t.surfaces);
        for (kind, (set, paths)) in BsdfKind::ALL.into_iter().zip(sets.iter_mut()) {
            if set.len() > 0 {
                self.shade_kind(kind, &mut chunk, set, paths);
                set.clear();
                paths.clear();
            }
        }
        std::mem::swap(alive, bounced);
    }

    /// Stage 5: occlusion of the shadow rays, and the light they bring.
    #[inline(always)]
    fn occlusion(&self, tile: &mut Tile) {
        let Tile { states, shadows, .. } = tile;
        shadows.trace(self.path.scene(), self.path.accel());
        for (&blocked, &(i, contribution)) in shadows.blocked.iter().zip(&shadows.light) {
            if !blocked {
                states[i].radiance += contribution;
            }
        }
    }

    /// [`shade_lanes`](Self::shade_lanes) with the code of `kind`'s BSDF.
    #[inline(never)]
    fn shade_kind(
        &self,
        kind: BsdfKind,
        chunk: &mut Chunk,
        lanes: &mut VertexLanes,
        paths: &[usize],
    ) {
        crate::material::with_bsdf_type!(kind, B => self.shade_lanes::<B>(chunk, lanes, paths))
    }

    /// Draws the numbers of `lanes` (the vertices of `paths`, whose BSDFs are `B`s), shades
    /// them, and takes their results: shadow rays, and the next rays of the paths that go on.
    #[inline(never)]
    fn shade_lanes<B: LaneBsdf>(
        &self,
        chunk: &mut Chunk,
        lanes: &mut VertexLanes,
        paths: &[usize],
    ) {
        let path = self.path;
        chunk.numbers.draw(chunk.samplers, paths);
        chunk.lap.end(|t| &t.draws);
        // The lanes the scalar steps decide in part or whole (for the stage table).
        debug_assert!(paths.len() <= vertices::LANES, "a chunk at a time");
        let mut scalar = 0u32;
        // The lights the lanes do not sample themselves: the scalar code samples them, for the
        // chunk's lanes together (`LightSet::sample_each`), and the lanes take the samples from
        // there (a BSDF of delta lobes alone samples no light).
        let mut picks = [None; vertices::LANES];
        let nowhere = SurfacePoint { p: Vec3::ZERO, error: Vec3::ZERO, normal: Vec3::ZERO };
        let mut others = [0usize; vertices::LANES];
        let (mut points, mut us) = ([nowhere; vertices::LANES], [Vec2::ZERO; vertices::LANES]);
        let mut n = 0;
        for (lane, pick) in picks[..paths.len()].iter_mut().enumerate() {
            let drawn = chunk.numbers.drawn[lane];
            let light = path.lights().pick_for_lanes(drawn.point);
            if B::SMOOTH && light.role() == LaneRole::Other {
                (others[n], points[n], us[n]) = (lane, lanes.surface_point(lane), drawn.point);
                n += 1;
            }
            *pick = Some(light);
        }
        let mut given = [None; vertices::LANES];
        path.lights().sample_each(&points[..n], &us[..n], &mut given[..n]);
        let mut next = 0;
        for (lane, pick) in picks[..paths.len()].iter().enumerate() {
            let drawn = chunk.numbers.drawn[lane];
            let given = match others[..n].get(next) {
                Some(&other) if other == lane => {
                    next += 1;
                    given[next - 1]
                }
                _ => None,
            };
            lanes.set_draws(
                lane,
                &LaneDraws {
                    light: pick.expect("picked above"),
                    given,
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
        if let Some(times) = self.times {
            let vertices = paths.len() as u64;
            times.vertices.fetch_add(vertices, Ordering::Relaxed);
            times.lanes.fetch_add(vertices - u64::from(scalar.count_ones()), Ordering::Relaxed);
            times.chunks.fetch_add(1, Ordering::Relaxed);
        }
        chunk.lap.end(|t| &t.shading);
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
                *blocked = occluded_opaque(scene, accel, ray);
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
