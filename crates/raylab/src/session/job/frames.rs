//! An animation's frames, each to its own file: [`RenderJob::render_frames`] and the files'
//! names ([`frame_path`]).

use std::path::{Path, PathBuf};

use super::{Event, FrameOutcome, RenderJob};
use crate::camera::Camera;
use crate::parts::Part;
use crate::session::SessionError;
use crate::session::checkpoint::checkpoint_path;

impl RenderJob<'_> {
    /// Renders frames `first..=last` of the scene's animation, each through the camera
    /// `camera_at` gives for it, to `pattern` with the frame's number in place (see
    /// [`frame_path`]); `resume` goes on with the frame whose checkpoint it is. `each` gets
    /// every frame's outcome. Returns the frame it stopped before, if the stop flag stopped it.
    pub fn render_frames<E: From<SessionError>>(
        &mut self,
        (first, last): (u32, u32),
        pattern: &Path,
        camera_at: &dyn Fn(&mut Self, u32) -> Result<Camera, SessionError>,
        mut resume: Option<Part>,
        events: &(dyn Fn(Event) + Sync),
        each: &mut dyn FnMut(&Self, FrameOutcome) -> Result<(), E>,
    ) -> Result<Option<u32>, E> {
        if self.scene.keyframes.is_empty() {
            return Err(SessionError::Invalid(format!(
                "frames are an animation's, and {} has no camera keyframes ([[keyframes]] in a \
                 scene file, see docs/scene-format.md)",
                self.scene.name
            ))
            .into());
        }
        frame_path(pattern, first)?;
        for frame in first..=last {
            if self.stopped() {
                return Ok(Some(frame));
            }
            let output = frame_path(pattern, frame)?;
            let camera = camera_at(self, frame)?;
            let checkpoint = checkpoint_path(&output);
            let outcome = self.render_frame(
                &camera,
                &output,
                resume.take_if(|s| s.path == checkpoint),
                events,
            )?;
            let interrupted = outcome.interrupted;
            each(self, outcome)?;
            if interrupted {
                return Ok(Some(frame + 1));
            }
        }
        Ok(None)
    }
}

/// The file of frame `frame` of an animation written to `pattern`: its printf-style `%d` or
/// `%0Nd` replaced by the frame's number (`out_%04d.exr`, frame 7: `out_0007.exr`).
pub fn frame_path(pattern: &Path, frame: u32) -> Result<PathBuf, SessionError> {
    let name = pattern.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let missing = || {
        SessionError::Invalid(format!(
            "an animation is written a file per frame: the output name needs the frame number's \
             place, like out_%04d.exr, not {}",
            pattern.display()
        ))
    };
    let start = name.find('%').ok_or_else(missing)?;
    let rest = &name[start + 1..];
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    if !rest[digits.len()..].starts_with('d') {
        return Err(missing());
    }
    let width: usize = if digits.is_empty() { 0 } else { digits.parse().map_err(|_| missing())? };
    if width > 10 {
        return Err(SessionError::Invalid(format!(
            "{}: at most 10 digits for the frame number",
            pattern.display()
        )));
    }
    let number = format!("{frame:0width$}");
    let file = format!("{}{number}{}", &name[..start], &rest[digits.len() + 1..]);
    if file.contains('%') {
        return Err(SessionError::Invalid(format!(
            "{}: one frame number place only",
            pattern.display()
        )));
    }
    Ok(pattern.with_file_name(file))
}
