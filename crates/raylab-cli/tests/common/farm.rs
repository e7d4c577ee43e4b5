//! What the farm tests share: reading a part's pixels as bits, and a scene with camera keyframes.

use std::path::Path;

use raylab::parts::{self, PartKind};

/// A part's channels as bits, with its sample count and region.
pub fn bits(path: &Path) -> (Vec<(String, Vec<u32>)>, u32, raylab::Region) {
    let part = parts::read_part(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(part.header.kind, PartKind::Image);
    let channels = part
        .channels
        .into_iter()
        .map(|(name, values)| (name, values.into_iter().map(f32::to_bits).collect()))
        .collect();
    (channels, part.header.samples, part.header.region)
}

/// Mitsuba's box with camera keyframes: frame 0 is its own camera, frame 4 one moved and turned
/// 15° (the box has no meshes, so the file may live anywhere).
pub fn animated_box(dir: &Path) -> String {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/cornell-mitsuba.toml"
    ))
    .unwrap();
    let keys = r#"
[[keyframes]]
frame = 0
position = [0, 0, 3.9000000953674316]
target = [0, 0, 2.9000000953674316]
up = [0, 1, 0]
fov = 39.3077
fov_axis = "smaller"

[[keyframes]]
frame = 4
position = [0.4, 0.1, 3.5]
yaw = 15
pitch = -5
fov = 45
fov_axis = "smaller"
"#;
    let path = dir.join("animated.toml");
    std::fs::write(&path, format!("{text}\n{keys}")).unwrap();
    path.display().to_string()
}
