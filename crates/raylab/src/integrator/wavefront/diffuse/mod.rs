//! The wavefront's diffuse vertices, sixteen lanes per instruction: the shading frame and the
//! direction toward the viewer (from the shading normal and the arriving ray), light sampling (a
//! triangle light's point, the shadow ray, the BSDF's value and the MIS weight), BSDF sampling
//! (the cosine-weighted direction and the next ray) and Russian roulette.
//!
//! ## Lanes
//! The vertices are gathered sixteen to a [`Chunk`]: every quantity a row of sixteen floats
//! (structure of arrays), `chunk.input.p.x[k]` the `x` of lane `k`'s point. One function
//! ([`shade_lane`]) says what happens to one lane, in straight-line arithmetic whose branches
//! are selects; a loop runs it over a chunk's sixteen lanes, and the compiler turns the loop
//! into vector code: one AVX-512 instruction per operation for all sixteen lanes, two with
//! AVX2. The same loop compiled for the baseline instruction set is the scalar twin.
//!
//! ## The scalar path's bits
//! `shade_lane` is the scalar path's arithmetic, operation for operation: it calls the same
//! frame ([`Frame::about`], [`facing`]), the same [`Diffuse`] BSDF, the same warps
//! ([`square_to_uniform_triangle`], [`square_to_cosine_hemisphere`] with its polynomial sine and
//! cosine), the light's rescaled number ([`rescaled`]), the same
//! [`power_heuristic`] and the same ray offset ([`offset_ray_origin_finite`]), and Rust neither
//! fuses nor reorders floating-point operations, in vector code or not. So a lane's shadow ray,
//! contribution, next ray and throughput are those of [`Path::sample_light_with`],
//! [`Path::bounce`] and [`Path::survives_roulette`] to the bit (`tests/wavefront.rs` compares
//! whole renders; `tests.rs` compares lanes on hostile inputs on every instruction set).
//!
//! What the lanes cannot do they leave to the scalar code, lane by lane: a light other than a
//! triangle sampled by area with a constant radiance ([`LanePick::Other`]), and the rare point
//! whose offset is not finite (`exact` is false: the scalar offset's fallback decides it).
//!
//! [`Path::sample_light_with`]: super::super::Path
//! [`Path::bounce`]: super::super::Path
//! [`Path::survives_roulette`]: super::super::Path

use glam::{Vec2, Vec3};

use std::borrow::Cow;

use super::super::light_sampler::{LanePick, SHADOW_RAY_LENGTH};
use super::super::path::{DiffuseSurface, Frame, Vertex, facing};
use crate::cpu::Isa;
use crate::material::{Bsdf, Diffuse};
use crate::ray::{Ray, SurfacePoint, offset_ray_origin_finite};
#[cfg(doc)]
use crate::sampling::square_to_cosine_hemisphere;
use crate::sampling::{power_heuristic, rescaled, square_to_uniform_triangle};

/// Lanes per chunk: one AVX-512 register of floats.
pub(super) const LANES: usize = 16;

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

/// What a diffuse vertex needs: the vertex, its path, the light picked and the numbers drawn.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Input {
    /// The surface point, its rounding-error bound and geometric normal.
    p: Rows3,
    error: Rows3,
    normal: Rows3,
    /// The shading normal: the frame is its own ([`Frame::about`]).
    shading_normal: Rows3,
    /// Whether the material is two-sided (directions are mirrored into its front).
    two_sided: [bool; LANES],
    /// The direction of the ray that arrived (not normalized).
    arrival: Rows3,
    reflectance: Rows3,
    throughput: Rows3,
    eta: Row,
    /// Whether Russian roulette plays after this vertex's bounce.
    roulette: [bool; LANES],
    /// Whether the lane samples a triangle light (the next fields).
    has_light: [bool; LANES],
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
    /// The numbers: the light's point, the BSDF's direction, the roulette's.
    u_point: [Row; 2],
    u_direction: [Row; 2],
    u_roulette: Row,
}

/// What became of a diffuse vertex.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Output {
    /// The shadow ray (a segment to `origin + direction`, [`SHADOW_RAY_LENGTH`] of it) and the
    /// light it brings if unblocked, where `shadowed`.
    shadow_origin: Rows3,
    shadow_direction: Rows3,
    contribution: Rows3,
    shadowed: [bool; LANES],
    /// The next ray, the throughput after the bounce and the roulette, and the BSDF sample's
    /// density, where `goes_on`.
    origin: Rows3,
    direction: Rows3,
    throughput: Rows3,
    pdf: Row,
    goes_on: [bool; LANES],
    /// False where an offset point was not finite: the scalar code must decide the lane.
    exact: [bool; LANES],
}

/// One lane's shading: light sampling, BSDF sampling and roulette, as the scalar path does them
/// (see the module documentation).
#[inline(always)]
fn shade_lane(input: &Input, output: &mut Output, k: usize) {
    let point =
        SurfacePoint { p: input.p.get(k), error: input.error.get(k), normal: input.normal.get(k) };
    // Path::vertex's frame, mirroring and direction toward the viewer.
    let (frame, flip, wi) =
        facing(input.two_sided[k], input.arrival.get(k), Frame::about(input.shading_normal.get(k)));
    let Frame { tangent, bitangent, normal } = frame;
    let bsdf = Diffuse { reflectance: input.reflectance.get(k) };
    let throughput = input.throughput.get(k);

    // LightSet::sample's triangle, sampled by area.
    let u_x = rescaled(input.u_point[0][k], input.start[k], input.selection[k]);
    let u = Vec2::new(u_x, input.u_point[1][k]);
    let [b0, b1, b2] = square_to_uniform_triangle(u);
    let target = b0 * input.v0.get(k) + b1 * input.v1.get(k) + b2 * input.v2.get(k);
    let to_light = target - point.p;
    let distance_squared = to_light.length_squared();
    let direction = to_light / distance_squared.sqrt();
    let light_normal = input.light_normal.get(k);
    let cos_light = -direction.dot(light_normal);
    // The scalar test's very words: a NaN cosine passes it, as it passes the scalar one.
    #[allow(clippy::nonminimal_bool, clippy::neg_cmp_op_on_partial_ord)]
    let faces = !(cos_light <= 0.0 || !distance_squared.is_normal());
    let end = SurfacePoint { p: target, error: input.light_error.get(k), normal: light_normal };
    let (end, end_finite) = offset_ray_origin_finite(&end, point.p - target);
    let (shadow_origin, origin_finite) = offset_ray_origin_finite(&point, end - point.p);
    let light_pdf = input.selection[k] * (distance_squared / (cos_light * input.area[k]));
    // Path::sample_light_with.
    let mut wo = Vec3::new(direction.dot(tangent), direction.dot(bitangent), direction.dot(normal));
    if flip {
        wo.z = -wo.z;
    }
    let f = bsdf.eval(wi, wo);
    let weight = power_heuristic(light_pdf, bsdf.pdf(wi, wo));
    let contribution = throughput * f * input.radiance.get(k) * (weight / light_pdf);
    let shadowed = input.has_light[k] && faces && f != Vec3::ZERO;

    // Path::bounce.
    let u = Vec2::new(input.u_direction[0][k], input.u_direction[1][k]);
    let (sampled, mut wo, pdf, weight) = match bsdf.sample(wi, 0.0, u) {
        Some(sample) => (true, sample.wo, sample.pdf, sample.weight),
        None => (false, Vec3::Z, 0.0, Vec3::ZERO),
    };
    if flip {
        wo.z = -wo.z;
    }
    let direction = wo.x * tangent + wo.y * bitangent + wo.z * normal;
    let mut next_throughput = throughput * weight;
    let (origin, finite) = offset_ray_origin_finite(&point, direction);
    let throughput_max = next_throughput.max_element();
    let bounced = sampled && throughput_max > 0.0 && throughput_max.is_finite();
    // Path::survives_roulette (the diffuse BSDF leaves η alone).
    let mut survives = true;
    if input.roulette[k] {
        let eta = input.eta[k];
        let q = (throughput_max * eta * eta).min(0.95);
        if input.u_roulette[k] >= q {
            survives = false;
        } else {
            next_throughput /= q;
        }
    }

    output.shadow_origin.set(k, shadow_origin);
    output.shadow_direction.set(k, end - shadow_origin);
    output.contribution.set(k, contribution);
    output.shadowed[k] = shadowed;
    output.origin.set(k, origin);
    output.direction.set(k, direction);
    output.throughput.set(k, next_throughput);
    output.pdf[k] = pdf;
    output.goes_on[k] = bounced && survives;
    output.exact[k] = (!shadowed || (end_finite && origin_finite)) && (!bounced || finite);
}

/// Every lane of a chunk. Input and output apart, so that the compiler knows the stores
/// cannot change the loads: then the loop becomes vector code (with the two in one struct it
/// stayed scalar, "too many memory checks needed").
#[inline(always)]
fn shade_chunk(input: &Input, output: &mut Output) {
    for k in 0..LANES {
        shade_lane(input, output, k);
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
unsafe fn shade_chunk_avx512(input: &Input, output: &mut Output) {
    shade_chunk(input, output);
}

/// [`shade_chunk`] compiled for AVX2: eight lanes per instruction.
///
/// # Safety
/// The CPU must support AVX2 ([`Isa::Avx2`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline(never)]
unsafe fn shade_chunk_avx2(input: &Input, output: &mut Output) {
    shade_chunk(input, output);
}

/// The baseline build of [`shade_chunk`]: the scalar twin (SSE2 on x86-64, four lanes where
/// the compiler finds it pays).
#[inline(never)]
fn shade_chunk_baseline(input: &Input, output: &mut Output) {
    shade_chunk(input, output);
}

/// A wavefront's diffuse vertices in lanes: gathered ([`push`](Self::push)), shaded together
/// ([`shade`](Self::shade)), then read back lane by lane ([`result`](Self::result)).
#[derive(Debug, Default)]
pub(super) struct DiffuseLanes {
    inputs: Vec<Input>,
    outputs: Vec<Output>,
    len: usize,
}

/// A diffuse vertex, as [`DiffuseLanes::push`] takes it: the vertex and its path.
pub(super) struct LaneVertex {
    pub surface: DiffuseSurface,
    /// The direction of the ray that arrived.
    pub arrival: Vec3,
    pub throughput: Vec3,
    pub eta: f32,
    pub roulette: bool,
}

/// A lane's light and numbers, as [`DiffuseLanes::set_draws`] takes them.
pub(super) struct LaneDraws {
    pub light: LanePick,
    /// The light's numbers as drawn (the lanes rescale the first within the light's share).
    pub u_point: Vec2,
    pub u_direction: Vec2,
    pub u_roulette: f32,
}

/// What [`DiffuseLanes::result`] gives for a lane.
pub(super) struct LaneResult {
    /// The shadow ray and what it brings if unblocked.
    pub shadow: Option<(Ray, Vec3)>,
    /// The next ray, throughput and BSDF density, if the path goes on.
    pub next: Option<(Ray, Vec3, f32)>,
    /// False where the scalar code must decide the lane instead.
    pub exact: bool,
    /// Whether the lanes sampled the lane's light (a triangle: [`LanePick::Triangle`]).
    pub light_in_lanes: bool,
}

impl DiffuseLanes {
    /// Room for `n` lanes, so that gathering them never moves the chunks.
    pub(super) fn with_capacity(n: usize) -> DiffuseLanes {
        let chunks = n.div_ceil(LANES);
        DiffuseLanes {
            inputs: Vec::with_capacity(chunks),
            outputs: Vec::with_capacity(chunks),
            len: 0,
        }
    }

    /// No lanes.
    pub(super) fn clear(&mut self) {
        self.len = 0;
    }

    /// Lanes gathered.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Adds a lane (the next index).
    #[inline]
    pub(super) fn push(&mut self, v: &LaneVertex) {
        let (c, k) = (self.len / LANES, self.len % LANES);
        if c == self.inputs.len() {
            self.inputs.push(Input::default());
            self.outputs.push(Output::default());
        }
        self.len += 1;
        let input = &mut self.inputs[c];
        let surface = &v.surface;
        input.p.set(k, surface.point.p);
        input.error.set(k, surface.point.error);
        input.normal.set(k, surface.point.normal);
        input.shading_normal.set(k, surface.normal);
        input.two_sided[k] = surface.two_sided;
        input.arrival.set(k, v.arrival);
        input.reflectance.set(k, surface.reflectance);
        input.throughput.set(k, v.throughput);
        input.eta[k] = v.eta;
        input.roulette[k] = v.roulette;
    }

    /// Gives lane `i` its light and numbers.
    #[inline]
    pub(super) fn set_draws(&mut self, i: usize, draws: &LaneDraws) {
        let input = &mut self.inputs[i / LANES];
        let k = i % LANES;
        let light = match draws.light {
            LanePick::Triangle(light) => Some(light),
            LanePick::Nothing | LanePick::Other => None,
        };
        input.has_light[k] = light.is_some();
        // A lane without a triangle computes a harmless light (the last one, or zeros) that
        // `has_light` discards.
        if let Some(light) = light {
            input.v0.set(k, light.corners[0]);
            input.v1.set(k, light.corners[1]);
            input.v2.set(k, light.corners[2]);
            input.light_normal.set(k, light.normal);
            input.light_error.set(k, light.error);
            input.area[k] = light.area;
            input.radiance.set(k, light.radiance);
            input.selection[k] = light.selection;
            input.start[k] = light.start;
        }
        input.u_point[0][k] = draws.u_point.x;
        input.u_point[1][k] = draws.u_point.y;
        input.u_direction[0][k] = draws.u_direction.x;
        input.u_direction[1][k] = draws.u_direction.y;
        input.u_roulette[k] = draws.u_roulette;
    }

    /// Lane `i`'s vertex, for the scalar steps ([`LanePick::Other`] lights, lanes that are not
    /// exact).
    pub(super) fn vertex(&self, i: usize) -> Vertex<'static> {
        let (input, k) = (&self.inputs[i / LANES], i % LANES);
        let reflectance = input.reflectance.get(k);
        let (frame, flip, wi) = facing(
            input.two_sided[k],
            input.arrival.get(k),
            Frame::about(input.shading_normal.get(k)),
        );
        Vertex {
            point: SurfacePoint {
                p: input.p.get(k),
                error: input.error.get(k),
                normal: input.normal.get(k),
            },
            frame,
            flip,
            wi,
            bsdf: Cow::Owned(Bsdf::Diffuse(Diffuse { reflectance })),
        }
    }

    /// Lane `i`'s point.
    #[inline]
    pub(super) fn point(&self, i: usize) -> Vec3 {
        self.inputs[i / LANES].p.get(i % LANES)
    }

    /// Shades every lane with the instruction set `isa` (which the CPU must support).
    pub(super) fn shade(&mut self, isa: Isa) {
        let n = self.len.div_ceil(LANES);
        let chunks = self.inputs[..n].iter().zip(&mut self.outputs[..n]);
        assert!(isa.is_supported(), "{} is not supported by this CPU", isa.name());
        match isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => chunks.for_each(|(input, output)| {
                // SAFETY: the CPU supports the instruction set (asserted above).
                unsafe { shade_chunk_avx512(input, output) }
            }),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => chunks.for_each(|(input, output)| {
                // SAFETY: as above.
                unsafe { shade_chunk_avx2(input, output) }
            }),
            _ => chunks.for_each(|(input, output)| shade_chunk_baseline(input, output)),
        }
    }

    /// Lane `i`'s result, after [`shade`](Self::shade).
    #[inline]
    pub(super) fn result(&self, i: usize) -> LaneResult {
        let (c, k) = (i / LANES, i % LANES);
        let output = &self.outputs[c];
        let shadow = output.shadowed[k].then(|| {
            let mut ray =
                Ray::segment(output.shadow_origin.get(k), output.shadow_direction.get(k), 1.0);
            ray.t_max = SHADOW_RAY_LENGTH;
            (ray, output.contribution.get(k))
        });
        let next = output.goes_on[k].then(|| {
            (
                Ray::new(output.origin.get(k), output.direction.get(k)),
                output.throughput.get(k),
                output.pdf[k],
            )
        });
        let light_in_lanes = self.inputs[c].has_light[k];
        LaneResult { shadow, next, exact: output.exact[k], light_in_lanes }
    }
}

#[cfg(test)]
mod tests;
