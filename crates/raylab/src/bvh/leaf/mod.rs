//! Leaf records: a leaf's triangles as a small table of the vertices they share and three byte
//! indices per triangle.
//!
//! # Record layout
//! The leaves of a tree live in one arena of 32-bit words ([`Leaves`]). A leaf is one or more
//! consecutive records of at most [`RECORD_VERTICES`] distinct vertices and
//! [`RECORD_TRIANGLES`] triangles; each record is
//!
//! | words | what |
//! |---|---|
//! | 1 | header: vertices `nv` (bits 0–7), triangles `nt` (bits 8–15), bit 16 set when another record of the same leaf follows |
//! | `3·nv` | the vertices' coordinates, axis by axis: `x[0..nv]`, `y[0..nv]`, `z[0..nv]` (`f32`) |
//! | `⌈3·nt / 4⌉` | the corners of each triangle as byte indices into the table, corner by corner: `v0[0..nt]`, `v1[0..nt]`, `v2[0..nt]` (the last word padded) |
//! | `nt` | each triangle's index in the caller's list (the hit's `triangle`) |
//!
//! For example a leaf of two triangles `(p, q, r)` and `(r, q, s)`, ids 7 and 9, is one record
//! of 1 + 12 + 2 + 2 = 17 words: header `0x0000_0204`, the coordinates of `p, q, r, s`, the
//! index bytes `[0, 2 | 1, 1 | 2, 3]` in two words, and `7, 9`. As four-triangle blocks of
//! copied vertices (the layout before records) the two took 160 bytes; here 68.
//!
//! # Why it stays watertight and exact
//! A vertex shared by the triangles of a record is stored once and transformed into the ray's
//! frame once; the watertight test's edge functions then take exactly the values the scalar test
//! ([`WatertightRay::intersect`](crate::triangle::WatertightRay::intersect)) computes from the
//! caller's corners, because they are the same bits (vertices are shared only when their bits are
//! equal) put through the same operations. So two triangles that share an edge still share its
//! edge function, and every kernel agrees with brute force bit for bit.
//!
//! A mesh's triangles share most of their vertices: on the dragon a leaf record of about six
//! triangles holds about as many vertices, and the leaves take about 22 bytes per triangle
//! instead of 43 (9 floats and an id per triangle, in blocks about 93 % full).
//!
//! # Padding
//! The arena ends with [`PAD_WORDS`] zero words, so that a kernel may read 16 index bytes from
//! anywhere inside a record without reading past the arena; lanes past `nt` are garbage that the
//! kernels mask off.

use glam::Vec3;

pub(crate) mod kernel;
#[cfg(target_arch = "x86_64")]
pub(crate) mod lanes;

use crate::triangle::WatertightRay;

/// The most distinct vertices in one record: two AVX registers of each coordinate (or one
/// AVX-512 register).
pub(crate) const RECORD_VERTICES: usize = 16;
/// The most triangles in one record: one AVX register of each corner, so that a record is
/// tested in one pass. (Sixteen triangles in AVX-512 registers were slower on the
/// AVX-512 CPU measured: 512-bit instructions take a vector port from the 8-wide node kernel.)
pub(crate) const RECORD_TRIANGLES: usize = 8;
/// Zero words after the last record.
pub(crate) const PAD_WORDS: usize = 4;

const MORE: u32 = 1 << 16;

/// A ray prepared for the triangle tests of a kernel whose per-ray form is `R`: the scalar test's
/// setup (for the triangles a kernel leaves undecided) and the kernel's.
#[derive(Clone, Copy)]
pub(crate) struct TriangleRay<R> {
    pub ray: WatertightRay,
    pub lanes: R,
}

/// Every leaf's records, one after another, then [`PAD_WORDS`] zero words.
#[derive(Clone, Debug)]
pub(crate) struct Leaves {
    words: Vec<u32>,
}

impl Default for Leaves {
    fn default() -> Self {
        Leaves { words: vec![0; PAD_WORDS] }
    }
}

impl Leaves {
    /// An arena with room for about `triangles` triangles' records.
    pub fn with_capacity(triangles: usize) -> Self {
        // About 5.5 words per triangle on meshes (see the module documentation).
        let mut words = Vec::with_capacity(triangles * 11 / 2 + PAD_WORDS);
        words.resize(PAD_WORDS, 0);
        Leaves { words }
    }

    /// Appends a leaf of `triangles` (caller's index, corners), in order, as few records as
    /// they fit in greedily; returns the word offset of its first record. A leaf has at least
    /// one triangle.
    pub fn push_leaf(&mut self, triangles: &[(u32, [Vec3; 3])]) -> u32 {
        assert!(!triangles.is_empty(), "a leaf has triangles");
        self.words.truncate(self.words.len() - PAD_WORDS);
        let first = self.words.len();
        let mut rest = triangles;
        while !rest.is_empty() {
            let plan = fit_record(rest);
            debug_assert!(plan.triangles > 0, "one triangle has at most 3 vertices");
            let (head, tail) = rest.split_at(plan.triangles);
            self.push_record(&plan, head, !tail.is_empty());
            rest = tail;
        }
        self.words.resize(self.words.len() + PAD_WORDS, 0);
        u32::try_from(first).expect("leaf arena beyond 2^32 words")
    }

    fn push_record(&mut self, plan: &RecordPlan, triangles: &[(u32, [Vec3; 3])], more: bool) {
        let (nv, nt) = (plan.vertices, plan.triangles);
        self.words.push(nv as u32 | (nt as u32) << 8 | if more { MORE } else { 0 });
        for axis in 0..3 {
            self.words.extend(plan.table[..nv].iter().map(|v| v[axis]));
        }
        let mut bytes = [0u8; 3 * RECORD_TRIANGLES];
        for corner in 0..3 {
            for (t, c) in plan.corners[..nt].iter().enumerate() {
                bytes[corner * nt + t] = c[corner];
            }
        }
        self.words.extend(bytes[..3 * nt].chunks(4).map(|chunk| {
            let mut word = [0u8; 4];
            word[..chunk.len()].copy_from_slice(chunk);
            // In memory order, so that the words' memory holds the bytes in order.
            u32::from_ne_bytes(word)
        }));
        self.words.extend(triangles.iter().map(|&(id, _)| id));
    }

    /// The record at word `offset` (a leaf's first record, or one that follows).
    #[inline(always)]
    pub fn record(&self, offset: u32) -> Record<'_> {
        let words = &self.words[offset as usize..];
        Record { words, header: words[0] }
    }

    /// The records of the leaf starting at `offset`.
    #[inline(always)]
    pub fn leaf(&self, offset: u32) -> LeafRecords<'_> {
        LeafRecords { next: Some(self.record(offset)) }
    }

    /// The address of word `offset`, for prefetching.
    #[inline(always)]
    pub fn address(&self, offset: u32) -> *const u32 {
        self.words.as_ptr().wrapping_add(offset as usize)
    }

    /// The arena's words, padding included (to compare trees).
    #[cfg(test)]
    pub fn words(&self) -> &[u32] {
        &self.words
    }

    /// Bytes of the arena (its padding included).
    pub fn bytes(&self) -> usize {
        self.words.len() * 4
    }
}

/// Splits off the longest run of `triangles` from its start that fits in one record: at most
/// [`RECORD_TRIANGLES`] triangles over at most [`RECORD_VERTICES`] distinct vertices (equal
/// when their bits are). Returns the vertex table and each triangle's corners in it.
fn fit_record(triangles: &[(u32, [Vec3; 3])]) -> RecordPlan {
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    let mut plan = RecordPlan {
        table: [[0; 3]; RECORD_VERTICES],
        vertices: 0,
        corners: [[0; 3]; RECORD_TRIANGLES],
        triangles: 0,
    };
    for &(_, triangle) in triangles.iter().take(RECORD_TRIANGLES) {
        // Place the corners in a copy of the table's length, committing only if all fit.
        let mut len = plan.vertices;
        let mut slots = [0u8; 3];
        for (slot, corner) in slots.iter_mut().zip(triangle) {
            let corner = bits(corner);
            let found = plan.table[..len].iter().position(|&w| w == corner);
            *slot = match found {
                Some(k) => k as u8,
                None if len < RECORD_VERTICES => {
                    plan.table[len] = corner;
                    len += 1;
                    (len - 1) as u8
                }
                None => return plan,
            };
        }
        plan.vertices = len;
        plan.corners[plan.triangles] = slots;
        plan.triangles += 1;
    }
    plan
}

/// What [`fit_record`] fits in one record: the vertex table (as bits) and the triangles'
/// corners in it.
struct RecordPlan {
    table: [[u32; 3]; RECORD_VERTICES],
    vertices: usize,
    corners: [[u8; 3]; RECORD_TRIANGLES],
    triangles: usize,
}

/// One record of a leaf (see the module documentation), from its header to the arena's end.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Record<'a> {
    words: &'a [u32],
    header: u32,
}

impl<'a> Record<'a> {
    /// Distinct vertices.
    #[inline(always)]
    pub fn vertices(&self) -> usize {
        (self.header & 0xFF) as usize
    }

    /// Triangles.
    #[inline(always)]
    pub fn triangles(&self) -> usize {
        (self.header >> 8 & 0xFF) as usize
    }

    /// Words of this record.
    #[inline(always)]
    fn len(&self) -> usize {
        let (nv, nt) = (self.vertices(), self.triangles());
        1 + 3 * nv + (3 * nt).div_ceil(4) + nt
    }

    /// The next record of the same leaf.
    #[inline(always)]
    pub fn next(&self) -> Option<Record<'a>> {
        (self.header & MORE != 0).then(|| {
            let words = &self.words[self.len()..];
            Record { words, header: words[0] }
        })
    }

    /// Coordinate `axis` of every vertex: [`vertices`](Self::vertices) floats (a kernel loads
    /// a register from here with the lanes past them masked off).
    #[inline(always)]
    pub fn coordinates(&self, axis: usize) -> *const f32 {
        debug_assert!(axis < 3);
        self.words[1 + axis * self.vertices()..].as_ptr().cast()
    }

    /// Corner `corner` of every triangle, as byte indices into the vertex table; at least 16
    /// bytes are readable from it (lanes past [`triangles`](Self::triangles) are garbage).
    #[inline(always)]
    pub fn corner_indices(&self, corner: usize) -> *const u8 {
        debug_assert!(corner < 3);
        let bytes: *const u8 = self.words[1 + 3 * self.vertices()..].as_ptr().cast();
        bytes.wrapping_add(corner * self.triangles())
    }

    /// The vertex table's coordinate rows `[x, y, z]`, [`vertices`](Self::vertices) floats each.
    #[inline(always)]
    pub fn rows(&self) -> [&'a [f32]; 3] {
        let nv = self.vertices();
        let table = &self.words[1..1 + 3 * nv];
        // SAFETY: `f32` has the size and alignment of `u32`, and every bit pattern is an `f32`.
        let table: &'a [f32] =
            unsafe { std::slice::from_raw_parts(table.as_ptr().cast(), table.len()) };
        let (x, rest) = table.split_at(nv);
        let (y, z) = rest.split_at(nv);
        [x, y, z]
    }

    /// The corner rows: `corner_rows()[c][t]` is the table index of corner `c` of triangle `t`
    /// (each below [`vertices`](Self::vertices)).
    #[inline(always)]
    pub fn corner_rows(&self) -> [&'a [u8]; 3] {
        let (nv, nt) = (self.vertices(), self.triangles());
        let words = &self.words[1 + 3 * nv..1 + 3 * nv + (3 * nt).div_ceil(4)];
        // SAFETY: the words' memory holds `4·len >= 3·nt` initialized bytes, and `u8` has
        // alignment 1 (the bytes were stored in memory order: `u32::from_ne_bytes`).
        let bytes: &'a [u8] = unsafe { std::slice::from_raw_parts(words.as_ptr().cast(), 3 * nt) };
        let (a, rest) = bytes.split_at(nt);
        let (b, c) = rest.split_at(nt);
        [a, b, c]
    }

    /// Vertex `v` of the table.
    #[inline(always)]
    pub fn vertex(&self, v: usize) -> Vec3 {
        let [x, y, z] = self.rows();
        Vec3::new(x[v], y[v], z[v])
    }

    /// The table indices of triangle `t`'s corners (each below [`vertices`](Self::vertices)).
    #[inline(always)]
    pub fn corners(&self, t: usize) -> [usize; 3] {
        let [a, b, c] = self.corner_rows();
        [a[t] as usize, b[t] as usize, c[t] as usize]
    }

    /// The corners of triangle `t`, as the caller gave them.
    #[inline(always)]
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        debug_assert!(t < self.triangles());
        self.corners(t).map(|v| self.vertex(v))
    }

    /// The caller's index of triangle `t`.
    #[inline(always)]
    pub fn id(&self, t: usize) -> u32 {
        let (nv, nt) = (self.vertices(), self.triangles());
        self.words[1 + 3 * nv + (3 * nt).div_ceil(4) + t]
    }
}

/// The records of one leaf, in order.
pub(crate) struct LeafRecords<'a> {
    next: Option<Record<'a>>,
}

impl<'a> Iterator for LeafRecords<'a> {
    type Item = Record<'a>;

    #[inline(always)]
    fn next(&mut self) -> Option<Record<'a>> {
        let record = self.next?;
        self.next = record.next();
        Some(record)
    }
}

impl Leaves {
    /// Every triangle of the leaf at `offset`, in order: (caller's index, corners).
    pub fn leaf_triangles(&self, offset: u32) -> impl Iterator<Item = (u32, [Vec3; 3])> + '_ {
        self.leaf(offset).flat_map(|r| (0..r.triangles()).map(move |t| (r.id(t), r.triangle(t))))
    }
}

/// What a record test decides for each of its triangles (lane `t` for triangle `t`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct RecordHits {
    /// Triangles hit, with their `t` and barycentrics below, exactly as `intersect` computes
    /// them.
    pub hits: u32,
    /// Triangles that only [`WatertightRay::intersect`] can decide (an edge function rounded to
    /// zero and must be recomputed in double precision).
    pub undecided: u32,
    /// Ray parameter per triangle (meaningful where `hits` has the bit).
    pub t: [f32; RECORD_TRIANGLES],
    /// Barycentric weight of `v1` per triangle.
    pub b1: [f32; RECORD_TRIANGLES],
    /// Barycentric weight of `v2` per triangle.
    pub b2: [f32; RECORD_TRIANGLES],
}

/// The scalar twin of the record kernels: [`WatertightRay::intersect`] on each triangle.
/// Decides every triangle (`undecided` is empty).
#[inline(always)]
pub(crate) fn record_hits_scalar(ray: &WatertightRay, record: &Record, t_max: f32) -> RecordHits {
    let mut out = RecordHits::default();
    for t in 0..record.triangles() {
        let [v0, v1, v2] = record.triangle(t);
        if let Some(h) = ray.intersect(v0, v1, v2, t_max) {
            out.hits |= 1 << t;
            out.t[t] = h.t;
            out.b1[t] = h.b1;
            out.b2[t] = h.b2;
        }
    }
    out
}

impl Record<'_> {
    /// Whether [`WatertightRay::intersect`] hits any of the triangles whose bits are set in
    /// `triangles` (those a vector test left undecided). Rare, so out of line: a call in a
    /// traversal loop would make the compiler keep its vector values on the stack. The ray is
    /// taken by value, as by [`WatertightRay::intersect_rarely`].
    #[inline(always)]
    pub fn any_hit(&self, ray: WatertightRay, triangles: u32, t_max: f32) -> bool {
        triangles != 0 && self.any_hit_rarely(ray, triangles, t_max)
    }

    #[cold]
    #[inline(never)]
    fn any_hit_rarely(&self, ray: WatertightRay, mut triangles: u32, t_max: f32) -> bool {
        while triangles != 0 {
            let t = triangles.trailing_zeros() as usize;
            triangles &= triangles - 1;
            let [v0, v1, v2] = self.triangle(t);
            if ray.intersect(v0, v1, v2, t_max).is_some() {
                return true;
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3::new(x, y, z)
    }

    #[test]
    fn the_documented_example_takes_seventeen_words() {
        let (p, q, r, s) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(1.0, 1.0, 0.0));
        let mut leaves = Leaves::default();
        let offset = leaves.push_leaf(&[(7, [p, q, r]), (9, [r, q, s])]);
        assert_eq!(offset, 0);
        assert_eq!(leaves.bytes(), (17 + PAD_WORDS) * 4);
        assert_eq!(leaves.words[0], 0x0000_0204);
        // v0 = [p, r], v1 = [q, q], v2 = [r, s]: bytes 0, 2, 1, 1, 2, 3.
        assert_eq!(leaves.words[13], u32::from_ne_bytes([0, 2, 1, 1]));
        assert_eq!(leaves.words[14], u32::from_ne_bytes([2, 3, 0, 0]));
        assert_eq!(&leaves.words[15..17], &[7, 9]);
        let back: Vec<_> = leaves.leaf_triangles(0).collect();
        assert_eq!(back, vec![(7, [p, q, r]), (9, [r, q, s])]);
    }

    /// Hostile leaves: triangle soups (three new vertices each), fans sharing one vertex, equal
    /// values with other bits (−0.0, NaN payloads), and leaves of 1 to 64 triangles.
    #[test]
    fn every_leaf_reads_back_exactly_within_the_record_limits() {
        let mut next = crate::bvh::tests::xorshift(0x2545_f491_4f6c_dd1du64);
        let mut leaves = Leaves::default();
        let mut expected = Vec::new();
        for case in 0..400u32 {
            let n = 1 + (next() % 64) as usize;
            // A small pool makes shared vertices; a large one makes soups.
            let pool: Vec<Vec3> = (0..[4, 12, 40, 200][case as usize % 4])
                .map(|_| match next() % 8 {
                    0 => v(-0.0, 0.0, 1.0),
                    1 => v(0.0, 0.0, 1.0),
                    2 => v(f32::from_bits(0x7FC0_0001), 1.0, 2.0),
                    _ => v(next() as f32, (next() % 1000) as f32 * 0.25, -(next() as f32)),
                })
                .collect();
            let leaf: Vec<(u32, [Vec3; 3])> = (0..n)
                .map(|i| {
                    let pick = |_| pool[next() as usize % pool.len()];
                    (case * 100 + i as u32, [0, 1, 2].map(pick))
                })
                .collect();
            let offset = leaves.push_leaf(&leaf);
            expected.push((offset, leaf));
        }
        let bits = |t: [Vec3; 3]| t.map(|v| v.to_array().map(f32::to_bits));
        for (offset, leaf) in &expected {
            let back: Vec<_> = leaves.leaf_triangles(*offset).collect();
            assert_eq!(back.len(), leaf.len());
            for ((id, t), (want_id, want)) in back.iter().zip(leaf) {
                assert_eq!((id, bits(*t)), (want_id, bits(*want)));
            }
            for record in leaves.leaf(*offset) {
                assert!((1..=RECORD_VERTICES).contains(&record.vertices()));
                assert!((1..=RECORD_TRIANGLES).contains(&record.triangles()));
            }
        }
        assert_eq!(&leaves.words[leaves.words.len() - PAD_WORDS..], &[0; PAD_WORDS]);
    }
}
