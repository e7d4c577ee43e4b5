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
    assert_eq!(loaded.triangle_count(), 121_496);
    assert_eq!(loaded.mesh.materials.len(), 34);
    let meshes = std::iter::once(&loaded.mesh).chain(loaded.instanced.iter().map(|m| &m.mesh));
    let mut ids = meshes.flat_map(|m| m.material_ids.iter());
    assert!(ids.all(|id| id.is_some_and(|i| i < 34)));
    let (lo, hi) = loaded.bounds().unwrap();
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

/// sRGB to linear (IEC 61966-2-1), written out here apart from the library's.
fn srgb_decode(code: u8) -> f32 {
    let c = f32::from(code) / 255.0;
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// The textured box seen face on: every pixel whose hit lies inside a patch of one colour in
/// the PNG (read here by the `image` crate apart from raylab's textures) shows that colour,
/// the right way round. The front face reads u ∈ [3, 4] of an image that wraps MIRRORED_REPEAT
/// in s: read with REPEAT it would show mirrored, so the sun would be on the left.
#[test]
fn the_textured_box_shows_its_texels_the_right_way_round() {
    use raylab::{Accelerator, Aov, AovKind, BruteForce, Camera, Integrator, Scene};
    let path = data("BoxTextured/BoxTextured.gltf");
    let scene = Scene::from_mesh(&load_mesh(&path).unwrap().mesh);
    let accel = BruteForce::new(&scene.vertices());
    let aov = Aov::new(&scene, &accel, AovKind::Albedo);
    let png = image::open(data("BoxTextured/CesiumLogoFlat.png")).unwrap().to_rgba8();
    let (w, h) = png.dimensions();
    // The face (glTF z = 0.5, the lab's z = −0.5) seen from (0, 0, −3): the middle 90 % of
    // it fills a 96² image.
    let mut camera = Camera::lab(96, 96);
    camera.focal_length_px = 96.0 * 2.5 / 0.9;
    let mut sampler =
        raylab::sampling::Sampler::new(raylab::SamplerKind::Independent, 0, (0, 0), 0);
    let (mut checked, mut sun_right, mut sun_left) = (0, 0, 0);
    for y in 0..96 {
        for x in 0..96 {
            let ray = camera.pixel_ray(x, y);
            let hit = accel.closest_hit(&ray).expect("the face fills the view");
            let p = ray.at(hit.t);
            assert!((p.z + 0.5).abs() < 1e-5, "the front face");
            // Lab x to the right and y down: s = x + ½, t = y + ½ (t = 0 the image's top).
            let (s, t) = (p.x + 0.5, p.y + 0.5);
            let (tx, ty) = ((s * w as f32) as i64, (t * h as f32) as i64);
            // Only where the texel's 3×3 neighbourhood is one colour (bilinear = the texel).
            let texel = |dx: i64, dy: i64| {
                let (x, y) = ((tx + dx).clamp(0, w as i64 - 1), (ty + dy).clamp(0, h as i64 - 1));
                png.get_pixel(x as u32, y as u32).0
            };
            let centre = texel(0, 0);
            if (-1..=1).any(|dy| (-1..=1).any(|dx| texel(dx, dy) != centre)) {
                continue;
            }
            let expected =
                Vec3::new(srgb_decode(centre[0]), srgb_decode(centre[1]), srgb_decode(centre[2]));
            let got = aov.radiance(&ray, &mut sampler);
            assert!(got.abs_diff_eq(expected, 1e-5), "pixel ({x}, {y}): {got} against {expected}");
            checked += 1;
            // The sun: the white disc in the sky, right of the middle in the PNG.
            let white = centre[..3].iter().all(|&c| c > 250);
            if white && t < 0.32 {
                if s > 0.5 { sun_right += 1 } else { sun_left += 1 }
            }
        }
    }
    assert!(checked > 96 * 96 / 2, "{checked} pixels checked");
    assert!(sun_right > 10 && sun_left == 0, "sun at right {sun_right}, at left {sun_left}");
}

/// The metallic-roughness factors become the `Pbr` BSDF, transmission makes glass of the file's
/// index, and `KHR_lights_punctual` lights light the scene in the lab's frame: a point light
/// (intensity in candela: power 4π·I), a spot light (its cone angles, glTF's falloff, along its
/// node's −z) and a directional light (lux as irradiance, along its node's −z); a missing image
/// is a warning.
#[test]
fn materials_and_punctual_lights_map_to_raylab() {
    use raylab::material::{Bsdf, Dielectric, Pbr};
    let (_dir, path) = broken_box(|json| {
        *json = json
            .replace(
                r#""metallicFactor": 0.0"#,
                r#""metallicFactor": 0.25, "roughnessFactor": 0.5, "baseColorFactor": [0.5, 0.6, 0.7, 0.9]"#,
            )
            .replace(r#""name": "Texture""#, r#""name": "Texture", "alphaMode": "MASK", "alphaCutoff": 0.3"#)
            .replace(
                r#""scene": 0,"#,
                r#""scene": 0,
                "extensionsUsed": ["KHR_lights_punctual"],
                "extensions": {"KHR_lights_punctual": {"lights": [
                    {"type": "point", "color": [1, 0.5, 0.25], "intensity": 10},
                    {"type": "directional", "intensity": 3},
                    {"type": "spot", "intensity": 5, "range": 2,
                     "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}]}},"#,
            )
            .replacen(
                "\"nodes\": [\n                0\n            ]",
                "\"nodes\": [0, 2, 3, 4]",
                1,
            )
            .replace(
                "            \"mesh\": 0\n        }\n    ],",
                "            \"mesh\": 0\n        },
                {\"translation\": [1, 2, 3], \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}},
                {\"extensions\": {\"KHR_lights_punctual\": {\"light\": 1}}},
                {\"translation\": [0, 1, 0], \"rotation\": [0.70710678, 0, 0, 0.70710678],
                 \"extensions\": {\"KHR_lights_punctual\": {\"light\": 2}}}\n    ],",
            );
    });
    let loaded = load_mesh(&path).unwrap();
    // (The copy has no PNG beside it: a missing image is a warning, and the model loads.)
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(
        loaded.warnings[0].contains("material \"Texture\": its base colour texture is ignored")
    );
    assert!(loaded.warnings[0].contains("CesiumLogoFlat.png: cannot read it"));
    let scene = raylab::Scene::from_loaded(&loaded);
    // alphaMode MASK: cut out below the cutoff, the factor's alpha kept.
    let mask = scene.materials[0].textures.alpha_mask;
    assert_eq!(mask, Some(raylab::material::AlphaMask { cutoff: 0.3, factor: 0.9 }));
    let Bsdf::Pbr(pbr) = &scene.materials[0].bsdf else {
        panic!("{:?}", scene.materials[0].bsdf);
    };
    assert_eq!(*pbr, Pbr { base_color: Vec3::new(0.5, 0.6, 0.7), metallic: 0.25, roughness: 0.5 });
    let points: Vec<raylab::PointLight> = scene
        .lights
        .iter()
        .filter_map(|l| if let raylab::Light::Point(p) = l { Some(*p) } else { None })
        .collect();
    let power = 4.0 * std::f32::consts::PI * 10.0 * Vec3::new(1.0, 0.5, 0.25);
    assert_eq!(points, [raylab::PointLight { position: Vec3::new(1.0, -2.0, -3.0), power }]);
    // The directional light shines along its node's −z: the lab's +z.
    let directional =
        raylab::light::DirectionalLight { direction: Vec3::Z, irradiance: Vec3::splat(3.0) };
    assert!(scene.lights.contains(&raylab::Light::Directional(directional)), "{:?}", scene.lights);
    // The spot's node turns −z a quarter turn about x, to the file's +y: the lab's −y.
    let Some(raylab::Light::Spot(spot)) = scene.lights.iter().find(|l| l.kind() == "spot") else {
        panic!("no spot light in {:?}", scene.lights);
    };
    assert!((spot.axis() - Vec3::NEG_Y).length() < 1e-6, "{}", spot.axis());
    assert_eq!(spot.position(), Vec3::new(0.0, -1.0, 0.0));
    assert_eq!((spot.intensity(), spot.angles()), (Vec3::splat(5.0), (0.5, 0.2)));
    assert_eq!(spot.profile(), raylab::light::SpotProfile::Gltf);

    // Transmission: glass of the file's index (smooth at roughness 0).
    let (_dir, path) = broken_box(|json| {
        *json = json
            .replace(r#""metallicFactor": 0.0"#, r#""metallicFactor": 0.0, "roughnessFactor": 0.0"#)
            .replace(
                r#""name": "Texture""#,
                r#""name": "Texture", "alphaMode": "BLEND", "extensions": {
                    "KHR_materials_transmission": {"transmissionFactor": 1.0},
                    "KHR_materials_ior": {"ior": 1.33}}"#,
            );
    });
    let loaded = load_mesh(&path).unwrap();
    assert!(loaded.warnings.iter().any(|w| w.contains("alphaMode BLEND is rendered opaque")));
    let scene = raylab::Scene::from_loaded(&loaded);
    assert_eq!(scene.materials[0].bsdf, Bsdf::Dielectric(Dielectric { eta: 1.33 }));

    // An index below 1 (or 0, "not set") is no glass's: 1.5, with a warning.
    for ior in ["0", "0.5"] {
        let (_dir, path) = broken_box(|json| {
            *json = json.replace(
                r#""name": "Texture""#,
                &format!(
                    r#""name": "Texture", "extensions": {{
                    "KHR_materials_transmission": {{"transmissionFactor": 1.0}},
                    "KHR_materials_ior": {{"ior": {ior}}}}}"#
                ),
            );
        });
        let loaded = load_mesh(&path).unwrap();
        let warning = format!("material \"Texture\": ior {ior} is not a refractive index");
        assert!(loaded.warnings.iter().any(|w| w.contains(&warning)), "{:?}", loaded.warnings);
        let scene = raylab::Scene::from_loaded(&loaded);
        assert!(matches!(&scene.materials[0].bsdf, Bsdf::RoughDielectric(r) if r.eta == 1.5));
    }
}

/// Generated tangents follow glTF's convention: its normal maps' green channel points up the
/// image, toward decreasing `v`, so the bitangent `w · n × t` runs along `−∂p/∂v` (the Khronos
/// sample viewer's `n × t`), and `t` along `∂p/∂u`.
#[test]
fn generated_tangents_follow_gltf_s_normal_map_convention() {
    let (dir, path) = broken_box(|json| {
        *json = json
            .replace(r#""name": "Texture""#, r#""name": "Texture", "normalTexture": {"index": 0}"#);
    });
    std::fs::copy(data("BoxTextured/CesiumLogoFlat.png"), dir.path().join("CesiumLogoFlat.png"))
        .unwrap();
    let loaded = load_mesh(&path).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let mesh = &loaded.mesh;
    let (tangents, uvs, normals) = (
        mesh.tangents.as_ref().unwrap(),
        mesh.uvs.as_ref().unwrap(),
        mesh.normals.as_ref().unwrap(),
    );
    for (i, corners) in mesh.triangles.iter().enumerate() {
        let p = corners.map(|v| mesh.positions[v as usize]);
        let uv = uvs.triangles[i].map(|k| uvs.values[k as usize]);
        // ∂p/∂u and ∂p/∂v from the triangle's edges.
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
        let det = d1.x * d2.y - d1.y * d2.x;
        let dp_du = (e1 * d2.y - e2 * d1.y) / det;
        let dp_dv = (e2 * d1.x - e1 * d2.x) / det;
        for c in 0..3 {
            let t = tangents.values[tangents.triangles[i][c] as usize];
            let n = normals.values[normals.triangles[i][c] as usize];
            let bitangent = t.w * n.cross(t.truncate());
            assert!(t.truncate().dot(dp_du) > 0.0, "triangle {i}: t against ∂p/∂u");
            assert!(bitangent.dot(-dp_dv) > 0.0, "triangle {i}: w · n × t along ∂p/∂v");
        }
    }
}

/// An emissive texture multiplies the emissive factor: the material shines in its pattern.
#[test]
fn an_emissive_texture_shines_in_its_pattern() {
    let (dir, path) = broken_box(|json| {
        *json = json.replace(
            r#""name": "Texture""#,
            r#""name": "Texture", "emissiveFactor": [1, 0.5, 0], "emissiveTexture": {"index": 0}"#,
        );
    });
    std::fs::copy(data("BoxTextured/CesiumLogoFlat.png"), dir.path().join("CesiumLogoFlat.png"))
        .unwrap();
    let loaded = load_mesh(&path).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let material = &loaded.mesh.materials[0];
    assert_eq!(material.emission, Vec3::new(1.0, 0.5, 0.0));
    let texture = material.textures.emission.as_ref().expect("the emissive texture");
    // The logo's corner texel is the same colour as its base colour texture gives there.
    let query = raylab::texture::TextureQuery { uv: glam::Vec2::splat(0.01), ..Default::default() };
    let base = material.textures.base_color.as_ref().unwrap().rgb(&query);
    assert_eq!(texture.rgb(&query), base);
    let scene = raylab::Scene::from_loaded(&loaded);
    let emitted = scene.materials[0].emission_at(&query);
    assert!(emitted.abs_diff_eq(Vec3::new(1.0, 0.5, 0.0) * base, 1e-6), "{emitted}");
}

/// `KHR_texture_transform` on a normal texture (which the `gltf` crate gives no reader for)
/// moves the normal map as the same transform on the base colour texture moves the colours;
/// a malformed one leaves the normal map out with a warning, and the model loads.
#[test]
fn a_normal_texture_s_transform_is_read() {
    use raylab::texture::Texture;
    let transform =
        r#"{"KHR_texture_transform": {"offset": [0.25, 0.5], "rotation": 0.3, "scale": [2, 3]}}"#;
    let (dir, path) = broken_box(|json| {
        *json = json
            .replace(
                r#""index": 0"#,
                &format!(r#""index": 0, "extensions": {transform}"#),
            )
            .replace(
                r#""name": "Texture""#,
                &format!(
                    r#""name": "Texture", "normalTexture": {{"index": 0, "extensions": {transform}}}"#
                ),
            );
    });
    std::fs::copy(data("BoxTextured/CesiumLogoFlat.png"), dir.path().join("CesiumLogoFlat.png"))
        .unwrap();
    let loaded = load_mesh(&path).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let textures = &loaded.mesh.materials[0].textures;
    let (Some(Texture::Image(base)), Some(normal)) = (&textures.base_color, &textures.normal)
    else {
        panic!("both textures: {textures:?}");
    };
    let Texture::Image(normal) = &normal.texture else { panic!("an image") };
    assert_ne!(base.transform, glam::Affine2::IDENTITY, "the base colour's transform is read");
    assert_eq!(normal.transform, base.transform);

    let (dir, path) = broken_box(|json| {
        *json = json.replace(
            r#""name": "Texture""#,
            r#""name": "Texture", "normalTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"scale": 2}}}"#,
        );
    });
    std::fs::copy(data("BoxTextured/CesiumLogoFlat.png"), dir.path().join("CesiumLogoFlat.png"))
        .unwrap();
    let loaded = load_mesh(&path).unwrap();
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(
        loaded.warnings[0].ends_with(
            "material \"Texture\": its normal texture is ignored: its KHR_texture_transform's \
             scale is not two numbers"
        ),
        "{}",
        loaded.warnings[0]
    );
    assert!(loaded.mesh.materials[0].textures.normal.is_none());
}
