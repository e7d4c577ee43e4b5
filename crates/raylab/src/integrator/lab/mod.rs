//! `lab`: the lab's light model (KTH DH2323 Lab 2, §"Illumination").
//!
//! A point light gives a surface the power per area `D = P·max(r̂·n̂, 0) / (4πr²)` (eq. 27),
//! zero when a shadow ray toward the light is blocked; a constant `N` stands in for indirect
//! light; the colour is `R = ρ ∗ (D + N)` (eq. 30). Shown as the lab shows it: each channel
//! clamped to `[0, 1]`, no gamma (see [`Film::to_rgb8_clamped`](crate::Film::to_rgb8_clamped)).
//!
//! [`Stage`] replays the lab step by step for learners, from flat colours to the full model.
//! Surfaces are two-sided: the normal is turned toward the viewer, so a wall seen from behind is
//! lit only by a light on that side. Shadow rays leave the surface with a rounding-error-aware offset (see [`crate::ray`]) rather
//! than a magic epsilon, so there is no shadow acne at any scene scale.

mod gather;
mod model;
mod tile;

pub use model::{Lab, Stage};

use glam::Vec3;

use super::Integrator;
use crate::accel::Accelerator;
use crate::ray::Ray;
use crate::sampling::{Sampler, SamplerKind};
use model::TILE;
use tile::TileArrays;

impl<A: Accelerator + ?Sized> Integrator for Lab<'_, A> {
    fn radiance(&self, ray: &Ray, _sampler: &mut Sampler) -> Vec3 {
        let hit = super::closest_opaque_hit(self.scene, self.accel, ray);
        let shading = self.shade(ray, hit);
        let occluded = shading
            .shadow_ray
            .is_some_and(|shadow| super::occluded_opaque(self.scene, self.accel, &shadow));
        self.finish(hit.is_some(), &shading, occluded)
    }

    /// Camera rays together, then their shadow rays together (toward one light, so they are
    /// coherent too), the shading in between lane by lane over the tile (`TileShading`).
    fn radiance_each(&self, rays: &[Ray], samplers: &mut [Sampler], out: &mut [Vec3]) {
        assert_eq!(rays.len(), out.len(), "one colour per ray");
        assert_eq!(rays.len(), samplers.len(), "one sampler per ray");
        // Cut-out holes are passed ray by ray.
        if self.scene.has_cut_outs() {
            for ((ray, sampler), colour) in rays.iter().zip(samplers).zip(out) {
                *colour = self.radiance(ray, sampler);
            }
            return;
        }
        // A tile at a time, in this thread's arrays: no allocation or clearing per tile. The
        // hits come back in rows, and the shadow rays go in rows, side by side (the lanes
        // with one): the packets read and write rows, so nothing is turned into records.
        let mut arrays = TileArrays::take();
        let TileArrays { hits, shading, gathered, shadow_rays } = &mut *arrays;
        for (rays, out) in rays.chunks(TILE).zip(out.chunks_mut(TILE)) {
            self.accel.closest_hits_rows(rays, hits);
            shading.shade(gathered, self, rays, hits);
            let shadows = shading.shadow_rows(self, rays, hits, shadow_rays);
            let blocked = if shadows > 0 { self.accel.occluded_rows(shadow_rays) } else { 0 };
            let mut j = 0;
            for (i, colour) in out.iter_mut().enumerate() {
                let mut occluded = false;
                if shading.shadow[i] {
                    occluded = blocked >> j & 1 != 0;
                    j += 1;
                }
                *colour = self.finish(hits.is_hit(i), &shading.lane(i), occluded);
            }
        }
        TileArrays::give_back(arrays);
    }

    /// The lab's pixel sampling: one sample is the ray through the pixel's centre.
    fn sampler_kind(&self) -> SamplerKind {
        SamplerKind::Lab
    }

    /// The lab's model draws no numbers: its pixel positions are its only samples.
    fn draws_numbers(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_parse_by_name_and_number() {
        for (i, stage) in Stage::ALL.into_iter().enumerate() {
            assert_eq!(stage.name().parse::<Stage>(), Ok(stage));
            assert_eq!((i + 1).to_string().parse::<Stage>(), Ok(stage));
        }
        assert!("6".parse::<Stage>().is_err());
        assert!("Flat".parse::<Stage>().is_err());
        assert_eq!(Stage::default(), Stage::Ambient);
    }
}
