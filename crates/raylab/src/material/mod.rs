//! Materials: how surfaces scatter and emit light.
//!
//! A [`Material`] is a BSDF, whether it is two-sided, and the radiance it emits from its front
//! side (an emissive material makes its triangles area lights). Names and parameters follow
//! Mitsuba 3's plugins, so that its scenes translate one to one; like Mitsuba's, materials are
//! **one-sided** unless wrapped in `twosided`: seen from behind (against the shading normal)
//! they are black. The dielectrics transmit, so they have two sides by nature.
//!
//! Each BSDF lives in its own file with `eval`, `pdf` and `sample` side by side, in the local
//! shading frame (z is the shading normal). Directions follow Mitsuba's convention: `wi` points
//! back toward where the light ends up (the camera side), `wo` is the direction sampled or
//! evaluated toward the light; both point away from the surface. `eval` returns the BSDF times
//! the cosine `|cos θo|`, and a sample's `weight` is `eval / pdf`.

mod conductor;
mod dielectric;
mod diffuse;
pub mod fresnel;
pub(crate) mod lanes;
pub mod microfacet;
mod pbr;
mod plastic;
mod rough_conductor;
mod rough_dielectric;
mod sample;

use std::borrow::Cow;

use glam::{Vec2, Vec3};

pub use conductor::{Conductor, METALS};
pub use dielectric::Dielectric;
pub use diffuse::Diffuse;
pub use microfacet::Ggx;
pub use pbr::Pbr;
pub use plastic::Plastic;
pub use rough_conductor::RoughConductor;
pub use rough_dielectric::RoughDielectric;
pub use sample::BsdfSample;
pub(crate) use sample::cos_theta;

use crate::interaction::SurfaceInteraction;
use crate::texture::{Texture, TextureQuery};

/// A surface's scattering, emission and sidedness.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The name scenes refer to it by.
    pub name: String,
    /// How it scatters light.
    pub bsdf: Bsdf,
    /// Scatters from both sides (Mitsuba's `twosided`); otherwise black from behind.
    pub two_sided: bool,
    /// Radiance emitted from the front side; zero for surfaces that do not emit.
    pub emission: Vec3,
    /// Inputs that vary over the surface (none: the BSDF is the same everywhere).
    pub textures: MaterialTextures,
}

/// A material's inputs that vary over the surface.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialTextures {
    /// Multiplies the BSDF's colour (see [`Bsdf::tinted`]): glTF's `baseColorTexture`, MTL's
    /// `map_Kd`. Its alpha is the surface's coverage.
    pub base_color: Option<Texture>,
    /// glTF's `metallicRoughnessTexture`: its green channel multiplies the [`Pbr`] roughness,
    /// its blue channel the metallic factor (linear data).
    pub metallic_roughness: Option<Texture>,
    /// A tangent-space normal map (glTF's `normalTexture`).
    pub normal: Option<NormalMap>,
    /// The roughness, from the texture's red channel: α for the rough conductor and
    /// dielectric (both axes), the perceptual roughness for [`Pbr`].
    pub roughness: Option<Texture>,
    /// Cut-out coverage (glTF's `alphaMode: MASK`): where the base colour's alpha is below the
    /// cutoff, the surface is not there and rays pass through.
    pub alpha_mask: Option<AlphaMask>,
    /// Multiplies the emitted radiance (glTF's `emissiveTexture`): an emitter that shines in a
    /// pattern. Light sampling reads it at the sampled point (the `light` module).
    pub emission: Option<Texture>,
}

/// Cut-out coverage: the alpha is `factor` times the base colour texture's alpha (where there is
/// one); below `cutoff` the surface is a hole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaMask {
    /// glTF's `alphaCutoff` (0.5 unless it says otherwise).
    pub cutoff: f32,
    /// The base colour factor's alpha.
    pub factor: f32,
}

/// A tangent-space normal map: each texel's RGB holds `(n + 1)/2` for a normal `n` in the frame
/// of the surface's tangent `t` (x, toward +u), bitangent `b = w · n × t` (y) and normal (z),
/// as glTF and MikkTSpace define them.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    /// The normals (linear data).
    pub texture: Texture,
    /// Multiplies the x and y of each normal (glTF's `normalTexture.scale`): 0 flattens it.
    pub scale: f32,
}

impl MaterialTextures {
    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.base_color.is_none()
            && self.metallic_roughness.is_none()
            && self.normal.is_none()
            && self.roughness.is_none()
            && self.alpha_mask.is_none()
            && self.emission.is_none()
    }
}

impl Material {
    /// A one-sided diffuse material that does not emit.
    pub fn diffuse(name: &str, reflectance: Vec3) -> Material {
        Material {
            name: name.to_string(),
            bsdf: Bsdf::Diffuse(Diffuse { reflectance }),
            two_sided: false,
            emission: Vec3::ZERO,
            textures: MaterialTextures::default(),
        }
    }

    /// The BSDF at a point, its textured inputs read at `query` (the BSDF itself where it has
    /// none).
    #[inline]
    pub fn bsdf_at(&self, query: &TextureQuery) -> Cow<'_, Bsdf> {
        if self.textures.is_empty() {
            return Cow::Borrowed(&self.bsdf);
        }
        let mut bsdf = match &self.textures.base_color {
            None => self.bsdf.clone(),
            Some(texture) => self.bsdf.tinted(texture.rgb(query)),
        };
        if let (Some(texture), Bsdf::Pbr(pbr)) = (&self.textures.metallic_roughness, &mut bsdf) {
            let value = texture.eval(query);
            pbr.roughness = (pbr.roughness * value.y).clamp(0.0, 1.0);
            pbr.metallic = (pbr.metallic * value.z).clamp(0.0, 1.0);
        }
        if let Some(texture) = &self.textures.roughness {
            let value = texture.eval(query).x;
            let alpha = if value.is_finite() { value.clamp(1e-3, 1.0) } else { 1.0 };
            match &mut bsdf {
                Bsdf::RoughConductor(b) => b.distribution = Ggx::new(alpha, alpha),
                Bsdf::RoughDielectric(b) => b.distribution = Ggx::new(alpha, alpha),
                Bsdf::Pbr(b) => b.roughness = alpha,
                _ => {}
            }
        }
        Cow::Owned(bsdf)
    }

    /// Whether the surface is a hole at `query` (see [`AlphaMask`]).
    #[inline]
    pub fn is_cut_out(&self, query: &TextureQuery) -> bool {
        let Some(mask) = self.textures.alpha_mask else { return false };
        let alpha = match &self.textures.base_color {
            Some(texture) => texture.eval(query).w,
            None => 1.0,
        };
        mask.factor * alpha < mask.cutoff
    }

    /// The shading normal at `interaction`, bent by the normal map where the material has one
    /// and the mesh has tangents. A mapped normal that would turn away from the viewer (toward
    /// `-towards_viewer`) while the unmapped one faces it is not used: the surface would turn
    /// black there.
    #[inline]
    pub fn shading_normal(&self, interaction: &SurfaceInteraction, towards_viewer: Vec3) -> Vec3 {
        let n = interaction.shading_normal;
        let (Some(map), tangent) = (&self.textures.normal, interaction.tangent) else {
            return n;
        };
        // Gram-Schmidt: the tangent made perpendicular to the interpolated normal.
        let t = (tangent.truncate() - n * n.dot(tangent.truncate())).normalize_or_zero();
        if t == Vec3::ZERO {
            return n;
        }
        let b = n.cross(t) * if tangent.w < 0.0 { -1.0 } else { 1.0 };
        let texel = map.texture.eval(&interaction.texture_query()).truncate() * 2.0 - Vec3::ONE;
        let local = Vec3::new(texel.x * map.scale, texel.y * map.scale, texel.z);
        let mapped = (t * local.x + b * local.y + n * local.z).normalize_or_zero();
        let facing = |v: Vec3| v.dot(towards_viewer) > 0.0;
        if mapped == Vec3::ZERO || (facing(n) && !facing(mapped)) { n } else { mapped }
    }

    /// The colour flat renderings show at a point ([`Bsdf::albedo`], textured).
    #[inline]
    pub fn albedo_at(&self, query: &TextureQuery) -> Vec3 {
        match &self.textures.base_color {
            None => self.bsdf.albedo(),
            Some(texture) => self.bsdf.tinted(texture.rgb(query)).albedo(),
        }
    }

    /// The radiance it emits at a point: [`emission`](Self::emission), times its emission
    /// texture there where it has one.
    #[inline]
    pub fn emission_at(&self, query: &TextureQuery) -> Vec3 {
        match &self.textures.emission {
            None => self.emission,
            Some(texture) => self.emission * texture.rgb(query).max(Vec3::ZERO),
        }
    }

    /// Whether it emits light.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// Checks that every parameter is finite and in its range, naming the first that is not.
    pub fn validate(&self) -> Result<(), MaterialError> {
        if !self.emission.is_finite() || self.emission.min_element() < 0.0 {
            return Err(MaterialError::Emission(self.emission));
        }
        if self.two_sided && matches!(self.bsdf, Bsdf::Dielectric(_) | Bsdf::RoughDielectric(_)) {
            // As Mitsuba's twosided: a material that transmits already has two sides, and
            // mirroring its back into its front would turn every exit into an entry.
            return Err(MaterialError::TwoSidedDielectric);
        }
        self.bsdf.validate()
    }
}

/// The one list of BSDFs: each entry names a variant of [`Bsdf`] and the type it holds (they
/// share a name), with the variant's documentation.
///
/// `bsdf_list!(callback!(args))` hands the list to `callback!`, after `(args)`. Everything that
/// goes over every BSDF is made from it: the [`Bsdf`] enum and its kinds (`BsdfKind`, below),
/// dispatch on a BSDF (`each_bsdf!`) and on a kind (`with_bsdf_type!`, which the wavefront's
/// lanes compile each kind's code with). A new BSDF is a line here, its own file with `eval`,
/// `pdf` and `sample`, and its lane form (`LaneBsdf`, `lanes.rs`); the compiler then names
/// every `match` that must learn it.
macro_rules! bsdf_list {
    ($callback:ident!($($args:tt)*)) => {
        $crate::material::$callback! { ($($args)*)
            /// Lambertian reflection (Mitsuba's `diffuse`).
            Diffuse,
            /// A smooth metal (Mitsuba's `conductor`).
            Conductor,
            /// A rough metal (Mitsuba's `roughconductor`).
            RoughConductor,
            /// Smooth glass (Mitsuba's `dielectric`).
            Dielectric,
            /// Rough glass (Mitsuba's `roughdielectric`).
            RoughDielectric,
            /// A diffuse base under a smooth coating (Mitsuba's `plastic`).
            Plastic,
            /// glTF's metallic-roughness material.
            Pbr,
        }
    };
}
pub(crate) use bsdf_list;

/// Declares [`Bsdf`], `BsdfKind` and `Bsdf::kind` from the list.
macro_rules! declare_bsdfs {
    (() $($(#[$doc:meta])* $name:ident,)*) => {
        /// A bidirectional scattering distribution function: one variant per BSDF, each
        /// holding the BSDF of the same name.
        #[derive(Clone, Debug, PartialEq)]
        pub enum Bsdf {
            $($(#[$doc])* $name($name),)*
        }

        /// Which BSDF a [`Bsdf`] is, without its parameters: the wavefront groups its
        /// vertices by it.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub(crate) enum BsdfKind {
            $($(#[$doc])* $name,)*
        }

        impl BsdfKind {
            /// Every kind, in the list's order (`kind as usize` is its index).
            pub(crate) const ALL: [BsdfKind; [$(stringify!($name)),*].len()] =
                [$(BsdfKind::$name),*];
        }

        impl Bsdf {
            /// Which BSDF it is.
            #[inline(always)]
            pub(crate) fn kind(&self) -> BsdfKind {
                match self {
                    $(Bsdf::$name(_) => BsdfKind::$name,)*
                }
            }
        }
    };
}
pub(crate) use declare_bsdfs;

bsdf_list!(declare_bsdfs!());

/// `each_bsdf!(bsdf, b => expr)`: `expr` with `b` bound to the BSDF that `bsdf` (a `&Bsdf`)
/// holds, whichever it is.
macro_rules! each_bsdf {
    ($bsdf:expr, $b:ident => $body:expr) => {
        $crate::material::bsdf_list!(each_bsdf_match!($bsdf, $b => $body))
    };
}
pub(crate) use each_bsdf;

/// The `match` of [`each_bsdf!`], over the list.
macro_rules! each_bsdf_match {
    (($bsdf:expr, $b:ident => $body:expr) $($(#[$doc:meta])* $name:ident,)*) => {
        match $bsdf {
            $($crate::material::Bsdf::$name($b) => $body,)*
        }
    };
}
pub(crate) use each_bsdf_match;

/// `with_bsdf_type!(kind, B => expr)`: `expr` with the type `B` the BSDF of kind `kind` (a
/// `BsdfKind`): how code generic over the BSDF type is run for a kind known only at run time.
macro_rules! with_bsdf_type {
    ($kind:expr, $B:ident => $body:expr) => {
        $crate::material::bsdf_list!(with_bsdf_type_match!($kind, $B => $body))
    };
}
pub(crate) use with_bsdf_type;

/// The `match` of [`with_bsdf_type!`], over the list.
macro_rules! with_bsdf_type_match {
    (($kind:expr, $B:ident => $body:expr) $($(#[$doc:meta])* $name:ident,)*) => {
        match $kind {
            $($crate::material::BsdfKind::$name => {
                type $B = $crate::material::$name;
                $body
            })*
        }
    };
}
pub(crate) use with_bsdf_type_match;

impl Bsdf {
    /// The BSDF times `|cos θo|` for light arriving from `wo` and leaving toward `wi` (local
    /// frame). Zero for delta lobes: the smooth conductor and dielectric have nothing else.
    #[inline]
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        match self {
            Bsdf::Conductor(_) | Bsdf::Dielectric(_) => Vec3::ZERO,
            Bsdf::Diffuse(b) => b.eval(wi, wo),
            Bsdf::RoughConductor(b) => b.eval(wi, wo),
            Bsdf::RoughDielectric(b) => b.eval(wi, wo),
            Bsdf::Plastic(b) => b.eval(wi, wo),
            Bsdf::Pbr(b) => b.eval(wi, wo),
        }
    }

    /// The density with which [`sample`](Self::sample) picks `wo` given `wi`, per unit solid
    /// angle (zero for delta lobes).
    #[inline]
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        match self {
            Bsdf::Conductor(_) | Bsdf::Dielectric(_) => 0.0,
            Bsdf::Diffuse(b) => b.pdf(wi, wo),
            Bsdf::RoughConductor(b) => b.pdf(wi, wo),
            Bsdf::RoughDielectric(b) => b.pdf(wi, wo),
            Bsdf::Plastic(b) => b.pdf(wi, wo),
            Bsdf::Pbr(b) => b.pdf(wi, wo),
        }
    }

    /// Samples `wo` given `wi` from two uniform numbers (`u1` picks a lobe, `u2` a direction), or
    /// `None` where the BSDF absorbs.
    #[inline]
    pub fn sample(&self, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        each_bsdf!(self, b => b.sample(wi, u1, u2))
    }

    /// Whether the BSDF has a lobe that is not a delta: light sampling can help it.
    #[inline]
    pub fn is_smooth(&self) -> bool {
        !matches!(self, Bsdf::Conductor(_) | Bsdf::Dielectric(_))
    }

    /// Whether the BSDF depends on the tangent's direction, not only on the normal (rough
    /// materials with `alpha_u ≠ alpha_v`).
    #[inline]
    pub fn is_anisotropic(&self) -> bool {
        match self {
            Bsdf::RoughConductor(r) => r.distribution.alpha_u != r.distribution.alpha_v,
            Bsdf::RoughDielectric(r) => r.distribution.alpha_u != r.distribution.alpha_v,
            _ => false,
        }
    }

    /// The BSDF with its colour multiplied by `colour` (clamped to `[0, 1]`): the diffuse
    /// reflectance, the plastic's diffuse reflectance, the conductors' specular reflectance.
    /// The dielectrics have no colour to tint.
    pub fn tinted(&self, colour: Vec3) -> Bsdf {
        let colour = colour.clamp(Vec3::ZERO, Vec3::ONE);
        let mut bsdf = self.clone();
        match &mut bsdf {
            Bsdf::Diffuse(d) => d.reflectance *= colour,
            Bsdf::Conductor(c) => c.specular_reflectance *= colour,
            Bsdf::RoughConductor(r) => r.conductor.specular_reflectance *= colour,
            // Rebuilt: the lobes' sampling weights follow the diffuse reflectance.
            Bsdf::Plastic(p) => {
                *p = Plastic::new(
                    p.diffuse_reflectance * colour,
                    p.specular_reflectance,
                    p.eta,
                    p.nonlinear,
                )
            }
            Bsdf::Pbr(p) => p.base_color *= colour,
            Bsdf::Dielectric(_) | Bsdf::RoughDielectric(_) => {}
        }
        bsdf
    }

    /// The colour a surface shows in flat renderings (the lab's ρ, the albedo AOV): the diffuse
    /// reflectance, or the lobe's tint.
    pub fn albedo(&self) -> Vec3 {
        match self {
            Bsdf::Diffuse(d) => d.reflectance,
            Bsdf::Conductor(c) => c.reflectance(1.0),
            Bsdf::RoughConductor(r) => r.conductor.reflectance(1.0),
            Bsdf::Dielectric(_) | Bsdf::RoughDielectric(_) => Vec3::ONE,
            Bsdf::Plastic(p) => p.diffuse_reflectance,
            Bsdf::Pbr(p) => p.base_color,
        }
    }

    fn validate(&self) -> Result<(), MaterialError> {
        let positive_ior = |eta: f32| {
            if eta.is_finite() && eta > 0.0 { Ok(()) } else { Err(MaterialError::Ior(eta)) }
        };
        let roughness = |g: &Ggx| {
            if g.alpha_u.is_finite() && g.alpha_v.is_finite() && g.alpha_u > 0.0 && g.alpha_v > 0.0
            {
                Ok(())
            } else {
                Err(MaterialError::Roughness { alpha_u: g.alpha_u, alpha_v: g.alpha_v })
            }
        };
        let conductor = |c: &Conductor| {
            let magnitude = c.eta * c.eta + c.k * c.k;
            if c.eta.is_finite()
                && c.k.is_finite()
                && c.eta.min_element() >= 0.0
                && c.k.min_element() >= 0.0
                && magnitude.min_element() > 0.0
            {
                unit_interval("specular_reflectance", c.specular_reflectance)
            } else {
                Err(MaterialError::Conductor { eta: c.eta, k: c.k })
            }
        };
        match self {
            Bsdf::Diffuse(d) => unit_interval("reflectance", d.reflectance),
            Bsdf::Conductor(c) => conductor(c),
            Bsdf::RoughConductor(r) => conductor(&r.conductor).and(roughness(&r.distribution)),
            Bsdf::Dielectric(d) => positive_ior(d.eta),
            Bsdf::RoughDielectric(r) => positive_ior(r.eta).and(roughness(&r.distribution)),
            Bsdf::Pbr(p) => unit_interval("base_color", p.base_color)
                .and(unit_interval("metallic", Vec3::splat(p.metallic)))
                .and(unit_interval("roughness", Vec3::splat(p.roughness))),
            Bsdf::Plastic(p) => positive_ior(p.eta)
                .and(unit_interval("diffuse_reflectance", p.diffuse_reflectance))
                .and(unit_interval("specular_reflectance", p.specular_reflectance)),
        }
    }
}

/// Checks that a colour is finite with every channel in `[0, 1]`.
fn unit_interval(name: &'static str, value: Vec3) -> Result<(), MaterialError> {
    if value.is_finite() && value.min_element() >= 0.0 && value.max_element() <= 1.0 {
        Ok(())
    } else {
        Err(MaterialError::OutOfRange { name, value })
    }
}

/// Why a material's parameters cannot be rendered: the first parameter out of its range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MaterialError {
    /// Emission must be finite and not negative.
    #[error("emission {0} must be finite and not negative")]
    Emission(Vec3),
    /// A two-sided material around a dielectric.
    #[error("twosided cannot hold a dielectric: it transmits, and has two sides already")]
    TwoSidedDielectric,
    /// A relative index of refraction that is not finite and positive.
    #[error("the relative index of refraction {0} must be finite and above 0")]
    Ior(f32),
    /// A microfacet roughness that is not finite and positive.
    #[error("alpha ({alpha_u}, {alpha_v}) must be finite and above 0")]
    Roughness {
        /// Along the tangent.
        alpha_u: f32,
        /// Along the bitangent.
        alpha_v: f32,
    },
    /// A conductor's complex index of refraction that is negative, not finite or zero.
    #[error("eta {eta} and k {k} must be finite, not negative and not both 0")]
    Conductor {
        /// The real part.
        eta: Vec3,
        /// The imaginary part (absorption).
        k: Vec3,
    },
    /// A colour or factor outside `[0, 1]`.
    #[error("{name} {value} must be between 0 and 1 in every channel")]
    OutOfRange {
        /// The parameter's name in scene files.
        name: &'static str,
        /// Its value.
        value: Vec3,
    },
}

#[cfg(test)]
pub(crate) mod tests;
