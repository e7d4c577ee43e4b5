use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::*;
use crate::color::{linear_to_srgb, srgb_to_linear};

/// A one-row linear image whose texel `i` is `i` in every channel (over 255).
fn ramp(width: u32) -> TextureImage {
    let texels = (0..width).map(|i| [i as u8; 4]).collect();
    TextureImage::from_rgba8("ramp", width, 1, texels, false)
}

/// The red channel, back in the ramp's units.
fn red(v: Vec4) -> f32 {
    v.x * 255.0
}

#[test]
fn srgb_decodes_to_the_published_values() {
    // IEC 61966-2-1 at 8-bit codes (as tabulated, e.g. by Poynton and colour-science).
    let known = [
        (0u8, 0.0f32),
        (10, 0.003_035_27),
        (64, 0.051_269_46),
        (128, 0.215_860_5),
        (200, 0.577_580_4),
        (255, 1.0),
    ];
    for (code, linear) in known {
        let got = srgb_to_linear(f32::from(code) / 255.0);
        assert!((got - linear).abs() < 1e-6, "{code}: {got} against {linear}");
        // The 8-bit lookup table gives the same, and encoding goes back.
        let image = TextureImage::from_rgba8("one", 1, 1, vec![[code, code, code, 255]], true);
        assert_eq!(image.texel(0, 0, 0), Vec4::new(got, got, got, 1.0));
        let back = linear_to_srgb(got) * 255.0;
        assert!((back - f32::from(code)).abs() < 1e-3, "{code}: encoded back as {back}");
    }
    // The two pieces meet: no jump at the threshold.
    let below = srgb_to_linear(0.040_45);
    let above = srgb_to_linear(0.040_45 + 1e-6);
    assert!((above - below).abs() < 1e-6);
    // Linear images and alpha are not decoded.
    let image = TextureImage::from_rgba8("lin", 1, 1, vec![[128, 128, 128, 128]], false);
    assert_eq!(image.texel(0, 0, 0), Vec4::splat(128.0 / 255.0));
    let image = TextureImage::from_rgba8("srgb", 1, 1, vec![[0, 0, 0, 128]], true);
    assert_eq!(image.texel(0, 0, 0).w, 128.0 / 255.0);
}

#[test]
fn wrap_modes_find_the_texels_beyond_the_edges() {
    use Wrap::*;
    // A row of 4: indices −9 … 12.
    let expect: [(Wrap, [u32; 22]); 3] = [
        (Repeat, [3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0]),
        (Clamp, [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3]),
        (Mirror, [0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1, 2, 3, 3]),
    ];
    for (wrap, indices) in expect {
        let got: Vec<u32> = (-9..13).map(|i| wrap.index(i, 4)).collect();
        assert_eq!(got, indices, "{wrap:?}");
        // The extremes of the index range stay in range.
        for i in [i64::MIN, i64::MIN + 1, i64::MAX] {
            assert!(wrap.index(i, 4) < 4, "{wrap:?} at {i}");
        }
    }
}

#[test]
fn bilinear_lookups_at_the_borders_follow_the_wrap_mode() {
    let image = ramp(4);
    let at = |s: f32, wrap: Wrap| red(image.bilinear(0, Vec2::new(s, 0.5), [wrap, Wrap::Clamp]));
    // Texel centres are at (i + ½)/4: exactly the texel there.
    for i in 0..4 {
        assert_eq!(at((i as f32 + 0.5) / 4.0, Wrap::Repeat), i as f32);
    }
    // Halfway between centres: the mean.
    assert_eq!(at(0.25, Wrap::Repeat), 0.5);
    // (s, texel read) beyond each edge, and at the edges themselves (halfway between the edge
    // texel and the one beyond).
    let cases = [
        (Wrap::Repeat, [(-0.125, 3.0), (1.125, 0.0), (0.0, 1.5), (1.0, 1.5), (2.375, 1.0)]),
        (Wrap::Clamp, [(-0.125, 0.0), (1.125, 3.0), (0.0, 0.0), (1.0, 3.0), (-7.0, 0.0)]),
        (Wrap::Mirror, [(-0.125, 0.0), (-0.375, 1.0), (1.125, 3.0), (1.375, 2.0), (2.125, 0.0)]),
    ];
    for (wrap, pairs) in cases {
        for (s, expected) in pairs {
            assert_eq!(at(s, wrap), expected, "{wrap:?} at s = {s}");
        }
    }
    // t wraps on its own: a column of 4 read with t beyond its edges.
    let column =
        TextureImage::from_rgba8("column", 1, 4, (0..4u8).map(|i| [i; 4]).collect(), false);
    let at_t = |t: f32, wrap: Wrap| red(column.bilinear(0, Vec2::new(0.5, t), [Wrap::Clamp, wrap]));
    assert_eq!(at_t(-0.125, Wrap::Repeat), 3.0);
    assert_eq!(at_t(-0.125, Wrap::Clamp), 0.0);
    assert_eq!(at_t(1.375, Wrap::Mirror), 2.0);
    // Absurd coordinates read some texel, never out of bounds.
    for s in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30, -1e30] {
        for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror] {
            let v = at(s, wrap);
            assert!((0.0..=3.0).contains(&v), "{wrap:?} at {s}: {v}");
        }
    }
}

#[test]
fn the_pyramid_halves_each_level_down_to_one_texel() {
    let image = TextureImage::from_rgba8("big", 300, 200, vec![[9; 4]; 300 * 200], true);
    let sizes: Vec<(u32, u32)> = image.levels().iter().map(Level::size).collect();
    assert_eq!(
        sizes,
        [(300, 200), (150, 100), (75, 50), (37, 25), (18, 12), (9, 6), (4, 3), (2, 1), (1, 1)]
    );
    // A constant image stays that constant at every level.
    for level in 0..sizes.len() {
        assert_eq!(image.texel(level, 0, 0), image.texel(0, 0, 0));
    }
    // Black and white average in linear light: 0.5, not sRGB's 0.5 (which is 0.214 linear).
    let image =
        TextureImage::from_rgba8("bw", 2, 1, vec![[0, 0, 0, 255], [255, 255, 255, 255]], true);
    let mean = image.texel(1, 0, 0);
    assert!((mean.x - 0.5).abs() < 4e-3, "{mean}");
    assert_eq!(mean.w, 1.0);
    // An odd row leaves no texel out: 3 texels (0, 0, 1) become one of 1/3, where taking the
    // first two would give 0; 7 become 3, each 7/3 wide: the middle one covers 2/3 of texel 2,
    // all of 3 and 2/3 of 4.
    let row = |values: &[f32]| {
        let texels = values.iter().map(|&v| [0.0, 0.0, v, 1.0]).collect();
        TextureImage::from_rgba_f32("row", values.len() as u32, 1, texels)
    };
    assert!((row(&[0.0, 0.0, 1.0]).texel(1, 0, 0).z - 1.0 / 3.0).abs() < 1e-6);
    let seven = row(&[0.0, 0.0, 3.0, 6.0, 9.0, 0.0, 0.0]);
    assert_eq!(seven.levels()[1].size(), (3, 1));
    let expected =
        [(3.0 / 3.0) * 3.0 / 7.0, (2.0 + 6.0 + 6.0) * 3.0 / 7.0, (9.0 / 3.0) * 3.0 / 7.0];
    for (x, e) in expected.iter().enumerate() {
        let got = seven.texel(1, x as u32, 0).z;
        assert!((got - e).abs() < 1e-5, "texel {x}: {got}, not {e}");
    }
    // The mean over the row is kept at every level: nothing is dropped or counted twice.
    let total: f32 = (0..3).map(|x| seven.texel(1, x, 0).z).sum::<f32>() / 3.0;
    assert!((total - 18.0 / 7.0).abs() < 1e-5, "{total}");
}

#[test]
fn a_wide_footprint_averages_a_checkerboard_to_grey() {
    // One-texel squares, black and white (linear): the worst case for aliasing.
    let n = 256u32;
    let texels = (0..n * n)
        .map(|i| if (i % n + i / n).is_multiple_of(2) { [0, 0, 0, 255] } else { [255; 4] })
        .collect();
    let image = TextureImage::from_rgba8("checker", n, n, texels, false);
    let wrap = [Wrap::Repeat; 2];
    // Sampled at scattered points, a point lookup flips between black and white; a footprint
    // of four texels or more gives the mean, 0.5.
    let mut point_extremes = 0;
    for k in 0..200 {
        let st = Vec2::new((k as f32 * 0.618_034).fract(), (k as f32 * 0.414_214).fract());
        let texel = |x: f32, y: f32| Vec2::new((x + 0.5) / n as f32, (y + 0.5) / n as f32);
        let centre = texel((st.x * n as f32).floor(), (st.y * n as f32).floor());
        let point = image.filtered(centre, 0.0, wrap).x;
        point_extremes += usize::from(point == 0.0 || point == 1.0);
        for footprint in [4.0, 16.0, 1000.0] {
            let v = image.filtered(st, footprint / n as f32, wrap).x;
            // 8-bit levels: the mean 127.5/255 is stored as 128/255.
            assert!((v - 0.5).abs() < 3e-3, "footprint {footprint}: {v}");
        }
    }
    assert_eq!(point_extremes, 200, "texel centres read pure black or white");
}

#[test]
fn image_textures_apply_the_factor_and_obj_flips_v() {
    // Two rows: the top red, the bottom blue.
    let image = Arc::new(TextureImage::from_rgba8(
        "rows",
        1,
        2,
        vec![[255, 0, 0, 255], [0, 0, 255, 255]],
        false,
    ));
    let query = |v: f32| TextureQuery { uv: Vec2::new(0.5, v), ..TextureQuery::default() };
    let gltf =
        ImageTexture { factor: Vec4::new(0.5, 1.0, 1.0, 1.0), ..ImageTexture::new(image.clone()) };
    // glTF: v = 0 is the top row.
    assert_eq!(gltf.eval(&query(0.25)), Vec4::new(0.5, 0.0, 0.0, 1.0));
    let obj = ImageTexture::obj(image);
    // OBJ: v = 0 is the bottom row.
    assert_eq!(obj.eval(&query(0.25)), Vec4::new(0.0, 0.0, 1.0, 1.0));
    assert_eq!(obj.eval(&query(0.75)), Vec4::new(1.0, 0.0, 0.0, 1.0));
}

/// An encoded image of `width × height` in `format`.
fn encode(image: &::image::DynamicImage, format: ::image::ImageFormat) -> Vec<u8> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, format).unwrap();
    bytes.into_inner()
}

#[test]
fn png_and_jpeg_decode_at_8_and_16_bits() {
    use ::image::{DynamicImage, ImageBuffer, ImageFormat, Luma, Rgb, Rgba};
    // 8-bit RGBA PNG: texels exact, sRGB decoded.
    let rgba = ImageBuffer::from_fn(3, 2, |x, y| Rgba([(x * 100) as u8, (y * 200) as u8, 7, 99]));
    let png = encode(&DynamicImage::ImageRgba8(rgba), ImageFormat::Png);
    let image = decode_texture("a.png", &png, true).unwrap();
    assert_eq!(image.size(), (3, 2));
    let v = image.texel(0, 2, 1);
    assert_eq!(
        v,
        Vec4::new(
            srgb_to_linear(200.0 / 255.0),
            srgb_to_linear(200.0 / 255.0),
            srgb_to_linear(7.0 / 255.0),
            99.0 / 255.0
        )
    );
    // Grey: the same value in every channel, alpha 1.
    let grey = ImageBuffer::from_fn(2, 2, |x, _| Luma([(x * 255) as u8]));
    let png = encode(&DynamicImage::ImageLuma8(grey), ImageFormat::Png);
    let image = decode_texture("g.png", &png, false).unwrap();
    assert_eq!(image.texel(0, 1, 0), Vec4::ONE);
    assert_eq!(image.texel(0, 0, 1), Vec4::new(0.0, 0.0, 0.0, 1.0));
    // 16 bits: decoded to floats, with the full precision.
    let deep = ImageBuffer::from_fn(1, 1, |_, _| Rgb([32768u16, 65535, 1]));
    let png = encode(&DynamicImage::ImageRgb16(deep), ImageFormat::Png);
    for srgb in [false, true] {
        let image = decode_texture("d.png", &png, srgb).unwrap();
        let v = image.texel(0, 0, 0);
        let half = 32768.0 / 65535.0;
        let expected = if srgb { srgb_to_linear(half) } else { half };
        assert_eq!(v.x, expected);
        assert_eq!((v.y, v.w), (1.0, 1.0));
        assert_eq!(v.z, if srgb { srgb_to_linear(1.0 / 65535.0) } else { 1.0 / 65535.0 });
    }
    // JPEG: lossy, so close to a flat colour.
    let flat = ImageBuffer::from_fn(16, 16, |_, _| Rgb([200u8, 100, 50]));
    let jpeg = encode(&DynamicImage::ImageRgb8(flat), ImageFormat::Jpeg);
    let image = decode_texture("f.jpg", &jpeg, false).unwrap();
    let v = image.texel(0, 8, 8) * 255.0;
    assert!(
        (v.x - 200.0).abs() < 4.0 && (v.y - 100.0).abs() < 4.0 && (v.z - 50.0).abs() < 4.0,
        "{v}"
    );
}

#[test]
fn broken_and_oversized_images_are_refused_before_allocating() {
    use ::image::{DynamicImage, ImageBuffer, ImageFormat, Rgb};
    let png = encode(
        &DynamicImage::ImageRgb8(ImageBuffer::from_fn(1, 1, |_, _| Rgb([1u8, 2, 3]))),
        ImageFormat::Png,
    );
    // The header says 100,000 × 100,000 (the IHDR chunk's width and height, its CRC redone).
    let mut huge = png.clone();
    huge[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    huge[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    let mut crc = flate2::Crc::new();
    crc.update(&huge[12..29]);
    huge[29..33].copy_from_slice(&crc.sum().to_be_bytes());
    let error = decode_texture("huge.png", &huge, true).unwrap_err().to_string();
    assert!(error.contains("over the texture size limit"), "{error}");
    // Within each side's limit but too many texels in all.
    let error = check_size(16_384, 16_384).unwrap_err();
    assert!(matches!(error, TextureError::TooLarge { width: 16_384, height: 16_384 }));
    assert!(error.to_string().contains("over the texture size limit"));
    assert!(check_size(8192, 8192).is_ok());
    assert!(check_size(0, 5).unwrap_err().to_string().contains("empty"));
    // Truncated, and not an image at all.
    let error = decode_texture("cut.png", &png[..png.len() - 20], true).unwrap_err().to_string();
    assert!(error.starts_with("a damaged image"), "{error}");
    let error = decode_texture("text.png", b"hello, world", true).unwrap_err();
    assert!(matches!(error, TextureError::Format));
    assert_eq!(error.to_string(), "not a PNG or JPEG image");
}

#[test]
fn perlin_noise_is_zero_on_the_lattice_smooth_and_bounded() {
    let noise = Perlin::new(7);
    let mut rng = crate::sampling::Pcg32::new(1, 2);
    let mut random = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    // Zero at every lattice point, negative coordinates included.
    for p in [Vec3::ZERO, Vec3::new(3.0, -7.0, 250.0), Vec3::new(-1.0, -1.0, -1.0)] {
        assert_eq!(noise.noise(p), 0.0, "{p}");
    }
    let (mut sum, mut max, n) = (0.0f64, 0.0f32, 100_000);
    for _ in 0..n {
        let p = (random() - 0.5) * 40.0;
        let v = noise.noise(p);
        sum += f64::from(v);
        max = max.max(v.abs());
        // Continuous: a step of 1e-3 changes it by at most about the gradient's size times it.
        let step = noise.noise(p + Vec3::splat(1e-3)) - v;
        assert!(step.abs() < 1e-2, "{p}: {step}");
    }
    assert!(max <= 1.05, "bounded: {max}");
    assert!(max > 0.6, "and not flat: {max}");
    assert!((sum / n as f64).abs() < 0.01, "mean {}", sum / n as f64);
    // Another seed is another noise; the same seed the same.
    let p = Vec3::new(0.3, 1.7, -2.2);
    assert_ne!(Perlin::new(8).noise(p), noise.noise(p));
    assert_eq!(Perlin::new(7).noise(p), noise.noise(p));
    // fBm stays within the sum of its amplitudes.
    for _ in 0..10_000 {
        let p = (random() - 0.5) * 10.0;
        assert!(noise.fbm(p, 6).abs() <= 1.05 * (2.0 - 2f32.powi(-5)));
        assert!(noise.turbulence(p, 6) >= 0.0);
    }
}

#[test]
fn patterns_blend_their_two_colours() {
    let colors = [glam::Vec3::new(1.0, 0.0, 0.0), glam::Vec3::new(0.0, 0.0, 1.0)];
    for name in Pattern::NAMES {
        let texture = NoiseTexture {
            pattern: Pattern::from_name(name).unwrap(),
            noise: Perlin::new(0),
            scale: 3.0,
            octaves: 5,
            turbulence: 2.0,
            colors,
        };
        let (mut low, mut high) = (1.0f32, 0.0f32);
        for i in 0..4000 {
            let p = Vec3::new(i as f32 * 0.013, (i as f32 * 0.37).sin(), (i as f32 * 0.11).cos());
            let v = texture.eval(&TextureQuery { p, ..TextureQuery::default() });
            // Always a blend of the two: red + blue = 1, no green.
            assert!((v.x + v.z - 1.0).abs() < 1e-5 && v.y == 0.0, "{name}: {v}");
            low = low.min(v.z);
            high = high.max(v.z);
        }
        assert!(high - low > 0.5, "{name} varies: {low} to {high}");
    }
    assert_eq!(Pattern::from_name("plaid"), None);
}
