//! Parts written and read back, merged, and refused.

use super::*;
use crate::film::Film;

fn header(region: Region, samples: u32) -> PartHeader {
    PartHeader {
        kind: PartKind::Image,
        image: (5, 4),
        region,
        samples,
        scene_hash: "00000000deadbeef".into(),
        settings: "size=5x4; spp=2; seed=0".into(),
        command: None,
    }
}

/// A part of `region` whose pixel values are their own image coordinates (`R` = x, `G` = y).
fn part(name: &str, region: Region, samples: u32) -> Part {
    let coordinates = |f: fn(u32, u32) -> f32| -> Vec<f32> {
        (region.y0..region.y1).flat_map(|y| (region.x0..region.x1).map(move |x| f(x, y))).collect()
    };
    Part {
        path: name.into(),
        header: header(region, samples),
        channels: vec![
            ("B".into(), coordinates(|_, _| -0.0)),
            ("G".into(), coordinates(|_, y| y as f32)),
            ("R".into(), coordinates(|x, _| x as f32)),
        ],
    }
}

fn region(x0: u32, y0: u32, x1: u32, y1: u32) -> Region {
    Region { x0, y0, x1, y1 }
}

#[test]
fn a_part_reads_back_as_written() {
    let dir = tempfile::tempdir().unwrap();
    for kind in [PartKind::Image, PartKind::Checkpoint] {
        let r = region(1, 2, 4, 4);
        let mut written = part("p.exr", r, 7);
        written.path = dir.path().join("p.exr");
        written.header.kind = kind;
        written.header.command = Some(r#"{"arguments":["é"]}"#.into());
        written.channels[0].1[3] = f32::NAN;
        written.channels[1].1[1] = f32::from_bits(1); // a subnormal: bits survive
        write_exr(&written.path, (5, 4), r, written.channels.clone(), Some(&written.header))
            .unwrap();
        let read = read_part(&written.path).unwrap();
        assert_eq!(read.header, written.header);
        let bits = |p: &Part| -> Vec<(String, Vec<u32>)> {
            let channel = |c: &Channel| (c.0.clone(), c.1.iter().map(|v| v.to_bits()).collect());
            p.channels.iter().map(channel).collect()
        };
        assert_eq!(bits(&read), bits(&written));
    }
}

#[test]
fn a_plain_exr_is_not_a_part() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plain.exr");
    let film = Film::from_pixels(2, 1, vec![glam::Vec3::ONE; 2]);
    crate::image_io::save_exr_layers(&path, &film, &[]).unwrap();
    let error = read_part(&path).unwrap_err().to_string();
    assert!(error.ends_with("plain.exr: no raylab.kind attribute: not a part raylab wrote"));
}

#[test]
fn parts_merge_into_place() {
    let parts = [
        part("c", region(0, 3, 5, 4), 2),
        part("a", region(0, 0, 2, 3), 2),
        part("b", region(2, 0, 5, 3), 2),
    ];
    let (merged, channels) = merge(parts.to_vec()).unwrap();
    assert_eq!(merged.region, Region::full(5, 4));
    let whole = part("whole", Region::full(5, 4), 2);
    assert_eq!(channels, whole.channels);
}

#[test]
fn parts_that_do_not_fit_are_refused() {
    let a = part("a", region(0, 0, 5, 2), 2);
    let b = part("b", region(0, 2, 5, 4), 2);
    let fails = |parts: &[Part]| merge(parts.to_vec()).unwrap_err().to_string();
    assert_eq!(fails(&[]), "no parts to merge");
    let mut fewer = b.clone();
    fewer.header.samples = 1;
    assert_eq!(
        fails(&[a.clone(), fewer]),
        "b does not belong with a: another sample count (1 samples per pixel against 2; an \
         interrupted part must be resumed or rendered again)"
    );
    let mut other = b.clone();
    other.header.settings = "size=5x4; spp=2; seed=1".into();
    assert_eq!(
        fails(&[a.clone(), other]),
        "b does not belong with a: other settings (seed=1 against seed=0)"
    );
    let mut layers = b.clone();
    layers.channels.push(("depth.Z".into(), vec![0.0; 10]));
    assert!(fails(&[a.clone(), layers]).starts_with("b does not belong with a: other channels"));
    let mut state = b.clone();
    state.header.kind = PartKind::Checkpoint;
    assert!(fails(&[a.clone(), state]).starts_with("b: a checkpoint, not a finished part"));
    // Holes: the first uncovered pixel, found row by row.
    let left = part("l", region(0, 2, 2, 4), 2);
    let right = part("r", region(3, 2, 5, 4), 2);
    assert_eq!(
        fails(&[a.clone(), right, left]),
        "the parts leave 2 of 20 pixels uncovered, the first at column 2, row 2"
    );
    let short = part("s", region(0, 2, 4, 4), 2);
    assert_eq!(
        fails(&[a.clone(), short]),
        "the parts leave 2 of 20 pixels uncovered, the first at column 4, row 2"
    );
    assert_eq!(
        fails(&[a.clone(), part("o", region(4, 1, 5, 4), 2)]),
        "o overlaps a: both hold pixels of 4,1,5,2"
    );
    assert_eq!(fails(&[a.clone(), a.clone(), b]), "a: given twice");
}
