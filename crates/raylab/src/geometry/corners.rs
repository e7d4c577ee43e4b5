//! Values at triangles' corners (shading normals, texture coordinates, tangents), indexed.

/// Values at triangles' corners, indexed as the meshes give them: each value stored once
/// however many corners share it (a normal per vertex costs 12 bytes a vertex, not 36 a
/// triangle).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct CornerTable<T> {
    pub(super) values: Vec<T>,
    /// Each triangle's three indices into `values`; empty when no mesh has the attribute.
    pub(super) corners: Vec<[u32; 3]>,
}

impl<T: Copy> CornerTable<T> {
    /// Triangle `i`'s three values, if the table has them.
    #[inline]
    pub(super) fn get(&self, i: usize) -> Option<[T; 3]> {
        let corners = self.corners.get(i)?;
        Some(corners.map(|k| self.values[k as usize]))
    }

    /// Gives every triangle before `until` that has no values the corners `fill`.
    pub(super) fn pad(&mut self, until: usize, fill: [T; 3]) {
        if self.corners.len() < until {
            let base = self.values.len() as u32;
            self.values.extend(fill);
            self.corners.resize(until, [base, base + 1, base + 2]);
        }
    }

    /// Appends a mesh's values and its triangles' indices into them.
    pub(super) fn append(&mut self, values: impl IntoIterator<Item = T>, corners: &[[u32; 3]]) {
        let base = self.values.len() as u32;
        self.values.extend(values);
        self.corners.extend(corners.iter().map(|c| c.map(|k| base + k)));
    }

    pub(super) fn bytes(&self) -> usize {
        std::mem::size_of_val(self.values.as_slice())
            + std::mem::size_of_val(self.corners.as_slice())
    }
}
