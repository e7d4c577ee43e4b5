//! `[[lights]]`: Mitsuba 3's emitters by their names and keys (`point`, `envmap`, `directional`,
//! `spot`), a `sun` disc and the constant `environment`, in the file's y-up frame.

use std::f32::consts::PI;
use std::ops::Range;
use std::sync::Arc;

use glam::Vec3;
use serde::Deserialize;
use toml::Spanned;

use super::builder::{Builder, Result, RotateDoc, SceneFileError};
use crate::light::{
    DirectionalLight, EnvironmentMap, Light, PointLight, SpotLight, SpotProfile, SunLight,
};
use crate::scene::model_to_lab;

/// A colour: one number for grey, or `[r, g, b]`.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged)]
pub(super) enum ColorDoc {
    Grey(f32),
    Rgb([f32; 3]),
}

impl ColorDoc {
    fn rgb(self) -> Vec3 {
        match self {
            ColorDoc::Grey(g) => Vec3::splat(g),
            ColorDoc::Rgb(c) => Vec3::from_array(c),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub(super) enum LightDoc {
    Point {
        position: [f32; 3],
        intensity: Option<ColorDoc>,
        power: Option<ColorDoc>,
    },
    Environment {
        radiance: ColorDoc,
    },
    Envmap {
        filename: String,
        scale: Option<f32>,
        rotate: Option<RotateDoc>,
        to_world: Option<[[f32; 4]; 4]>,
    },
    Directional {
        direction: Option<[f32; 3]>,
        to_world: Option<[[f32; 4]; 4]>,
        irradiance: Option<ColorDoc>,
    },
    Spot {
        intensity: Option<ColorDoc>,
        cutoff_angle: Option<f32>,
        beam_width: Option<f32>,
        position: Option<[f32; 3]>,
        target: Option<[f32; 3]>,
        to_world: Option<[[f32; 4]; 4]>,
    },
    Sun {
        direction: Option<[f32; 3]>,
        to_world: Option<[[f32; 4]; 4]>,
        aperture: Option<f32>,
        radiance: Option<ColorDoc>,
        irradiance: Option<ColorDoc>,
    },
}

impl<F: Fn(Option<Range<usize>>, String) -> SceneFileError> Builder<'_, F> {
    pub(super) fn light(&self, light: &Spanned<LightDoc>) -> Result<Light> {
        let span = light.span();
        let fail = |message: String| self.error::<Light>(span.clone(), message);
        let light = match light.get_ref() {
            LightDoc::Point { position, intensity, power } => {
                let power = match (intensity, power) {
                    (Some(i), None) => i.rgb() * (4.0 * PI),
                    (None, Some(p)) => p.rgb(),
                    _ => return fail("a point light needs one of intensity or power".into()),
                };
                Light::Point(PointLight {
                    position: model_to_lab(Vec3::from_array(*position)),
                    power,
                })
            }
            LightDoc::Environment { radiance } => Light::Environment { radiance: radiance.rgb() },
            LightDoc::Envmap { filename, scale, rotate, to_world } => {
                let placement = self.placement(None, rotate.as_ref(), None, *to_world)?;
                let path = self.folder.join(filename);
                let image = crate::image_io::load_film(&path)
                    .map_err(|e| (self.at)(Some(span.clone()), format!("envmap: {e}")))?;
                let name = path.display().to_string();
                let map = EnvironmentMap::new(
                    name,
                    image,
                    scale.unwrap_or(1.0),
                    placement.matrix3.into(),
                )
                .map_err(|e| (self.at)(Some(span.clone()), format!("envmap {e}")))?;
                Light::EnvironmentMap(Arc::new(map))
            }
            LightDoc::Directional { direction, to_world, irradiance } => {
                let direction =
                    self.direction("a directional light", *direction, *to_world, &span)?;
                let irradiance = irradiance.map_or(Vec3::ONE, ColorDoc::rgb);
                Light::Directional(DirectionalLight { direction, irradiance })
            }
            LightDoc::Spot { intensity, cutoff_angle, beam_width, position, target, to_world } => {
                let (position, axis) = match (position, target, to_world) {
                    (Some(p), Some(t), None) => {
                        let (p, t) = (Vec3::from_array(*p), Vec3::from_array(*t));
                        (p, t - p)
                    }
                    (None, None, Some(_)) => {
                        let m = self.placement(None, None, None, *to_world)?;
                        (Vec3::from(m.translation), m.transform_vector3(Vec3::Z))
                    }
                    _ => {
                        return fail(
                            "a spot light needs position and target, or to_world (not both)".into(),
                        );
                    }
                };
                let cutoff = cutoff_angle.unwrap_or(20.0);
                let beam = beam_width.unwrap_or(0.75 * cutoff);
                let spot = SpotLight::new(
                    model_to_lab(position),
                    model_to_lab(axis),
                    intensity.map_or(Vec3::ONE, ColorDoc::rgb),
                    cutoff.to_radians(),
                    beam.to_radians(),
                    SpotProfile::Mitsuba,
                );
                match spot {
                    Some(spot) if position.is_finite() => Light::Spot(spot),
                    _ => {
                        return fail(format!(
                            "a spot light needs a finite position, a direction (target ≠ \
                             position) and 0 ≤ beam_width ≤ cutoff_angle ≤ 180 degrees (here \
                             {beam} and {cutoff})"
                        ));
                    }
                }
            }
            LightDoc::Sun { direction, to_world, aperture, radiance, irradiance } => {
                let direction = self.direction("a sun", *direction, *to_world, &span)?;
                let aperture = aperture.unwrap_or(SunLight::EARTH_APERTURE_DEG);
                let radius = 0.5 * aperture.to_radians();
                let sun = match (radiance, irradiance) {
                    (Some(l), None) => SunLight::new(direction, radius, l.rgb()),
                    (None, Some(e)) => SunLight::with_irradiance(direction, radius, e.rgb()),
                    _ => return fail("a sun needs one of radiance or irradiance".into()),
                };
                let Some(sun) = sun else {
                    return fail(format!(
                        "a sun's aperture must be more than 0 and at most 180 degrees (here \
                         {aperture})"
                    ));
                };
                Light::Sun(sun)
            }
        };
        Ok(light)
    }

    /// The way a light travels: `direction`, or `to_world`'s +z (Mitsuba's convention), one of
    /// them, not zero; in the lab's frame, unit.
    fn direction(
        &self,
        what: &str,
        direction: Option<[f32; 3]>,
        to_world: Option<[[f32; 4]; 4]>,
        span: &Range<usize>,
    ) -> Result<Vec3> {
        let direction = match (direction, to_world) {
            (Some(d), None) => Vec3::from_array(d),
            (None, Some(_)) => {
                self.placement(None, None, None, to_world)?.transform_vector3(Vec3::Z)
            }
            _ => {
                return self.error(
                    span.clone(),
                    format!("{what} needs direction or to_world (one of them)"),
                );
            }
        };
        match model_to_lab(direction).try_normalize() {
            Some(d) => Ok(d),
            None => self.error(
                span.clone(),
                format!("{what}'s direction {direction} must be finite and not zero"),
            ),
        }
    }
}
