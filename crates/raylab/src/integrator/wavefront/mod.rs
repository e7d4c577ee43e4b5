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
//! 4. **shading**: light sampling, BSDF sampling and Russian roulette. The lanes (`vertices/`:
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

mod clock;
mod stages;
mod surface;
mod vertices;

use glam::Vec3;

pub use clock::StageTimes;

use super::Integrator;
use super::path::{PathScalar, PathSettings};
use crate::accel::Accelerator;
use crate::cpu::Isa;
use crate::ray::Ray;
use crate::sampling::Sampler;
use crate::scene::Scene;
use clock::StageClock;
use stages::Stages;

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
    /// has (the same samples, to the bit): for tests and benchmarks, with the `support`
    /// feature. (`RAYLAB_ISA` caps the instruction set of a whole process: [`Isa::detect`].)
    ///
    /// # Panics
    /// If this CPU does not support `isa`.
    #[cfg(feature = "support")]
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
        let stages = Stages { path: &self.path, isa: self.isa, times: self.times.as_ref() };
        stages.run(rays, samplers, out);
    }
}
