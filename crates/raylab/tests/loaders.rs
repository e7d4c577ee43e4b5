//! Whole mesh files through [`raylab::load_mesh`]: the test meshes' exact triangle counts,
//! bounding boxes and materials (from `tests/data/meshes/README.md`); one mesh written as ASCII,
//! little-endian and big-endian PLY, plain and gzip'd, loading identically; and malformed files,
//! each of which must fail with one line that names the file, the place and what was wrong —
//! never with a panic.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{Vec2, Vec3};
use proptest::prelude::*;
use raylab::scene::Location;
use raylab::{LoadError, LoadedMesh, Mesh, load_mesh};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes").join(name)
}

fn load(path: &Path) -> LoadedMesh {
    load_mesh(path).unwrap_or_else(|e| panic!("{e}"))
}

/// Checks the triangle count and the bounding box (given to 6 or 7 significant digits).
fn assert_counts_and_bounds(mesh: &Mesh, triangles: usize, min: [f64; 3], max: [f64; 3]) {
    assert_eq!(mesh.triangles.len(), triangles, "{}", mesh.name);
    let (lo, hi) = mesh.bounds().expect("triangles");
    for (found, expected) in
        lo.to_array().into_iter().zip(min).chain(hi.to_array().into_iter().zip(max))
    {
        assert!(
            (f64::from(found) - expected).abs() <= 5e-6 * expected.abs().max(1.0),
            "{}: bounds {lo} – {hi}, expected {min:?} – {max:?}",
            mesh.name
        );
    }
    let used = mesh.triangles.iter().flatten().all(|&v| (v as usize) < mesh.positions.len());
    assert!(used, "{}: an index is out of range", mesh.name);
}

/// Writes `bytes` to `name` in a new temporary folder; returns both (the folder lives as long
/// as its handle).
fn temporary_file(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let folder = tempfile::tempdir().unwrap();
    let path = folder.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    (folder, path)
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(bytes).unwrap();
    encoder.finish().unwrap()
}

/// The error message for loading `bytes` as `name`, checked to be one line naming the file.
fn error_for(name: &str, bytes: &[u8]) -> String {
    let (_folder, path) = temporary_file(name, bytes);
    let message = load_mesh(&path).expect_err("the file is malformed").to_string();
    assert!(message.starts_with(&format!("{}: ", path.display())), "{message}");
    assert!(!message.contains('\n'), "{message}");
    message
}

#[test]
fn teapot() {
    let loaded = load(&data("teapot.obj"));
    let mesh = &loaded.mesh;
    assert_counts_and_bounds(mesh, 992, [-16.070313, -7.875, -10.0], [16.070313, 7.875, 10.0]);
    assert_eq!(mesh.positions.len(), 792);
    assert_eq!((mesh.normals.is_none(), mesh.uvs.is_none(), mesh.materials.len()), (true, true, 0));
    assert!(mesh.material_ids.is_empty());
    assert_eq!(mesh.zero_area_triangles(), 0);
    assert_eq!(mesh.name, "teapot.obj");
    assert_eq!(loaded.warnings, Vec::<String>::new());
    // File order: the first face is `f 1 2 3`, and v 1 is (5.929688, 4.125, 0).
    assert_eq!(mesh.triangle(0)[0], Vec3::new(5.929688, 4.125, 0.0));
}

#[test]
fn bunny_lowres() {
    let mesh = load(&data("bunny_lowres.obj")).mesh;
    assert_counts_and_bounds(
        &mesh,
        3674,
        [-4.958475, -0.003149, -3.729833],
        [4.94885, 9.654748, 3.810639],
    );
    assert_eq!(mesh.positions.len(), 1839);
}

#[test]
fn bunny_gzip() {
    let mesh = load(&data("bunny.obj.gz")).mesh;
    assert_counts_and_bounds(
        &mesh,
        75408,
        [-0.498959, -0.493434, -0.38649],
        [0.49922, 0.493767, 0.386086],
    );
    assert_eq!(mesh.positions.len(), 37706);
    assert_eq!(mesh.zero_area_triangles(), 0);
    assert_eq!(mesh.name, "bunny.obj.gz");
}

#[test]
fn cornell_box_with_its_four_materials() {
    let loaded = load(&data("cornell_box/cornell_box.obj"));
    assert_eq!(loaded.warnings, Vec::<String>::new());
    let mesh = &loaded.mesh;
    assert_counts_and_bounds(mesh, 32, [0.0; 3], [55.6, 54.88, 55.92]);
    let materials: Vec<(&str, Vec3, Vec3)> =
        mesh.materials.iter().map(|m| (m.name.as_str(), m.diffuse, m.emission)).collect();
    assert_eq!(
        materials,
        [
            ("white", Vec3::splat(0.75), Vec3::ZERO),
            ("red", Vec3::new(0.4275, 0.01875, 0.01875), Vec3::ZERO),
            ("green", Vec3::new(0.01875, 0.177, 0.01875), Vec3::ZERO),
            ("light", Vec3::splat(0.78), Vec3::new(15.0, 10.05, 3.15)),
        ]
    );
    let count = |name: &str| (0..32).filter(|&i| mesh.material(i).unwrap().name == name).count();
    assert_eq!([count("white"), count("red"), count("green"), count("light")], [26, 2, 2, 2]);
    // The light is the last two faces, at the height of the light box's lower face.
    for i in [30, 31] {
        assert_eq!(mesh.material(i).unwrap().name, "light");
        assert!(mesh.triangle(i).iter().all(|v| v.y == 54.87), "{:?}", mesh.triangle(i));
    }
}

#[test]
fn spider_with_materials_texture_coordinates_and_normals() {
    let loaded = load(&data("spider/spider.obj"));
    // The library's texture paths have Windows separators (`map_Kd .\SpiderTex.jpg`): every
    // one is found and decoded.
    assert_eq!(loaded.warnings, Vec::<String>::new());
    let mesh = &loaded.mesh;
    assert_counts_and_bounds(
        mesh,
        1368,
        [-92.655235, -42.233826, -106.6912],
        [57.936218, 37.503952, 86.6912],
    );
    assert_eq!(mesh.zero_area_triangles(), 56);
    let names: Vec<&str> = mesh.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["Skin", "Brusttex", "HLeibTex", "BeinTex", "Augentex"]);
    assert_eq!(mesh.materials[0].diffuse, Vec3::new(0.827451, 0.792157, 0.772549));
    let count = |name: &str| (0..1368).filter(|&i| mesh.material(i).unwrap().name == name).count();
    assert_eq!(
        [count("Skin"), count("Brusttex"), count("HLeibTex"), count("BeinTex"), count("Augentex")],
        [260, 0, 80, 952, 76]
    );
    let normals = mesh.normals.as_ref().expect("normals");
    let uvs = mesh.uvs.as_ref().expect("texture coordinates");
    assert_eq!((normals.triangles.len(), uvs.triangles.len()), (1368, 1368));
    // The first face is `f 1/1/1 2/2/2 3/3/3`; check its first corner against the file.
    let first_line = |prefix: &str| {
        let text = std::fs::read_to_string(data("spider/spider.obj")).unwrap();
        let line = text.lines().find(|l| l.starts_with(prefix)).unwrap().to_string();
        line.split_whitespace().skip(1).map(|w| w.parse::<f32>().unwrap()).collect::<Vec<f32>>()
    };
    assert_eq!(mesh.triangle(0)[0].to_array().to_vec(), first_line("v "));
    assert_eq!(
        normals.values[normals.triangles[0][0] as usize].to_array().to_vec(),
        first_line("vn ")
    );
    assert_eq!(uvs.values[uvs.triangles[0][0] as usize].to_array().to_vec(), first_line("vt "));
    // Each material's `map_Kd`, at the size the JPEG's header gives (`file`), shared where two
    // materials name one file.
    let texture = |m: usize| match &mesh.materials[m].textures.base_color {
        Some(raylab::texture::Texture::Image(t)) => (t.image.name.clone(), t.image.size()),
        other => panic!("material {m}: {other:?}"),
    };
    let expected = [
        ("wal67ar_small.jpg", (250, 250)),
        ("wal69ar_small.jpg", (250, 250)),
        ("SpiderTex.jpg", (249, 250)),
        ("drkwood2.jpg", (768, 768)),
        ("engineflare1.jpg", (128, 128)),
    ];
    for (m, (name, size)) in expected.into_iter().enumerate() {
        assert_eq!(texture(m), (name.to_string(), size));
    }
}

/// `map_Kd` options and file names as the MTL specification writes them, and textures that
/// cannot be read: a warning naming the library, its line and the material, never an error.
#[test]
fn mtl_textures_with_options_and_missing_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::copy(data("spider/SpiderTex.jpg"), d.join("a b.jpg")).unwrap();
    std::fs::write(d.join("broken.jpg"), b"not a jpeg").unwrap();
    std::fs::write(
        d.join("m.mtl"),
        "newmtl scaled\nKd 1 1 1\nmap_Kd -s 2 3 -o 0.5 0.25 -clamp on -bm 1 a b.jpg\n\
         newmtl missing\nmap_Kd gone.png\nnewmtl broken\nmap_Kd broken.jpg\n\
         newmtl odd\nmap_Kd -zz 1 x.png\nnewmtl bare\nmap_Kd -clamp a b.jpg\n",
    )
    .unwrap();
    std::fs::write(
        d.join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
         usemtl scaled\nf 1/1 2/2 3/3\nusemtl missing\nf 1/1 2/2 3/3\n\
         usemtl broken\nf 1/1 2/2 3/3\nusemtl odd\nf 1/1 2/2 3/3\nusemtl bare\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    let loaded = load(&d.join("m.obj"));
    let Some(raylab::texture::Texture::Image(t)) = &loaded.mesh.materials[0].textures.base_color
    else {
        panic!("the scaled texture loads");
    };
    assert_eq!(t.image.size(), (249, 250));
    assert_eq!(t.wrap, [raylab::texture::Wrap::Clamp; 2]);
    // (u, v) scaled, offset, then flipped to the image's rows: (s, t) = (2u + ½, 1 − (3v + ¼)).
    let st = t.transform.transform_point2(glam::Vec2::new(0.25, 0.5));
    assert!(st.abs_diff_eq(glam::Vec2::new(1.0, -0.75), 1e-6), "{st}");
    assert!(loaded.mesh.materials[1].textures.base_color.is_none());
    assert!(loaded.mesh.materials[2].textures.base_color.is_none());
    // A `map_Kd` line that cannot be read leaves its material untextured, with a warning.
    assert!(loaded.mesh.materials[3].textures.base_color.is_none());
    // `-clamp` without `on` or `off`: the next word is the file, and the texture tiles.
    let Some(raylab::texture::Texture::Image(bare)) = &loaded.mesh.materials[4].textures.base_color
    else {
        panic!("the bare -clamp texture loads");
    };
    assert_eq!(bare.wrap, [raylab::texture::Wrap::Repeat; 2]);
    assert_eq!(loaded.warnings.len(), 3, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].contains("m.mtl:9: ignored: `map_Kd`: unknown option \"-zz\""));
    assert!(loaded.warnings[1].contains("m.mtl:5: the texture of material \"missing\" is ignored"));
    assert!(loaded.warnings[1].contains("gone.png"));
    assert!(loaded.warnings[2].contains("m.mtl:7: the texture of material \"broken\" is ignored"));
    assert!(loaded.warnings[2].contains("not a PNG or JPEG image"), "{}", loaded.warnings[2]);
}

#[test]
fn extensions_are_matched_in_any_case() {
    let bytes = std::fs::read(data("teapot.obj")).unwrap();
    let (_folder, path) = temporary_file("TEAPOT.Obj", &bytes);
    assert_eq!(load(&path).mesh.triangles.len(), 992);
    let (_folder, path) = temporary_file("teapot.OBJ.GZ", &gzip(&bytes));
    assert_eq!(load(&path).mesh.triangles.len(), 992);
}

/// The PLY encodings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

/// Writes `mesh` as PLY, with per-vertex `normals` and `uvs`, an unknown element and unknown
/// properties (a list among them) for the reader to skip, and varied types.
fn write_ply(mesh: &Mesh, normals: &[Vec3], uvs: &[Vec2], encoding: Encoding) -> Vec<u8> {
    let format = match encoding {
        Encoding::Ascii => "ascii",
        Encoding::LittleEndian => "binary_little_endian",
        Encoding::BigEndian => "binary_big_endian",
    };
    let mut bytes = format!(
        "ply\nformat {format} 1.0\ncomment written by tests/loaders.rs\nobj_info test\n\
         element vertex {}\nproperty float32 x\nproperty float y\nproperty double z\n\
         property uchar confidence\nproperty float nx\nproperty float ny\nproperty float nz\n\
         property float texture_u\nproperty float texture_v\n\
         element camera 1\nproperty list uint8 int16 view\n\
         element face {}\nproperty list uchar uint vertex_indices\nproperty list ushort float weights\n\
         end_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    )
    .into_bytes();
    let big = encoding == Encoding::BigEndian;
    macro_rules! put {
        ($value:expr) => {
            if big {
                bytes.extend($value.to_be_bytes())
            } else {
                bytes.extend($value.to_le_bytes())
            }
        };
    }
    for ((p, n), t) in mesh.positions.iter().zip(normals).zip(uvs) {
        if encoding == Encoding::Ascii {
            let line = format!(
                "{} {} {} 200 {} {} {} {} {}\n",
                p.x,
                p.y,
                f64::from(p.z),
                n.x,
                n.y,
                n.z,
                t.x,
                t.y
            );
            bytes.extend(line.bytes());
        } else {
            put!(p.x);
            put!(p.y);
            put!(f64::from(p.z));
            bytes.push(200);
            for value in [n.x, n.y, n.z, t.x, t.y] {
                put!(value);
            }
        }
    }
    if encoding == Encoding::Ascii {
        bytes.extend(b"3 -1 0 1\n");
    } else {
        bytes.push(3);
        for view in [-1i16, 0, 1] {
            put!(view);
        }
    }
    for t in &mesh.triangles {
        if encoding == Encoding::Ascii {
            bytes.extend(format!("3 {} {} {} 1 0.5\n", t[0], t[1], t[2]).bytes());
        } else {
            bytes.push(3);
            for v in t {
                put!(*v);
            }
            put!(1u16);
            put!(0.5f32);
        }
    }
    bytes
}

/// The teapot, its per-vertex normals and texture coordinates (made up), and its PLY files.
fn teapot_ply(encoding: Encoding) -> (Mesh, Vec<Vec3>, Vec<Vec2>, Vec<u8>) {
    let mesh = load(&data("teapot.obj")).mesh;
    let normals: Vec<Vec3> = mesh.positions.iter().map(|p| p.normalize_or_zero()).collect();
    let uvs: Vec<Vec2> = mesh.positions.iter().map(|p| Vec2::new(p.x / 7.0, p.y)).collect();
    let bytes = write_ply(&mesh, &normals, &uvs, encoding);
    (mesh, normals, uvs, bytes)
}

#[test]
fn one_mesh_in_three_ply_encodings_plain_and_gzipped() {
    let mut loaded_meshes = Vec::new();
    for encoding in [Encoding::Ascii, Encoding::LittleEndian, Encoding::BigEndian] {
        let (obj, normals, uvs, bytes) = teapot_ply(encoding);
        for (name, bytes) in [("teapot.ply", bytes.clone()), ("teapot.ply.gz", gzip(&bytes))] {
            let (_folder, path) = temporary_file(name, &bytes);
            let loaded = load(&path);
            assert_eq!(loaded.warnings, Vec::<String>::new(), "{encoding:?}");
            let mut mesh = loaded.mesh;
            assert_eq!(mesh.name, name);
            assert_eq!(mesh.positions, obj.positions, "{encoding:?} {name}");
            assert_eq!(mesh.triangles, obj.triangles, "{encoding:?} {name}");
            let mesh_normals = mesh.normals.as_ref().expect("normals");
            assert_eq!((&mesh_normals.values, &mesh_normals.triangles), (&normals, &obj.triangles));
            assert_eq!(mesh.uvs.as_ref().expect("uvs").values, uvs);
            mesh.name.clear();
            loaded_meshes.push(mesh);
        }
    }
    assert!(loaded_meshes.windows(2).all(|pair| pair[0] == pair[1]));
}

#[test]
fn cut_obj_files_name_the_line() {
    let text = std::fs::read_to_string(data("teapot.obj")).unwrap();
    // Cut inside line 100, a `v` line, after its second number.
    let line_100 = text.lines().nth(99).unwrap();
    assert!(line_100.starts_with("v "));
    let start = text.lines().take(99).map(|l| l.len() + 1).sum::<usize>();
    let second_space = line_100.match_indices(' ').nth(2).unwrap().0;
    let cut = &text[..start + second_space];
    let message = error_for("teapot.obj", cut.as_bytes());
    assert!(
        message.ends_with(&format!(
            "teapot.obj: line 100: expected `v x y z` with 3 numbers (and an optional weight), found {:?}",
            &line_100[..second_space]
        )),
        "{message}"
    );
    // Cut inside the last face: a face of two corners is skipped with a warning.
    let cut = &text[..text.trim_end().rfind(' ').unwrap()];
    let (_folder, path) = temporary_file("teapot.obj", cut.as_bytes());
    let loaded = load(&path);
    assert_eq!(loaded.mesh.triangles.len(), 991);
    assert_eq!(
        loaded.warnings,
        [format!("{}: skipped 1 faces with fewer than 3 corners", path.display())]
    );
}

#[test]
fn cut_ply_files_name_the_line_or_byte() {
    // ASCII, cut after the line of face 499: the header has 20 lines and the data 792 + 1
    // lines before the faces.
    let (_, _, _, bytes) = teapot_ply(Encoding::Ascii);
    let text = String::from_utf8(bytes).unwrap();
    let lines_kept = 20 + 792 + 1 + 500;
    let length = text.lines().take(lines_kept).map(|l| l.len() + 1).sum::<usize>();
    let message = error_for("teapot.ply", &text.as_bytes()[..length]);
    assert!(
        message.ends_with(&format!(
            "teapot.ply: line {}: the file ends before face 500 (the header declares 992 of them)",
            lines_kept + 1
        )),
        "{message}"
    );
    // Cut inside a line: the same file without its last weight ("0.5\n").
    let message = error_for("teapot.ply", &text.as_bytes()[..text.len() - 4]);
    assert!(
        message.ends_with(&format!(
            "teapot.ply: line {}: face 991: the line ends before 1 value of list weights (it has 5 values)",
            text.lines().count()
        )),
        "{message}"
    );
    // Binary: cut inside the last face's indices (each face is 1 + 12 + 2 + 4 bytes).
    for encoding in [Encoding::LittleEndian, Encoding::BigEndian] {
        let (_, _, _, bytes) = teapot_ply(encoding);
        let cut = &bytes[..bytes.len() - 6 - 5];
        let message = error_for("teapot.ply", cut);
        assert!(
            message.ends_with(&format!(
                "teapot.ply: byte {}: the file ends inside face 991 (expected 3 indices)",
                cut.len()
            )),
            "{encoding:?}: {message}"
        );
    }
}

#[test]
fn bad_indices_name_the_line_or_byte() {
    let vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    for (face, expected) in [
        ("f 1 2 0", "bad.obj: line 5: vertex index 0 in face corner \"0\": OBJ indices start at 1"),
        (
            "f 1 2 4",
            "bad.obj: line 5: vertex index 4 is out of range: 3 vertices are defined before this line",
        ),
        (
            "f -1 -2 -4",
            "bad.obj: line 5: relative vertex index -4 reaches before the first one: 3 vertices are defined before this line",
        ),
    ] {
        let message = error_for("bad.obj", format!("{vertices}f 1 2 3\n{face}\n").as_bytes());
        assert!(message.ends_with(expected), "{message}\n  expected: {expected}");
    }
    let ply = |face: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
             0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n{face}\n"
        )
    };
    let message = error_for("bad.ply", ply("3 0 1 3").as_bytes());
    assert!(
        message.ends_with(
            "bad.ply: line 14: face 1: vertex index 3 is out of range (the file has 3 vertices)"
        ),
        "{message}"
    );
    let message = error_for("bad.ply", ply("3 0 -1 2").as_bytes());
    assert!(message.ends_with("bad.ply: line 14: face 1: negative vertex index -1"), "{message}");
    // Binary: the offset of the bad index.
    let (mesh, _, _, mut bytes) = teapot_ply(Encoding::BigEndian);
    let at = bytes.len() - 6 - 4;
    bytes[at..at + 4].copy_from_slice(&(mesh.positions.len() as u32).to_be_bytes());
    let message = error_for("bad.ply", &bytes);
    assert!(message.ends_with(&format!("bad.ply: byte {at}: face 991: vertex index 792 is out of range (the file has 792 vertices)")), "{message}");
}

#[test]
fn values_that_are_not_finite_name_the_line_or_byte() {
    let message = error_for("nan.obj", b"v 0 0 0\nv 1 0 0\nv 0 NaN 0\nf 1 2 3\n");
    assert!(message.ends_with("nan.obj: line 3: vertex 3 is not finite (0, NaN, 0)"), "{message}");
    let message = error_for("inf.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 -inf\nf 1 2 3\n");
    assert!(message.ends_with("inf.obj: line 3: vertex 3 is not finite (0, 1, -inf)"), "{message}");
    // The first vertex line of the ASCII PLY (line 21) gets an infinite normal x.
    let (_, _, _, bytes) = teapot_ply(Encoding::Ascii);
    let mut lines: Vec<String> =
        String::from_utf8(bytes).unwrap().lines().map(str::to_string).collect();
    let mut words: Vec<&str> = lines[20].split(' ').collect();
    words[4] = "inf";
    lines[20] = words.join(" ");
    let message = error_for("inf.ply", (lines.join("\n") + "\n").as_bytes());
    assert!(message.ends_with("inf.ply: line 21: vertex 0: nx is not finite (inf)"), "{message}");
    let (_, _, _, mut bytes) = teapot_ply(Encoding::LittleEndian);
    let data_start = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    // Vertex 1's y: after vertex 0 (4 + 4 + 8 + 1 + 5 × 4 bytes) and vertex 1's x.
    let at = data_start + 37 + 4;
    bytes[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let message = error_for("nan.ply", &bytes);
    assert!(
        message.ends_with(&format!("nan.ply: byte {at}: vertex 1: y is not finite (NaN)")),
        "{message}"
    );
}

#[test]
fn absurd_element_counts_are_refused() {
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n\
        property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        .to_vec();
    bytes.extend([0u8; 60]);
    let message = error_for("absurd.ply", &bytes);
    assert!(
        message.ends_with(
            "absurd.ply: line 3: element vertex declares 4000000000 of them, which take at least \
             48000000000 bytes with what comes before, but only 60 bytes follow the header"
        ),
        "{message}"
    );
}

#[test]
fn file_level_errors_name_the_path() {
    let message = error_for("teapot.obj.gz", &std::fs::read(data("teapot.obj")).unwrap());
    assert!(
        message.ends_with("teapot.obj.gz: not a valid gzip file: invalid gzip header"),
        "{message}"
    );
    let message = error_for("teapot.stl", b"solid teapot\n");
    assert!(
        message.ends_with(
            "teapot.stl: unknown mesh file type; the supported extensions are .obj, .obj.gz, .ply, \
             .ply.gz, .gltf, .glb (in any case)"
        ),
        "{message}"
    );
    let message = error_for("comments.obj", b"# nothing here\nv 0 0 0\n");
    assert!(message.ends_with("comments.obj: no triangles (an empty mesh)"), "{message}");

    let folder = tempfile::tempdir().unwrap();
    let missing = folder.path().join("missing.obj");
    let error = load_mesh(&missing).unwrap_err();
    assert!(matches!(error, LoadError::File(raylab::file_bytes::ReadError::Read { .. })));
    assert_eq!(
        error.to_string(),
        format!("{}: cannot read: No such file or directory (os error 2)", missing.display())
    );
    for name in ["meshes", "looks_like.obj"] {
        let path = folder.path().join(name);
        std::fs::create_dir(&path).unwrap();
        let error = load_mesh(&path).unwrap_err();
        assert_eq!(error.to_string(), format!("{}: is a folder, not a mesh file", path.display()));
    }
}

#[test]
fn errors_carry_their_location_as_data() {
    let (_folder, path) = temporary_file("bad.obj", b"v 0 0 0\nf 1 1 2\n");
    match load_mesh(&path) {
        Err(LoadError::Syntax { location: Location::Line(2), path: error_path, .. }) => {
            assert_eq!(error_path, path);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_missing_material_library_is_a_warning() {
    let text = std::fs::read(data("cornell_box/cornell_box.obj")).unwrap();
    let (_folder, path) = temporary_file("cornell_box.obj", &text);
    let loaded = load(&path);
    assert_eq!(loaded.mesh.triangles.len(), 32);
    assert!(loaded.mesh.materials.is_empty());
    assert_eq!(loaded.warnings.len(), 1);
    let expected = format!(
        "{}: line 6: material library ignored, the surfaces get the default grey: {}: cannot read: No such file",
        path.display(),
        path.with_extension("mtl").display()
    );
    assert!(loaded.warnings[0].starts_with(&expected), "{}", loaded.warnings[0]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Cut or damaged files, in every format and gzip'd, fail cleanly or load a valid mesh.
    #[test]
    fn cut_or_damaged_files_never_panic(which in 0..4usize, cut in 0.0..1.0f64, at in 0.0..1.0f64, byte in any::<u8>(), zip in any::<bool>()) {
        let (name, bytes) = match which {
            0 => ("cut.obj", std::fs::read(data("teapot.obj")).unwrap()),
            1 => ("cut.ply", teapot_ply(Encoding::Ascii).3),
            2 => ("cut.ply", teapot_ply(Encoding::LittleEndian).3),
            _ => ("cut.ply", teapot_ply(Encoding::BigEndian).3),
        };
        let mut bytes = bytes[..(bytes.len() as f64 * cut) as usize].to_vec();
        if let Some(last) = bytes.len().checked_sub(1) {
            let index = ((bytes.len() as f64 * at) as usize).min(last);
            bytes[index] = byte;
        }
        let (name, bytes) = if zip {
            (format!("{name}.gz"), gzip(&bytes))
        } else {
            (name.to_string(), bytes)
        };
        let (_folder, path) = temporary_file(&name, &bytes);
        if let Ok(loaded) = load_mesh(&path) {
            let mesh = loaded.mesh;
            prop_assert!(!mesh.triangles.is_empty());
            prop_assert!(mesh.triangles.iter().flatten().all(|&v| (v as usize) < mesh.positions.len()));
            prop_assert!(mesh.positions.iter().all(|p| p.is_finite()));
        }
    }

    /// Random bytes under every supported name fail cleanly (or, rarely, load).
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512), which in 0..4usize) {
        let name = ["x.obj", "x.ply", "x.obj.gz", "x.ply.gz"][which];
        let (_folder, path) = temporary_file(name, &bytes);
        let _ = load_mesh(&path);
    }
}

/// The shared mesh collection beside the repository, if it is there (it is not shipped).
fn shared_data(name: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data").join(name);
    path.exists().then_some(path)
}

/// The full Stanford dragon and the other large meshes of the shared collection. Run with
/// `cargo test --release -p raylab --test loaders -- --ignored --nocapture` to see load times.
#[test]
#[ignore = "needs the shared mesh collection beside the repository; slow in debug builds"]
fn large_shared_meshes() {
    struct Case {
        name: &'static str,
        triangles: usize,
        min: [f64; 3],
        max: [f64; 3],
        zero_area: usize,
    }
    let cases = [
        Case {
            name: "dragon.obj.gz",
            triangles: 871_414,
            min: [-0.108324, 0.0527295, -0.0504143],
            max: [0.0965662, 0.197173, 0.0412075],
            zero_area: 108,
        },
        Case {
            name: "dragon_res2.obj.gz",
            triangles: 202_520,
            min: [-0.108188, 0.0527392, -0.0503454],
            max: [0.0964062, 0.197139, 0.0411367],
            zero_area: 0,
        },
        Case {
            name: "2CylinderEngine/2CylinderEngine.obj.gz",
            triangles: 121_496,
            min: [-371.6922629127621, -180.9715576171875, -139.9999929500657],
            max: [371.69216918961064, 92.04156168904416, 127.99999618810878],
            zero_area: 11_160,
        },
    ];
    for Case { name, triangles, min, max, zero_area } in cases {
        let Some(path) = shared_data(name) else {
            println!("{name}: not found beside the repository; skipped");
            continue;
        };
        let start = Instant::now();
        let loaded = load(&path);
        let elapsed = start.elapsed();
        println!(
            "{name}: {} triangles, {} positions, loaded in {:.0} ms",
            loaded.mesh.triangles.len(),
            loaded.mesh.positions.len(),
            elapsed.as_secs_f64() * 1e3
        );
        for warning in &loaded.warnings {
            println!("  warning: {warning}");
        }
        assert_counts_and_bounds(&loaded.mesh, triangles, min, max);
        assert_eq!(loaded.mesh.zero_area_triangles(), zero_area, "{name}");
        if name == "dragon.obj.gz" {
            time_ply_encodings(&loaded.mesh);
        }
    }
}

/// Writes `mesh` in each PLY encoding and prints how long loading it takes.
fn time_ply_encodings(mesh: &Mesh) {
    let normals = vec![Vec3::Z; mesh.positions.len()];
    let uvs = vec![Vec2::ZERO; mesh.positions.len()];
    for encoding in [Encoding::Ascii, Encoding::LittleEndian, Encoding::BigEndian] {
        let bytes = write_ply(mesh, &normals, &uvs, encoding);
        let (_folder, path) = temporary_file("dragon.ply", &bytes);
        let start = Instant::now();
        let loaded = load(&path);
        println!(
            "  as {encoding:?} PLY ({} MB, with normals and texture coordinates): loaded in {:.0} ms",
            bytes.len() >> 20,
            start.elapsed().as_secs_f64() * 1e3
        );
        assert_eq!(
            (loaded.mesh.positions, loaded.mesh.triangles),
            (mesh.positions.clone(), mesh.triangles.clone())
        );
    }
}
