//! What the stages cost ([`StageTimes`], for the benchmarks' stage table): a clock the threads
//! add to, and a stopwatch that reads it only when times are measured.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

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
pub(super) struct StageClock {
    pub(super) closest_hits: AtomicU64,
    pub(super) surfaces: AtomicU64,
    pub(super) draws: AtomicU64,
    pub(super) shading: AtomicU64,
    pub(super) occlusion: AtomicU64,
    pub(super) paths: AtomicU64,
    pub(super) vertices: AtomicU64,
    pub(super) lanes: AtomicU64,
    pub(super) chunks: AtomicU64,
}

impl StageClock {
    pub(super) fn read(&self) -> StageTimes {
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
pub(super) struct Lap<'c> {
    clock: Option<(&'c StageClock, Instant)>,
}

impl<'c> Lap<'c> {
    pub(super) fn start(clock: Option<&'c StageClock>) -> Lap<'c> {
        Lap { clock: clock.map(|clock| (clock, Instant::now())) }
    }

    /// Adds the time since the last lap to the stage `slot` picks.
    #[inline]
    pub(super) fn end(&mut self, slot: impl Fn(&StageClock) -> &AtomicU64) {
        if let Some((clock, last)) = &mut self.clock {
            let now = Instant::now();
            slot(clock).fetch_add((now - *last).as_nanos() as u64, Ordering::Relaxed);
            *last = now;
        }
    }
}
