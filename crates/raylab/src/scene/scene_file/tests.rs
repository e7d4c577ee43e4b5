//! The scene format: every part parsed, and every mistake a one-line error with its place.

use std::path::Path;

use glam::Vec3;

use super::*;
use crate::film::Film;
use crate::light::{DirectionalLight, Light};
use crate::material::Bsdf;

fn parse(text: &str) -> std::result::Result<Scene, SceneFileError> {
    parse_scene(text, Path::new("test.toml"))
}

fn error(text: &str) -> String {
    parse(text).unwrap_err().to_string()
}

const ROOM: &str = r#"
[render]
size = [64, 48]
spp = 16
max_depth = 8
integrator = "path"
filter = "gaussian"

[camera]
position = [0, 0, 3.9]
target = [0, 0, 0]
up = [0, 1, 0]
fov = 39.3077

[materials.white]
type = "diffuse"
reflectance = [0.8, 0.7, 0.6]

[materials.both]
type = "twosided"
bsdf = { type = "diffuse", reflectance = [0.1, 0.2, 0.3] }

[[shapes]]
type = "rectangle"
material = "white"
rotate = { axis = [1, 0, 0], angle = -90 }
translate = [0, -1, 0]

[[shapes]]
type = "rectangle"
emission = [10, 10, 10]
scale = 0.25
to_world = [[1, 0, 0, 0], [0, 0, -1, 0.99], [0, 1, 0, 0], [0, 0, 0, 1]]

[[shapes]]
type = "sphere"
center = [0.3, -0.5, 0]
radius = 0.25
material = "both"

[[lights]]
type = "environment"
radiance = [0.1, 0.1, 0.1]
"#;

#[test]
fn a_room_parses_into_the_lab_frame() {
    let scene = parse(ROOM).unwrap();
    assert_eq!(scene.settings.size, Some((64, 48)));
    assert_eq!(scene.settings.spp, Some(16));
    assert_eq!(scene.settings.max_depth, Some(crate::settings::MaxDepth::Segments(8)));
    assert_eq!(scene.settings.integrator, Some(crate::settings::IntegratorKind::Path));
    assert_eq!(scene.settings.filter, Some(Filter::GAUSSIAN));
    // The camera at y-up (0, 0, 3.9) looking at −z is the lab's camera at (0, 0, −3.9), yaw 0.
    let camera = scene.camera.unwrap();
    assert_eq!(camera.position, Vec3::new(0.0, 0.0, -3.9));
    assert!(camera.yaw.abs() < 1e-6 && camera.pitch.abs() < 1e-6, "{camera:?}");
    assert!((camera.camera(64, 48).fov_x_deg() - 39.3077).abs() < 1e-3);
    // The floor: y-up −1 is the lab's +1 (down), facing up (−y in the lab).
    let floor = scene.geometry.triangle(0);
    assert!(floor.iter().all(|p| (p.y - 1.0).abs() < 1e-6), "{floor:?}");
    assert!(
        (scene.geometry.normal(0) - Vec3::NEG_Y).length() < 1e-6,
        "{}",
        scene.geometry.normal(0)
    );
    // The light: at y-up 0.99 (lab −0.99), facing down (+y in the lab), a quarter of [-1, 1]².
    let light = scene.geometry.triangle(2);
    assert!(light.iter().all(|p| (p.y + 0.99).abs() < 1e-6 && p.x.abs() <= 0.25 + 1e-6));
    assert!((scene.geometry.normal(2) - Vec3::Y).length() < 1e-6);
    let emitting = &scene.materials[scene.geometry.material_id(2) as usize];
    assert_eq!(emitting.emission, Vec3::splat(10.0));
    assert!(scene.has_area_lights());
    // The sphere faces out and is two-sided.
    let sphere_triangle = 4 + 100;
    let [a, b, c] = scene.geometry.triangle(sphere_triangle);
    let centre = crate::scene::model_to_lab(Vec3::new(0.3, -0.5, 0.0));
    assert!(scene.geometry.normal(sphere_triangle).dot((a + b + c) / 3.0 - centre) > 0.0);
    assert!(scene.materials[scene.geometry.material_id(sphere_triangle) as usize].two_sided);
    assert_eq!(scene.lights, vec![Light::Environment { radiance: Vec3::splat(0.1) }]);
}

#[test]
fn mistakes_name_the_line_and_column() {
    let cases = [
        ("[camera]\nposition = [0, 0]\n", "test.toml:2:12:", "expected an array of length 3"),
        ("[render]\nspp = 0\n", "test.toml:1:1:", "spp must be at least 1"),
        ("[render]\nintegrator = \"bdpt\"\n", "test.toml:2:14:", "unknown integrator 'bdpt'"),
        (
            "[[shapes]]\ntype = \"torus\"\nmaterial = \"x\"\n",
            "test.toml:2:8:",
            "unknown shape type 'torus'",
        ),
        (
            "[[shapes]]\ntype = \"cube\"\nmaterial = \"gold\"\n",
            "test.toml:3:12:",
            "no material named 'gold'",
        ),
        (
            "[materials.a]\ntype = \"diffuse\"\nreflectance = [2, 0, 0]\n",
            "test.toml:1:1:",
            "reflectance",
        ),
        ("[materials.a]\ntype = \"velvet\"\n", "test.toml:2:", "velvet"),
        ("colour = 3\n", "test.toml:1:1:", "unknown field `colour`"),
        (
            "[camera]\nposition = [0, 0, 0]\ntarget = [0, 0, -1]\nup = [0, 0, 1]\n",
            "test.toml:4:6:",
            "along the view direction",
        ),
        ("[render]\nmax_depth = -2\n", "test.toml:1:1:", "max_depth -2"),
        ("[[shapes]]\ntype = \"mesh\"\nfile = \"missing.obj\"\n", "test.toml:3:8:", "missing.obj"),
        (
            "[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\n",
            "test.toml:1:1:",
            "intensity or power",
        ),
        (
            "[[shapes]]\ntype = \"cube\"\nemission = [1, 1, 1]\nscale = 0\n",
            "test.toml:4:9:",
            "not zero",
        ),
        ("[camera\n", "test.toml:1:8:", ""),
    ];
    for (text, place, message) in cases {
        let e = error(text);
        assert!(e.starts_with(place) && e.contains(message), "{text:?}: {e}");
        assert!(!e.contains('\n'), "one line: {e}");
    }
}

#[test]
fn meshes_load_beside_the_scene_file_with_their_own_materials() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.mtl"), "newmtl glow\nKd 0.5 0.5 0.5\nKe 2 3 4\n").unwrap();
    std::fs::write(
        dir.path().join("tri.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glow\nf 1 2 3\n",
    )
    .unwrap();
    let scene_path = dir.path().join("s.toml");
    std::fs::write(
        &scene_path,
        "[[shapes]]\ntype = \"mesh\"\nfile = \"tri.obj\"\ntranslate = [0, 0, 1]\n",
    )
    .unwrap();
    let scene = load_scene_file(&scene_path).unwrap();
    assert_eq!(scene.geometry.len(), 1);
    // Translated along y-up +z: the lab's −z.
    assert_eq!(scene.geometry.triangle(0)[0], Vec3::new(0.0, 0.0, -1.0));
    let material = &scene.materials[scene.geometry.material_id(0) as usize];
    assert_eq!((material.name.as_str(), material.emission), ("glow", Vec3::new(2.0, 3.0, 4.0)));
    let e = load_scene_file(&dir.path().join("absent.toml")).unwrap_err().to_string();
    assert!(e.contains("absent.toml:1:1: cannot read"), "{e}");
}

#[test]
fn every_material_type_parses_with_mitsuba_s_names_and_defaults() {
    let scene = parse(
        r#"
[materials.gold]
type = "roughconductor"
material = "Au"
alpha_u = 0.2
alpha_v = 0.05

[materials.mirror]
type = "conductor"

[materials.glass]
type = "dielectric"
int_ior = "bk7"

[materials.frosted]
type = "roughdielectric"
int_ior = 1.33
ext_ior = "air"
alpha = 0.3

[materials.red_plastic]
type = "plastic"
diffuse_reflectance = [0.6, 0.1, 0.1]
nonlinear = true
"#,
    )
    .unwrap();
    let by_name = |name: &str| &scene.materials.iter().find(|m| m.name == name).unwrap().bsdf;
    let Bsdf::RoughConductor(gold) = by_name("gold") else { panic!() };
    assert_eq!((gold.distribution.alpha_u, gold.distribution.alpha_v), (0.2, 0.05));
    assert_eq!(gold.conductor.eta, Vec3::new(0.183, 0.421, 1.373));
    let Bsdf::Conductor(mirror) = by_name("mirror") else { panic!() };
    assert!((mirror.reflectance(0.5) - Vec3::ONE).abs().max_element() < 1e-5, "a perfect mirror");
    let Bsdf::Dielectric(glass) = by_name("glass") else { panic!() };
    assert!((glass.eta - 1.5046 / 1.000_277).abs() < 1e-6);
    let Bsdf::RoughDielectric(frosted) = by_name("frosted") else { panic!() };
    assert!((frosted.eta - 1.33 / 1.000_277).abs() < 1e-6 && frosted.distribution.alpha_u == 0.3);
    let Bsdf::Plastic(plastic) = by_name("red_plastic") else { panic!() };
    assert!(plastic.nonlinear && (plastic.eta - 1.49 / 1.000_277).abs() < 1e-6);
    assert_eq!(plastic.specular_reflectance, Vec3::ONE);
}

#[test]
fn material_mistakes_are_named() {
    let cases = [
        ("[materials.a]\ntype = \"conductor\"\nmaterial = \"Pt\"\n", "unknown metal 'Pt'"),
        (
            "[materials.a]\ntype = \"dielectric\"\nint_ior = \"glass\"\n",
            "unknown index of refraction 'glass'",
        ),
        ("[materials.a]\ntype = \"roughconductor\"\ndistribution = \"beckmann\"\n", "only ggx"),
        ("[materials.a]\ntype = \"roughconductor\"\nalpha = -1\n", "alpha"),
        ("[materials.a]\ntype = \"roughconductor\"\nalhpa = 0.1\n", "alhpa"),
        (
            "[materials.a]\ntype = \"plastic\"\ndiffuse_reflectance = [1.5, 0, 0]\n",
            "diffuse_reflectance",
        ),
        ("[materials.a]\ntype = \"dielectric\"\nint_ior = 0\n", "index of refraction"),
        (
            "[materials.a]\ntype = \"twosided\"\nbsdf = { type = \"dielectric\" }\n",
            "cannot hold a dielectric",
        ),
        ("[materials.a]\ntype = \"conductor\"\neta = [0, 0, 0]\nk = [0, 0, 0]\n", "not both 0"),
    ];
    for (text, message) in cases {
        let e = error(text);
        assert!(e.starts_with("test.toml:") && e.contains(message), "{text:?}: {e}");
    }
}

#[test]
fn the_documented_example_parses() {
    let doc = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md"),
    )
    .unwrap();
    let example = doc
        .split("## A complete example")
        .nth(1)
        .and_then(|rest| rest.split("```toml\n").nth(1))
        .and_then(|rest| rest.split("```").next())
        .expect("docs/scene-format.md has its example");
    let scene = parse(example).unwrap();
    assert_eq!(scene.settings.size, Some((640, 480)));
    assert!(scene.has_area_lights());
    assert_eq!(scene.geometry.len(), 2 + 9024 + 2);
}

#[test]
fn an_up_vector_rolls_the_camera() {
    // Looking along −z from the origin with up = +x: the picture's up is the world's +x.
    let scene =
        parse("[camera]\nposition = [0, 0, 0]\ntarget = [0, 0, -1]\nup = [1, 0, 0]\n").unwrap();
    let camera = scene.camera.unwrap().camera(8, 8);
    let up = camera.rotation() * Vec3::NEG_Y;
    assert!((up - crate::scene::model_to_lab(Vec3::X)).length() < 1e-5, "{up}");
    assert!((camera.roll.to_degrees().abs() - 90.0).abs() < 1e-3, "{}", camera.roll);
    // A tilted up, seen obliquely: still the picture's up, projected.
    let scene = parse("[camera]\nposition = [1, 2, 3]\ntarget = [0, 0.5, 0]\nup = [0.3, 1, 0.2]\n")
        .unwrap();
    let camera = scene.camera.unwrap().camera(8, 8);
    let forward = crate::scene::model_to_lab(Vec3::new(-1.0, -1.5, -3.0)).normalize();
    assert!((camera.forward() - forward).length() < 1e-5);
    let up = crate::scene::model_to_lab(Vec3::new(0.3, 1.0, 0.2));
    let expected = (up - up.dot(forward) * forward).normalize();
    assert!((camera.rotation() * Vec3::NEG_Y - expected).length() < 1e-5);
    // The default up is level: no roll.
    let scene = parse("[camera]\nposition = [1, 2, 3]\ntarget = [0, 0.5, 0]\n").unwrap();
    assert!(scene.camera.unwrap().roll.abs() < 1e-6);
    let scene = parse("[camera]\nposition = [0, 0, 0]\nyaw = 10\nroll = 30\n").unwrap();
    assert!((scene.camera.unwrap().roll.to_degrees() - 30.0).abs() < 1e-4);
}

/// NaN, infinities and numbers beyond a 32-bit float are refused wherever they are, with their
/// key and place, before they can mean anything.
#[test]
fn numbers_that_are_not_finite_are_named_with_their_place() {
    assert_eq!(
        error("[camera]\nposition = [0, nan, 3]\n"),
        "test.toml:2:16: camera.position[1] = nan is not a finite number"
    );
    assert_eq!(
        error("[materials.m]\ntype = \"diffuse\"\nreflectance = [0.5, 0.5, +inf]\n"),
        "test.toml:3:26: materials.m.reflectance[2] = +inf is not a finite number"
    );
    assert_eq!(
        error("[[shapes]]\ntype = \"cube\"\nto_world = [[1, 0, 0, 0], [0, -inf, 0, 0]]\n"),
        "test.toml:3:31: shapes[0].to_world[1][1] = -inf is not a finite number"
    );
    assert_eq!(
        error("[camera]\nfov = 1e39\n"),
        "test.toml:2:7: camera.fov = 1e39 is not a finite number"
    );
    // The largest finite float is still a number (refused or not by the key's own rule).
    assert!(!error("[camera]\nfov = 3e38\n").contains("not a finite number"));
}

#[test]
fn keyframes_parse_in_order_and_mistakes_are_named() {
    let keys = "[[keyframes]]\nframe = 0\nposition = [0, 0, 4]\n\n[[keyframes]]\nframe = 10\nposition = [2, 0, 4]\nyaw = 90\n";
    let scene = parse(keys).unwrap();
    assert_eq!(scene.keyframes.iter().map(|k| k.frame).collect::<Vec<_>>(), [0, 10]);
    assert_eq!(scene.camera, None, "keyframes are not the still camera");
    let middle = scene.camera_at(5.0).unwrap();
    assert!((middle.yaw.to_degrees() - 45.0).abs() < 1e-4);
    assert!(
        middle.position.abs_diff_eq(super::super::model_to_lab(Vec3::new(1.0, 0.0, 4.0)), 1e-6)
    );
    assert_eq!(
        error("[[keyframes]]\nposition = [0, 0, 4]\n"),
        "test.toml:1:1: a keyframe needs its frame (a whole number)"
    );
    assert_eq!(
        error(
            "[[keyframes]]\nframe = 3\nposition = [0, 0, 4]\n[[keyframes]]\nframe = 3\nposition = [0, 0, 5]\n"
        ),
        "test.toml:4:1: keyframe 3: keyframes must be in order of frame, each once"
    );
    assert_eq!(
        error("[camera]\nframe = 1\nposition = [0, 0, 4]\n"),
        "test.toml:1:1: camera: frame belongs in [[keyframes]]"
    );
    assert!(
        error("[[keyframes]]\nframe = 0\nposition = [0, 0, 4]\n[[keyframes]]\nframe = 1\nposition = [0, 0, 5]\nfov_axis = \"y\"\n")
            .ends_with("keyframes must all have the same fov_axis")
    );
    assert!(
        error("[[keyframes]]\nframe = -1\nposition = [0, 0, 4]\n").starts_with("test.toml:2:9")
    );
}

#[test]
fn colour_and_roughness_inputs_take_textures() {
    use crate::texture::{Pattern, Texture, TextureQuery};
    let scene = parse(
        r#"
[materials.floor]
type = "diffuse"
reflectance = { texture = "marble", scale = 4, colors = [[0.9, 0.9, 0.9], [0.1, 0.1, 0.1]] }

[materials.brushed]
type = "roughconductor"
material = "Al"
alpha = { texture = "clouds", scale = 8, range = [0.05, 0.4], seed = 3 }

[materials.wood]
type = "pbr"
base_color = { texture = "wood", turbulence = 0.3 }
roughness = 0.4
"#,
    )
    .unwrap();
    let named = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap();
    let [floor, brushed, wood] = ["floor", "brushed", "wood"].map(named);
    let Some(Texture::Noise(marble)) = &floor.textures.base_color else { panic!("{floor:?}") };
    assert_eq!((marble.pattern, marble.scale, marble.octaves), (Pattern::Marble, 4.0, 6));
    let Some(Texture::Noise(clouds)) = &brushed.textures.roughness else { panic!("{brushed:?}") };
    assert_eq!(clouds.colors, [Vec3::splat(0.05), Vec3::splat(0.4)]);
    // The inputs vary over space: the BSDF read at two points differs.
    let at = |x: f32| TextureQuery { p: Vec3::new(x, 0.3, 0.7), ..TextureQuery::default() };
    let albedos: Vec<Vec3> = (0..20).map(|i| floor.albedo_at(&at(i as f32 * 0.1))).collect();
    assert!(albedos.iter().any(|a| a.x > 0.6) && albedos.iter().any(|a| a.x < 0.4));
    let alphas: Vec<f32> = (0..50)
        .map(|i| match &*brushed.bsdf_at(&at(i as f32 * 0.05)) {
            Bsdf::RoughConductor(r) => r.distribution.alpha_u,
            other => panic!("{other:?}"),
        })
        .collect();
    assert!(alphas.iter().all(|a| (0.05..=0.4).contains(a)), "{alphas:?}");
    assert!(alphas.iter().any(|&a| a > alphas[0] + 0.02 || a < alphas[0] - 0.02));
    assert!(matches!(wood.bsdf, Bsdf::Pbr(_)) && wood.textures.base_color.is_some());
    // Mistakes are named with their place.
    let cases = [
        ("reflectance = { texture = \"plaid\" }", "unknown texture 'plaid'"),
        ("reflectance = { texture = \"wood\", octaves = 0 }", "octaves 0"),
        ("reflectance = { texture = \"wood\", range = [0, 1] }", "takes `colors`"),
        ("reflectance = { texture = \"wood\", scale = -2 }", "scale -2"),
        ("reflectance = { texture = \"missing.png\" }", "missing.png"),
        ("reflectance = { texture = \"a.png\", wrap = \"tile\" }", "unknown wrap 'tile'"),
    ];
    for (line, message) in cases {
        let e = error(&format!("[materials.a]\ntype = \"diffuse\"\n{line}\n"));
        assert!(e.starts_with("test.toml:") && e.contains(message), "{line}: {e}");
    }
}

/// A glTF model is a shape like any mesh: its metallic-roughness materials and textures come
/// with it, and the scene's transform places it.
#[test]
fn a_gltf_model_is_a_mesh_shape() {
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/BoxTextured");
    for file in ["BoxTextured.gltf", "BoxTextured0.bin", "CesiumLogoFlat.png"] {
        std::fs::copy(data.join(file), dir.path().join(file)).unwrap();
    }
    let scene_path = dir.path().join("s.toml");
    std::fs::write(
        &scene_path,
        "[[shapes]]\ntype = \"mesh\"\nfile = \"BoxTextured.gltf\"\nscale = 2\n",
    )
    .unwrap();
    let scene = load_scene_file(&scene_path).unwrap();
    assert_eq!(scene.geometry.len(), 12);
    let (lo, hi) = scene.bounds().unwrap();
    assert!(lo.abs_diff_eq(Vec3::splat(-1.0), 1e-6) && hi.abs_diff_eq(Vec3::ONE, 1e-6));
    let material = &scene.materials[scene.geometry.material_id(0) as usize];
    assert!(matches!(material.bsdf, Bsdf::Pbr(_)), "{:?}", material.bsdf);
    assert!(material.textures.base_color.is_some());
    assert_eq!(scene.warnings, Vec::<String>::new());
    // The model's warnings reach the scene's, for the caller to show.
    std::fs::remove_file(dir.path().join("CesiumLogoFlat.png")).unwrap();
    let scene = load_scene_file(&scene_path).unwrap();
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].contains("CesiumLogoFlat.png: cannot read it"),
        "{:?}",
        scene.warnings
    );
}

/// A mesh file that several shapes place is read once and placed by each: the same triangles
/// and materials as copies of the file, in shape order, and the file's warnings reported once.
#[test]
fn a_file_placed_by_several_shapes_is_read_once() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.mtl"), "newmtl grey\nKd 0.5 0.5 0.5\n").unwrap();
    // The polyline is skipped with a warning, once per read of the file.
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl grey\nf 1 2 3\nl 1 2\n";
    for name in ["a.obj", "b.obj", "c.obj"] {
        std::fs::write(dir.path().join(name), obj).unwrap();
    }
    let shapes = |files: [&str; 4]| {
        files
            .iter()
            .enumerate()
            .map(|(k, file)| {
                let material = if k == 2 { "material = \"red\"\n" } else { "" };
                format!("[[shapes]]\ntype = \"mesh\"\nfile = \"{file}\"\ntranslate = [{k}, 0, 0]\n{material}")
            })
            .collect::<String>()
    };
    let red = "[materials.red]\ntype = \"diffuse\"\nreflectance = [1, 0, 0]\n";
    let load = |files: [&str; 4], name: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, format!("{red}{}", shapes(files))).unwrap();
        load_scene_file(&path).unwrap()
    };
    let shared = load(["a.obj", "a.obj", "a.obj", "b.obj"], "shared.toml");
    let apart = load(["a.obj", "b.obj", "c.obj", "b.obj"], "apart.toml");
    assert_eq!(shared.geometry.len(), 4);
    for i in 0..4 {
        assert_eq!(shared.geometry.triangle(i), apart.geometry.triangle(i), "triangle {i}");
        let name =
            |scene: &Scene| scene.materials[scene.geometry.material_id(i) as usize].name.clone();
        assert_eq!(name(&shared), name(&apart), "triangle {i}");
    }
    assert_eq!(shared.geometry.triangle(1)[0], Vec3::new(1.0, 0.0, 0.0));
    // One warning per file read: a.obj and b.obj in the shared scene; a, b and c apart.
    let count =
        |scene: &Scene, file: &str| scene.warnings.iter().filter(|w| w.contains(file)).count();
    assert_eq!(shared.warnings.len(), 2, "{:?}", shared.warnings);
    assert_eq!((count(&shared, "a.obj"), count(&shared, "b.obj")), (1, 1), "{:?}", shared.warnings);
    assert_eq!(apart.warnings.len(), 3, "{:?}", apart.warnings);
    // A shared file that cannot be read is an error at its first use.
    let path = dir.path().join("missing.toml");
    std::fs::write(&path, shapes(["a.obj", "gone.obj", "gone.obj", "a.obj"])).unwrap();
    let e = load_scene_file(&path).unwrap_err().to_string();
    assert!(e.contains("missing.toml:7:") && e.contains("gone.obj"), "{e}");
}

#[test]
fn a_mesh_given_in_memory_takes_the_place_of_its_file() {
    let triangle = crate::mesh::Mesh {
        name: "tri".into(),
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        triangles: vec![[0, 1, 2]],
        ..Default::default()
    };
    let loaded = LoadedMesh { mesh: triangle, ..Default::default() };
    let meshes = BTreeMap::from([("<python mesh 0>".to_string(), loaded)]);
    let text = r#"
[materials.white]
type = "diffuse"
reflectance = [0.8, 0.8, 0.8]

[[shapes]]
type = "mesh"
file = "<python mesh 0>"
material = "white"
translate = [0, 0, 2]

[[shapes]]
type = "mesh"
file = "<python mesh 0>"
material = "white"
"#;
    let path = Path::new("made-in-python.toml");
    let scene = parse_scene_with_meshes(text, path, &LoadOptions::default(), &meshes).unwrap();
    assert_eq!(scene.geometry.len(), 2);
    // Without the mesh in memory, the name is a file that is not there.
    let error = parse_scene(text, path).unwrap_err().to_string();
    assert!(error.contains("<python mesh 0>"), "{error}");
}

/// Every kind of light, in the file's y-up frame, becomes its light in the lab's (y and z
/// turned); Mitsuba's defaults fill what is not given.
#[test]
fn lights_of_every_kind_parse_into_the_lab_frame() {
    use crate::light::{SpotProfile, SunLight};
    let dir = tempfile::tempdir().unwrap();
    let sky = Film::from_pixels(4, 2, vec![Vec3::new(0.5, 1.0, 2.0); 8]);
    crate::image_io::save_film(&dir.path().join("sky.pfm"), &sky, &crate::film::Display::LAB)
        .unwrap();
    let text = r#"
[[lights]]
type = "envmap"
filename = "sky.pfm"
scale = 2
rotate = { axis = [0, 1, 0], angle = 90 }

[[lights]]
type = "directional"
direction = [0, -2, 0]
irradiance = 3

[[lights]]
type = "directional"
to_world = [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]]

[[lights]]
type = "spot"
position = [0, 3, 0]
target = [0, 0, 0]
intensity = [1, 2, 3]

[[lights]]
type = "sun"
direction = [1, -1, 0]
irradiance = [4, 4, 4]
"#;
    let scene = parse_scene(text, &dir.path().join("lights.toml")).unwrap();
    let [map, down, to_world, spot, sun] = &scene.lights[..] else {
        panic!("{:?}", scene.lights);
    };
    let Light::EnvironmentMap(map) = map else { panic!("{map:?}") };
    assert_eq!(map.size(), (4, 2));
    assert!((map.mean() - Vec3::new(1.0, 2.0, 4.0)).abs().max_element() < 1e-5);
    // The map's left edge looks along its −z, which a quarter turn about y takes to the
    // world's −x: the lab's −x.
    assert!((map.direction(glam::Vec2::new(0.0, 0.5)) - Vec3::NEG_X).length() < 1e-6);
    let expected = DirectionalLight { direction: Vec3::Y, irradiance: Vec3::splat(3.0) };
    assert_eq!(*down, Light::Directional(expected));
    // `to_world` (rows as written) takes +z, the way the light travels, to the world's −y
    // (down): the lab's +y; the irradiance is Mitsuba's default, 1.
    let Light::Directional(d) = to_world else { panic!("{to_world:?}") };
    assert!((d.direction - Vec3::Y).length() < 1e-6 && d.irradiance == Vec3::ONE, "{d:?}");
    let Light::Spot(spot) = spot else { panic!("{spot:?}") };
    assert_eq!((spot.position(), spot.axis()), (Vec3::new(0.0, -3.0, 0.0), Vec3::Y));
    assert_eq!(spot.intensity(), Vec3::new(1.0, 2.0, 3.0));
    let (cutoff, beam) = spot.angles();
    assert!((cutoff - 20f32.to_radians()).abs() < 1e-6 && (beam - 15f32.to_radians()).abs() < 1e-6);
    assert_eq!(spot.profile(), SpotProfile::Mitsuba);
    let Light::Sun(sun) = sun else { panic!("{sun:?}") };
    let radius = (SunLight::EARTH_APERTURE_DEG / 2.0).to_radians();
    assert!((sun.angular_radius() - radius).abs() < 1e-7);
    assert!((sun.irradiance() - Vec3::splat(4.0)).abs().max_element() < 1e-4);
    assert!((sun.direction() - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    assert_eq!(scene.lights_the_lab_ignores(), ["envmap", "directional", "spot", "sun"]);
    assert!(scene.needs_path_tracing());
}

#[test]
fn light_mistakes_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let sky = Film::from_pixels(2, 2, vec![Vec3::ONE; 4]);
    crate::image_io::save_film(&dir.path().join("sky.pfm"), &sky, &crate::film::Display::LAB)
        .unwrap();
    let light = |body: &str| format!("[[lights]]\n{body}\n");
    let cases = [
        (light("type = \"envmap\"\nfilename = \"missing.hdr\""), "envmap: cannot read"),
        (light("type = \"envmap\"\nfilename = \"sky.pfm\"\nscale = -1"), "scale -1"),
        (
            light(
                "type = \"envmap\"\nfilename = \"sky.pfm\"\n\
                 to_world = [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]",
            ),
            "to_world must be a rotation",
        ),
        (light("type = \"directional\"\ndirection = [0, 0, 0]"), "finite and not zero"),
        (light("type = \"directional\""), "direction or to_world"),
        (light("type = \"spot\"\nposition = [0, 1, 0]"), "position and target, or to_world"),
        (
            light("type = \"spot\"\nposition = [0, 1, 0]\ntarget = [0, 0, 0]\nbeam_width = 30"),
            "beam_width",
        ),
        (light("type = \"spot\"\nposition = [0, 1, 0]\ntarget = [0, 1, 0]"), "direction"),
        (light("type = \"sun\"\ndirection = [0, -1, 0]"), "one of radiance or irradiance"),
        (light("type = \"sun\"\ndirection = [0, -1, 0]\nradiance = 1\naperture = 0"), "aperture"),
        (light("type = \"area\""), "area"),
    ];
    for (text, message) in cases {
        let e = parse_scene(&text, &dir.path().join("lights.toml")).unwrap_err().to_string();
        assert!(e.contains("lights.toml:") && e.contains(message), "{text:?}: {e}");
        assert!(!e.contains('\n'), "one line: {e}");
    }
}
