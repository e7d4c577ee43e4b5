//! The lab's shading of a tile of hits, lane by lane in arrays ([`TileShading`]): what
//! [`Lab::shade`] computes for one hit, bit for bit, for 64 at a time.

use std::f32::consts::PI;

use glam::Vec3;

use super::gather::Gathered;
use super::model::{Lab, Shading, Stage, TILE};
use crate::accel::{Accelerator, Hit, HitRows, RayRows};
use crate::float::gamma;
use crate::ray::{Ray, step_away};

/// [`Lab::shade`] for a tile's hits, lane by lane in arrays: the triangles' data gathered
/// first, then every lane computed by the same operations as `shade` (and
/// [`SurfacePoint::spawn_ray_to`](crate::ray::SurfacePoint::spawn_ray_to)), in the same order
/// and without branches, which the compiler vectorizes. The values are `shade`'s bit for bit
/// (the test below compares them). Only the lanes of the tile's rays mean something: the
/// arrays are kept from tile to tile, so lanes past them hold another tile's values.
pub(super) struct TileShading {
    pub(super) albedo: [[f32; TILE]; 3],
    pub(super) direct: [[f32; TILE]; 3],
    /// Whether the lane's shadow ray decides its `direct`.
    pub(super) shadow: [bool; TILE],
    /// The shadow rays' origins, moved off their surfaces, where `shadow` is set.
    pub(super) shadow_origin: [[f32; TILE]; 3],
    /// Lanes whose moved origin is not finite: their shadow ray is `shade`'s own.
    pub(super) unusual: [bool; TILE],
}

/// A thread's arrays for the lab's tiles (10 KB), kept from tile to tile and call to call, as
/// the packets keep theirs: nothing is allocated, cleared or moved per tile.
pub(super) struct TileArrays {
    pub(super) hits: HitRows,
    pub(super) shading: TileShading,
    pub(super) gathered: Gathered,
    pub(super) shadow_rays: RayRows,
}

thread_local! {
    /// Each thread's spare [`TileArrays`].
    static SPARE_TILE: std::cell::Cell<Option<Box<TileArrays>>> =
        const { std::cell::Cell::new(None) };
}

impl TileArrays {
    /// This thread's arrays, or new ones.
    pub(super) fn take() -> Box<TileArrays> {
        SPARE_TILE.take().unwrap_or_else(|| {
            Box::new(TileArrays {
                hits: HitRows::default(),
                shading: TileShading {
                    albedo: [[0.0; TILE]; 3],
                    direct: [[0.0; TILE]; 3],
                    shadow: [false; TILE],
                    shadow_origin: [[0.0; TILE]; 3],
                    unusual: [false; TILE],
                },
                gathered: Gathered {
                    corner: [[[0.0; TILE]; 3]; 3],
                    normal: [[0.0; TILE]; 3],
                    direction: [[0.0; TILE]; 3],
                    b1: [0.0; TILE],
                    b2: [0.0; TILE],
                    hit_mask: [false; TILE],
                },
                shadow_rays: RayRows::default(),
            })
        })
    }

    /// Keeps `arrays` for this thread's next call.
    pub(super) fn give_back(arrays: Box<TileArrays>) {
        SPARE_TILE.set(Some(arrays));
    }
}

impl TileShading {
    /// Shades the tile of `rays` and their `hits` (lane `i` for `rays[i]`, at most [`TILE`])
    /// into `self`, through
    /// `gathered`, compiled for AVX2 where the CPU has it (the arithmetic is the same
    /// operations either way: Rust never fuses a multiply and an add, so the lanes are the
    /// same bits; the test below checks both forms). Lanes from `rays.len()` on hold values of
    /// no meaning.
    pub(super) fn shade<A: Accelerator + ?Sized>(
        &mut self,
        gathered: &mut Gathered,
        lab: &Lab<'_, A>,
        rays: &[Ray],
        hits: &HitRows,
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::Isa::detect().at_least(crate::cpu::Isa::Avx2) {
            // SAFETY: AVX2 was detected just above (`detect` names only sets this CPU has).
            return unsafe { self.shade_avx2(gathered, lab, rays, hits) };
        }
        self.shade_portable(gathered, lab, rays, hits)
    }

    /// [`shade`](Self::shade) with AVX2 enabled, its hits gathered from the triangles' lines
    /// where the geometry has them ([`Gathered::gather_avx2`]).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn shade_avx2<A: Accelerator + ?Sized>(
        &mut self,
        gathered: &mut Gathered,
        lab: &Lab<'_, A>,
        rays: &[Ray],
        hits: &HitRows,
    ) {
        match lab.scene.geometry.triangle_lines() {
            // SAFETY: the caller guarantees AVX2.
            Some(lines) => unsafe {
                gathered.gather_avx2(&mut self.albedo, lab, lines, rays, hits)
            },
            None => gathered.gather_portable(&mut self.albedo, lab, rays, hits),
        }
        self.light(gathered, lab, rays.len(), hits);
    }

    /// [`shade`](Self::shade) for any instruction set.
    #[inline(always)]
    fn shade_portable<A: Accelerator + ?Sized>(
        &mut self,
        gathered: &mut Gathered,
        lab: &Lab<'_, A>,
        rays: &[Ray],
        hits: &HitRows,
    ) {
        gathered.gather_portable(&mut self.albedo, lab, rays, hits);
        self.light(gathered, lab, rays.len(), hits);
    }

    /// The light's part of [`shade`](Self::shade), on the gathered hits.
    #[inline(always)]
    fn light<A: Accelerator + ?Sized>(
        &mut self,
        gathered: &Gathered,
        lab: &Lab<'_, A>,
        n: usize,
        hits: &HitRows,
    ) {
        let tile = self;
        if lab.stage == Stage::Flat {
            // No light: no direct term, no shadow rays.
            tile.direct = [[0.0; TILE]; 3];
            tile.shadow = [false; TILE];
            return;
        }
        if lab.scene.geometry.is_instanced() {
            tile.light_lanes::<true, A>(lab, n, hits, gathered);
        } else {
            tile.light_lanes::<false, A>(lab, n, hits, gathered);
        }
    }

    /// The light's part of [`shade`](Self::shade) for the hits gathered in `g`: the loop has no
    /// call where the geometry is not instanced, so that the compiler vectorizes it.
    #[inline(always)]
    fn light_lanes<const INSTANCED: bool, A: Accelerator + ?Sized>(
        &mut self,
        lab: &Lab<'_, A>,
        n: usize,
        hits: &HitRows,
        g: &Gathered,
    ) {
        let Gathered { corner, normal, direction, b1, b2, hit_mask } = g;
        let light = lab.light.position.to_array();
        let power = lab.light.power.to_array();
        let shadows = matches!(lab.stage, Stage::Shadows | Stage::Ambient);
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for i in 0..TILE {
            let mut p = [0.0f32; 3];
            let mut error = [0.0f32; 3];
            if INSTANCED
                && i < n
                && let Some(hit) = hits.hit(i)
            {
                // An instance's point is found in its own space, with the bound of the way
                // there and back.
                let point = lab.scene.geometry.surface_point(&hit);
                (p, error) = (point.p.to_array(), point.error.to_array());
            } else {
                // `Geometry::surface_point`, on the gathered corners.
                let b0 = 1.0 - b1[i] - b2[i];
                for axis in 0..3 {
                    let (a, b, c) = (
                        b0 * corner[0][axis][i],
                        b1[i] * corner[1][axis][i],
                        b2[i] * corner[2][axis][i],
                    );
                    p[axis] = a + b + c;
                    error[axis] = gamma(7) * (a.abs() + b.abs() + c.abs());
                }
            }
            let mut n = [normal[0][i], normal[1][i], normal[2][i]];
            let d = [direction[0][i], direction[1][i], direction[2][i]];
            // Toward the viewer (see `shade`).
            if dot(n, d) >= 0.0 {
                n = n.map(|x| -x);
            }
            // `PointLight::direct`.
            let to_light = [light[0] - p[0], light[1] - p[1], light[2] - p[2]];
            let r2 = dot(to_light, to_light);
            let w_dot_n = dot(to_light, n);
            let r_dot_n = w_dot_n.max(0.0);
            let scale = r_dot_n / (4.0 * PI * r2 * r2.sqrt());
            let mut nonzero = false;
            for (row, power) in self.direct.iter_mut().zip(power) {
                let direct = if r2 == 0.0 { 0.0 } else { power * scale };
                row[i] = direct;
                nonzero |= direct != 0.0;
            }
            self.shadow[i] = hit_mask[i] & shadows & nonzero;
            // `offset_ray_origin` toward the light.
            let along = n[0].abs() * error[0] + n[1].abs() * error[1] + n[2].abs() * error[2];
            let mut finite = true;
            for axis in 0..3 {
                let offset = if w_dot_n < 0.0 { -(along * n[axis]) } else { along * n[axis] };
                let po = p[axis] + offset;
                finite &= po.is_finite();
                self.shadow_origin[axis][i] = step_away(po, offset);
            }
            self.unusual[i] = !finite;
        }
    }

    /// The shadow rays of the tile's lanes that have one (`shadow`), side by side in `out` in
    /// lane order, each as [`shadow_ray`](Self::shadow_ray) makes it: `Ray::segment(origin,
    /// light − origin, 1)`, in lanes, and `shade`'s own ray where the moved origin is not
    /// finite (`unusual`). Sets `out.len` to their number and returns it.
    #[inline(always)]
    pub(super) fn shadow_rows<A: Accelerator + ?Sized>(
        &self,
        lab: &Lab<'_, A>,
        rays: &[Ray],
        hits: &HitRows,
        out: &mut RayRows,
    ) -> usize {
        const _: () = assert!(TILE == crate::accel::ROWS);
        let n = rays.len();
        let (mut shadows, mut unusual) = (0, false);
        for i in (0..n).filter(|&i| self.shadow[i]) {
            for axis in 0..3 {
                out.origin[axis][shadows] = self.shadow_origin[axis][i];
            }
            unusual |= self.unusual[i];
            shadows += 1;
        }
        let light = lab.light.position.to_array();
        let rows = out.direction.iter_mut().zip(&out.origin).zip(light);
        for ((direction, origin), light) in rows {
            for (d, o) in direction.iter_mut().zip(origin) {
                *d = light - o;
            }
        }
        (out.t_min, out.t_max) = ([0.0; TILE], [1.0; TILE]);
        if unusual {
            for (j, i) in (0..n).filter(|&i| self.shadow[i]).enumerate() {
                if self.unusual[i] {
                    out.set(j, &self.shadow_ray(i, lab, &rays[i], hits.hit(i)));
                }
            }
        }
        out.len = shadows;
        shadows
    }

    /// Lane `i` as `shade` returns it (its shadow ray as a flag).
    #[inline]
    pub(super) fn lane(&self, i: usize) -> Shading {
        let get = |rows: &[[f32; TILE]; 3]| Vec3::new(rows[0][i], rows[1][i], rows[2][i]);
        Shading { albedo: get(&self.albedo), direct: get(&self.direct), shadow_ray: None }
    }

    /// Lane `i`'s shadow ray, as `shade` makes it for `ray` and `hit` (that lane's).
    #[inline]
    pub(super) fn shadow_ray<A: Accelerator + ?Sized>(
        &self,
        i: usize,
        lab: &Lab<'_, A>,
        ray: &Ray,
        hit: Option<Hit>,
    ) -> Ray {
        if self.unusual[i] {
            return lab.shade(ray, hit).shadow_ray.expect("a lane with a shadow ray");
        }
        let get = |axis: usize| self.shadow_origin[axis][i];
        let origin = Vec3::new(get(0), get(1), get(2));
        Ray::segment(origin, lab.light.position - origin, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    /// The tile's lanes are `shade`'s values bit for bit, shadow rays included, for rays from
    /// inside and outside the lab's box in every direction, at every stage, with the light
    /// inside the box and on a wall; and the same compiled for AVX2 and for any instruction set.
    #[test]
    fn tile_shading_is_shade_lane_by_lane() {
        use crate::bvh::Bvh;
        let scene = Scene::built_in("cornell").expect("the lab scene");
        assert!(scene.geometry.triangle_lines().is_some(), "the lab's box has lines");
        let bvh = Bvh::new(&scene.vertices());
        let mut seed = 5u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let mut shadows = 0;
        for (k, stage) in Stage::ALL.into_iter().cycle().take(40).enumerate() {
            let mut lab = Lab::new(&scene, &bvh, stage);
            if k % 2 == 1 {
                lab.light.position = Vec3::new(next(), 1.0, next());
            }
            let rays: Vec<Ray> = (0..TILE - k % 3)
                .map(|_| {
                    let origin = Vec3::new(next(), next(), next()) * [0.9, 3.0][k % 2];
                    Ray::new(origin, Vec3::new(next(), next(), next()))
                })
                .collect();
            shadows += tile_matches_shade(&lab, &rays);
        }
        assert!(shadows > 300, "only {shadows} shadow rays");
    }

    /// The same on textured glTF boxes, kept instanced (one box drawn 18 times: the tiles take
    /// the other copy of the light loop, the instance's own surface point) and flattened (a
    /// flat geometry with textures: the triangles' lines, and the albedo looked up per hit).
    #[test]
    fn tile_shading_is_shade_lane_by_lane_on_textured_instances() {
        use crate::bvh::SceneBvh;
        use crate::scene::{Instancing, LoadOptions};
        let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mitsuba-gltf/boxes.gltf");
        for instancing in [Instancing::Keep, Instancing::Flatten] {
            let options = LoadOptions { instancing };
            let scene = Scene::open(file, &options).expect("the glTF boxes").scene;
            assert_eq!(scene.geometry.is_instanced(), instancing == Instancing::Keep);
            assert_eq!(
                scene.geometry.triangle_lines().is_some(),
                instancing == Instancing::Flatten
            );
            assert!(scene.materials.iter().any(|m| !m.textures.is_empty()), "a texture");
            let accel = SceneBvh::build(&scene.geometry).expect("a tree");
            let bounds = (0..scene.geometry.len())
                .flat_map(|i| scene.geometry.triangle(i))
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
            let (centre, size) = ((bounds.0 + bounds.1) * 0.5, (bounds.1 - bounds.0).length());
            let mut seed = 11u64;
            let mut next = || {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (seed >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
            };
            let (mut shadows, mut hits) = (0, 0);
            for (k, stage) in Stage::ALL.into_iter().cycle().take(20).enumerate() {
                let mut lab = Lab::new(&scene, &accel, stage);
                lab.light.position = centre + Vec3::new(next(), 1.0, next()) * size;
                // Rays from around the boxes toward a random triangle's centre.
                let rays: Vec<Ray> = (0..TILE - k % 3)
                    .map(|_| {
                        let origin = centre + Vec3::new(next(), next(), next()) * size;
                        let pick = ((next() * 0.5 + 0.5) * scene.geometry.len() as f32) as usize;
                        let [a, b, c] = scene.geometry.triangle(pick.min(scene.geometry.len() - 1));
                        Ray::new(origin, (a + b + c) / 3.0 - origin)
                    })
                    .collect();
                hits += rays.iter().filter(|r| accel.closest_hit(r).is_some()).count();
                shadows += tile_matches_shade(&lab, &rays);
            }
            assert!(hits > 600 && shadows > 200, "only {hits} hits and {shadows} shadow rays");
        }
    }

    /// The shadow rays side by side in rows are each lane's own, in lane order, also where a
    /// lane's moved origin is not finite and its ray is `shade`'s (such lanes are marked here:
    /// the lab's box never makes one).
    #[test]
    fn shadow_rows_are_each_lanes_ray_in_order() {
        use crate::bvh::Bvh;
        let scene = Scene::built_in("cornell").expect("the lab scene");
        let bvh = Bvh::new(&scene.vertices());
        let lab = Lab::new(&scene, &bvh, Stage::Ambient);
        let mut arrays = TileArrays::take();
        let TileArrays { hits, shading, gathered, shadow_rays } = &mut *arrays;
        let mut compared = 0;
        for tile in 0..4 {
            let rays: Vec<Ray> = (0..TILE - tile)
                .map(|i| {
                    let (x, y) = ((i % 8) as f32 * 0.1 - 0.35, (i / 8) as f32 * 0.1 - 0.35);
                    Ray::new(Vec3::new(0.0, 0.0, -3.0), Vec3::new(x + tile as f32 * 0.2, y, 1.0))
                })
                .collect();
            lab.accel.closest_hits_rows(&rays, hits);
            shading.shade(gathered, &lab, &rays, hits);
            // Every third lane with a shadow ray marked unusual, its origin made nonsense.
            let mut k = 0;
            for i in (0..rays.len()).filter(|&i| shading.shadow[i]) {
                shading.unusual[i] = k % 3 == tile % 3;
                if shading.unusual[i] {
                    shading.shadow_origin[0][i] = f32::NAN;
                }
                k += 1;
            }
            let n = shading.shadow_rows(&lab, &rays, hits, shadow_rays);
            assert_eq!((n, shadow_rays.len), (k, k));
            let lanes = (0..rays.len()).filter(|&i| shading.shadow[i]);
            for (j, i) in lanes.enumerate() {
                let want = shading.shadow_ray(i, &lab, &rays[i], hits.hit(i));
                let got = shadow_rays.ray(j);
                let bits = |r: &Ray| {
                    let v = |v: Vec3| v.to_array().map(f32::to_bits);
                    (v(r.origin), v(r.direction), r.t_min.to_bits(), r.t_max.to_bits())
                };
                assert_eq!(bits(&got), bits(&want), "lane {i}, row {j}");
                assert!(got.origin.is_finite(), "lane {i}: shade's own ray");
                compared += 1;
            }
        }
        TileArrays::give_back(arrays);
        assert!(compared > 150, "only {compared} shadow rays");
    }

    /// A scene without triangles: every lane misses, and there are no lines to read.
    #[test]
    fn tile_shading_of_an_empty_scene_is_black() {
        use crate::geometry::Geometry;
        let mut scene = Scene::built_in("cornell").expect("the lab scene");
        scene.geometry = Geometry::new();
        assert!(scene.geometry.triangle_lines().is_some(), "an empty geometry has (no) lines");
        let accel = crate::BruteForce::new(&[]);
        let rays: Vec<Ray> =
            (0..TILE).map(|i| Ray::new(Vec3::ZERO, Vec3::new(1.0, i as f32, 0.5))).collect();
        for stage in Stage::ALL {
            assert_eq!(tile_matches_shade(&Lab::new(&scene, &accel, stage), &rays), 0);
        }
    }

    /// Checks a tile of `rays` lane by lane: `TileShading::shade` (AVX2 where the CPU has it) and
    /// its portable form against `shade`, bit for bit; returns how many shadow rays it compared.
    fn tile_matches_shade<A: Accelerator + ?Sized>(lab: &Lab<'_, A>, rays: &[Ray]) -> usize {
        let mut shadows = 0;
        let stage = lab.stage;
        let hit_list: Vec<Option<Hit>> = rays.iter().map(|r| lab.accel.closest_hit(r)).collect();
        // In rows, as the accelerator answers them; lanes past the rays hold another tile's
        // hits, which must not leak into this one.
        let mut hits = HitRows::default();
        for i in 0..TILE {
            hits.set(i, Some(Hit { t: 1.0, triangle: 0, b1: f32::NAN, b2: 0.5 }));
        }
        lab.accel.closest_hits_rows(rays, &mut hits);
        for (i, hit) in hit_list.iter().enumerate() {
            let bits =
                |h: Option<Hit>| h.map(|h| (h.triangle, [h.t, h.b1, h.b2].map(f32::to_bits)));
            assert_eq!(bits(hits.hit(i)), bits(*hit), "the rows hold the one-ray answers");
        }
        // Arrays left from another tile (lanes of other values) must not leak into this one.
        let mut arrays = TileArrays::take();
        let TileArrays { shading: tile, gathered, .. } = &mut *arrays;
        // The AVX2 form wherever the CPU has it, whatever `RAYLAB_ISA` asks of `shade`.
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::Isa::Avx2.is_supported() {
            // SAFETY: AVX2 is supported (checked just above).
            unsafe { tile.shade_avx2(gathered, lab, rays, &hits) };
        } else {
            tile.shade(gathered, lab, rays, &hits);
        }
        #[cfg(not(target_arch = "x86_64"))]
        tile.shade(gathered, lab, rays, &hits);
        // The form for any instruction set too, in arrays of NaN.
        let mut fresh = TileArrays::take();
        fresh.shading.albedo = [[f32::NAN; TILE]; 3];
        fresh.shading.direct = [[f32::NAN; TILE]; 3];
        fresh.shading.shadow = [true; TILE];
        fresh.gathered.corner = [[[f32::NAN; TILE]; 3]; 3];
        fresh.gathered.hit_mask = [true; TILE];
        let TileArrays { shading: portable, gathered, .. } = &mut *fresh;
        portable.shade_portable(gathered, lab, rays, &hits);
        for (i, (ray, hit)) in rays.iter().zip(&hit_list).enumerate() {
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            let (lane, other) = (tile.lane(i), portable.lane(i));
            assert_eq!(bits(lane.albedo), bits(other.albedo));
            assert_eq!(bits(lane.direct), bits(other.direct));
            assert_eq!(tile.shadow[i], portable.shadow[i]);
            // The shadow ray's origin and flag mean something only where there is one.
            if tile.shadow[i] {
                assert_eq!(tile.unusual[i], portable.unusual[i]);
                let origin = |t: &TileShading| [0, 1, 2].map(|a| t.shadow_origin[a][i].to_bits());
                assert_eq!(origin(tile), origin(portable));
            }
            let expected = lab.shade(ray, *hit);
            assert_eq!(bits(lane.albedo), bits(expected.albedo), "{ray:?} {stage}");
            assert_eq!(bits(lane.direct), bits(expected.direct), "{ray:?} {stage}");
            assert_eq!(tile.shadow[i], expected.shadow_ray.is_some(), "{ray:?} {stage}");
            if let Some(shadow) = expected.shadow_ray {
                shadows += 1;
                let got = tile.shadow_ray(i, lab, ray, *hit);
                assert_eq!(bits(got.origin), bits(shadow.origin), "{ray:?}");
                assert_eq!(bits(got.direction), bits(shadow.direction), "{ray:?}");
                assert_eq!((got.t_min, got.t_max), (shadow.t_min, shadow.t_max));
            }
        }
        // Kept for the next tile, whose rays are others (as `radiance_each` keeps them).
        TileArrays::give_back(arrays);
        shadows
    }
}
