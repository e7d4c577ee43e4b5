//! glTF 2.0 models: the Khronos samples load with their known counts, bounds, attributes and
//! camera, and broken files are one-line errors naming the file and the part.

use std::path::{Path, PathBuf};

use glam::Vec3;
use raylab::scene::load_mesh;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes").join(name)
}

/// The engine's known figures (`shared/data/stats.json`, measured apart from raylab): 121,496
/// triangles once every instance is placed, and the bounding box of its flattened OBJ.
#[test]
fn the_engine_loads_with_its_known_triangles_and_bounds() {
    let loaded = load_mesh(&data("2CylinderEngine/2CylinderEngine.glb")).unwrap();
    let mesh = &loaded.mesh;
    assert_eq!(mesh.triangles.len(), 121_496);
    assert_eq!(mesh.materials.len(), 34);
    assert!(mesh.material_ids.iter().all(|id| id.is_some_and(|i| i < 34)));
    let (lo, hi) = mesh.bounds().unwrap();
    let expected_lo = Vec3::new(-371.692_26, -180.971_56, -139.999_99);
    let expected_hi = Vec3::new(371.692_17, 92.041_56, 128.0);
    assert!(lo.abs_diff_eq(expected_lo, 2e-3), "{lo}");
    assert!(hi.abs_diff_eq(expected_hi, 2e-3), "{hi}");
    let camera = loaded.camera.expect("the engine has a perspective camera");
    assert!(camera.position.is_finite() && camera.fov_deg > 1.0 && camera.fov_deg < 90.0);
}

/// The textured box: 12 triangles of a unit cube turned 90° about x by its root node, with
/// unit normals and texture coordinates spanning u ∈ [0, 6].
#[test]
fn the_textured_box_loads_with_normals_and_texture_coordinates() {
    let loaded = load_mesh(&data("BoxTextured/BoxTextured.gltf")).unwrap();
    let mesh = &loaded.mesh;
    assert_eq!(mesh.triangles.len(), 12);
    let (lo, hi) = mesh.bounds().unwrap();
    assert!(lo.abs_diff_eq(Vec3::splat(-0.5), 1e-6) && hi.abs_diff_eq(Vec3::splat(0.5), 1e-6));
    let normals = mesh.normals.as_ref().expect("normals");
    assert_eq!(normals.triangles.len(), 12);
    assert!(normals.values.iter().all(|n| (n.length() - 1.0).abs() < 1e-5), "{:?}", normals.values);
    // Each face's normal points away from the cube's centre, through the root's rotation.
    for (t, corners) in mesh.triangles.iter().enumerate() {
        let centre = corners.iter().map(|&v| mesh.positions[v as usize]).sum::<Vec3>() / 3.0;
        let n = normals.values[normals.triangles[t][0] as usize];
        assert!(n.dot(centre) > 0.0, "triangle {t}");
    }
    let uvs = mesh.uvs.as_ref().expect("texture coordinates");
    let max_u = uvs.values.iter().map(|uv| uv.x).fold(f32::MIN, f32::max);
    let min_u = uvs.values.iter().map(|uv| uv.x).fold(f32::MAX, f32::min);
    assert_eq!((min_u, max_u), (0.0, 6.0));
    assert_eq!(loaded.camera, None);
}

/// A copy of the textured box's files in a folder of their own, with its JSON edited.
fn broken_box(edit: impl FnOnce(&mut String)) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let mut json = std::fs::read_to_string(data("BoxTextured/BoxTextured.gltf")).unwrap();
    edit(&mut json);
    std::fs::copy(data("BoxTextured/BoxTextured0.bin"), dir.path().join("BoxTextured0.bin"))
        .unwrap();
    let path = dir.path().join("box.gltf");
    std::fs::write(&path, json).unwrap();
    (dir, path)
}

fn error(path: &Path) -> String {
    let message = load_mesh(path).unwrap_err().to_string();
    assert!(message.starts_with(&path.display().to_string()), "{message}");
    assert!(!message.contains('\n'), "one line: {message}");
    message
}

#[test]
fn broken_files_are_one_line_errors() {
    // A truncated .glb.
    let dir = tempfile::tempdir().unwrap();
    let engine = std::fs::read(data("2CylinderEngine/2CylinderEngine.glb")).unwrap();
    let truncated = dir.path().join("engine.glb");
    std::fs::write(&truncated, &engine[..engine.len() / 3]).unwrap();
    error(&truncated);
    std::fs::write(&truncated, &engine[..10]).unwrap();
    error(&truncated);
    // A missing buffer file.
    let (dir, path) = broken_box(|_| {});
    std::fs::remove_file(dir.path().join("BoxTextured0.bin")).unwrap();
    error(&path);
    // An accessor that reads past its buffer view.
    let (_dir, path) = broken_box(|json| {
        *json = json.replacen("\"count\": 36", "\"count\": 360000", 1);
    });
    let message = error(&path);
    assert!(message.contains("outside") || message.contains("accessor"), "{message}");
    // Lines, not triangles.
    let (_dir, path) = broken_box(|json| *json = json.replacen("\"mode\": 4", "\"mode\": 1", 1));
    assert!(error(&path).ends_with("mesh 0 primitive 0: mode Lines: only triangles are supported"));
    // An index beyond the vertices: the POSITION accessor shortened to 20 of 24.
    let (_dir, path) = broken_box(|json| {
        let position = json.find("\"count\": 24").unwrap();
        json.replace_range(position..position + 11, "\"count\": 20");
    });
    let message = error(&path);
    assert!(message.contains("index") || message.contains("values for"), "{message}");
    // Not JSON at all.
    let (_dir, path) = broken_box(|json| json.truncate(100));
    error(&path);
}

/// A one-triangle glTF with an embedded buffer and a camera node with `camera_node`'s transform.
fn with_camera(dir: &Path, camera_node: &str) -> PathBuf {
    let floats: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    let mut base64 = String::new();
    const TABLE: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for chunk in bytes.chunks(3) {
        let n = chunk.iter().fold(0u32, |n, &b| n << 8 | b as u32) << (8 * (3 - chunk.len()));
        for i in 0..=chunk.len() {
            base64.push(TABLE[(n >> (18 - 6 * i) & 63) as usize] as char);
        }
        base64.push_str(&"=".repeat(3 - chunk.len()));
    }
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0,
        "scenes": [{{"nodes": [0, 1]}}],
        "nodes": [{{"mesh": 0}}, {{"camera": 0, {camera_node}}}],
        "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.5, "znear": 0.1}}}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0]}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
        "buffers": [{{"byteLength": 36, "uri": "data:application/octet-stream;base64,{base64}"}}]}}"#
    );
    let path = dir.join("camera.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

/// A glTF camera (looking along its −z, up its +y, in a y-up file) becomes the same view in the
/// lab's frame: at (0, 0, 5) it is at the lab's (0, 0, −5) looking along +z, level; turned 90°
/// about y it looks along the file's −x, yaw −90°; rolled, it rolls.
#[test]
fn the_file_camera_is_the_same_view() {
    let dir = tempfile::tempdir().unwrap();
    let camera = |node: &str| load_mesh(&with_camera(dir.path(), node)).unwrap().camera.unwrap();
    let c = camera(r#""translation": [0, 0, 5]"#);
    assert!(c.position.abs_diff_eq(Vec3::new(0.0, 0.0, -5.0), 1e-6));
    assert!(c.yaw.abs() < 1e-6 && c.pitch.abs() < 1e-6 && c.roll.abs() < 1e-6);
    assert!((c.fov_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let c = camera(&format!(r#""rotation": [0, {half}, 0, {half}]"#));
    assert!((c.yaw.to_degrees() + 90.0).abs() < 1e-3, "{}", c.yaw.to_degrees());
    assert!(c.pitch.abs() < 1e-5 && c.roll.abs() < 1e-5);
    // Rolled 30° about its view axis (−z), counter-clockwise as seen from behind.
    let (s, w) = (15f32.to_radians().sin(), 15f32.to_radians().cos());
    let c = camera(&format!(r#""rotation": [0, 0, {s}, {w}]"#));
    // Its up turns toward −x, to the left: a roll of −30° (positive turns up to the right).
    assert!((c.roll.to_degrees() + 30.0).abs() < 1e-3, "{}", c.roll.to_degrees());
    assert!(c.yaw.abs() < 1e-5 && c.pitch.abs() < 1e-5);
}
