//! What a ray query answers: the closest hit ([`Hit`]), and the order every accelerator keeps
//! between hits ([`Hit::precedes`]).

/// The closest intersection of a ray with a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Index of the triangle hit. Between hits at exactly equal `t`, the lowest index wins, so
    /// every accelerator gives the same answer.
    pub triangle: u32,
    /// Barycentric weight of the triangle's `v1`.
    pub b1: f32,
    /// Barycentric weight of the triangle's `v2`.
    pub b2: f32,
}

impl Hit {
    /// Whether this hit comes before `other` in the order every accelerator answers by: nearer,
    /// or at exactly equal `t` the lower triangle index.
    #[inline]
    pub fn precedes(&self, other: &Hit) -> bool {
        self.t < other.t || (self.t == other.t && self.triangle < other.triangle)
    }

    /// Keeps in `best` whichever of it and `self` comes first ([`precedes`](Self::precedes)).
    #[inline]
    pub fn keep_first(self, best: &mut Option<Hit>) {
        if best.is_none_or(|b| self.precedes(&b)) {
            *best = Some(self);
        }
    }

    /// Barycentric weight of the triangle's `v0`.
    #[inline]
    pub fn b0(&self) -> f32 {
        1.0 - self.b1 - self.b2
    }
}
