//! `lab`: the lab's light model (KTH DH2323 Lab 2, §"Illumination").
//!
//! A point light gives a surface the power per area `D = P·max(r̂·n̂, 0) / (4πr²)` (eq. 27),
//! zero when a shadow ray toward the light is blocked; a constant `N` stands in for indirect
//! light; the colour is `R = ρ ∗ (D + N)` (eq. 30). Shown as the lab shows it: each channel
//! clamped to `[0, 1]`, no gamma (see [`Film::to_rgb8_clamped`](crate::Film::to_rgb8_clamped)).
//!
//! [`Stage`] replays the lab step by step for learners, from flat colours to the full model.
//! Surfaces are two-sided: the normal is turned toward the viewer, so a wall seen from behind is
//! lit only by a light on that side. Shadow rays leave the surface with a rounding-error-aware offset (see [`crate::ray`]) rather
//! than a magic epsilon, so there is no shadow acne at any scene scale.

use std::f32::consts::PI;
use std::fmt;
use std::str::FromStr;

use glam::Vec3;

use super::Integrator;
use crate::accel::{Accelerator, Hit};
use crate::camera::Camera;
use crate::float::gamma;
use crate::light::PointLight;
use crate::ray::{Ray, step_away};
use crate::sampling::{Sampler, SamplerKind};
use crate::scene::Scene;

/// One step of the lab, each adding one idea to the previous.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "io", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "io", serde(rename_all = "lowercase"))]
pub enum Stage {
    /// The colour ρ of the closest triangle, black where nothing is hit.
    Flat,
    /// The light's power per area `D` alone (eq. 27), no colour and no shadows.
    Direct,
    /// Reflected light `ρ ∗ D`, no shadows.
    Reflected,
    /// `ρ ∗ D` with shadow rays.
    Shadows,
    /// The full model `ρ ∗ (D + N)` with shadows (eq. 30).
    #[default]
    Ambient,
}

impl Stage {
    /// Every stage, in the lab's order.
    pub const ALL: [Stage; 5] =
        [Stage::Flat, Stage::Direct, Stage::Reflected, Stage::Shadows, Stage::Ambient];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Flat => "flat",
            Stage::Direct => "direct",
            Stage::Reflected => "reflected",
            Stage::Shadows => "shadows",
            Stage::Ambient => "ambient",
        }
    }

    /// What the stage shows, in a few words.
    pub fn description(self) -> &'static str {
        match self {
            Stage::Flat => "flat triangle colour ρ",
            Stage::Direct => "direct light D only (eq. 27)",
            Stage::Reflected => "reflected light ρ∗D",
            Stage::Shadows => "ρ∗D with shadows",
            Stage::Ambient => "ρ∗(D+N) with shadows and ambient (eq. 30)",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The stage name was not one of [`Stage::ALL`].
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("unknown stage '{0}': expected one of flat, direct, reflected, shadows, ambient (or 1–5)")]
pub struct UnknownStage(pub String);

impl FromStr for Stage {
    type Err = UnknownStage;

    /// A stage by name or by its number in the lab's order, 1 to 5.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Stage::ALL
            .into_iter()
            .enumerate()
            .find(|(i, stage)| s == stage.name() || s == (i + 1).to_string())
            .map(|(_, stage)| stage)
            .ok_or_else(|| UnknownStage(s.to_string()))
    }
}

/// The lab's integrator over a scene and an accelerator built from its
/// [`vertices`](Scene::vertices).
#[derive(Debug)]
pub struct Lab<'a, A: ?Sized> {
    scene: &'a Scene,
    accel: &'a A,
    stage: Stage,
    /// The point light: the scene's, unless moved (as `raylab view` moves it).
    pub light: PointLight,
    /// The constant indirect light `N` of eq. (30).
    pub ambient: Vec3,
    /// The angle one pixel subtends, in radians ([`Camera::pixel_spread`]): textures are
    /// filtered over the ray cone it gives (see [`crate::texture`]), so that one sample per
    /// pixel does not alias. 0 reads them at a point.
    pub pixel_spread: f32,
}

// By hand: the derive would ask `A: Copy`, but a `Lab` only holds a reference to it.
impl<A: ?Sized> Clone for Lab<'_, A> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<A: ?Sized> Copy for Lab<'_, A> {}

impl<'a, A: Accelerator + ?Sized> Lab<'a, A> {
    /// The lab's model at `stage`, with the scene's [`lab_light`](Scene::lab_light) and the lab's
    /// ambient light `N = 0.5`.
    pub fn new(scene: &'a Scene, accel: &'a A, stage: Stage) -> Self {
        Lab {
            scene,
            accel,
            stage,
            light: scene.lab_light(),
            ambient: Vec3::splat(0.5),
            pixel_spread: 0.0,
        }
    }

    /// Reads textures over the ray cone of a camera's pixels ([`pixel_spread`](Self::pixel_spread)).
    pub fn for_camera(mut self, camera: &Camera) -> Self {
        self.pixel_spread = camera.pixel_spread();
        self
    }

    /// The colour of material `id` where `ray` meets `hit`.
    #[inline]
    fn albedo(&self, ray: &Ray, hit: &Hit, id: u32) -> Vec3 {
        let material = &self.scene.materials[id as usize];
        if material.textures.is_empty() {
            material.bsdf.albedo()
        } else {
            material.albedo_at(&self.scene.geometry.texture_query(ray, hit, self.pixel_spread))
        }
    }
}

/// What a camera ray sees before the shadow test: the colour, the light's `D` and the shadow
/// ray that decides whether `D` counts.
struct Shading {
    albedo: Vec3,
    direct: Vec3,
    shadow_ray: Option<Ray>,
}

impl Shading {
    /// Nothing seen.
    const NONE: Shading = Shading { albedo: Vec3::ZERO, direct: Vec3::ZERO, shadow_ray: None };
}

/// Rays shaded together: one tile of [`Integrator::radiance_each`].
const TILE: usize = 64;

/// [`Lab::shade`] for a tile's hits, lane by lane in arrays: the triangles' data gathered
/// first, then every lane computed by the same operations as `shade` (and
/// [`SurfacePoint::spawn_ray_to`](crate::ray::SurfacePoint::spawn_ray_to)), in the same order and without branches, which the compiler
/// vectorizes. The values are `shade`'s bit for bit (the test below compares them).
struct TileShading {
    albedo: [[f32; TILE]; 3],
    direct: [[f32; TILE]; 3],
    /// Whether the lane's shadow ray decides its `direct`.
    shadow: [bool; TILE],
    /// The shadow rays' origins, moved off their surfaces, where `shadow` is set.
    shadow_origin: [[f32; TILE]; 3],
    /// Lanes whose moved origin is not finite: their shadow ray is `shade`'s own.
    unusual: [bool; TILE],
}

/// The hits of a tile gathered for [`TileShading`]: corners, normals, ray directions and
/// barycentrics, row by row (zeros where a lane misses).
struct Gathered {
    corner: [[[f32; TILE]; 3]; 3],
    normal: [[f32; TILE]; 3],
    direction: [[f32; TILE]; 3],
    b1: [f32; TILE],
    b2: [f32; TILE],
    hit_mask: [bool; TILE],
}

/// A thread's arrays for the lab's tiles, kept from tile to tile and call to call (as the
/// packets keep theirs): made afresh for each tile of 64 rays, their 10 KB were zeroed and
/// moved every time.
struct TileArrays {
    hits: [Option<Hit>; TILE],
    shading: TileShading,
    gathered: Gathered,
    shadow_rays: [Ray; TILE],
    occluded: [bool; TILE],
}

thread_local! {
    /// Each thread's spare [`TileArrays`].
    static SPARE_TILE: std::cell::Cell<Option<Box<TileArrays>>> =
        const { std::cell::Cell::new(None) };
}

impl TileArrays {
    /// This thread's arrays, or new ones.
    fn take() -> Box<TileArrays> {
        SPARE_TILE.take().unwrap_or_else(|| {
            Box::new(TileArrays {
                hits: [None; TILE],
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
                shadow_rays: [Ray::new(Vec3::ZERO, Vec3::Z); TILE],
                occluded: [false; TILE],
            })
        })
    }

    /// Keeps `arrays` for this thread's next call.
    fn give_back(arrays: Box<TileArrays>) {
        SPARE_TILE.set(Some(arrays));
    }
}

impl TileShading {
    /// Shades the tile of `rays` and their `hits` (at most [`TILE`]) into `self`, through
    /// `gathered`, compiled for AVX2 where the CPU has it (the arithmetic is the same
    /// operations either way: Rust never fuses a multiply and an add, so the lanes are the
    /// same bits; the test below checks both forms). Lanes from `rays.len()` on hold values of
    /// no meaning.
    fn shade<A: Accelerator + ?Sized>(
        &mut self,
        gathered: &mut Gathered,
        lab: &Lab<'_, A>,
        rays: &[Ray],
        hits: &[Option<Hit>],
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::Isa::detect().at_least(crate::cpu::Isa::Avx2) {
            // SAFETY: AVX2 was detected just above (`detect` names only sets this CPU has).
            return unsafe { self.shade_avx2(gathered, lab, rays, hits) };
        }
        self.shade_portable(gathered, lab, rays, hits)
    }

    /// [`shade`](Self::shade) with AVX2 enabled.
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
        hits: &[Option<Hit>],
    ) {
        self.shade_portable(gathered, lab, rays, hits)
    }

    /// [`shade`](Self::shade) for any instruction set.
    #[inline(always)]
    fn shade_portable<A: Accelerator + ?Sized>(
        &mut self,
        gathered: &mut Gathered,
        lab: &Lab<'_, A>,
        rays: &[Ray],
        hits: &[Option<Hit>],
    ) {
        assert!(rays.len() <= TILE && hits.len() == rays.len(), "a tile of rays and hits");
        let geometry = &lab.scene.geometry;
        let tile = self;
        // Gathered: the corners, normal and barycentrics of each hit, zeros for misses (every
        // lane of the tile written, so nothing needs clearing first).
        let Gathered { corner, normal, direction, b1, b2, hit_mask } = &mut *gathered;
        // Neighbouring hits mostly share a material: its albedo is looked up once for them
        // (unless it has a texture).
        let mut material = (u32::MAX, Vec3::ZERO, false);
        let instanced = geometry.is_instanced();
        for (i, (hit, ray)) in hits.iter().zip(rays).enumerate() {
            let Some(hit) = hit else {
                for axis in 0..3 {
                    tile.albedo[axis][i] = 0.0;
                    for corner in corner.iter_mut() {
                        corner[axis][i] = 0.0;
                    }
                    normal[axis][i] = 0.0;
                    direction[axis][i] = 0.0;
                }
                (b1[i], b2[i]) = (0.0, 0.0);
                hit_mask[i] = false;
                continue;
            };
            let triangle = hit.triangle as usize;
            // (A `match`, not `unwrap_or_else`: a closure is not inlined into the AVX2 copy.)
            let (vertices, n, id) = match geometry.flat_triangle(triangle) {
                Some(flat) => flat,
                None => {
                    let id = geometry.material_id(triangle);
                    (geometry.triangle(triangle), geometry.normal(triangle), id)
                }
            };
            if id != material.0 {
                let m = &lab.scene.materials[id as usize];
                material = (id, m.bsdf.albedo(), !m.textures.is_empty());
            }
            let albedo = if material.2 { lab.albedo(ray, hit, id) } else { material.1 };
            for axis in 0..3 {
                tile.albedo[axis][i] = albedo[axis];
                for (j, v) in vertices.iter().enumerate() {
                    corner[j][axis][i] = v[axis];
                }
                normal[axis][i] = n[axis];
                direction[axis][i] = ray.direction[axis];
            }
            (b1[i], b2[i]) = (hit.b1, hit.b2);
            hit_mask[i] = true;
        }
        if lab.stage == Stage::Flat {
            // No light: no direct term, no shadow rays.
            tile.direct = [[0.0; TILE]; 3];
            tile.shadow = [false; TILE];
            return;
        }
        if instanced {
            tile.light_lanes::<true, A>(lab, hits, gathered);
        } else {
            tile.light_lanes::<false, A>(lab, hits, gathered);
        }
    }

    /// The light's part of [`new`](Self::new) for the hits gathered in `g`: the loop has no
    /// call where the geometry is not instanced, so that the compiler vectorizes it.
    #[inline(always)]
    fn light_lanes<const INSTANCED: bool, A: Accelerator + ?Sized>(
        &mut self,
        lab: &Lab<'_, A>,
        hits: &[Option<Hit>],
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
            if INSTANCED && let Some(Some(hit)) = hits.get(i) {
                // An instance's point is found in its own space, with the bound of the way
                // there and back.
                let point = lab.scene.geometry.surface_point(hit);
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

    /// Lane `i` as `shade` returns it (its shadow ray as a flag).
    #[inline]
    fn lane(&self, i: usize) -> Shading {
        let get = |rows: &[[f32; TILE]; 3]| Vec3::new(rows[0][i], rows[1][i], rows[2][i]);
        Shading { albedo: get(&self.albedo), direct: get(&self.direct), shadow_ray: None }
    }

    /// Lane `i`'s shadow ray, as `shade` makes it for `ray` and `hit` (that lane's).
    #[inline]
    fn shadow_ray<A: Accelerator + ?Sized>(
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

impl<A: Accelerator + ?Sized> Lab<'_, A> {
    /// Shades a hit up to the shadow test (inlined into the tile loop: it returns a large
    /// value, which a call would copy through memory).
    #[inline(always)]
    fn shade(&self, ray: &Ray, hit: Option<Hit>) -> Shading {
        let Some(hit) = hit else {
            return Shading::NONE;
        };
        // The lab needs the point, its normal and the colour: not the whole interaction.
        let geometry = &self.scene.geometry;
        let albedo = self.albedo(ray, &hit, geometry.material_id(hit.triangle as usize));
        if self.stage == Stage::Flat {
            return Shading { albedo, direct: Vec3::ZERO, shadow_ray: None };
        }
        let mut point = geometry.surface_point(&hit);
        // Triangles are hit from both sides: light the side the ray sees. (With a one-sided
        // normal, a wall seen from behind would be lit through itself by a light on its front.)
        // A grazing ray (a zero product) gets the lab's own normal `(v2 − v0) × (v1 − v0)`, the
        // opposite of the geometric one.
        if point.normal.dot(ray.direction) >= 0.0 {
            point.normal = -point.normal;
        }
        let light = &self.light;
        // Lab eq. (27): D = P max(r̂·n̂, 0) / (4πr²).
        let direct = light.direct(point.p, point.normal);
        let shadows = matches!(self.stage, Stage::Shadows | Stage::Ambient);
        let shadow_ray =
            (shadows && direct != Vec3::ZERO).then(|| point.spawn_ray_to(light.position));
        Shading { albedo, direct, shadow_ray }
    }

    /// The colour of a shaded hit, given whether its shadow ray is blocked.
    #[inline]
    fn finish(&self, hit: bool, shading: &Shading, occluded: bool) -> Vec3 {
        if !hit {
            return Vec3::ZERO;
        }
        let direct = if occluded { Vec3::ZERO } else { shading.direct };
        match self.stage {
            Stage::Flat => shading.albedo,
            Stage::Direct => direct,
            Stage::Reflected | Stage::Shadows => shading.albedo * direct,
            // Lab eq. (30): R = ρ ∗ (D + N).
            Stage::Ambient => shading.albedo * (direct + self.ambient),
        }
    }
}

impl<A: Accelerator + ?Sized> Integrator for Lab<'_, A> {
    fn radiance(&self, ray: &Ray, _sampler: &mut Sampler) -> Vec3 {
        let hit = super::closest_opaque_hit(self.scene, self.accel, ray);
        let shading = self.shade(ray, hit);
        let occluded = shading
            .shadow_ray
            .is_some_and(|shadow| super::occluded_opaque(self.scene, self.accel, &shadow));
        self.finish(hit.is_some(), &shading, occluded)
    }

    /// Camera rays together, then their shadow rays together (toward one light, so they are
    /// coherent too), the shading in between lane by lane over the tile (`TileShading`).
    fn radiance_each(&self, rays: &[Ray], samplers: &mut [Sampler], out: &mut [Vec3]) {
        assert_eq!(rays.len(), out.len(), "one colour per ray");
        assert_eq!(rays.len(), samplers.len(), "one sampler per ray");
        // Cut-out holes are passed ray by ray.
        if self.scene.has_cut_outs() {
            for ((ray, sampler), colour) in rays.iter().zip(samplers).zip(out) {
                *colour = self.radiance(ray, sampler);
            }
            return;
        }
        // A tile at a time, in this thread's arrays: no allocation or clearing per tile.
        let mut arrays = TileArrays::take();
        let TileArrays { hits, shading, gathered, shadow_rays, occluded } = &mut *arrays;
        for (rays, out) in rays.chunks(TILE).zip(out.chunks_mut(TILE)) {
            let n = rays.len();
            let hits = &mut hits[..n];
            self.accel.closest_hits(rays, hits);
            shading.shade(gathered, self, rays, hits);
            let mut shadows = 0;
            for i in (0..n).filter(|&i| shading.shadow[i]) {
                shadow_rays[shadows] = shading.shadow_ray(i, self, &rays[i], hits[i]);
                shadows += 1;
            }
            self.accel.occluded_each(&shadow_rays[..shadows], &mut occluded[..shadows]);
            let mut blocked = occluded[..shadows].iter();
            for (i, (colour, hit)) in out.iter_mut().zip(hits.iter()).enumerate() {
                let occluded =
                    shading.shadow[i] && *blocked.next().expect("one answer per shadow ray");
                *colour = self.finish(hit.is_some(), &shading.lane(i), occluded);
            }
        }
        TileArrays::give_back(arrays);
    }

    /// The lab's pixel sampling: one sample is the ray through the pixel's centre.
    fn sampler_kind(&self) -> SamplerKind {
        SamplerKind::Lab
    }

    /// The lab's model draws no numbers: its pixel positions are its only samples.
    fn draws_numbers(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tile's lanes are `shade`'s values bit for bit, shadow rays included, for rays from
    /// inside and outside the lab's box in every direction, at every stage, with the light
    /// inside the box and on a wall; and the same compiled for AVX2 and for any instruction set.
    #[test]
    fn tile_shading_is_shade_lane_by_lane() {
        use crate::bvh::Bvh;
        let scene = Scene::built_in("cornell").expect("the lab scene");
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

    /// The same on instanced geometry (the glTF boxes kept instanced: one box drawn 18 times),
    /// whose tiles take the other copy of the light loop (the instance's own surface point).
    #[test]
    fn tile_shading_is_shade_lane_by_lane_on_instances() {
        use crate::bvh::SceneBvh;
        use crate::scene::{Instancing, LoadOptions};
        let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mitsuba-gltf/boxes.gltf");
        let options = LoadOptions { instancing: Instancing::Keep };
        let scene = Scene::open(file, &options).expect("the glTF boxes").scene;
        assert!(scene.geometry.is_instanced());
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

    /// Checks a tile of `rays` lane by lane: `TileShading::new` (AVX2 where the CPU has it) and
    /// its portable form against `shade`, bit for bit; returns how many shadow rays it compared.
    fn tile_matches_shade<A: Accelerator + ?Sized>(lab: &Lab<'_, A>, rays: &[Ray]) -> usize {
        let mut shadows = 0;
        let stage = lab.stage;
        let hits: Vec<Option<Hit>> = rays.iter().map(|r| lab.accel.closest_hit(r)).collect();
        // Arrays left from another tile (lanes of other values) must not leak into this one.
        let mut arrays = TileArrays::take();
        let TileArrays { shading: tile, gathered, .. } = &mut *arrays;
        tile.shade(gathered, lab, rays, &hits);
        // The form for any instruction set too, where `shade` picked AVX2, in arrays of NaN.
        let mut fresh = TileArrays::take();
        fresh.shading.albedo = [[f32::NAN; TILE]; 3];
        fresh.shading.direct = [[f32::NAN; TILE]; 3];
        fresh.shading.shadow = [true; TILE];
        fresh.gathered.corner = [[[f32::NAN; TILE]; 3]; 3];
        fresh.gathered.hit_mask = [true; TILE];
        let TileArrays { shading: portable, gathered, .. } = &mut *fresh;
        portable.shade_portable(gathered, lab, rays, &hits);
        for (i, (ray, hit)) in rays.iter().zip(&hits).enumerate() {
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

    #[test]
    fn stages_parse_by_name_and_number() {
        for (i, stage) in Stage::ALL.into_iter().enumerate() {
            assert_eq!(stage.name().parse::<Stage>(), Ok(stage));
            assert_eq!((i + 1).to_string().parse::<Stage>(), Ok(stage));
        }
        assert!("6".parse::<Stage>().is_err());
        assert!("Flat".parse::<Stage>().is_err());
        assert_eq!(Stage::default(), Stage::Ambient);
    }
}
