//! A frame's render in a few lines of text, as `raylab render` prints it.

use std::fmt;
use std::time::Duration;

use super::{FrameOutcome, RenderJob};
use crate::camera::tidy;
use crate::film::format_bytes;
use crate::region::Region;
use crate::settings::IntegratorKind;

/// What a frame's render did, for people: the output, the size, the scene, the integrator, the
/// time and throughput; the camera; the memory; the lab's light; the mean radiance of float
/// output. Shown with `{}`, one fact per line.
pub struct FrameSummary<'a> {
    /// The job that rendered it.
    pub job: &'a RenderJob<'a>,
    /// What it did.
    pub outcome: &'a FrameOutcome,
    /// How long opening the scene took.
    pub load_time: Duration,
}

impl fmt::Display for FrameSummary<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (job, outcome) = (self.job, self.outcome);
        let (scene, settings, camera) = (job.scene(), job.settings(), &outcome.camera);
        let (width, height) = (camera.width, camera.height);
        let region = job.region((width, height));
        let spp = outcome.samples;
        let what = match settings.integrator {
            IntegratorKind::Lab => format!("stage {}", settings.stage),
            IntegratorKind::Path | IntegratorKind::PathScalar => format!(
                "path tracing{}, max depth {}",
                if settings.integrator == IntegratorKind::PathScalar { " (scalar)" } else { "" },
                settings.max_depth.map_or("unlimited".to_string(), |d| d.to_string())
            ),
            other => other.to_string(),
        };
        let spp_text = if spp == 1 { String::new() } else { format!(", {spp} samples per pixel") };
        let size = if region != Region::full(width, height) {
            format!("region {region} of {width}×{height}")
        } else {
            format!("{width}×{height}")
        };
        let (threads, elapsed) = (job.threads(), outcome.elapsed.as_secs_f64());
        let samples = region.pixels() as f64 * (spp - outcome.first_sample) as f64;
        writeln!(
            f,
            "{}: {size}, {} ({} triangles) {what}{spp_text}, {:.1} ms on {threads} thread{} \
             (+{:.1} ms BVH build), {:.2} M samples/s",
            outcome.output.display(),
            scene.name,
            scene.geometry.len(),
            elapsed * 1e3,
            if threads == 1 { "" } else { "s" },
            job.build_time().as_secs_f64() * 1e3,
            samples / elapsed.max(1e-9) / 1e6,
        )?;
        writeln!(f, "{camera}")?;
        let (texture_bytes, images) = scene.texture_bytes();
        let textures = match images {
            0 => String::new(),
            1 => format!(", 1 texture {}", format_bytes(texture_bytes)),
            n => format!(", {n} textures {}", format_bytes(texture_bytes)),
        };
        let geometry = &scene.geometry;
        let instances = if geometry.is_instanced() {
            let placed = geometry.instances().iter().filter(|x| x.placement.is_some()).count();
            format!(" ({} triangles stored; {placed} instances)", geometry.stored_len())
        } else {
            String::new()
        };
        let bvh_bytes = job.built_accel().map_or(0, |bvh| bvh.bytes() as u64);
        writeln!(
            f,
            "scene loaded in {:.1} ms; memory: geometry {}{instances}, BVH {}{textures}",
            self.load_time.as_secs_f64() * 1e3,
            format_bytes(geometry.bytes()),
            format_bytes(bvh_bytes),
        )?;
        if settings.integrator == IntegratorKind::Lab {
            let light = scene.lab_light();
            let p = light.position;
            let position = format!("({}, {}, {})", tidy(p.x), tidy(p.y), tidy(p.z));
            writeln!(f, "light at {position} power {}", tidy(light.power.x))?;
        }
        let extension = outcome.output.extension().map(|e| e.to_string_lossy().to_lowercase());
        if let Some(film) = &outcome.film
            && matches!(extension.as_deref(), Some("exr" | "pfm"))
        {
            let sum = film.pixels().iter().map(|p| p.as_dvec3()).sum::<glam::DVec3>();
            let mean = sum / film.pixels().len() as f64;
            writeln!(f, "mean radiance ({:.6}, {:.6}, {:.6})", mean.x, mean.y, mean.z)?;
        }
        Ok(())
    }
}
