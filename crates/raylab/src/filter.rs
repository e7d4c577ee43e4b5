//! Pixel filters: where in and around its pixel a sample is taken.
//!
//! A sample's position is drawn from the filter's distribution, so every sample has the same
//! weight and a pixel is the plain mean of its samples (importance-sampled filtering). The
//! filter is part of the sample settings: see `render::SampleSettings`.

use glam::Vec2;

use crate::sampling::square_to_truncated_gaussian;
use crate::unknown_name::UnknownName;

/// The pixel filter: how a sample's position in and around its pixel is drawn. Samples are
/// distributed as the filter, so every sample has the same weight (importance-sampled filtering).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "io", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "io", serde(rename_all = "lowercase"))]
pub enum Filter {
    /// Uniform over the pixel: each pixel is the plain mean of the radiance over its area.
    #[default]
    Box,
    /// A Gaussian about the pixel's centre, truncated at `radius` pixels on each axis.
    Gaussian {
        /// Standard deviation in pixels (Mitsuba's default is 0.5).
        sigma: f32,
        /// Truncation radius in pixels (Mitsuba's default is 4σ = 2).
        radius: f32,
    },
}

impl std::str::FromStr for Filter {
    type Err = UnknownName;

    /// `box`, or `gaussian` ([`Filter::GAUSSIAN`]).
    fn from_str(name: &str) -> Result<Filter, UnknownName> {
        match name {
            "box" => Ok(Filter::Box),
            "gaussian" => Ok(Filter::GAUSSIAN),
            other => Err(UnknownName::new("filter", other, "box or gaussian")),
        }
    }
}

impl Filter {
    /// Mitsuba's default Gaussian: σ = 0.5 px, radius 2 px.
    pub const GAUSSIAN: Filter = Filter::Gaussian { sigma: 0.5, radius: 2.0 };

    /// A sample's offset from the pixel's top-left corner for the uniform numbers `u`.
    #[inline]
    pub fn offset(&self, u: Vec2) -> Vec2 {
        match *self {
            Filter::Box => u,
            Filter::Gaussian { sigma, radius } => {
                Vec2::splat(0.5) + square_to_truncated_gaussian(u, sigma, radius)
            }
        }
    }
}
