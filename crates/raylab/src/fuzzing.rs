//! Entry points for the fuzz targets in `fuzz/` (cargo-fuzz): each takes arbitrary bytes and
//! must return, whatever they are, without a panic, an abort or an allocation beyond the
//! declared limits. Not part of the API; the regression tests in `tests/fuzz_crashes.rs` run
//! every crash input ever found through them.

use std::io::Cursor;
use std::path::Path;

use crate::scene::{LoadedMesh, Scene};

/// Meshes up to this many triangles are also built into a BVH and asked a ray.
const BVH_LIMIT: usize = 4096;

/// What a loaded mesh goes through in `raylab render`: a scene, a BVH, a ray.
fn use_mesh(loaded: &LoadedMesh) {
    // Instances count as many times as they are drawn: that is what a render traces.
    let drawn = loaded.triangle_count();
    if drawn == 0 || drawn > BVH_LIMIT {
        return;
    }
    let scene = Scene::from_loaded(loaded);
    use_scene(&scene);
}

fn use_scene(scene: &Scene) {
    if scene.geometry.len() > BVH_LIMIT {
        return;
    }
    let _ = scene.content_hash();
    let Ok(bvh) = crate::bvh::SceneBvh::build(&scene.geometry) else { return };
    let ray = crate::ray::Ray::new(glam::Vec3::new(0.1, 0.2, -5.0), glam::Vec3::Z);
    let _ = crate::accel::Accelerator::closest_hit(&bvh, &ray);
}

/// An OBJ file and the material library it names: the first byte splits the rest between them.
pub fn obj(data: &[u8]) {
    let Some((&split, rest)) = data.split_first() else { return };
    let at = rest.len() * split as usize / 256;
    let (obj, mtl) = rest.split_at(at);
    // In a folder that does not exist, so that textures the library names are not found.
    let library = |name: &str| Ok((Path::new("/nonexistent/raylab").join(name), mtl.to_vec()));
    if let Ok(loaded) = crate::scene::obj::parse_obj_with(Path::new("fuzz.obj"), obj, &library) {
        use_mesh(&loaded);
    }
}

/// A PLY file.
pub fn ply(data: &[u8]) {
    if let Ok(loaded) = crate::scene::ply::parse_ply(Path::new("fuzz.ply"), data) {
        use_mesh(&loaded);
    }
}

/// A glTF file, JSON or binary (external buffers are looked for in a folder that does not
/// exist).
pub fn gltf(data: &[u8]) {
    let path = Path::new("/nonexistent/raylab/fuzz.glb");
    if let Ok(loaded) = crate::scene::gltf::parse_gltf(path, data) {
        use_mesh(&loaded);
    }
}

/// A TOML scene file (meshes it names are looked for in a folder that does not exist).
pub fn scene_file(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(scene) = crate::scene::parse_scene(text, Path::new("/nonexistent/raylab/fuzz.toml")) {
        use_scene(&scene);
    }
}

/// An OpenEXR part as `raylab merge` reads it, merged with itself alone.
pub fn exr_part(data: &[u8]) {
    if let Ok(part) = crate::parts::read_part_from(Path::new("fuzz.exr"), Cursor::new(data)) {
        let _ = crate::parts::merge(vec![part]);
    }
}

/// A Radiance HDR image, as an environment map's file is read.
pub fn hdr_image(data: &[u8]) {
    if let Ok(film) = crate::image_io::parse_hdr(data) {
        let _ = film.pixel(0, 0);
    }
}

/// An OpenEXR image, as `load_film` (and an environment map's file) reads it.
pub fn exr_image(data: &[u8]) {
    if let Ok(film) = crate::image_io::openexr::read_exr_film(data) {
        let _ = film.pixel(0, 0);
    }
}
