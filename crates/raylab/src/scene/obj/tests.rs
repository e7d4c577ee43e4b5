//! The OBJ reader on good and broken files.
use std::collections::HashMap;

use proptest::prelude::*;
use std::io;

use super::*;
use crate::mesh::MeshMaterial;
use crate::scene::mtl::parse_mtl;
use std::path::PathBuf;

/// Reads `obj` with the material libraries in `libraries` (name → content).
fn parse_with(obj: &str, libraries: &[(&str, &str)]) -> Result<LoadedMesh, LoadError> {
    let libraries: HashMap<&str, &str> = libraries.iter().copied().collect();
    let read = |name: &str| match libraries.get(name) {
        Some(text) => Ok((PathBuf::from(name), text.as_bytes().to_vec())),
        None => Err(LoadError::File(crate::file_bytes::ReadError::Read {
            path: name.into(),
            error: io::Error::new(io::ErrorKind::NotFound, "not found"),
        })),
    };
    parse_obj_with(Path::new("test.obj"), obj.as_bytes(), &read)
}

fn parse(obj: &str) -> LoadedMesh {
    parse_with(obj, &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn error(obj: &str) -> String {
    let message = parse_with(obj, &[]).expect_err("the file is malformed").to_string();
    assert!(!message.contains('\n'), "{message}");
    message
}

const SIX_VERTICES: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n";

fn p(i: usize) -> Vec3 {
    [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.], [2., 0., 0.], [2., 1., 0.]][i].into()
}

const MTL: &str = "newmtl red\nKd 1 0 0\n\nnewmtl green\nKd 0 1 0\nKe 0.5 2 3\nnewmtl grey\nKd 0.25\nnewmtl plain\nKs 1 1 1\n";

#[test]
fn triangles_keep_file_order_across_groups_and_materials() {
    let obj = format!(
        "mtllib lib.mtl\n{SIX_VERTICES}g a\nusemtl red\nf 1 2 3 4\nusemtl green\nf 1 2 3\n\
         o b\nf 4 5 6 1 2\nusemtl red\nf 2 3 4\ng c\nusemtl none\nf 1 2 3\n"
    );
    let loaded = parse_with(&obj, &[("lib.mtl", MTL)]).unwrap();
    let mesh = &loaded.mesh;
    let expected =
        [[0, 1, 2], [0, 2, 3], [0, 1, 2], [3, 4, 5], [3, 5, 0], [3, 0, 1], [1, 2, 3], [0, 1, 2]];
    let corners: Vec<[Vec3; 3]> = mesh.triangle_vertices().collect();
    assert_eq!(corners, expected.map(|t| t.map(p)));
    let names: Vec<Option<&str>> =
        (0..mesh.triangles.len()).map(|i| mesh.material(i).map(|m| m.name.as_str())).collect();
    let (red, green) = (Some("red"), Some("green"));
    assert_eq!(names, [red, red, green, green, green, green, red, None]);
    assert_eq!(
        loaded.warnings,
        [
            "test.obj: line 18: usemtl \"none\": no material library defines it; the surfaces get the default grey"
        ]
    );
}

#[test]
fn materials_keep_kd_and_ke() {
    let obj = format!("mtllib lib.mtl\n{SIX_VERTICES}usemtl grey\nf 1 2 3\n");
    let mesh = parse_with(&obj, &[("lib.mtl", MTL)]).unwrap().mesh;
    let expected = [
        ("red", Vec3::X, Vec3::ZERO),
        ("green", Vec3::Y, Vec3::new(0.5, 2.0, 3.0)),
        ("grey", Vec3::splat(0.25), Vec3::ZERO),
        ("plain", MeshMaterial::DEFAULT_DIFFUSE, Vec3::ZERO),
    ];
    let found: Vec<(&str, Vec3, Vec3)> =
        mesh.materials.iter().map(|m| (m.name.as_str(), m.diffuse, m.emission)).collect();
    assert_eq!(found, expected);
    assert_eq!(mesh.material_ids, [Some(2)]);
}

#[test]
fn a_missing_library_is_a_warning() {
    let obj = format!("# comment\nmtllib gone.mtl\n{SIX_VERTICES}usemtl red\nf 1 2 3\n");
    let loaded = parse(&obj);
    assert_eq!(loaded.mesh.triangles.len(), 1);
    assert_eq!((loaded.mesh.materials.len(), loaded.mesh.material_ids.len()), (0, 0));
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(
        loaded.warnings[0].starts_with("test.obj: line 2: material library ignored, the surfaces get the default grey: gone.mtl: cannot read"),
        "{}",
        loaded.warnings[0]
    );
}

#[test]
fn library_names_may_use_backslashes_spaces_or_lists() {
    let obj = format!(
        "mtllib .\\sub\\a.mtl\nmtllib my lib.mtl\nmtllib b.mtl c.mtl\n{SIX_VERTICES}f 1 2 3\n"
    );
    let libraries = [
        ("./sub/a.mtl", "newmtl a\n"),
        ("my lib.mtl", "newmtl spaced\n"),
        ("b.mtl", "newmtl b\n"),
        ("c.mtl", "newmtl c\n"),
    ];
    let loaded = parse_with(&obj, &libraries).unwrap();
    let names: Vec<&str> = loaded.mesh.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["a", "spaced", "b", "c"]);
    assert_eq!(loaded.warnings, Vec::<String>::new());
}

#[test]
fn a_malformed_library_is_an_error_naming_it() {
    let obj = format!("mtllib lib.mtl\n{SIX_VERTICES}f 1 2 3\n");
    for (mtl, expected) in [
        (
            "newmtl a\nKd 1 0\n",
            "lib.mtl: line 2: expected `Kd r g b` (or `Kd r` for grey) with finite numbers, found \"1 0\"",
        ),
        ("newmtl a\r\nKe 1 nan 0\r\n", "lib.mtl: line 2: expected `Ke r g b`"),
        ("newmtl a\nKd spectral x.rfl\n", "lib.mtl: line 2: expected `Kd r g b`"),
        ("Kd 1 1 1\n", "lib.mtl: line 1: `Kd` before any `newmtl`"),
        ("# x\n\nnewmtl\n", "lib.mtl: line 3: expected a material name after `newmtl`"),
    ] {
        let message = parse_with(&obj, &[("lib.mtl", mtl)]).unwrap_err().to_string();
        assert!(message.starts_with(expected), "{message}\n  expected: {expected}");
    }
}

#[test]
fn normals_and_texture_coordinates_follow_their_own_indices() {
    let obj = format!(
        "{SIX_VERTICES}vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nvn 0 0 -1\n\
         g a\nf 1/1/2 2/2/2 3/3/2 4/1/1\ng b\nf -3/-1/-1 -2/-2/-1 -1/-3/-2\n"
    );
    let mesh = parse(&obj).mesh;
    let normals = mesh.normals.as_ref().unwrap();
    let uvs = mesh.uvs.as_ref().unwrap();
    let corner_normals: Vec<[Vec3; 3]> =
        normals.triangles.iter().map(|t| t.map(|i| normals.values[i as usize])).collect();
    let corner_uvs: Vec<[Vec2; 3]> =
        uvs.triangles.iter().map(|t| t.map(|i| uvs.values[i as usize])).collect();
    let (up, down) = (Vec3::Z, Vec3::NEG_Z);
    assert_eq!(corner_normals, [[down, down, down], [down, down, up], [down, down, up]]);
    let uv = [Vec2::ZERO, Vec2::X, Vec2::ONE];
    assert_eq!(corner_uvs, [[uv[0], uv[1], uv[2]], [uv[0], uv[2], uv[0]], [uv[2], uv[1], uv[0]]]);
    assert_eq!(mesh.triangle(2), [p(3), p(4), p(5)]);
}

#[test]
fn attributes_on_some_corners_only_are_dropped() {
    let obj = format!("{SIX_VERTICES}vt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\nf 1//1 2//1 3//1\n");
    let loaded = parse(&obj);
    assert!(loaded.mesh.normals.is_some());
    assert_eq!(loaded.mesh.uvs, None);
    assert_eq!(
        loaded.warnings,
        ["test.obj: texture coordinates ignored: 3 of the 6 face corners have none"]
    );
}

#[test]
fn points_lines_colours_comments_and_other_encodings_are_harmless() {
    // Latin-1 text, CRLF line endings, coloured and weighted vertices.
    let bytes = b"# caf\xe9\r\nv 0 0 0 1 0 0\r\nv 1 0 0\r\nv 0 1 0 0.5 0.5 0.5\r\nv 2 2 2 2\r\n\
               l 1 2 3\r\np 1\r\nf 1\r\nf 1 2\r\ng gr\xfcn\r\nf 1 2 3\r\nf 1 2 4\r\n";
    let loaded = parse_obj_with(Path::new("test.obj"), bytes, &|_| unreachable!()).unwrap();
    assert_eq!(
        loaded.mesh.triangle_vertices().collect::<Vec<_>>(),
        [[Vec3::ZERO, Vec3::X, Vec3::Y], [Vec3::ZERO, Vec3::X, Vec3::ONE],]
    );
    assert_eq!(
        loaded.warnings,
        [
            "test.obj: skipped 2 faces with fewer than 3 corners",
            "test.obj: skipped 1 polylines (`l`)"
        ]
    );
}

#[test]
fn bad_indices_name_the_line() {
    let cases = [
        ("f 1 2 0\n", "line 7: vertex index 0 in face corner \"0\": OBJ indices start at 1"),
        (
            "f 1 2 7\n",
            "line 7: vertex index 7 is out of range: 6 vertices are defined before this line",
        ),
        (
            "f 1 2 -7\n",
            "line 7: relative vertex index -7 reaches before the first one: 6 vertices are defined before this line",
        ),
        ("f 1 2 x\n", "line 7: expected a vertex index in face corner \"x\", found \"x\""),
        ("f 1 2 99999999999999999999\n", "line 7: expected a vertex index"),
        ("f 1/0 2/1 3/1\n", "line 7: texture coordinate index 0 in face corner \"1/0\""),
        (
            "f 1/1 2/1 3/1\n",
            "line 7: texture coordinate index 1 is out of range: 0 texture coordinates are defined",
        ),
        (
            "f 1//-1 2//1 3//1\n",
            "line 7: relative normal index -1 reaches before the first one: 0 normals",
        ),
        (
            "f 1///4 2 3\n",
            "line 7: expected a face corner like 1, 1/2, 1//3 or 1/2/3, found \"1///4\"",
        ),
        ("f /1 2 3\n", "line 7: face corner \"/1\" has no vertex index"),
        ("f\n", "line 7: expected face corners after `f`"),
        ("f 1 2 3\nf 7 8 9\nv 0 0 0\nv 0 0 0\nv 0 0 0\n", "line 8: vertex index 7 is out of range"),
    ];
    for (faces, expected) in cases {
        let message = error(&format!("{SIX_VERTICES}{faces}"));
        assert!(
            message.starts_with(&format!("test.obj: {expected}")),
            "{message}\n  expected: {expected}"
        );
    }
}

#[test]
fn malformed_lines_name_the_line_and_what_was_expected() {
    let cases = [
        (
            "v 1 2\n",
            "line 7: expected `v x y z` with 3 numbers (and an optional weight), found \"v 1 2\"",
        ),
        ("v 1 2 x\n", "line 7: expected `v x y z` with 3 numbers"),
        ("v 1 2 3 0\n", "line 7: the vertex weight w is 0, found \"v 1 2 3 0\""),
        ("v 1 2 3 4 5\n", "line 7: expected `v x y z`, `v x y z w` or `v x y z r g b`"),
        ("vn 1 2\n", "line 7: expected `vn x y z` with 3 numbers"),
        ("vt x y\n", "line 7: expected `vt u v` with 2 numbers"),
        ("usemtl\n", "line 7: expected `usemtl <name>`"),
    ];
    for (line, expected) in cases {
        let message = error(&format!("{SIX_VERTICES}{line}f 1 2 3\n"));
        assert!(
            message.starts_with(&format!("test.obj: {expected}")),
            "{message}\n  expected: {expected}"
        );
    }
}

#[test]
fn values_that_are_not_finite_name_their_line() {
    let cases = [
        ("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: vertex 2 is not finite (NaN, 0, 0)"),
        ("v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n", "line 3: vertex 3 is not finite (0, inf, 0)"),
        (
            "v 0 0 0\nv 1 0 0\nv 1 1 1 1e-45\nf 1 2 3\n",
            "line 3: vertex 3 is not finite (inf, inf, inf)",
        ),
        // The used vertex is named, not an unused bad one before it.
        (
            "v inf 0 0\nv 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 2 3 4\n",
            "line 4: vertex 4 is not finite (0, -inf, 0)",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 inf 1\nf 1//1 2//2 3//1\n",
            "line 5: normal 2 is not finite (0, inf, 1)",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 NaN\nf 1/1 2/1 3/1\n",
            "line 4: texture coordinate 1 is not finite (0, NaN)",
        ),
    ];
    for (obj, expected) in cases {
        let message = error(obj);
        assert!(
            message.starts_with(&format!("test.obj: {expected}")),
            "{message}\n  expected: {expected}"
        );
    }
    // An unused bad vertex does no harm.
    assert_eq!(parse("v nan 0 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 2 3 4\n").mesh.triangles.len(), 1);
}

#[test]
fn an_error_in_the_last_line_without_a_line_ending_is_found() {
    let message = error(&format!("{SIX_VERTICES}f 1 2 3\nvn 1 2"));
    assert_eq!(message, "test.obj: line 8: expected `vn x y z` with 3 numbers, found \"vn 1 2\"");
}

/// A small OBJ with every kind of line, for damaging.
fn sample() -> String {
    format!(
        "mtllib lib.mtl\n{SIX_VERTICES}vt 0 0\nvt 1 1\nvn 0 0 1\ng a\nusemtl red\n\
         f 1/1/1 2/2/1 3/1/1 4/2/1\no b\nf -1/-1/-1 -2/-2/-1 -3/-1/-1\nl 1 2\n"
    )
}

proptest! {
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let read = |_: &str| Ok((PathBuf::from("lib.mtl"), bytes.clone()));
        let _ = parse_obj_with(Path::new("x.obj"), &bytes, &read);
        let _ = parse_mtl(&bytes);
    }

    #[test]
    fn random_text_never_panics(text in "([vfnt/ 0-9.eE+-]|\n|usemtl|mtllib|nan|inf|-9223372036854775808){0,60}") {
        let read = |_: &str| Ok((PathBuf::from("lib.mtl"), text.clone().into_bytes()));
        let _ = parse_obj_with(Path::new("x.obj"), text.as_bytes(), &read);
    }

    #[test]
    fn cut_or_damaged_files_never_panic(cut in 0.0..1.0f64, at in 0.0..1.0f64, byte in any::<u8>()) {
        let obj = sample().into_bytes();
        let cut_obj = &obj[..(obj.len() as f64 * cut) as usize];
        let read = |_: &str| Ok((PathBuf::from("lib.mtl"), MTL.as_bytes()[..(MTL.len() as f64 * cut) as usize].to_vec()));
        let _ = parse_obj_with(Path::new("x.obj"), cut_obj, &read);
        let mut damaged = obj.clone();
        let index = ((damaged.len() as f64 * at) as usize).min(damaged.len() - 1);
        damaged[index] = byte;
        if let Ok(loaded) = parse_obj_with(Path::new("x.obj"), &damaged, &read) {
            let n = loaded.mesh.positions.len() as u32;
            prop_assert!(loaded.mesh.triangles.iter().flatten().all(|&v| v < n));
            prop_assert!(loaded.mesh.positions.iter().all(|p| p.is_finite()));
        }
    }
}
