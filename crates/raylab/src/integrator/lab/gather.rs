//! Gathering a tile's hits for the lab's tile shading (`tile.rs`): each hit's
//! triangle (corners, normal, material) and barycentrics into rows, and its albedo. The light
//! is computed on them in `tile.rs`.

use glam::Vec3;

use super::model::{Lab, TILE};
use crate::accel::{Accelerator, Hit, HitRows};
use crate::geometry::TriangleLine;
use crate::ray::Ray;

/// The hits of a tile gathered for the tile shading: corners, normals, ray directions and
/// barycentrics, row by row (zeros where a lane misses).
pub(super) struct Gathered {
    pub(super) corner: [[[f32; TILE]; 3]; 3],
    pub(super) normal: [[f32; TILE]; 3],
    pub(super) direction: [[f32; TILE]; 3],
    pub(super) b1: [f32; TILE],
    pub(super) b2: [f32; TILE],
    pub(super) hit_mask: [bool; TILE],
}

impl Gathered {
    /// Gathers the tile's hits into `self` (and their albedo into `albedo`) one lane at a
    /// time: the twin of [`gather_avx2`](Self::gather_avx2), and the form for instanced
    /// geometry.
    #[inline(always)]
    pub(super) fn gather_portable<A: Accelerator + ?Sized>(
        &mut self,
        albedo: &mut [[f32; TILE]; 3],
        lab: &Lab<'_, A>,
        rays: &[Ray],
        hits: &HitRows,
    ) {
        assert!(rays.len() <= TILE, "a tile of rays");
        let geometry = &lab.scene.geometry;
        // Gathered: the corners, normal and barycentrics of each hit, zeros for misses (every
        // lane of the tile written, so nothing needs clearing first).
        let Gathered { corner, normal, direction, b1, b2, hit_mask } = self;
        let mut materials = Albedos::new();
        for (i, ray) in rays.iter().enumerate() {
            let Some(hit) = &hits.hit(i) else {
                for axis in 0..3 {
                    albedo[axis][i] = 0.0;
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
            let value = materials.albedo(lab, ray, hit, id);
            for axis in 0..3 {
                albedo[axis][i] = value[axis];
                for (j, v) in vertices.iter().enumerate() {
                    corner[j][axis][i] = v[axis];
                }
                normal[axis][i] = n[axis];
                direction[axis][i] = ray.direction[axis];
            }
            (b1[i], b2[i]) = (hit.b1, hit.b2);
            hit_mask[i] = true;
        }
    }

    /// [`gather_portable`](Self::gather_portable) for a flat geometry's triangle `lines`,
    /// eight lanes at a time: each hit's line is two 32-byte loads (a miss, and each
    /// lane beyond the rays, loads triangle 0's and is zeroed after), and the eight lanes'
    /// lines are turned into rows by two 8×8 transpositions. The same values (moved, not
    /// computed). Where the arrays would take three dependent reads per hit (the triangle,
    /// its corners' indices, their positions), or sixteen gathers per eight, a line is one.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn gather_avx2<A: Accelerator + ?Sized>(
        &mut self,
        albedo: &mut [[f32; TILE]; 3],
        lab: &Lab<'_, A>,
        lines: &[TriangleLine],
        rays: &[Ray],
        hits: &HitRows,
    ) {
        use crate::bvh::simd::transpose8_at;
        use std::arch::x86_64::*;
        assert!(rays.len() <= TILE, "a tile of rays");
        let n = rays.len();
        let Gathered { corner, normal, direction, b1, b2, hit_mask } = self;
        // The hits' triangles (0 for a miss and past the rays), each a line: checked here,
        // since the loads below read unchecked.
        let mut index = [0usize; TILE];
        for (i, ray) in rays.iter().enumerate() {
            let t = hits.triangle[i];
            let hit = t != HitRows::MISS;
            let t = if hit { t as usize } else { 0 };
            assert!(!hit || t < lines.len(), "the hit's triangle {t} is in the geometry");
            index[i] = t;
            let (u, v) = if hit { (hits.b1[i], hits.b2[i]) } else { (0.0, 0.0) };
            (b1[i], b2[i], hit_mask[i]) = (u, v, hit);
            let d = if hit { ray.direction } else { Vec3::ZERO };
            for axis in 0..3 {
                direction[axis][i] = d[axis];
            }
        }
        if lines.is_empty() {
            // Every lane missed (the checks above passed): nothing to read.
            *albedo = [[0.0; TILE]; 3];
            *corner = [[[0.0; TILE]; 3]; 3];
            *normal = [[0.0; TILE]; 3];
            return;
        }
        let mut material = [0u32; TILE];
        for base in (0..TILE).step_by(8) {
            // Every load reads inside `lines`: `index` holds triangles below `lines.len()`
            // (asserted above, and 0 elsewhere, with `lines` not empty), and each line is 64
            // bytes, so its two halves are eight floats each. Loads and stores of rows are 8
            // lanes from `base ≤ TILE − 8`.
            // SAFETY: AVX2 is the caller's guarantee; every read and write is in bounds (above).
            unsafe {
                let hit = _mm256_castsi256_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(
                    hit_mask.as_ptr().add(base).cast(),
                )));
                // A hit's lane is all ones: `bool` is the byte 1, so compare, not shift.
                let hit = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
                    _mm256_castps_si256(hit),
                    _mm256_set1_epi32(1),
                ));
                // Each lane's line, its two halves (pointer arithmetic only in the closure).
                let line: [*const f32; 8] =
                    std::array::from_fn(|i| lines.as_ptr().wrapping_add(index[base + i]).cast());
                let low = transpose8_at(line);
                let high = transpose8_at(line.map(|p| p.wrapping_add(8)));
                // Words 0–8 are the corners, 9–11 the normal, 12 the material.
                for (c, corner) in corner.iter_mut().enumerate() {
                    for (axis, row) in corner.iter_mut().enumerate() {
                        let k = 3 * c + axis;
                        let word = if k < 8 { low[k] } else { high[k - 8] };
                        _mm256_storeu_ps(row.as_mut_ptr().add(base), _mm256_and_ps(word, hit));
                    }
                }
                for axis in 0..3 {
                    let row = _mm256_and_ps(high[1 + axis], hit);
                    _mm256_storeu_ps(normal[axis].as_mut_ptr().add(base), row);
                }
                _mm256_storeu_ps(material.as_mut_ptr().add(base).cast(), high[4]);
            }
        }
        // The albedo, by material, one lane at a time (a texture's is looked up per hit).
        let mut materials = Albedos::new();
        for i in 0..n {
            let value = match &hits.hit(i) {
                None => Vec3::ZERO,
                Some(hit) => materials.albedo(lab, &rays[i], hit, material[i]),
            };
            for axis in 0..3 {
                albedo[axis][i] = value[axis];
            }
        }
    }
}

/// The albedo of hits one after another: neighbouring hits mostly share a material, whose
/// albedo is looked up once for them (unless it has a texture, which is read per hit).
struct Albedos {
    /// The last material's id, albedo and whether it has textures.
    last: (u32, Vec3, bool),
}

impl Albedos {
    fn new() -> Self {
        Albedos { last: (u32::MAX, Vec3::ZERO, false) }
    }

    /// The albedo of material `id` where `ray` meets `hit` ([`Lab::albedo`]).
    #[inline(always)]
    fn albedo<A: Accelerator + ?Sized>(
        &mut self,
        lab: &Lab<'_, A>,
        ray: &Ray,
        hit: &Hit,
        id: u32,
    ) -> Vec3 {
        if id != self.last.0 {
            let m = &lab.scene.materials[id as usize];
            self.last = (id, m.bsdf.albedo(), !m.textures.is_empty());
        }
        if self.last.2 { lab.albedo(ray, hit, id) } else { self.last.1 }
    }
}
