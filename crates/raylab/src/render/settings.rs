//! How samples are drawn and the work is cut ([`SampleSettings`]): the seed, the sampler, the
//! filter, the tiles, and how many passes are traced together ([`PASS_GROUP`]).

use crate::filter::Filter;
use crate::sampling::SamplerKind;

/// Rows per unit of parallel work by default: small enough to balance two cores; a band is
/// traced in tiles of `tile`×`band` rays (a group of `n` passes makes a tile `tile / n` pixels
/// wide, each pixel's `n` samples side by side), whose rays are coherent (the accelerator
/// traces camera rays as packets).
const BAND_ROWS: u32 = 8;
/// Tile width by default: the integrator's ([`Integrator::tile_width`](crate::integrator::Integrator::tile_width)).
const TILE: u32 = 0;

/// How samples are drawn: the seed, the sampler (`None`: the integrator's choice), the filter and
/// the tiling (which never changes the pixels, only the order of the work).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleSettings {
    /// The seed every sampler derives from.
    pub seed: u64,
    /// The sampler, or `None` for [`Integrator::sampler_kind`](crate::integrator::Integrator::sampler_kind).
    pub sampler: Option<SamplerKind>,
    /// The pixel filter.
    pub filter: Filter,
    /// Tile width (in rays: a group of `n` passes makes the tile `width / n` pixels wide) and
    /// height in pixels (their product at most 1,024); width 0 for the integrator's choice
    /// ([`Integrator::tile_width`](crate::integrator::Integrator::tile_width)).
    pub tile: (u32, u32),
    /// The samples per pixel the render is to reach, which the `multijitter` sampler lays out
    /// as one pattern ([`Sampler::counted`](crate::sampling::Sampler::counted)); 0 where no end
    /// is known (progressive frames, a time limit): `multijitter` is then `sobol`.
    pub count: u32,
}

impl Default for SampleSettings {
    fn default() -> Self {
        SampleSettings {
            seed: 0,
            sampler: None,
            filter: Filter::Box,
            tile: (TILE, BAND_ROWS),
            count: 0,
        }
    }
}

/// The most passes traced together ([`Accumulator::add_samples_with_progress`](super::Accumulator::add_samples_with_progress) splits larger
/// counts into groups of this many): a pixel's sixteen samples fill a quarter of a packet of
/// 64 rays.
pub const PASS_GROUP: u32 = 16;
