//! The PLY reader on good and broken files.

use proptest::prelude::*;

use super::*;

fn parse(bytes: &[u8]) -> Result<LoadedMesh, LoadError> {
    parse_ply(Path::new("test.ply"), bytes)
}

fn error(bytes: &[u8]) -> String {
    let message = parse(bytes).expect_err("the file is malformed").to_string();
    assert!(message.starts_with("test.ply: "), "{message}");
    assert!(!message.contains('\n'), "{message}");
    message
}

/// A header for `encoding` with the given element and property lines.
fn header(encoding: &str, body: &str) -> String {
    format!("ply\nformat {encoding} 1.0\ncomment made by hand\n{body}end_header\n")
}

const SQUARE_HEADER: &str = "element vertex 4\nproperty float x\nproperty float y\n\
    property float z\nelement face 1\nproperty list uchar int vertex_indices\n";

#[test]
fn an_ascii_polygon_is_a_fan_in_file_order() {
    let text = header("ascii", &SQUARE_HEADER.replace("face 1", "face 2"))
        + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n3 3 2 1\n";
    let mesh = parse(text.as_bytes()).unwrap().mesh;
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]]);
    assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
    assert_eq!((mesh.normals, mesh.uvs), (None, None));
    assert_eq!(mesh.name, "test.ply");
}

#[test]
fn every_type_name_and_alias_is_read() {
    let types = [
        ("char", "int8"),
        ("uchar", "uint8"),
        ("short", "int16"),
        ("ushort", "uint16"),
        ("int", "int32"),
        ("uint", "uint32"),
        ("float", "float32"),
        ("double", "float64"),
    ];
    for (name, alias) in types {
        for ty in [name, alias] {
            let body = format!(
                "element vertex 3\nproperty {ty} x\nproperty {ty} y\nproperty {ty} z\n\
                 element face 1\nproperty list {} {} vertex_indices\n",
                if ty.contains("float") || ty == "double" { "uchar" } else { ty },
                if ty.contains("float") || ty == "double" { "int" } else { ty },
            );
            let text = header("ascii", &body) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
            let mesh = parse(text.as_bytes()).unwrap_or_else(|e| panic!("{ty}: {e}")).mesh;
            assert_eq!(mesh.triangles, vec![[0, 1, 2]], "{ty}");
            assert_eq!(mesh.positions[1], Vec3::X, "{ty}");
        }
    }
}

/// The same mesh in the three encodings: a vertex with `x y z nx ny nz s t` and an unused
/// list, faces with an extra scalar and the index list second, and an unknown element with
/// a list between them.
fn rich_file(encoding: Encoding) -> Vec<u8> {
    let name = match encoding {
        Encoding::Ascii => "ascii",
        Encoding::BinaryLittleEndian => "binary_little_endian",
        Encoding::BinaryBigEndian => "binary_big_endian",
    };
    let mut bytes = header(
        name,
        "element vertex 4\nproperty double x\nproperty float y\nproperty float z\n\
         property list uchar short junk\nproperty float nx\nproperty float ny\n\
         property float nz\nproperty float s\nproperty float t\n\
         element edge 2\nproperty list ushort uint ends\nproperty uchar red\n\
         obj_info skip me\n\
         element face 2\nproperty short flags\nproperty list uchar uint vertex_indices\n",
    )
    .into_bytes();
    let vertices: [[f64; 8]; 4] = [
        [0.1, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        [1.0, 0.0, -2.5, 0.0, 0.0, 1.0, 1.0, 0.0],
        [1.0, 1.0, 3e-5, 0.0, 1.0, 0.0, 1.0, 1.0],
        [0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
    ];
    if encoding == Encoding::Ascii {
        for v in vertices {
            let [x, y, z, nx, ny, nz, s, t] = v;
            bytes.extend(format!("{x} {y} {z} 2 -7 8 {nx} {ny} {nz} {s} {t}\n").bytes());
        }
        bytes.extend(b"3 0 1 2 255\n\n0 9\n  7 4 0 1 2 3\n-1 3 3 2 1\r\n");
        return bytes;
    }
    let big = encoding == Encoding::BinaryBigEndian;
    fn put<const N: usize>(bytes: &mut Vec<u8>, big: bool, le: [u8; N], be: [u8; N]) {
        bytes.extend(if big { be } else { le });
    }
    for v in vertices {
        put(&mut bytes, big, v[0].to_le_bytes(), v[0].to_be_bytes());
        for c in [v[1], v[2]] {
            put(&mut bytes, big, (c as f32).to_le_bytes(), (c as f32).to_be_bytes());
        }
        bytes.push(2);
        for j in [-7i16, 8] {
            put(&mut bytes, big, j.to_le_bytes(), j.to_be_bytes());
        }
        for c in &v[3..] {
            put(&mut bytes, big, (*c as f32).to_le_bytes(), (*c as f32).to_be_bytes());
        }
    }
    for (ends, red) in [(&[0u32, 1, 2][..], 255u8), (&[], 9)] {
        let n = ends.len() as u16;
        put(&mut bytes, big, n.to_le_bytes(), n.to_be_bytes());
        for e in ends {
            put(&mut bytes, big, e.to_le_bytes(), e.to_be_bytes());
        }
        bytes.push(red);
    }
    for (flags, face) in [(7i16, &[0u32, 1, 2, 3][..]), (-1, &[3, 2, 1])] {
        put(&mut bytes, big, flags.to_le_bytes(), flags.to_be_bytes());
        bytes.push(face.len() as u8);
        for i in face {
            put(&mut bytes, big, i.to_le_bytes(), i.to_be_bytes());
        }
    }
    bytes
}

#[test]
fn the_three_encodings_give_the_same_mesh() {
    let ascii = parse(&rich_file(Encoding::Ascii)).unwrap();
    assert_eq!(ascii.warnings, Vec::<String>::new());
    let mesh = &ascii.mesh;
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]]);
    assert_eq!(mesh.positions[0], Vec3::new(0.1, 0.0, 0.0));
    assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 3e-5));
    let normals = mesh.normals.as_ref().expect("normals");
    assert_eq!(normals.values[3], Vec3::X);
    assert_eq!(normals.triangles, mesh.triangles);
    let uvs = mesh.uvs.as_ref().expect("uvs from s t");
    assert_eq!(uvs.values[2], Vec2::ONE);
    for encoding in [Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian] {
        let binary = parse(&rich_file(encoding)).unwrap();
        assert_eq!(binary, ascii, "{encoding:?}");
    }
}

#[test]
fn texture_coordinate_names_are_recognised() {
    for (u, v) in [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")] {
        let body = SQUARE_HEADER.replace(
            "property float z\n",
            &format!("property float z\nproperty float {u}\nproperty float {v}\n"),
        );
        let text =
            header("ascii", &body) + "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 .5\n0 1 0 0 1\n3 0 1 2\n";
        let mesh = parse(text.as_bytes()).unwrap().mesh;
        assert_eq!(mesh.uvs.unwrap().values[2], Vec2::new(1.0, 0.5), "{u} {v}");
    }
}

#[test]
fn ascii_floats_are_correctly_rounded_to_f32() {
    // 1.00000005960464477539062500000001 is just above the midpoint between 1 and the next
    // f32, so it rounds up; through f64 it would round to 1.0.
    let body = SQUARE_HEADER.replace("property float x", "property double x");
    let text = header("ascii", &body)
        + "1.00000005960464477539062500000001 0 0\n0 0 0\n0 1 0\n1 1 0\n3 0 1 2\n";
    let mesh = parse(text.as_bytes()).unwrap().mesh;
    assert_eq!(mesh.positions[0].x, 1.0 + f32::EPSILON);
}

#[test]
fn header_errors_name_the_line_and_what_was_expected() {
    let cases: &[(&str, &str)] = &[
        ("PLY\n", "line 1: expected `ply` on the first line"),
        ("", "line 1: expected `ply`"),
        ("ply\nformat ascii 1.0\nelement vertex 0\n", "line 4: the file ends inside the header"),
        ("ply\nformat ascii 2.0\nend_header\n", "line 2: expected version 1.0, found \"2.0\""),
        ("ply\nformat text 1.0\nend_header\n", "line 2: expected format ascii"),
        ("ply\nelement vertex 1\nend_header\n", "line 3: end of the header without a `format`"),
        ("ply\nformat ascii 1.0\nproperty float x\nend_header\n", "line 3: a property before any"),
        (
            "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
            "line 3: expected a count of vertex elements, found \"-1\"",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n",
            "line 4: expected a type",
        ),
        (
            "ply\nformat ascii 1.0\nelement f 1\nproperty list float int i\nend_header\n",
            "line 4: the count of list i must have an integer type, not float",
        ),
        ("ply\nformat ascii 1.0\nelemnt vertex 1\nend_header\n", "line 3: expected a header line"),
        (
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
            "line 3: element vertex has no property z",
        ),
        (
            "ply\nformat ascii 1.0\nelement face 0\nend_header\n",
            "line 4: the header declares no `element vertex`",
        ),
        (
            &header(
                "ascii",
                "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar float vertex_indices\n",
            ),
            "line 8: face indices must have an integer type, not float",
        ),
        (
            &header(
                "ascii",
                "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty int vertex_indices\n",
            ),
            "line 8: face property vertex_indices must be a list",
        ),
        (
            &header("ascii", "element vertex 0\nproperty float x\nproperty float x\n"),
            "line 6: a second property x in element vertex",
        ),
    ];
    for (text, expected) in cases {
        let message = error(text.as_bytes());
        assert!(message.contains(expected), "{message}\n  expected: {expected}");
    }
}

#[test]
fn absurd_counts_are_refused_before_reading() {
    // 4e9 vertices of 12 bytes each in a 24-byte body.
    let text =
        header("binary_little_endian", &SQUARE_HEADER.replace("vertex 4", "vertex 4000000000"));
    let message = error(&[text.as_bytes(), &[0; 24]].concat());
    assert!(message.contains("line 4: element vertex declares 4000000000 of them, which take at least 48000000000 bytes"), "{message}");
    assert!(message.contains("only 24 bytes follow the header"), "{message}");
    // A face's list needs at least its count byte; an ASCII value at least 2 bytes.
    let text = header(
        "binary_little_endian",
        &SQUARE_HEADER.replace("face 1", "face 18446744073709551615"),
    );
    let message = error(&[text.as_bytes(), &[0; 60]].concat());
    assert!(
        message.contains("line 8: element face declares 18446744073709551615 of them"),
        "{message}"
    );
    let text = header("ascii", &SQUARE_HEADER.replace("vertex 4", "vertex 5")) + "0 0 0\n";
    assert!(error(text.as_bytes()).contains("line 4: element vertex declares 5"));
    // A file that is exactly long enough passes this check: 4 vertices and a face of
    // "3 0 1 2" written as tightly as possible, with no final line ending.
    let text = header("ascii", SQUARE_HEADER) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2";
    assert_eq!(parse(text.as_bytes()).unwrap().mesh.triangles.len(), 1);
}

#[test]
fn cut_ascii_files_name_the_line() {
    // 10 header lines; the vertices are lines 11 to 14, the face line 15. (Where the rest
    // of the file is too short for what the header declares, the count check comes first:
    // see `absurd_counts_are_refused_before_reading`.)
    let whole = header("ascii", SQUARE_HEADER) + "0 0 0\n1 0 0\n1 1\n0 1 0\n4 0 1 2 3\n";
    let message = error(whole.as_bytes());
    assert!(message.contains("line 13: vertex 2: expected 3 values (x y z), found 2"), "{message}");
    let whole = header("ascii", SQUARE_HEADER) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    let cut = &whole[..whole.len() - 3];
    let message = error(cut.as_bytes());
    assert!(
        message.contains("line 15: face 0: the line ends before 4 indices (it has 4 values)"),
        "{message}"
    );
    let cut = header("ascii", &SQUARE_HEADER.replace("face 1", "face 2"))
        + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n";
    let message = error(cut.as_bytes());
    assert!(
        message.contains("line 16: the file ends before face 1 (the header declares 2 of them)"),
        "{message}"
    );
}

#[test]
fn cut_binary_files_name_the_byte() {
    for encoding in [Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian] {
        let whole = rich_file(encoding);
        // The last face: flags (2), count (1), three 4-byte indices.
        for cut in 1..=14 {
            let bytes = &whole[..whole.len() - cut];
            let message = error(bytes);
            let at = format!("byte {}: the file ends inside face 1 (expected ", bytes.len());
            assert!(message.contains(&at), "{message}");
            let what = match cut {
                1..=12 => "3 indices)",
                13 => "the length of list vertex_indices)",
                _ => "flags (short))",
            };
            assert!(message.ends_with(what), "{message}");
        }
    }
}

#[test]
fn bad_values_are_errors_with_their_place() {
    let file = |vertices: &str, face: &str| {
        let text = header("ascii", SQUARE_HEADER) + vertices + face;
        error(text.as_bytes())
    };
    let good = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
    let cases = [
        (
            file(good, "4 0 1 2 4\n"),
            "line 15: face 0: vertex index 4 is out of range (the file has 4 vertices)",
        ),
        (file(good, "4 0 -1 2 3\n"), "line 15: face 0: negative vertex index -1"),
        (
            file(good, "3 0 1 2 3\n"),
            "line 15: face 0: expected 4 values, found 5 (the first extra one is \"3\")",
        ),
        (
            file(good, "3 0 1 x\n"),
            "line 15: face 0: expected 3 indices as integers from -2147483648 to 2147483647, found \"x\"",
        ),
        (
            file(good, "256 0 1 2\n"),
            "line 15: face 0: expected the length of list vertex_indices as an integer from 0 to 255, found \"256\"",
        ),
        (
            file("0 0 0\n1 nan 0\n1 1 0\n0 1 0\n", "3 0 1 2\n"),
            "line 12: vertex 1: y is not finite (NaN)",
        ),
        (
            file("0 0 0\n1 0 0\n1 1 -inf\n0 1 0\n", "3 0 1 2\n"),
            "line 13: vertex 2: z is not finite (-inf)",
        ),
        (
            file("0 0 0\n1 0 0\n1 1 1e39\n0 1 0\n", "3 0 1 2\n"),
            "line 13: vertex 2: z is not finite (inf)",
        ),
        (
            file("0 0 0\n1 0 0\n1 1 0,5\n0 1 0\n", "3 0 1 2\n"),
            "line 13: vertex 2: expected z (float) as a number, found \"0,5\"",
        ),
    ];
    for (message, expected) in cases {
        assert!(message.contains(expected), "{message}\n  expected: {expected}");
    }
    // Binary: the offset is the value's.
    let mut bytes = rich_file(Encoding::BinaryLittleEndian);
    let last = bytes.len() - 4;
    bytes[last..].copy_from_slice(&4u32.to_le_bytes());
    let message = error(&bytes);
    assert!(
        message.contains(&format!("byte {last}: face 1: vertex index 4 is out of range")),
        "{message}"
    );
    let mut bytes = rich_file(Encoding::BinaryBigEndian);
    let start = String::from_utf8_lossy(&bytes).find("end_header\n").unwrap() + 11;
    bytes[start..start + 8].copy_from_slice(&f64::NAN.to_be_bytes());
    let message = error(&bytes);
    assert!(
        message.contains(&format!("byte {start}: vertex 0: x is not finite (NaN)")),
        "{message}"
    );
    // A negative list length in a signed count type.
    let body = SQUARE_HEADER.replace("list uchar", "list char");
    let mut bytes = header("binary_little_endian", &body).into_bytes();
    bytes.extend([0u8; 48]);
    let at = bytes.len();
    bytes.extend([0xff, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
    let message = error(&bytes);
    assert!(
        message
            .contains(&format!("byte {at}: face 0: list vertex_indices has a negative length -1")),
        "{message}"
    );
}

#[test]
fn short_faces_and_trailing_data_are_warnings() {
    let text = header("ascii", &SQUARE_HEADER.replace("face 1", "face 3"))
        + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 1\n0\n3 0 1 2\n\n9 9 9\n";
    let loaded = parse(text.as_bytes()).unwrap();
    assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(
        loaded.warnings,
        [
            "test.ply: line 19: ignored text after the last element",
            "test.ply: skipped 2 faces with fewer than 3 vertices"
        ]
    );
    let mut bytes = rich_file(Encoding::BinaryLittleEndian);
    let end = bytes.len();
    bytes.extend(b"\n");
    let loaded = parse(&bytes).unwrap();
    assert_eq!(
        loaded.warnings,
        [format!("test.ply: byte {end}: ignored 1 bytes after the last element")]
    );
}

#[test]
fn partial_normals_are_ignored_with_a_warning() {
    let body = SQUARE_HEADER.replace("property float z\n", "property float z\nproperty float nx\n");
    let text = header("ascii", &body) + "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n3 0 1 2\n";
    let loaded = parse(text.as_bytes()).unwrap();
    assert_eq!(loaded.mesh.normals, None);
    assert_eq!(
        loaded.warnings,
        ["test.ply: line 4: normals ignored: element vertex lacks some of nx, ny and nz"]
    );
}

/// Deterministic pseudo-random bytes, for hostile inputs without a seed from the entropy.
fn mutate(bytes: &mut [u8], seed: u64, flips: usize) {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    for _ in 0..flips {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        if !bytes.is_empty() {
            let at = (state % bytes.len() as u64) as usize;
            bytes[at] = (state >> 32) as u8;
        }
    }
}

proptest! {
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = parse(&bytes);
        let _ = parse(&[b"ply\nformat binary_little_endian 1.0\n".as_slice(), &bytes].concat());
    }

    #[test]
    fn cut_or_damaged_files_never_panic(which in 0..3usize, cut in 0.0..1.0f64, seed in any::<u64>(), flips in 0..4usize) {
        let encoding = [Encoding::Ascii, Encoding::BinaryLittleEndian, Encoding::BinaryBigEndian][which];
        let mut bytes = rich_file(encoding);
        bytes.truncate((bytes.len() as f64 * cut) as usize);
        let _ = parse(&bytes);
        let mut bytes = rich_file(encoding);
        mutate(&mut bytes, seed, flips);
        if let Ok(loaded) = parse(&bytes) {
            let n = loaded.mesh.positions.len() as u32;
            prop_assert!(loaded.mesh.triangles.iter().flatten().all(|&v| v < n));
            prop_assert!(loaded.mesh.positions.iter().all(|p| p.is_finite()));
        }
    }
}
