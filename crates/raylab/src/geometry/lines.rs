//! A flat geometry's triangles one cache line each ([`TriangleLine`]): the corners, the
//! geometric normal and the material of a triangle in 64 aligned bytes, for kernels that read
//! the triangles of many hits at once (the lab's tile shading). Two aligned 32-byte loads
//! fetch a hit's whole triangle, where the stored arrays take three dependent reads
//! (triangle, corner indices, positions) from as many places.
//!
//! The lines are derived from the stored arrays, made on first use and dropped whenever the
//! geometry changes ([`LazyLines`]); they take 64 bytes per triangle, so only geometry of at
//! most [`MOST_LINES`] triangles has them.

use std::sync::OnceLock;

use glam::Vec3;

/// The most triangles given lines: 64 MiB of them. Larger geometry is read from its arrays.
pub(crate) const MOST_LINES: usize = 1 << 20;

/// One triangle's corners `v0, v1, v2`, geometric normal and material id, as sixteen 32-bit
/// words: `[v0.x, v0.y, v0.z, v1.x, v1.y, v1.z, v2.x, v2.y | v2.z, n.x, n.y, n.z, material,
/// 0, 0, 0]`, the coordinates as their `f32` bits. The values are the stored arrays' own
/// (moved, not computed).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct TriangleLine {
    pub words: [u32; 16],
}

impl TriangleLine {
    /// The line of a triangle with `corners`, `normal` and `material`.
    pub fn new(corners: [Vec3; 3], normal: Vec3, material: u32) -> Self {
        let [a, b, c] = corners.map(|v| v.to_array().map(f32::to_bits));
        let n = normal.to_array().map(f32::to_bits);
        TriangleLine {
            words: [
                a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], n[0], n[1], n[2], material,
                0, 0, 0,
            ],
        }
    }

    /// The corners, normal and material back.
    #[cfg(test)]
    pub fn triangle(&self) -> ([Vec3; 3], Vec3, u32) {
        let w = self.words.map(f32::from_bits);
        let v = |i: usize| Vec3::new(w[i], w[i + 1], w[i + 2]);
        ([v(0), v(3), v(6)], v(9), self.words[12])
    }
}

/// Lines made on first use ([`get_or_make`](Self::get_or_make)) and forgotten by
/// [`forget`](Self::forget) whenever what they derive from changes. Derived data: two
/// geometries compare equal whatever their lines hold, and a copy of a geometry starts
/// without them (they are made again if asked for).
#[derive(Default)]
pub(crate) struct LazyLines(OnceLock<Box<[TriangleLine]>>);

impl Clone for LazyLines {
    fn clone(&self) -> Self {
        LazyLines::default()
    }
}

impl std::fmt::Debug for LazyLines {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0.get() {
            Some(lines) => write!(f, "{} lines", lines.len()),
            None => f.write_str("no lines"),
        }
    }
}

impl LazyLines {
    /// The lines, made by `make` if there are none yet.
    pub fn get_or_make(&self, make: impl FnOnce() -> Box<[TriangleLine]>) -> &[TriangleLine] {
        self.0.get_or_init(make)
    }

    /// Bytes of the lines made (0 before they are).
    pub fn bytes(&self) -> usize {
        self.0.get().map_or(0, |lines| std::mem::size_of_val(&**lines))
    }

    /// Forgets the lines (the geometry changed).
    pub fn forget(&mut self) {
        self.0 = OnceLock::new();
    }
}

impl PartialEq for LazyLines {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_holds_its_triangle_bit_for_bit() {
        let corners =
            [Vec3::new(-0.0, 1.5, f32::MIN_POSITIVE), Vec3::X, Vec3::new(3.0, -2.0, 1e-30)];
        // A material id whose bits are a signalling NaN as a float.
        let line = TriangleLine::new(corners, Vec3::new(0.0, -1.0, 0.0), 0x7F80_0001);
        let (back, normal, material) = line.triangle();
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for (a, b) in back.iter().zip(corners) {
            assert_eq!(bits(*a), bits(b));
        }
        assert_eq!(bits(normal), bits(Vec3::new(0.0, -1.0, 0.0)));
        assert_eq!(material, 0x7F80_0001);
        assert_eq!(std::mem::size_of::<TriangleLine>(), 64);
        assert_eq!(std::mem::align_of::<TriangleLine>(), 64);
    }

    /// A geometry's lines are its triangles, and follow its changes: a mesh added, materials
    /// restyled, positions moved.
    #[test]
    fn a_geometrys_lines_follow_the_geometry() {
        use crate::geometry::Geometry;
        let check = |g: &Geometry| {
            let lines = g.triangle_lines().expect("flat geometry has lines");
            assert_eq!(lines.len(), g.len());
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            for (i, line) in lines.iter().enumerate() {
                let ([a, b, c], n, m) = line.triangle();
                let ([x, y, z], normal, material) = g.flat_triangle(i).expect("flat");
                assert_eq!([a, b, c, n].map(bits), [x, y, z, normal].map(bits));
                assert_eq!(m, material);
            }
        };
        let mut g = Geometry::new();
        let t = |x: f32| ([Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 0.0, 0.0), Vec3::Y], 2);
        g.add_triangles("a", [t(0.0), t(1.0)]);
        check(&g);
        g.add_triangles("b", [t(5.0)]);
        check(&g);
        g.material_ids_mut()[1] = 7;
        check(&g);
        assert_eq!(g.triangle_lines().expect("lines")[1].triangle().2, 7);
        let moved = g.map_positions(|p| p * 2.0);
        check(&moved);
        let mut fresh = g.clone();
        fresh.material_ids_mut()[0] = 1;
        let before = fresh.bytes();
        check(&fresh);
        assert_eq!(fresh.bytes(), before + 64 * fresh.len() as u64, "lines counted once made");
    }

    #[test]
    fn lines_are_forgotten_and_made_again() {
        let mut lazy = LazyLines::default();
        let line = TriangleLine::new([Vec3::ZERO, Vec3::X, Vec3::Y], Vec3::Z, 3);
        assert_eq!(lazy.get_or_make(|| vec![line].into()).len(), 1);
        assert_eq!(lazy.get_or_make(|| unreachable!("kept")).len(), 1);
        lazy.forget();
        assert_eq!(lazy.get_or_make(|| vec![line; 2].into()).len(), 2);
    }
}
