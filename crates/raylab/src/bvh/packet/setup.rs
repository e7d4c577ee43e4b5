//! Filling a packet's lanes from its rays: every lane at once, in a form the compiler vectorizes.
//!
//! Setting up a ray for the slab and watertight tests (`1/d`, the dominant axis, the shear, the
//! checks that it can join a packet) takes a large part of a camera packet's time when done
//! ray by ray ([`PacketRays::set_lane`], kept as the scalar twin): a
//! division and several data-dependent branches per ray. Here the rays are first copied into
//! rows, one per component (`rows.rs`), then every lane is computed by the same operations without branches
//! (selects only), sixteen lanes per AVX-512 instruction in the instruction sets' entry points.
//! The values are those of `set_lane`, bit for bit (the test below compares them).

use super::leaf::PacketKernel;
use super::rays::{PACKET, PacketRays};
use super::rows::RestRows;
use crate::bvh::bounds::FAR_SCALE;
use crate::ray::Ray;

/// A lane that cannot join a packet (nothing to hit, a zero direction component or a
/// non-finite value): its ray is traced alone.
pub(super) const ALONE: u8 = u8::MAX;

/// Fills `lanes` from `rays` (at most [`PACKET`]), through `rows` (`K`'s copy of the rays into
/// rows), and returns each lane's group: its direction octant and dominant axis as
/// `octant·3 + axis`, `0..24`, or [`ALONE`]. Lanes from `rays.len()` on hold values of no
/// meaning.
///
/// # Safety
/// The CPU must support `K`'s instruction set.
#[inline(always)]
pub(super) unsafe fn fill<K: PacketKernel>(
    lanes: &mut PacketRays,
    rows: &mut RestRows,
    rays: &[Ray],
) -> [u8; PACKET] {
    assert!(rays.len() <= PACKET, "a packet holds at most {PACKET} rays");
    lanes.len = rays.len();
    // SAFETY: the caller's guarantee.
    unsafe { K::rows_of_rays(rays, &mut lanes.origin, rows) };
    let [direction @ .., t_min, t_max] = &*rows;
    fill_lanes(lanes, direction, t_min, t_max)
}

/// [`fill`] from rays already in rows: the origins copied into the lanes, the rest read where
/// they are. Lane `i` is filled as `fill` fills it from `rays.ray(i)`.
#[inline(always)]
pub(super) fn fill_rows(lanes: &mut PacketRays, rays: &crate::accel::RayRows) -> [u8; PACKET] {
    const _: () = assert!(crate::accel::ROWS == PACKET);
    assert!(rays.len <= PACKET, "a packet holds at most {PACKET} rays");
    lanes.len = rays.len;
    lanes.origin = rays.origin;
    fill_lanes(lanes, &rays.direction, &rays.t_min, &rays.t_max)
}

/// The lanes of [`fill`], the origins already in `lanes`: every lane computed by the same
/// operations, without branches.
#[inline(always)]
fn fill_lanes(
    lanes: &mut PacketRays,
    direction: &[[f32; PACKET]; 3],
    t_min: &[f32; PACKET],
    t_max: &[f32; PACKET],
) -> [u8; PACKET] {
    let mut groups = [ALONE; PACKET];
    for i in 0..PACKET {
        let (ox, oy, oz) = (lanes.origin[0][i], lanes.origin[1][i], lanes.origin[2][i]);
        let (dx, dy, dz) = (direction[0][i], direction[1][i], direction[2][i]);
        // `RayBoxTest::new`.
        let (ix, iy, iz) = (1.0 / dx, 1.0 / dy, 1.0 / dz);
        let box_t_min = t_min[i].max(0.0);
        // `dominant_axis`.
        let (ax, ay, az) = (dx.abs(), dy.abs(), dz.abs());
        let x_dominant = (ax >= ay) & (ax >= az);
        let y_dominant = !x_dominant & (ay >= az);
        let axis = if x_dominant {
            0u8
        } else if y_dominant {
            1
        } else {
            2
        };
        // `WatertightRay::with_shear_z`: `(kx, ky)` follow `kz`, swapped along a negative `kz`.
        let (p, q, d_kz, shear_z) = if x_dominant {
            (dy, dz, dx, ix)
        } else if y_dominant {
            (dz, dx, dy, iy)
        } else {
            (dx, dy, dz, iz)
        };
        let (d_kx, d_ky) = if d_kz < 0.0 { (q, p) } else { (p, q) };
        // `can_hit` and `Frustum::can_join`.
        let finite = |a: f32, b: f32, c: f32| a.is_finite() & b.is_finite() & c.is_finite();
        let can_hit = (t_min[i] <= t_max[i])
            & finite(ox, oy, oz)
            & !(dx.is_nan() | dy.is_nan() | dz.is_nan())
            & !((dx == 0.0) & (dy == 0.0) & (dz == 0.0));
        let can_join =
            finite(ix, iy, iz) & (ix != 0.0) & (iy != 0.0) & (iz != 0.0) & box_t_min.is_finite();
        let octant = dx.is_sign_negative() as u8
            | (dy.is_sign_negative() as u8) << 1
            | (dz.is_sign_negative() as u8) << 2;
        groups[i] = if can_hit & can_join { octant * 3 + axis } else { ALONE };

        lanes.inv_direction[0][i] = ix;
        lanes.inv_direction[1][i] = iy;
        lanes.inv_direction[2][i] = iz;
        lanes.box_t_min[i] = box_t_min;
        lanes.shear[0][i] = d_kx * shear_z;
        lanes.shear[1][i] = d_ky * shear_z;
        lanes.shear[2][i] = shear_z;
        lanes.triangle_t_min[i] = if t_min[i].is_nan() { f32::INFINITY } else { t_min[i] };
        lanes.triangle_limit[i] = t_max[i];
        lanes.box_limit[i] = t_max[i] * FAR_SCALE;
        lanes.best_t[i] = f32::INFINITY;
        lanes.best_triangle[i] = u32::MAX;
    }
    groups
}

/// What the rays of group `group` share: their direction signs and the watertight test's
/// `kx, ky, kz` (`kz` the dominant axis, `kx, ky` the next two, swapped when the direction
/// along `kz` is negative), as [`fill`] numbers the groups.
#[inline(always)]
pub(super) fn shared(group: u8) -> ([bool; 3], [usize; 3]) {
    let (octant, kz) = (group / 3, (group % 3) as usize);
    let negative = [octant & 1 != 0, octant & 2 != 0, octant & 4 != 0];
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    let k = if negative[kz] { [ky, kx, kz] } else { [kx, ky, kz] };
    (negative, k)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// [`fill`] by every instruction set this CPU has (their rows of rays by their own
    /// copies: the portable loop or the AVX transposition), checked to fill every lane below
    /// `rays.len()` alike; returns the first set's lanes in `lanes` and its groups.
    fn fill_each_isa(
        lanes: &mut PacketRays,
        other_rows: &mut RestRows,
        rays: &[Ray],
    ) -> [u8; PACKET] {
        use crate::bvh::isa::Scalar;
        let mut rows = [[f32::NAN; PACKET]; 5];
        // SAFETY: the scalar kernel needs no instruction set.
        let groups = unsafe { fill::<Scalar>(lanes, &mut rows, rays) };
        #[cfg(target_arch = "x86_64")]
        {
            use crate::bvh::isa::{Avx2, Avx512, Sse};
            use crate::cpu::Isa;
            let n = rays.len();
            let check = |other: &PacketRays, other_groups: [u8; PACKET], isa: Isa| {
                assert_eq!(groups[..n], other_groups[..n], "{isa:?}");
                let bits = |rows: &[[f32; PACKET]]| -> Vec<u32> {
                    rows.iter().flat_map(|row| row[..n].iter().map(|v| v.to_bits())).collect()
                };
                assert_eq!(bits(&lanes.origin), bits(&other.origin), "{isa:?}");
                assert_eq!(bits(&lanes.inv_direction), bits(&other.inv_direction), "{isa:?}");
                assert_eq!(bits(&lanes.shear), bits(&other.shear), "{isa:?}");
                for (a, b) in [
                    (&lanes.box_t_min, &other.box_t_min),
                    (&lanes.triangle_t_min, &other.triangle_t_min),
                    (&lanes.triangle_limit, &other.triangle_limit),
                    (&lanes.box_limit, &other.box_limit),
                ] {
                    assert_eq!(bits(&[*a]), bits(&[*b]), "{isa:?}");
                }
            };
            let mut other = PacketRays::new();
            for isa in [Isa::Sse2, Isa::Avx2, Isa::Avx512].into_iter().filter(|i| i.is_supported())
            {
                // SAFETY: each set runs only where `is_supported` says this CPU has it.
                let other_groups = unsafe {
                    match isa {
                        Isa::Sse2 => fill::<Sse>(&mut other, other_rows, rays),
                        Isa::Avx2 => fill::<Avx2>(&mut other, other_rows, rays),
                        _ => fill::<Avx512>(&mut other, other_rows, rays),
                    }
                };
                check(&other, other_groups, isa);
            }
        }
        groups
    }

    /// Every lane is filled as `set_lane` fills it, and grouped alike, for hostile rays: zero
    /// and negative-zero components, NaN and infinite values, reversed ranges, each octant and
    /// dominant axis, and ties between axes.
    #[test]
    fn lanes_are_filled_as_one_ray_at_a_time() {
        let values =
            [1.0, -1.0, 0.5, -2.0, 0.0, -0.0, 1e-30, -1e30, f32::NAN, f32::INFINITY, 3.0, -3.0];
        let mut seed = 1u64;
        let mut next = |n: usize| {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) as usize % n
        };
        let mut grouped = 0;
        // Rows kept from packet to packet, as a chunk keeps them: a longer packet's must not leak
        // into a shorter one's lanes.
        let mut kept_rows = [[f32::NAN; PACKET]; 5];
        for _ in 0..400 {
            let rays: Vec<Ray> = (0..1 + next(PACKET))
                .map(|_| {
                    let mut pick = || values[next(values.len())];
                    let mut ray = Ray::new(
                        Vec3::new(pick(), pick(), pick()),
                        Vec3::new(pick(), pick(), pick()),
                    );
                    (ray.t_min, ray.t_max) =
                        [(0.0, f32::INFINITY), (0.5, 2.0), (2.0, 1.0)][next(3)];
                    if next(50) == 0 {
                        ray.t_min = f32::NAN;
                    }
                    ray
                })
                .collect();
            let mut vector = PacketRays::new();
            let groups = fill_each_isa(&mut vector, &mut kept_rows, &rays);
            // The same lanes from the rays given in rows (`fill_rows`).
            let mut from_rows = PacketRays::new();
            let rows_groups = fill_rows(&mut from_rows, &crate::accel::RayRows::from_rays(&rays));
            let n = rays.len();
            assert_eq!((rows_groups[..n].to_vec(), from_rows.len), (groups[..n].to_vec(), n));
            let lanes = |p: &PacketRays| -> Vec<u32> {
                let rows = p.origin.iter().chain(&p.inv_direction).chain(&p.shear).chain([
                    &p.box_t_min,
                    &p.triangle_t_min,
                    &p.triangle_limit,
                    &p.box_limit,
                    &p.best_t,
                ]);
                rows.flat_map(|row| row[..n].iter().map(|v| v.to_bits())).collect()
            };
            assert_eq!(lanes(&from_rows), lanes(&vector), "filled from rows");
            let mut scalar = PacketRays::new();
            for (i, ray) in rays.iter().enumerate() {
                let expected = scalar.set_lane(i, ray);
                match expected {
                    None => assert_eq!(groups[i], ALONE, "{ray:?}"),
                    Some((group, share)) => {
                        grouped += 1;
                        assert_eq!(groups[i] as usize, group, "{ray:?}");
                        assert_eq!(shared(groups[i]), share, "{ray:?}");
                        let same = |a: &[f32; PACKET], b: &[f32; PACKET]| {
                            assert_eq!(a[i].to_bits(), b[i].to_bits(), "lane {i}: {ray:?}")
                        };
                        for axis in 0..3 {
                            same(&vector.origin[axis], &scalar.origin[axis]);
                            same(&vector.inv_direction[axis], &scalar.inv_direction[axis]);
                            same(&vector.shear[axis], &scalar.shear[axis]);
                        }
                        // `max(t_min, 0)` may give either zero for `t_min = -0`; equal as numbers.
                        assert_eq!(vector.box_t_min[i], scalar.box_t_min[i]);
                        same(&vector.triangle_t_min, &scalar.triangle_t_min);
                        same(&vector.triangle_limit, &scalar.triangle_limit);
                        same(&vector.box_limit, &scalar.box_limit);
                        same(&vector.best_t, &scalar.best_t);
                        assert_eq!(vector.best_triangle[i], scalar.best_triangle[i]);
                    }
                }
            }
            assert_eq!(vector.len, rays.len());
        }
        assert!(grouped > 1000, "only {grouped} rays could join a packet");
    }
}
