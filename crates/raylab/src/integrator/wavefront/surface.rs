//! A vertex as the wavefront's lanes take it ([`LaneSurface`]), and how the scalar path tracer's surfaces become it: in general
//! ([`PathScalar::lane_surface`]) and by the shortcut for the commonest hits
//! ([`PathScalar::plain_surface`]).

use std::borrow::Cow;

use glam::Vec3;

use crate::accel::{Accelerator, Hit};
use crate::integrator::path::PathScalar;
use crate::interaction::SurfaceInteraction;
use crate::material::Bsdf;
use crate::ray::{Ray, SurfacePoint};
use crate::texture::TextureQuery;

/// A vertex as the wavefront's lanes take it: its point, its shading normal, whether its
/// material is two-sided, `dp/du` where the BSDF is anisotropic (its frame follows it, as
/// `shading_frame` (`path.rs`)'s), and its BSDF (borrowed from the material where no texture changes
/// it). The lanes find the frame and the direction toward the viewer themselves, as
/// `shading_frame` (`path.rs`) does, and keep the BSDF as floats ([`LaneBsdf`](crate::material::lanes::LaneBsdf)).
#[derive(Clone, Debug)]
pub(super) struct LaneSurface<'s> {
    pub point: SurfacePoint,
    pub normal: Vec3,
    pub two_sided: bool,
    pub tangent: Option<Vec3>,
    pub bsdf: Cow<'s, Bsdf>,
}

impl<'a, A: Accelerator + ?Sized> PathScalar<'a, A> {
    /// `vertex` as the lanes take it ([`LaneSurface`]): the same shading
    /// normal, frame choice and BSDF, without making the frame.
    #[inline(never)]
    pub(super) fn lane_surface(
        &self,
        ray: &Ray,
        interaction: &SurfaceInteraction,
    ) -> LaneSurface<'a> {
        let material = self.scene().material(interaction);
        let normal = material.shading_normal(interaction, -ray.direction);
        // `shading_frame`'s choice of frame.
        let tangent = material.bsdf.is_anisotropic().then_some(interaction.dp_du);
        LaneSurface {
            point: interaction.point,
            normal,
            two_sided: material.two_sided,
            tangent,
            bsdf: material.bsdf_at(&interaction.texture_query()),
        }
    }

    /// The wavefront's shortcut for the commonest hits: a triangle that no instance places
    /// ([`Geometry::shaded_surface_point`](crate::geometry::Geometry::shaded_surface_point))
    /// and that is no light's, of a material without a normal map. It gives exactly what
    /// `arrive` and [`lane_surface`](Self::lane_surface) give there: no light
    /// found (only lights' triangles emit), and the same point, shading normal (the
    /// interpolated one, or the geometric one), sidedness, `dp/du` for an anisotropic BSDF
    /// ([`Geometry::dp_du`](crate::geometry::Geometry::dp_du)) and BSDF (its textures read at
    /// the same texture coordinates, [`Geometry::uv`](crate::geometry::Geometry::uv), where it
    /// has any). Without building the interaction: no tangent, and no texture coordinates or
    /// `dp/du` where nothing needs them. `None` for any other hit, which takes the general
    /// steps.
    #[inline]
    pub(super) fn plain_surface(&self, hit: &Hit) -> Option<LaneSurface<'a>> {
        let (point, normal, material) = self.scene().geometry.shaded_surface_point(hit)?;
        if self.lights().is_light_triangle(hit.triangle) {
            return None;
        }
        let material = &self.scene().materials[material as usize];
        if material.textures.normal.is_some() {
            return None;
        }
        // `lane_surface`'s choice of frame.
        let tangent = material.bsdf.is_anisotropic().then(|| self.scene().geometry.dp_du(hit));
        let bsdf = if material.textures.is_empty() {
            Cow::Borrowed(&material.bsdf)
        } else {
            let uv = self.scene().geometry.uv(hit);
            material.bsdf_at(&TextureQuery { uv, p: point.p, footprint: 0.0 })
        };
        Some(LaneSurface { point, normal, two_sided: material.two_sided, tangent, bsdf })
    }
}
