//! The ray-set benchmark protocol: primary, shadow and diffuse rays for a mesh, and their files.
//!
//! This is the protocol of `docs/benchmarking.md`, which the Embree reference program follows
//! too: primary rays are the same bits as the reference program's, and shadow and diffuse rays
//! are too when they start from the same primary hits (up to the last bit of a libm `cos`/`sin`
//! in rare cases), so hits can be compared ray by ray:
//! - the frame (camera, light, epsilon) comes from the bounding box of the used vertices;
//! - primary rays: one per pixel, row major, from a pinhole at `c − (0, 0, E + R)` looking along
//!   +z with image y along +y, `d = normalize(x + ½ − W/2, y + ½ − H/2, f)`;
//! - shadow rays: from each primary hit point to the light, `[eps, dist − eps]`;
//! - diffuse rays: from each primary hit point, cosine-weighted about the normal facing the
//!   primary ray, with PCG32 seeded by the pixel index (stream 54), Malley's method and the
//!   orthonormal basis of Duff et al. 2017.
//!
//! All arithmetic is in `f64`; values are rounded to `f32` only when stored in a record.
//!
//! File formats (little-endian): `.rays` = `"RAYS"`, version 1, count, 0, then per ray
//! `ox oy oz tmin dx dy dz tmax` as `f32`; `.hits` = `"HITS"`, version 1, count, 0, then per ray
//! `t: f32, prim: u32` (a miss is `+∞`, `0xFFFFFFFF`); `.occluded` = one byte per ray, no header.
//! Readers accept gzip-compressed files whose name ends in `.gz`.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};

use crate::accel::Hit;
use crate::mesh::Mesh;
use crate::ray::Ray;
use crate::sampling;
pub use crate::sampling::Pcg32;

/// Why a ray-set file could not be read or written. The message names the file.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", .path.display())]
pub struct RaySetError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong, e.g. "expected the magic 'RAYS', found 'HITS'".
    pub message: String,
}

impl RaySetError {
    fn new(path: &Path, message: impl Into<String>) -> Self {
        RaySetError { path: path.to_path_buf(), message: message.into() }
    }
}

/// The PCG32 stream of the diffuse rays.
pub const DIFFUSE_STREAM: u64 = 54;

/// Where the benchmark puts the camera and the light for a mesh (protocol §2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Lowest corner of the used vertices.
    pub lo: DVec3,
    /// Highest corner.
    pub hi: DVec3,
    /// Centre of the box.
    pub centre: DVec3,
    /// Half extent in x/y: `max(hi.x − lo.x, hi.y − lo.y) / 2`.
    pub half_extent_xy: f64,
    /// Half extent in z.
    pub half_extent_z: f64,
    /// `|hi − lo|`.
    pub diagonal: f64,
    /// `1e-4 · diagonal`: the shadow and diffuse rays' `t_min`.
    pub epsilon: f64,
    /// `c − (0, 0, E + R)`.
    pub camera: DVec3,
    /// `c + (0.3 E, −1.5 E, −1.5 E − R)`.
    pub light: DVec3,
}

impl Frame {
    /// The frame for a mesh, or `None` if it has no triangles.
    pub fn of(mesh: &Mesh) -> Option<Frame> {
        let (lo, hi) = mesh.bounds()?;
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        let centre = 0.5 * (lo + hi);
        let extent = hi - lo;
        let e = (0.5 * extent.x).max(0.5 * extent.y);
        let r = 0.5 * extent.z;
        let diagonal = extent.length();
        Some(Frame {
            lo,
            hi,
            centre,
            half_extent_xy: e,
            half_extent_z: r,
            diagonal,
            epsilon: 1e-4 * diagonal,
            camera: DVec3::new(centre.x, centre.y, centre.z - (e + r)),
            light: DVec3::new(centre.x + 0.3 * e, centre.y - 1.5 * e, centre.z - 1.5 * e - r),
        })
    }
}

fn ray_f32(origin: DVec3, t_min: f64, direction: DVec3, t_max: f64) -> Ray {
    Ray {
        origin: origin.as_vec3(),
        direction: direction.as_vec3(),
        t_min: t_min as f32,
        t_max: t_max as f32,
    }
}

/// Primary rays, row major (protocol §3); `focal_length_px = W` by default.
pub fn primary_rays(frame: &Frame, width: u32, height: u32, focal_length_px: f64) -> Vec<Ray> {
    let origin = frame.camera.as_vec3().as_dvec3();
    let (w, h) = (width as f64, height as f64);
    let mut rays = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        for x in 0..width {
            let d = DVec3::new(x as f64 + 0.5 - 0.5 * w, y as f64 + 0.5 - 0.5 * h, focal_length_px);
            rays.push(ray_f32(origin, 0.0, d / d.length(), f64::INFINITY));
        }
    }
    rays
}

/// A primary hit as stored in a `.hits` file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitRecord {
    /// Ray parameter; `+∞` for a miss.
    pub t: f32,
    /// Triangle index; [`HitRecord::MISS`] for a miss.
    pub prim: u32,
}

impl Default for HitRecord {
    /// A miss.
    fn default() -> Self {
        HitRecord::from_hit(None)
    }
}

impl HitRecord {
    /// The `prim` of a miss.
    pub const MISS: u32 = u32::MAX;

    /// The record of a query's answer.
    pub fn from_hit(hit: Option<Hit>) -> Self {
        match hit {
            Some(h) => HitRecord { t: h.t, prim: h.triangle },
            None => HitRecord { t: f32::INFINITY, prim: Self::MISS },
        }
    }

    /// Whether the ray hit something.
    pub fn is_hit(&self) -> bool {
        self.prim != Self::MISS
    }
}

/// How far two sets of closest hits for the same rays agree, by the protocol's rules: the same
/// hit or miss, `t` within [`Agreement::T_TOLERANCE`] relative, and a different triangle only
/// where the `t` values agree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Agreement {
    /// Rays compared.
    pub rays: usize,
    /// Rays that one side hits and the other misses.
    pub hit_miss: usize,
    /// Rays both hit, with `t` beyond the tolerance.
    pub t_differences: usize,
    /// The largest relative `t` difference among rays both hit.
    pub max_relative_t: f32,
    /// Rays both hit at agreeing `t`, on different triangles (a shared edge or vertex).
    pub other_triangles: usize,
}

impl Agreement {
    /// The relative `t` tolerance of the protocol.
    pub const T_TOLERANCE: f32 = 1e-5;

    /// Compares `ours` with `reference`, record by record (the shorter length if they differ).
    pub fn of(reference: &[HitRecord], ours: &[HitRecord]) -> Agreement {
        let mut a = Agreement { rays: reference.len().min(ours.len()), ..Agreement::default() };
        for (r, o) in reference.iter().zip(ours) {
            if r.is_hit() != o.is_hit() {
                a.hit_miss += 1;
            } else if r.is_hit() {
                let relative = relative_difference(r.t, o.t);
                a.max_relative_t = a.max_relative_t.max(relative);
                if relative > Self::T_TOLERANCE {
                    a.t_differences += 1;
                } else if r.prim != o.prim {
                    a.other_triangles += 1;
                }
            }
        }
        a
    }

    /// The indices of the rays both hit with `t` beyond the tolerance.
    pub fn t_outliers<'a>(
        reference: &'a [HitRecord],
        ours: &'a [HitRecord],
    ) -> impl Iterator<Item = usize> + 'a {
        reference.iter().zip(ours).enumerate().filter_map(|(i, (r, o))| {
            (r.is_hit() && o.is_hit() && relative_difference(r.t, o.t) > Self::T_TOLERANCE)
                .then_some(i)
        })
    }

    /// Rays that agree (differences at equal `t` on another triangle count as agreeing).
    pub fn agreeing(&self) -> usize {
        self.rays - self.hit_miss - self.t_differences
    }
}

fn relative_difference(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs())
}

impl std::fmt::Display for Agreement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of {} agree ({:.4} %); {} hit/miss and {} t differences (largest {:.1e}); \
             {} other triangles at equal t",
            self.agreeing(),
            self.rays,
            100.0 * self.agreeing() as f64 / self.rays.max(1) as f64,
            self.hit_miss,
            self.t_differences,
            self.max_relative_t,
            self.other_triangles
        )
    }
}

/// `o + t·d` in `f64` from the stored `f32` values, rounded to `f32` (protocol §4).
fn hit_point(ray: &Ray, t: f32) -> DVec3 {
    let p = ray.origin.as_dvec3() + t as f64 * ray.direction.as_dvec3();
    p.as_vec3().as_dvec3()
}

/// Shadow rays toward the light, one per primary hit in pixel order (protocol §4).
pub fn shadow_rays(frame: &Frame, primary: &[Ray], hits: &[HitRecord]) -> Vec<Ray> {
    let eps = frame.epsilon;
    primary
        .iter()
        .zip(hits)
        .filter(|(_, hit)| hit.is_hit())
        .map(|(ray, hit)| {
            let p = hit_point(ray, hit.t);
            let v = frame.light - p;
            let dist = v.length();
            ray_f32(p, eps, v / dist, dist - eps)
        })
        .collect()
}

/// Diffuse rays, one per primary hit in pixel order (protocol §5).
pub fn diffuse_rays(frame: &Frame, mesh: &Mesh, primary: &[Ray], hits: &[HitRecord]) -> Vec<Ray> {
    let eps = frame.epsilon;
    primary
        .iter()
        .zip(hits)
        .enumerate()
        .filter(|(_, (_, hit))| hit.is_hit())
        .map(|(pixel, (ray, hit))| {
            let p = ray.origin.as_dvec3() + hit.t as f64 * ray.direction.as_dvec3();
            let [v0, v1, v2] = mesh.triangle(hit.prim as usize).map(Vec3::as_dvec3);
            let mut n = (v1 - v0).cross(v2 - v0);
            n /= n.length();
            if n.dot(ray.direction.as_dvec3()) > 0.0 {
                n = -n;
            }
            let mut rng = Pcg32::new(pixel as u64, DIFFUSE_STREAM);
            let u1 = rng.next_unit();
            let u2 = rng.next_unit();
            let local = sampling::square_to_cosine_hemisphere_polar_f64(u1, u2);
            let (tangent, bitangent) = sampling::orthonormal_basis_f64(n);
            let d = local.x * tangent + local.y * bitangent + local.z * n;
            // The origin is the f64 hit point rounded once, as in the reference program.
            ray_f32(p, eps, d / d.length(), f64::INFINITY)
        })
        .collect()
}

/// Reads a whole file, decompressing it if its name ends in `.gz`, within the loaders' size
/// limit (so a gzip bomb cannot exhaust memory).
fn read_bytes(path: &Path) -> Result<Vec<u8>, RaySetError> {
    let gzip = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    crate::scene::read_file_bytes(path, gzip).map_err(|e| {
        RaySetError::new(path, e.to_string().replacen(&format!("{}: ", path.display()), "", 1))
    })
}

/// Checks a 16-byte header and returns the record count.
fn parse_header(
    path: &Path,
    bytes: &[u8],
    magic: &[u8; 4],
    record_size: usize,
) -> Result<usize, RaySetError> {
    if bytes.len() < 16 {
        return Err(RaySetError::new(
            path,
            format!("file too short for a header ({} bytes)", bytes.len()),
        ));
    }
    if &bytes[0..4] != magic {
        return Err(RaySetError::new(
            path,
            format!(
                "expected the magic '{}', found {:?}",
                String::from_utf8_lossy(magic),
                String::from_utf8_lossy(&bytes[0..4])
            ),
        ));
    }
    let word = |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    if word(4) != 1 {
        return Err(RaySetError::new(
            path,
            format!("unsupported version {} (expected 1)", word(4)),
        ));
    }
    let count = word(8) as usize;
    let expected = 16 + count * record_size;
    if bytes.len() != expected {
        return Err(RaySetError::new(
            path,
            format!(
                "header says {count} records ({expected} bytes), but the file has {} bytes",
                bytes.len()
            ),
        ));
    }
    Ok(count)
}

fn f32_at(bytes: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]])
}

/// Reads a `.rays` file (or `.rays.gz`).
pub fn read_rays(path: &Path) -> Result<Vec<Ray>, RaySetError> {
    let bytes = read_bytes(path)?;
    parse_header(path, &bytes, b"RAYS", 32)?;
    Ok(bytes[16..]
        .chunks_exact(32)
        .map(|r| {
            let f = |k: usize| f32_at(r, 4 * k);
            Ray {
                origin: Vec3::new(f(0), f(1), f(2)),
                t_min: f(3),
                direction: Vec3::new(f(4), f(5), f(6)),
                t_max: f(7),
            }
        })
        .collect())
}

/// Reads a `.hits` file (or `.hits.gz`).
pub fn read_hits(path: &Path) -> Result<Vec<HitRecord>, RaySetError> {
    let bytes = read_bytes(path)?;
    parse_header(path, &bytes, b"HITS", 8)?;
    Ok(bytes[16..]
        .chunks_exact(8)
        .map(|r| HitRecord { t: f32_at(r, 0), prim: f32_at(r, 4).to_bits() })
        .collect())
}

/// Reads a `.occluded` file (or `.occluded.gz`): one byte per ray, 0 or 1.
pub fn read_occluded(path: &Path) -> Result<Vec<bool>, RaySetError> {
    let bytes = read_bytes(path)?;
    bytes
        .iter()
        .enumerate()
        .map(|(i, &b)| match b {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(RaySetError::new(path, format!("byte {i}: expected 0 or 1, found {b}"))),
        })
        .collect()
}

/// Writes `path` whole or not at all, with the mechanism every raylab output uses
/// ([`crate::image_io::write_atomically`]).
fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), RaySetError> {
    crate::image_io::write_atomically(path, |out| {
        write(out).map_err(|source| crate::image_io::ImageIoError::Io {
            action: "write",
            path: path.to_path_buf(),
            source,
        })
    })
    .map_err(|e| {
        let message = e.to_string();
        // The message names the path already; keep it once.
        RaySetError::new(path, message.replacen(&format!(" '{}'", path.display()), "", 1))
    })
}

fn header(out: &mut dyn Write, magic: &[u8; 4], count: usize) -> io::Result<()> {
    let count = u32::try_from(count)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "more than 2³² records"))?;
    out.write_all(magic)?;
    for word in [1, count, 0] {
        out.write_all(&word.to_le_bytes())?;
    }
    Ok(())
}

/// Writes a `.rays` file.
pub fn write_rays(path: &Path, rays: &[Ray]) -> Result<(), RaySetError> {
    write_atomically(path, |out| {
        header(out, b"RAYS", rays.len())?;
        for r in rays {
            let values = [
                r.origin.x,
                r.origin.y,
                r.origin.z,
                r.t_min,
                r.direction.x,
                r.direction.y,
                r.direction.z,
                r.t_max,
            ];
            for v in values {
                out.write_all(&v.to_le_bytes())?;
            }
        }
        Ok(())
    })
}

/// Writes a `.hits` file.
pub fn write_hits(path: &Path, hits: &[HitRecord]) -> Result<(), RaySetError> {
    write_atomically(path, |out| {
        header(out, b"HITS", hits.len())?;
        for h in hits {
            out.write_all(&h.t.to_le_bytes())?;
            out.write_all(&h.prim.to_le_bytes())?;
        }
        Ok(())
    })
}

/// Writes a `.occluded` file.
pub fn write_occluded(path: &Path, occluded: &[bool]) -> Result<(), RaySetError> {
    write_atomically(path, |out| {
        out.write_all(&occluded.iter().map(|&o| o as u8).collect::<Vec<u8>>())
    })
}

#[cfg(test)]
mod tests {
    use std::fs;

    use super::*;

    #[test]
    fn pcg32_matches_the_protocol_test_vectors() {
        let mut demo = Pcg32::new(42, 54);
        assert_eq!(
            [demo.next_u32(), demo.next_u32(), demo.next_u32()],
            [0xa15c02b7, 0x7b47f409, 0xba1d3330]
        );
        let mut pixel0 = Pcg32::new(0, DIFFUSE_STREAM);
        assert_eq!([pixel0.next_u32(), pixel0.next_u32()], [0x47c28b93, 0xb98f6a27]);
        let mut pixel0 = Pcg32::new(0, DIFFUSE_STREAM);
        assert!((pixel0.next_unit() - 0.28031224).abs() < 1e-9);
        assert!((pixel0.next_unit() - 0.724844575).abs() < 1e-9);
        let mut pixel1 = Pcg32::new(1, DIFFUSE_STREAM);
        assert_eq!([pixel1.next_u32(), pixel1.next_u32()], [0x9b6bdda9, 0x0c31fc48]);
        let mut pixel1 = Pcg32::new(1, DIFFUSE_STREAM);
        assert!((pixel1.next_unit() - 0.607114613).abs() < 1e-9);
        assert!((pixel1.next_unit() - 0.047637701).abs() < 1e-9);
    }

    #[test]
    fn agreement_follows_the_protocol_rules() {
        let hit = |t, prim| HitRecord { t, prim };
        let miss = HitRecord::from_hit(None);
        let reference = [hit(1.0, 0), hit(1.0, 1), hit(2.0, 2), miss, hit(3.0, 3), miss];
        let ours = [hit(1.0, 0), hit(1.000001, 5), hit(2.001, 2), hit(1.0, 0), miss, miss];
        let a = Agreement::of(&reference, &ours);
        assert_eq!((a.rays, a.hit_miss, a.t_differences, a.other_triangles), (6, 2, 1, 1));
        assert_eq!(a.agreeing(), 3);
        assert!((a.max_relative_t - 0.001 / 2.001).abs() < 1e-6);
        assert_eq!(Agreement::t_outliers(&reference, &ours).collect::<Vec<_>>(), [2]);
        assert!(a.to_string().starts_with("3 of 6 agree (50.0000 %); 2 hit/miss and 1 t"), "{a}");
    }

    #[test]
    fn files_round_trip_and_bad_files_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let rays =
            vec![Ray { origin: Vec3::X, direction: Vec3::Y, t_min: 0.5, t_max: f32::INFINITY }];
        let path = dir.path().join("a.rays");
        write_rays(&path, &rays).unwrap();
        assert_eq!(fs::metadata(&path).unwrap().len(), 16 + 32);
        assert_eq!(read_rays(&path).unwrap(), rays);
        let hits = vec![HitRecord { t: 2.0, prim: 7 }, HitRecord::from_hit(None)];
        let hits_path = dir.path().join("a.hits");
        write_hits(&hits_path, &hits).unwrap();
        assert_eq!(read_hits(&hits_path).unwrap(), hits);
        let occluded_path = dir.path().join("shadow.occluded");
        write_occluded(&occluded_path, &[true, false]).unwrap();
        assert_eq!(read_occluded(&occluded_path).unwrap(), vec![true, false]);

        let message = read_rays(&hits_path).unwrap_err().to_string();
        assert!(message.contains("a.hits") && message.contains("magic 'RAYS'"), "{message}");
        fs::write(&path, &fs::read(&path).unwrap()[..40]).unwrap();
        let message = read_rays(&path).unwrap_err().to_string();
        assert!(message.contains("header says 1 records"), "{message}");
        let message = read_rays(&dir.path().join("missing.rays")).unwrap_err().to_string();
        assert!(message.contains("missing.rays") && message.contains("cannot read"), "{message}");
        let nowhere = dir.path().join("missing/a.rays");
        let message = write_rays(&nowhere, &rays).unwrap_err().to_string();
        assert!(
            message.starts_with(&format!("{}: cannot write: folder", nowhere.display())),
            "{message}"
        );
        fs::write(&occluded_path, [0, 1, 2]).unwrap();
        let message = read_occluded(&occluded_path).unwrap_err().to_string();
        assert!(message.contains("byte 2"), "{message}");
    }
}
