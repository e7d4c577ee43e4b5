//! `raylab view --headless`: the window's frames without the window, one line per frame, then
//! the median: the frame function's benchmark.

use std::time::{Duration, Instant};

use anyhow::Result;
use raylab::interactive::{FrameRenderer, HEADLESS_FPS, scripted_motions};

use crate::screenshot::save_screenshot;
use crate::stats;
use crate::view_session::Session;

/// `raylab view --headless`: the window's frames without the window, one line per frame, then
/// the median.
pub fn headless(mut session: Session, frames: u32, still: bool) -> Result<()> {
    let Session { scene, accel, pool, ref mut controller, mut view, .. } = session;
    // Benchmarks measure full-resolution frames: no budget.
    let mut renderer = FrameRenderer::new(None, session.max_spp);
    renderer.path_settings = session.path_settings;
    renderer.sample_settings = session.sample_settings;
    let mut times = Vec::with_capacity(frames as usize);
    let mut words = Vec::new();
    let run_start = Instant::now();
    for frame in 0..frames {
        // Simulated time: the path is the same on every machine.
        let at = Duration::from_secs(frame as u64) / HEADLESS_FPS;
        if !still {
            for (motion, held) in scripted_motions(frame) {
                match (held, controller.is_held(motion)) {
                    (true, false) => controller.press(motion, at),
                    (false, true) => controller.release(motion, at),
                    _ => {}
                }
            }
            controller.advance(at);
            view.pose = controller.pose();
        }
        if renderer.is_done(&view) {
            println!("the picture has all its {} samples per pixel: stopping", session.max_spp);
            break;
        }
        let info = pool.install(|| renderer.frame(scene, accel, &view, &mut words))?;
        let ms = info.render_time.as_secs_f64() * 1e3;
        times.push(ms);
        println!(
            "frame {}: {ms:.2} ms, {}×{}, {} spp{}",
            frame + 1,
            view.width,
            view.height,
            info.samples,
            if info.moving { ", moving" } else { "" }
        );
    }
    let total = run_start.elapsed();
    let summary = summarize(&mut times);
    println!(
        "{} frames of {} ({} triangles) at {}×{} on {} thread{}: median {:.2} ms ({:.1} frames \
         per second), mean {:.2} ms, 10th–90th percentile {:.2}–{:.2} ms; {:.2} s in all",
        times.len(),
        scene.name,
        scene.geometry.len(),
        view.width,
        view.height,
        pool.current_num_threads(),
        if pool.current_num_threads() == 1 { "" } else { "s" },
        summary.median,
        1e3 / summary.median,
        summary.mean,
        summary.p10,
        summary.p90,
        total.as_secs_f64(),
    );
    if let Some(path) = session.screenshot {
        save_screenshot(path, &words, view.width, view.height)?;
        println!("screenshot: {}", path.display());
    }
    Ok(())
}

struct Summary {
    median: f64,
    mean: f64,
    p10: f64,
    p90: f64,
}

/// Median, mean and 10th and 90th percentiles (nearest rank) of frame times.
fn summarize(times: &mut [f64]) -> Summary {
    let median = stats::median(times);
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    Summary {
        median,
        mean,
        p10: stats::nearest_rank(times, 0.1),
        p90: stats::nearest_rank(times, 0.9),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summaries_use_the_median() {
        let s = summarize(&mut [5.0, 1.0, 3.0, 100.0]);
        assert_eq!((s.median, s.mean, s.p10, s.p90), (4.0, 27.25, 1.0, 100.0));
        assert_eq!(summarize(&mut [2.0, 9.0, 4.0]).median, 4.0);
    }
}
