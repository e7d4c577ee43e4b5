//! The wavefront's vertices, sixteen lanes per instruction, grouped by BSDF: the shading frame
//! and the direction toward the viewer (from the shading normal, the tangent where the BSDF is
//! anisotropic, and the arriving ray), light sampling (a triangle light's point or a direction
//! toward the constant environment, or any other light's sample as the scalar code made it;
//! the shadow ray, the BSDF's value and the MIS weight), BSDF sampling (the direction and the
//! next ray) and Russian roulette.
//!
//! ## Vertices in lanes
//! The vertices of one BSDF kind are gathered sixteen to a chunk (`Input`): every quantity a
//! row of sixteen floats (structure of arrays), `input.p.x[k]` the `x` of lane `k`'s point, the
//! BSDF's parameters too ([`LaneBsdf`]: a rough conductor's η, k, tint and roughnesses are
//! eleven rows). One function ([`shade_lane`], generic over the kind) says what happens to one
//! lane, in straight-line arithmetic whose branches are selects; a loop runs it over a chunk's
//! sixteen lanes, and the compiler turns the loop into vector code: one AVX-512 instruction per
//! operation for all sixteen lanes, two with AVX2. The same loop compiled for the baseline
//! instruction set is the scalar twin.
//!
//! Grouping by kind is what keeps the lanes full and each BSDF's code on whole vectors: a
//! chunk holds one kind's vertices, whichever paths they belong to.
//!
//! ## The scalar path's bits
//! `shade_lane` is the scalar path's arithmetic, operation for operation: it calls the same
//! frame ([`Frame::about`], [`Frame::new`], [`facing`]), the same BSDF methods (rebuilt from
//! their rows exactly, [`LaneBsdf::from_params`]), the same light sampling (`light::lanes`:
//! the same warps, the polynomial sines and cosines), the light's rescaled
//! number ([`rescaled`]), the same [`power_heuristic`] and the same ray offset
//! ([`offset_ray_origin_finite`]), and Rust neither fuses nor reorders floating-point
//! operations, in vector code or not. So a lane's shadow ray, contribution, next ray,
//! throughput, density, η and delta flag are those of [`PathScalar::sample_light_with`],
//! [`PathScalar::bounce`] and [`PathScalar::survives_roulette`] to the bit (`tests/wavefront.rs` compares
//! whole renders; `tests.rs` compares lanes of every kind on hostile inputs on every
//! instruction set).
//!
//! The lights the lanes do not sample themselves ([`LaneRole::Other`]: point, spot and
//! directional lights, suns, environment maps, textured emitters, solid-angle sampling) are
//! sampled by the scalar code for the chunk's lanes together before it is shaded
//! (`LightSet::sample_each`, the same numbers), and the lanes take the sample from there
//! (`GIVEN`): the direction, radiance, density, whether it is a delta light's, and the shadow
//! ray. What the lanes leave to the scalar code, lane by lane, is the rare point whose offset
//! is not finite (`exact` is false: the scalar offset's fallback decides it).
//!
//! [`PathScalar::sample_light_with`]: super::super::PathScalar
//! [`PathScalar::bounce`]: super::super::PathScalar
//! [`PathScalar::survives_roulette`]: super::super::PathScalar

use glam::{Vec2, Vec3};

use std::borrow::Cow;

use super::super::light_sampler::LanePick;
use super::super::path::{Frame, Vertex, facing};
use super::surface::LaneSurface;
use crate::cpu::Isa;
use crate::light::LightSample;
use crate::light::lanes::{LaneRole, LaneSample, sample_environment, sample_triangle};
use crate::material::lanes::{LaneBsdf, PARAMS};
use crate::ray::{Ray, SurfacePoint, offset_ray_origin_finite};
use crate::sampling::{power_heuristic, rescaled};

/// Lanes per chunk: one AVX-512 register of floats (the BSDFs' parameter rows have as many).
pub(super) const LANES: usize = crate::material::lanes::LANES;

/// One float per lane.
type Row = [f32; LANES];

/// A vector per lane, coordinate by coordinate.
#[derive(Clone, Copy, Debug, Default)]
struct Rows3 {
    x: Row,
    y: Row,
    z: Row,
}

impl Rows3 {
    #[inline(always)]
    fn get(&self, k: usize) -> Vec3 {
        Vec3::new(self.x[k], self.y[k], self.z[k])
    }

    #[inline(always)]
    fn set(&mut self, k: usize, v: Vec3) {
        self.x[k] = v.x;
        self.y[k] = v.y;
        self.z[k] = v.z;
    }
}

/// What a vertex needs: the vertex, its path, the light picked and the numbers drawn.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Input {
    /// The surface point, its rounding-error bound and geometric normal.
    p: Rows3,
    error: Rows3,
    normal: Rows3,
    /// The shading normal: the frame is its own ([`Frame::about`]), or where `anisotropic`
    /// the one `dp_du` orients ([`Frame::new`]).
    shading_normal: Rows3,
    anisotropic: [bool; LANES],
    dp_du: Rows3,
    /// Whether the material is two-sided (directions are mirrored into its front).
    two_sided: [bool; LANES],
    /// The direction of the ray that arrived (not normalized).
    arrival: Rows3,
    /// The BSDF's parameters ([`LaneBsdf::to_params`]).
    params: [Row; PARAMS],
    throughput: Rows3,
    eta: Row,
    /// Whether Russian roulette plays after this vertex's bounce.
    roulette: [bool; LANES],
    /// Whether the lane samples a light (the next fields): a triangle, or where
    /// `environment` the constant environment (its radiance, selection and start alone).
    has_light: [bool; LANES],
    environment: [bool; LANES],
    v0: Rows3,
    v1: Rows3,
    v2: Rows3,
    light_normal: Rows3,
    light_error: Rows3,
    area: Row,
    radiance: Rows3,
    selection: Row,
    /// Where the light's share of the first number starts.
    start: Row,
    /// Whether the lane's light sample is given (a light the lanes do not sample themselves,
    /// sampled by the scalar code before the chunk is shaded: `LaneDraws::given`), and then
    /// whether there is one, its direction, density (the pick's probability included), whether
    /// it is a delta light's, and its shadow ray; its radiance is in `radiance`.
    given: [bool; LANES],
    given_found: [bool; LANES],
    given_direction: Rows3,
    given_pdf: Row,
    given_delta: [bool; LANES],
    given_origin: Rows3,
    given_shadow: Rows3,
    given_t_max: Row,
    /// The numbers: the light's point, the BSDF's lobe and direction, the roulette's.
    u_point: [Row; 2],
    u_lobe: Row,
    u_direction: [Row; 2],
    u_roulette: Row,
}

/// What became of a vertex.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Output {
    /// The shadow ray (a segment to `origin + direction`, `SHADOW_RAY_LENGTH` of it; toward
    /// the environment a ray without end) and the light it brings if unblocked, where
    /// `shadowed`.
    shadow_origin: Rows3,
    shadow_direction: Rows3,
    shadow_t_max: Row,
    contribution: Rows3,
    shadowed: [bool; LANES],
    /// The next ray, the throughput after the bounce and the roulette, the BSDF sample's
    /// density and whether it was a delta lobe's, and the path's η after it, where `goes_on`.
    origin: Rows3,
    direction: Rows3,
    throughput: Rows3,
    pdf: Row,
    delta: [bool; LANES],
    eta: Row,
    goes_on: [bool; LANES],
    /// False where an offset point was not finite: the scalar code must decide the lane.
    exact: [bool; LANES],
}

/// Lane `k`'s frame, whether it is mirrored and the direction toward the viewer, as
/// `PathScalar::vertex` makes them (`shading_frame`: the tangent's frame only for an anisotropic
/// BSDF, then [`facing`]), and its BSDF rebuilt from its rows.
#[inline(always)]
fn vertex_of<B: LaneBsdf>(input: &Input, k: usize) -> (Frame, bool, Vec3, B) {
    let normal = input.shading_normal.get(k);
    let frame = if B::ANISOTROPIC && input.anisotropic[k] {
        Frame::new(normal, input.dp_du.get(k))
    } else {
        Frame::about(normal)
    };
    let (frame, flip, wi) = facing(input.two_sided[k], input.arrival.get(k), frame);
    (frame, flip, wi, B::from_params(&std::array::from_fn(|j| input.params[j][k])))
}

/// One lane's shading: light sampling, BSDF sampling and roulette, as the scalar path does them
/// (see the module documentation).
#[inline(always)]
fn shade_lane<B: LaneBsdf, const SKY: bool, const GIVEN: bool>(
    input: &Input,
    output: &mut Output,
    k: usize,
) {
    let point =
        SurfacePoint { p: input.p.get(k), error: input.error.get(k), normal: input.normal.get(k) };
    let (frame, flip, wi, bsdf) = vertex_of::<B>(input, k);
    let throughput = input.throughput.get(k);

    // The light's sample (`light::lanes`): a triangle by area, or where the chunk has lanes
    // that sample it (`SKY`) the constant environment, or where it has lanes whose sample is
    // given (`GIVEN`) that sample.
    let u_x = rescaled(input.u_point[0][k], input.start[k], input.selection[k]);
    let u = Vec2::new(u_x, input.u_point[1][k]);
    let corners = [input.v0.get(k), input.v1.get(k), input.v2.get(k)];
    let (normal, error) = (input.light_normal.get(k), input.light_error.get(k));
    let triangle = sample_triangle(corners, normal, error, input.area[k], &point, u);
    let sky = sample_environment(&point, u);
    let LaneSample {
        direction,
        pdf: light_pdf,
        faces,
        shadow_origin,
        shadow_direction,
        shadow_t_max,
        finite: shadow_finite,
    } = if SKY && input.environment[k] { sky } else { triangle };
    let light_pdf = input.selection[k] * light_pdf;
    // (The given sample's rows are read whatever the lane, then chosen: loads under a
    // condition kept the loop from becoming vector code.)
    let given = GIVEN && input.given[k];
    let given_light = (input.given_direction.get(k), input.given_pdf[k], input.given_found[k]);
    let given_shadow = (input.given_origin.get(k), input.given_shadow.get(k), input.given_t_max[k]);
    let given_delta = input.given_delta[k];
    let (direction, light_pdf, faces) =
        if given { given_light } else { (direction, light_pdf, faces) };
    let (shadow_origin, shadow_direction, shadow_t_max, shadow_finite) = match given {
        true => (given_shadow.0, given_shadow.1, given_shadow.2, true),
        false => (shadow_origin, shadow_direction, shadow_t_max, shadow_finite),
    };
    // PathScalar::sample_light_with (which a BSDF of delta lobes alone skips).
    let mut wo = frame.to_local(direction);
    if flip {
        wo.z = -wo.z;
    }
    let f = bsdf.eval(wi, wo);
    let weight = power_heuristic(light_pdf, bsdf.pdf(wi, wo));
    // A delta light's sample has weight 1 (only light sampling finds it).
    let weight = if given & given_delta { 1.0 } else { weight };
    let contribution = throughput * f * input.radiance.get(k) * (weight / light_pdf);
    let shadowed = B::SMOOTH && input.has_light[k] && faces && f != Vec3::ZERO;

    // PathScalar::bounce.
    let u = Vec2::new(input.u_direction[0][k], input.u_direction[1][k]);
    let (sampled, mut wo, pdf, weight, delta, eta) = match bsdf.sample(wi, input.u_lobe[k], u) {
        Some(s) => (true, s.wo, s.pdf, s.weight, s.delta, s.eta),
        None => (false, Vec3::Z, 0.0, Vec3::ZERO, false, 1.0),
    };
    if flip {
        wo.z = -wo.z;
    }
    let direction = frame.to_world(wo);
    let mut next_throughput = throughput * weight;
    let eta = input.eta[k] * eta;
    let (origin, finite) = offset_ray_origin_finite(&point, direction);
    let throughput_max = next_throughput.max_element();
    let bounced = sampled && throughput_max > 0.0 && throughput_max.is_finite();
    // PathScalar::survives_roulette.
    let mut survives = true;
    if input.roulette[k] {
        let q = (throughput_max * eta * eta).min(0.95);
        if input.u_roulette[k] >= q {
            survives = false;
        } else {
            next_throughput /= q;
        }
    }

    output.shadow_origin.set(k, shadow_origin);
    output.shadow_direction.set(k, shadow_direction);
    output.shadow_t_max[k] = shadow_t_max;
    output.contribution.set(k, contribution);
    output.shadowed[k] = shadowed;
    output.origin.set(k, origin);
    output.direction.set(k, direction);
    output.throughput.set(k, next_throughput);
    output.pdf[k] = pdf;
    output.delta[k] = delta;
    output.eta[k] = eta;
    output.goes_on[k] = bounced && survives;
    output.exact[k] = (!shadowed || shadow_finite) && (!bounced || finite);
}

/// Every lane of a chunk. Input and output apart, so that the compiler knows the stores
/// cannot change the loads: then the loop becomes vector code (with the two in one struct it
/// stayed scalar, "too many memory checks needed").
#[inline(always)]
fn shade_chunk<B: LaneBsdf, const SKY: bool, const GIVEN: bool>(
    input: &Input,
    output: &mut Output,
) {
    for k in 0..LANES {
        shade_lane::<B, SKY, GIVEN>(input, output, k);
    }
}

/// [`shade_chunk`] compiled for AVX-512: sixteen lanes per instruction. Never inlined: its
/// arguments' promise not to overlap is what lets the loop be vectorized.
///
/// # Safety
/// The CPU must support AVX2 and AVX-512 F and VL ([`Isa::Avx512`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl")]
#[inline(never)]
unsafe fn shade_chunk_avx512<B: LaneBsdf, const SKY: bool, const GIVEN: bool>(
    input: &Input,
    output: &mut Output,
) {
    shade_chunk::<B, SKY, GIVEN>(input, output);
}

/// [`shade_chunk`] compiled for AVX2: eight lanes per instruction.
///
/// # Safety
/// The CPU must support AVX2 ([`Isa::Avx2`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline(never)]
unsafe fn shade_chunk_avx2<B: LaneBsdf, const SKY: bool, const GIVEN: bool>(
    input: &Input,
    output: &mut Output,
) {
    shade_chunk::<B, SKY, GIVEN>(input, output);
}

/// The baseline build of [`shade_chunk`]: the scalar twin (SSE2 on x86-64, four lanes where
/// the compiler finds it pays).
#[inline(never)]
fn shade_chunk_baseline<B: LaneBsdf, const SKY: bool, const GIVEN: bool>(
    input: &Input,
    output: &mut Output,
) {
    shade_chunk::<B, SKY, GIVEN>(input, output);
}

/// [`shade_chunk`] compiled for `isa`.
///
/// # Safety
/// The CPU must support `isa`.
#[inline(always)]
unsafe fn shade_chunk_on<B: LaneBsdf, const SKY: bool, const GIVEN: bool>(
    isa: Isa,
    input: &Input,
    output: &mut Output,
) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the caller's guarantee.
        Isa::Avx512 => unsafe { shade_chunk_avx512::<B, SKY, GIVEN>(input, output) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above.
        Isa::Avx2 => unsafe { shade_chunk_avx2::<B, SKY, GIVEN>(input, output) },
        _ => shade_chunk_baseline::<B, SKY, GIVEN>(input, output),
    }
}

/// A wavefront's vertices of one BSDF kind in lanes: gathered ([`push`](Self::push)), shaded
/// together ([`shade`](Self::shade), with the kind's code), then read back lane by lane
/// ([`result`](Self::result)).
#[derive(Debug, Default)]
pub(super) struct VertexLanes {
    inputs: Vec<Input>,
    outputs: Vec<Output>,
    len: usize,
}

/// A vertex's path, as [`VertexLanes::push`] takes it with the vertex.
pub(super) struct LaneVertex {
    /// The direction of the ray that arrived.
    pub arrival: Vec3,
    pub throughput: Vec3,
    pub eta: f32,
    pub roulette: bool,
}

/// A lane's light and numbers, as [`VertexLanes::set_draws`] takes them.
pub(super) struct LaneDraws<'a> {
    pub light: LanePick<'a>,
    /// For a light the lanes leave to the scalar code ([`LaneRole::Other`]), its sample as
    /// `LightSet::sample` made it from the same numbers (`None`: it gave none, or the lane's
    /// BSDF has delta lobes alone, which sample no light); the lanes take it from there.
    pub given: Option<LightSample>,
    /// The light's numbers as drawn (the lanes rescale the first within the light's share).
    pub u_point: Vec2,
    pub u_lobe: f32,
    pub u_direction: Vec2,
    pub u_roulette: f32,
}

/// A path's next segment, as a lane's BSDF sample and roulette leave it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Next {
    pub ray: Ray,
    pub throughput: Vec3,
    /// The BSDF sample's density, and whether it came from a delta lobe.
    pub pdf: f32,
    pub delta: bool,
    /// The path's η after the sample.
    pub eta: f32,
}

/// What [`VertexLanes::result`] gives for a lane.
pub(super) struct LaneResult {
    /// The shadow ray and what it brings if unblocked.
    pub shadow: Option<(Ray, Vec3)>,
    /// The next segment, if the path goes on.
    pub next: Option<Next>,
    /// False where the scalar code must decide the lane instead.
    pub exact: bool,
    /// Whether the lanes made the lane's light sample's contribution (any light: the scalar
    /// code samples the lights the lanes do not, and the lanes take the sample from there).
    pub light_in_lanes: bool,
}

impl VertexLanes {
    /// No lanes.
    pub(super) fn clear(&mut self) {
        self.len = 0;
    }

    /// Lanes gathered.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Adds a lane (the next index).
    #[inline(always)]
    pub(super) fn push(&mut self, surface: &LaneSurface, v: &LaneVertex) {
        let (c, k) = (self.len / LANES, self.len % LANES);
        if c == self.inputs.len() {
            self.inputs.push(Input::default());
            self.outputs.push(Output::default());
        }
        self.len += 1;
        let input = &mut self.inputs[c];
        input.p.set(k, surface.point.p);
        input.error.set(k, surface.point.error);
        input.normal.set(k, surface.point.normal);
        input.shading_normal.set(k, surface.normal);
        input.anisotropic[k] = surface.tangent.is_some();
        if let Some(tangent) = surface.tangent {
            input.dp_du.set(k, tangent);
        }
        input.two_sided[k] = surface.two_sided;
        input.arrival.set(k, v.arrival);
        crate::material::lanes::store(&surface.bsdf, &mut input.params, k);
        input.throughput.set(k, v.throughput);
        input.eta[k] = v.eta;
        input.roulette[k] = v.roulette;
    }

    /// Gives lane `i` its light and numbers.
    #[inline(always)]
    pub(super) fn set_draws(&mut self, i: usize, draws: &LaneDraws) {
        let input = &mut self.inputs[i / LANES];
        let k = i % LANES;
        // Every light's record whole, whatever its role, without a branch on it (the lanes
        // pick lights at random): a lane without a light in lanes computes a harmless one
        // (zeros) that `has_light` discards, and an environment lane a zero triangle that its
        // `sky` select discards.
        let LanePick { light, selection, start } = draws.light;
        input.v0.set(k, light.corners[0]);
        input.v1.set(k, light.corners[1]);
        input.v2.set(k, light.corners[2]);
        input.light_normal.set(k, light.normal);
        input.light_error.set(k, light.error);
        input.area[k] = light.area;
        input.radiance.set(k, light.radiance);
        input.selection[k] = selection;
        input.start[k] = start;
        input.has_light[k] = light.role != LaneRole::Nothing;
        input.environment[k] = light.role == LaneRole::Environment;
        input.given[k] = light.role == LaneRole::Other;
        input.given_found[k] = draws.given.is_some();
        if let Some(sample) = &draws.given {
            input.radiance.set(k, sample.radiance);
            input.given_direction.set(k, sample.direction);
            input.given_pdf[k] = sample.pdf;
            input.given_delta[k] = sample.delta;
            input.given_origin.set(k, sample.shadow_ray.origin);
            input.given_shadow.set(k, sample.shadow_ray.direction);
            input.given_t_max[k] = sample.shadow_ray.t_max;
        }
        input.u_point[0][k] = draws.u_point.x;
        input.u_point[1][k] = draws.u_point.y;
        input.u_lobe[k] = draws.u_lobe;
        input.u_direction[0][k] = draws.u_direction.x;
        input.u_direction[1][k] = draws.u_direction.y;
        input.u_roulette[k] = draws.u_roulette;
    }

    /// Lane `i`'s vertex, for the scalar steps ([`LaneRole::Other`] lights, lanes that are not
    /// exact); `B` is the lanes' kind.
    pub(super) fn vertex<B: LaneBsdf>(&self, i: usize) -> Vertex<'static> {
        let (input, k) = (&self.inputs[i / LANES], i % LANES);
        let (frame, flip, wi, bsdf) = vertex_of::<B>(input, k);
        Vertex {
            point: SurfacePoint {
                p: input.p.get(k),
                error: input.error.get(k),
                normal: input.normal.get(k),
            },
            frame,
            flip,
            wi,
            bsdf: Cow::Owned(bsdf.into_bsdf()),
        }
    }

    /// Lane `i`'s surface point.
    #[inline]
    pub(super) fn surface_point(&self, i: usize) -> SurfacePoint {
        let (input, k) = (&self.inputs[i / LANES], i % LANES);
        SurfacePoint { p: input.p.get(k), error: input.error.get(k), normal: input.normal.get(k) }
    }

    /// Lane `i`'s point.
    #[inline]
    pub(super) fn point(&self, i: usize) -> Vec3 {
        self.inputs[i / LANES].p.get(i % LANES)
    }

    /// Shades every lane with kind `B`'s code, on the instruction set `isa` (which the CPU must
    /// support).
    pub(super) fn shade<B: LaneBsdf>(&mut self, isa: Isa) {
        let n = self.len.div_ceil(LANES);
        assert!(isa.is_supported(), "{} is not supported by this CPU", isa.name());
        for (c, (input, output)) in self.inputs[..n].iter().zip(&mut self.outputs[..n]).enumerate()
        {
            // The environment's code only where a lane in use samples it.
            let used = (self.len - c * LANES).min(LANES);
            let sky = input.environment[..used].contains(&true);
            let given = input.given[..used].contains(&true);
            match (sky, given) {
                // SAFETY: the CPU supports the instruction set (asserted above).
                (false, false) => unsafe { shade_chunk_on::<B, false, false>(isa, input, output) },
                // SAFETY: as above.
                (true, false) => unsafe { shade_chunk_on::<B, true, false>(isa, input, output) },
                // SAFETY: as above.
                (false, true) => unsafe { shade_chunk_on::<B, false, true>(isa, input, output) },
                // SAFETY: as above.
                (true, true) => unsafe { shade_chunk_on::<B, true, true>(isa, input, output) },
            }
        }
    }

    /// Lane `i`'s result, after [`shade`](Self::shade).
    #[inline(always)]
    pub(super) fn result(&self, i: usize) -> LaneResult {
        let (c, k) = (i / LANES, i % LANES);
        let output = &self.outputs[c];
        let shadow = output.shadowed[k].then(|| {
            let (origin, direction) = (output.shadow_origin.get(k), output.shadow_direction.get(k));
            (Ray::segment(origin, direction, output.shadow_t_max[k]), output.contribution.get(k))
        });
        let next = output.goes_on[k].then(|| Next {
            ray: Ray::new(output.origin.get(k), output.direction.get(k)),
            throughput: output.throughput.get(k),
            pdf: output.pdf[k],
            delta: output.delta[k],
            eta: output.eta[k],
        });
        let light_in_lanes = self.inputs[c].has_light[k];
        LaneResult { shadow, next, exact: output.exact[k], light_in_lanes }
    }
}

#[cfg(test)]
mod tests;
