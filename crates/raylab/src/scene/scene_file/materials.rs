//! Materials in scene files: Mitsuba's plugin names and parameters, and its named indices of
//! refraction.

use std::ops::Range;

use glam::Vec3;
use serde::Deserialize;

use super::builder::{Builder, Result, SceneFileError};
use super::textures::{ColourDoc, ScalarDoc};
use crate::material::{
    Bsdf, Conductor, Dielectric, Ggx, METALS, Material, MaterialTextures, Pbr, Plastic,
    RoughConductor, RoughDielectric,
};

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub(super) enum MaterialDoc {
    Diffuse {
        reflectance: ColourDoc,
    },
    Conductor {
        #[serde(flatten)]
        metal: MetalDoc,
    },
    Roughconductor {
        #[serde(flatten)]
        metal: MetalDoc,
        #[serde(flatten)]
        roughness: RoughnessDoc,
    },
    Dielectric {
        int_ior: Option<IorDoc>,
        ext_ior: Option<IorDoc>,
    },
    Roughdielectric {
        int_ior: Option<IorDoc>,
        ext_ior: Option<IorDoc>,
        #[serde(flatten)]
        roughness: RoughnessDoc,
    },
    Plastic {
        diffuse_reflectance: Option<ColourDoc>,
        specular_reflectance: Option<[f32; 3]>,
        int_ior: Option<IorDoc>,
        ext_ior: Option<IorDoc>,
        #[serde(default)]
        nonlinear: bool,
    },
    Twosided {
        bsdf: Box<MaterialDoc>,
    },
    /// glTF's metallic-roughness material.
    Pbr {
        base_color: Option<ColourDoc>,
        metallic: Option<f32>,
        roughness: Option<ScalarDoc>,
    },
}

#[derive(Deserialize)]
pub(super) struct MetalDoc {
    /// A metal by name (Au, Ag, Cu, Al, none), or `eta` and `k`.
    material: Option<String>,
    eta: Option<[f32; 3]>,
    k: Option<[f32; 3]>,
    specular_reflectance: Option<[f32; 3]>,
}

#[derive(Deserialize)]
pub(super) struct RoughnessDoc {
    distribution: Option<String>,
    alpha: Option<ScalarDoc>,
    alpha_u: Option<f32>,
    alpha_v: Option<f32>,
}

/// An index of refraction: a number or a name from Mitsuba's table.
#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum IorDoc {
    Number(f32),
    Name(String),
}

/// Mitsuba's table of named indices of refraction.
const NAMED_IORS: [(&str, f32); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000_036),
    ("hydrogen", 1.000_132),
    ("air", 1.000_277),
    ("carbon dioxide", 1.000_45),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.520_45),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.47),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

impl<F: Fn(Option<Range<usize>>, String) -> SceneFileError> Builder<'_, F> {
    fn ior(&self, ior: &Option<IorDoc>, default: f32, span: &Range<usize>) -> Result<f32> {
        match ior {
            None => Ok(default),
            Some(IorDoc::Number(n)) => Ok(*n),
            Some(IorDoc::Name(name)) => {
                match NAMED_IORS.iter().find(|(n, _)| n == name) {
                    Some(&(_, value)) => Ok(value),
                    None => {
                        let names: Vec<&str> = NAMED_IORS.iter().map(|(n, _)| *n).collect();
                        self.error(span.clone(), format!("unknown index of refraction '{name}': expected a number or one of {}", names.join(", ")))
                    }
                }
            }
        }
    }

    fn conductor(&self, doc: &MetalDoc, span: &Range<usize>) -> Result<Conductor> {
        let (eta, k) = match (&doc.material, doc.eta, doc.k) {
            (Some(name), None, None) => match METALS.iter().find(|(n, _, _)| n == name) {
                Some(&(_, eta, k)) => (eta, k),
                None => {
                    let names: Vec<&str> = METALS.iter().map(|(n, _, _)| *n).collect();
                    return self.error(
                        span.clone(),
                        format!(
                            "unknown metal '{name}': expected one of {} (or eta and k)",
                            names.join(", ")
                        ),
                    );
                }
            },
            (None, Some(eta), Some(k)) => (eta, k),
            // Mitsuba's default: a perfect mirror.
            (None, None, None) => ([0.0; 3], [1.0; 3]),
            _ => {
                return self
                    .error(span.clone(), "a conductor takes `material` or both `eta` and `k`");
            }
        };
        Ok(Conductor {
            eta: Vec3::from_array(eta),
            k: Vec3::from_array(k),
            specular_reflectance: Vec3::from_array(doc.specular_reflectance.unwrap_or([1.0; 3])),
        })
    }

    /// The distribution; a textured `alpha` goes to `textures.roughness`.
    fn roughness(
        &self,
        doc: &RoughnessDoc,
        textures: &mut MaterialTextures,
        span: &Range<usize>,
    ) -> Result<Ggx> {
        if let Some(name) = &doc.distribution
            && name != "ggx"
        {
            return self
                .error(span.clone(), format!("distribution '{name}' is not supported: only ggx"));
        }
        let alpha = match &doc.alpha {
            Some(alpha) => {
                let (a, texture) = self.scalar(alpha, 0.1, span)?;
                textures.roughness = texture;
                Some(a)
            }
            None => None,
        };
        let (u, v) = match (alpha, doc.alpha_u, doc.alpha_v) {
            (Some(a), None, None) => (a, a),
            (None, Some(u), Some(v)) => (u, v),
            // Mitsuba's default roughness.
            (None, None, None) => (0.1, 0.1),
            _ => return self.error(span.clone(), "give `alpha`, or both `alpha_u` and `alpha_v`"),
        };
        if !(u > 0.0 && v > 0.0 && u.is_finite() && v.is_finite()) {
            return self
                .error(span.clone(), format!("alpha ({u}, {v}) must be finite and above 0"));
        }
        Ok(Ggx::new(u, v))
    }

    pub(super) fn material(
        &self,
        name: &str,
        doc: &MaterialDoc,
        span: Range<usize>,
    ) -> Result<Material> {
        let mut textures = MaterialTextures::default();
        let with = |bsdf, textures| Material {
            name: name.to_string(),
            bsdf,
            two_sided: false,
            emission: Vec3::ZERO,
            textures,
        };
        let material = match doc {
            MaterialDoc::Diffuse { reflectance } => {
                let (reflectance, texture) = self.colour(reflectance, &span)?;
                textures.base_color = texture;
                with(Bsdf::Diffuse(crate::material::Diffuse { reflectance }), textures)
            }
            MaterialDoc::Conductor { metal } => {
                with(Bsdf::Conductor(self.conductor(metal, &span)?), textures)
            }
            MaterialDoc::Roughconductor { metal, roughness } => {
                let distribution = self.roughness(roughness, &mut textures, &span)?;
                let conductor = self.conductor(metal, &span)?;
                with(Bsdf::RoughConductor(RoughConductor { conductor, distribution }), textures)
            }
            MaterialDoc::Dielectric { int_ior, ext_ior } => {
                let eta =
                    self.ior(int_ior, 1.5046, &span)? / self.ior(ext_ior, 1.000_277, &span)?;
                with(Bsdf::Dielectric(Dielectric { eta }), textures)
            }
            MaterialDoc::Roughdielectric { int_ior, ext_ior, roughness } => {
                let eta =
                    self.ior(int_ior, 1.5046, &span)? / self.ior(ext_ior, 1.000_277, &span)?;
                let distribution = self.roughness(roughness, &mut textures, &span)?;
                with(Bsdf::RoughDielectric(RoughDielectric { eta, distribution }), textures)
            }
            MaterialDoc::Plastic {
                diffuse_reflectance,
                specular_reflectance,
                int_ior,
                ext_ior,
                nonlinear,
            } => {
                let eta = self.ior(int_ior, 1.49, &span)? / self.ior(ext_ior, 1.000_277, &span)?;
                let diffuse = match diffuse_reflectance {
                    Some(doc) => {
                        let (colour, texture) = self.colour(doc, &span)?;
                        textures.base_color = texture;
                        colour
                    }
                    None => Vec3::splat(0.5),
                };
                let specular = Vec3::from_array(specular_reflectance.unwrap_or([1.0; 3]));
                with(Bsdf::Plastic(Plastic::new(diffuse, specular, eta, *nonlinear)), textures)
            }
            MaterialDoc::Pbr { base_color, metallic, roughness } => {
                let base_color = match base_color {
                    Some(doc) => {
                        let (colour, texture) = self.colour(doc, &span)?;
                        textures.base_color = texture;
                        colour
                    }
                    None => Vec3::ONE,
                };
                let roughness = match roughness {
                    Some(doc) => {
                        let (value, texture) = self.scalar(doc, 1.0, &span)?;
                        textures.roughness = texture;
                        value
                    }
                    None => 1.0,
                };
                let metallic = metallic.unwrap_or(0.0);
                with(Bsdf::Pbr(Pbr { base_color, metallic, roughness }), textures)
            }
            MaterialDoc::Twosided { bsdf } => {
                Material { two_sided: true, ..self.material(name, bsdf, span.clone())? }
            }
        };
        match material.validate() {
            Ok(()) => Ok(material),
            Err(problem) => self.error(span, format!("material '{name}': {problem}")),
        }
    }
}
