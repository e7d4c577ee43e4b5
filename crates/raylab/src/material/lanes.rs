//! The BSDFs as the path tracer's lanes hold them: each kind's parameters as a few floats, so
//! that sixteen vertices of one kind keep theirs row by row (structure of arrays) and one loop
//! evaluates and samples all sixteen, sixteen lanes per AVX-512 instruction
//! (`integrator/wavefront/vertices`).
//!
//! A kind's [`LaneBsdf::from_params`] rebuilds exactly the BSDF that
//! [`to_params`](LaneBsdf::to_params) took apart (every field, the derived ones too), and its
//! `eval`, `pdf` and `sample` are the BSDF's own methods: the lanes compute what the scalar
//! path computes, operation for operation. The methods are straight-line arithmetic whose
//! branches the compiler turns into selects (the sines and cosines are polynomials,
//! [`sin_cos_turns`](crate::sampling::sin_cos_turns)), which is what lets a loop over lanes
//! become vector code.

use glam::{Vec2, Vec3};

use super::{
    Bsdf, BsdfSample, Conductor, Dielectric, Diffuse, Ggx, Pbr, Plastic, RoughConductor,
    RoughDielectric,
};

/// Lanes per chunk: one AVX-512 register of floats.
pub(crate) const LANES: usize = 16;

/// A chunk's parameter rows: row `j` holds parameter `j` of every lane.
pub(crate) type ParamRows = [[f32; LANES]; PARAMS];

/// The most floats any kind's parameters take (a rough conductor's: η, k and the tint, and
/// two roughnesses).
pub(crate) const PARAMS: usize = 11;

/// A BSDF kind the lanes shade (see the module documentation).
pub(crate) trait LaneBsdf: Sized {
    /// Whether it has a lobe that is not a delta ([`Bsdf::is_smooth`]): light sampling helps.
    const SMOOTH: bool;
    /// Whether it may depend on the tangent's direction ([`Bsdf::is_anisotropic`]): only
    /// then do the lanes make the frame `dp/du` orients.
    const ANISOTROPIC: bool = false;
    /// How many floats its parameters take.
    const LEN: usize;
    /// Its parameters (the rows past its own are left zero).
    fn to_params(&self) -> [f32; PARAMS];
    /// The BSDF `to_params` took apart, exactly.
    fn from_params(p: &[f32; PARAMS]) -> Self;
    /// As the enum.
    fn into_bsdf(self) -> Bsdf;
    /// [`Bsdf::eval`].
    #[inline(always)]
    fn eval(&self, _wi: Vec3, _wo: Vec3) -> Vec3 {
        Vec3::ZERO
    }
    /// [`Bsdf::pdf`].
    #[inline(always)]
    fn pdf(&self, _wi: Vec3, _wo: Vec3) -> f32 {
        0.0
    }
    /// [`Bsdf::sample`].
    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample>;
}

/// Writes `values` into `p` from row `at` on.
#[inline(always)]
fn put<const N: usize>(p: &mut [f32; PARAMS], at: usize, values: [f32; N]) {
    p[at..at + N].copy_from_slice(&values);
}

#[inline(always)]
fn vec3(p: &[f32; PARAMS], at: usize) -> Vec3 {
    Vec3::new(p[at], p[at + 1], p[at + 2])
}

/// The smooth metal's rows: η, k, tint.
#[inline(always)]
fn conductor_params(c: &Conductor, p: &mut [f32; PARAMS]) {
    put(p, 0, c.eta.to_array());
    put(p, 3, c.k.to_array());
    put(p, 6, c.specular_reflectance.to_array());
}

#[inline(always)]
fn conductor_from(p: &[f32; PARAMS]) -> Conductor {
    Conductor { eta: vec3(p, 0), k: vec3(p, 3), specular_reflectance: vec3(p, 6) }
}

/// The BSDF methods that every smooth kind forwards as they are.
macro_rules! forward_smooth {
    () => {
        #[inline(always)]
        fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
            Self::eval(self, wi, wo)
        }
        #[inline(always)]
        fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
            Self::pdf(self, wi, wo)
        }
        #[inline(always)]
        fn sample(&self, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
            Self::sample(self, wi, u1, u2)
        }
    };
}

impl LaneBsdf for Diffuse {
    const SMOOTH: bool = true;
    const LEN: usize = 3;
    #[inline(always)]
    fn to_params(&self) -> [f32; PARAMS] {
        let mut p = [0.0; PARAMS];
        put(&mut p, 0, self.reflectance.to_array());
        p
    }
    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Diffuse { reflectance: vec3(p, 0) }
    }
    fn into_bsdf(self) -> Bsdf {
        Bsdf::Diffuse(self)
    }
    forward_smooth!();
}

impl LaneBsdf for Conductor {
    const SMOOTH: bool = false;
    const LEN: usize = 9;
    #[inline(always)]
    fn to_params(&self) -> [f32; PARAMS] {
        let mut p = [0.0; PARAMS];
        conductor_params(self, &mut p);
        p
    }
    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        conductor_from(p)
    }
    fn into_bsdf(self) -> Bsdf {
        Bsdf::Conductor(self)
    }
    #[inline(always)]
    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        Conductor::sample(self, wi, u1, u2)
    }
}

impl LaneBsdf for RoughConductor {
    const SMOOTH: bool = true;
    const LEN: usize = 11;
    const ANISOTROPIC: bool = true;
    #[inline(always)]
    fn to_params(&self) -> [f32; PARAMS] {
        let mut p = [0.0; PARAMS];
        conductor_params(&self.conductor, &mut p);
        put(&mut p, 9, [self.distribution.alpha_u, self.distribution.alpha_v]);
        p
    }
    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        RoughConductor {
            conductor: conductor_from(p),
            distribution: Ggx { alpha_u: p[9], alpha_v: p[10] },
        }
    }
    fn into_bsdf(self) -> Bsdf {
        Bsdf::RoughConductor(self)
    }
    forward_smooth!();
}

impl LaneBsdf for Dielectric {
    const SMOOTH: bool = false;
    const LEN: usize = 1;
    #[inline(always)]
    fn to_params(&self) -> [f32; PARAMS] {
        let mut p = [0.0; PARAMS];
        p[0] = self.eta;
        p
    }
    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Dielectric { eta: p[0] }
    }
    fn into_bsdf(self) -> Bsdf {
        Bsdf::Dielectric(self)
    }
    #[inline(always)]
    fn sample(&self, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        Dielectric::sample(self, wi, u1, u2)
    }
}

impl LaneBsdf for RoughDielectric {
    const SMOOTH: bool = true;
    const LEN: usize = 3;
    const ANISOTROPIC: bool = true;
    #[inline(always)]
    fn to_params(&self) -> [f32; PARAMS] {
        let mut p = [0.0; PARAMS];
        put(&mut p, 0, [self.eta, self.distribution.alpha_u, self.distribution.alpha_v]);
        p
    }
    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        RoughDielectric { eta: p[0], distribution: Ggx { alpha_u: p[1], alpha_v: p[2] } }
    }
    fn into_bsdf(self) -> Bsdf {
        Bsdf::RoughDielectric(self)
    }
    forward_smooth!();
}

impl LaneBsdf for Plastic {
    const SMOOTH: bool = true;
    const LEN: usize = 10;
    #[inline(always)]
    fn to_params(&self) -> [f32; PARAMS] {
        let mut p = [0.0; PARAMS];
        put(&mut p, 0, self.diffuse_reflectance.to_array());
        put(&mut p, 3, self.specular_reflectance.to_array());
        let nonlinear = if self.nonlinear { 1.0 } else { 0.0 };
        put(&mut p, 6, [self.eta, nonlinear, self.internal_reflectance, self.specular_weight]);
        p
    }
    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Plastic {
            diffuse_reflectance: vec3(p, 0),
            specular_reflectance: vec3(p, 3),
            eta: p[6],
            nonlinear: p[7] != 0.0,
            internal_reflectance: p[8],
            specular_weight: p[9],
        }
    }
    fn into_bsdf(self) -> Bsdf {
        Bsdf::Plastic(self)
    }
    forward_smooth!();
}

impl LaneBsdf for Pbr {
    const SMOOTH: bool = true;
    const LEN: usize = 5;
    #[inline(always)]
    fn to_params(&self) -> [f32; PARAMS] {
        let mut p = [0.0; PARAMS];
        put(&mut p, 0, self.base_color.to_array());
        put(&mut p, 3, [self.metallic, self.roughness]);
        p
    }
    #[inline(always)]
    fn from_params(p: &[f32; PARAMS]) -> Self {
        Pbr { base_color: vec3(p, 0), metallic: p[3], roughness: p[4] }
    }
    fn into_bsdf(self) -> Bsdf {
        Bsdf::Pbr(self)
    }
    forward_smooth!();
}

/// Writes `bsdf`'s parameters into lane `k` of `rows` (its own rows only).
#[inline(always)]
pub(crate) fn store_params<B: LaneBsdf>(bsdf: &B, rows: &mut ParamRows, k: usize) {
    let params = bsdf.to_params();
    for (row, value) in rows[..B::LEN].iter_mut().zip(params) {
        row[k] = value;
    }
}

/// Writes the parameters of whichever BSDF `bsdf` is into lane `k` of `rows`
/// ([`store_params`]).
#[inline(always)]
pub(crate) fn store(bsdf: &Bsdf, rows: &mut ParamRows, k: usize) {
    super::each_bsdf!(bsdf, b => store_params(b, rows, k))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every kind comes back from its floats as it was, field for field.
    #[test]
    fn params_rebuild_each_bsdf_exactly() {
        fn round_trip<B: LaneBsdf + Clone>(bsdf: B) {
            let params = bsdf.to_params();
            // Only the first `LEN` rows are its own.
            assert!(params[B::LEN..].iter().all(|&p| p == 0.0));
            let mut rows = [[0.0; LANES]; PARAMS];
            store_params(&bsdf, &mut rows, 3);
            let back = B::from_params(&std::array::from_fn(|j| rows[j][3])).into_bsdf();
            assert_eq!(back, bsdf.into_bsdf());
        }
        let (eta, k) = (Vec3::new(0.2, 0.4, 1.4), Vec3::new(3.4, 2.3, 1.8));
        let conductor = Conductor { eta, k, specular_reflectance: Vec3::new(0.9, 0.8, 0.7) };
        round_trip(Diffuse { reflectance: Vec3::new(0.1, 0.2, 0.3) });
        round_trip(conductor.clone());
        round_trip(RoughConductor { conductor, distribution: Ggx::new(0.05, 0.3) });
        round_trip(Dielectric { eta: 1.5 });
        round_trip(RoughDielectric { eta: 1.0 / 1.33, distribution: Ggx::new(0.2, 0.1) });
        for nonlinear in [false, true] {
            round_trip(Plastic::new(Vec3::new(0.1, 0.3, 0.7), Vec3::ONE, 1.49, nonlinear));
        }
        round_trip(Plastic::new(Vec3::ZERO, Vec3::ZERO, 1.2, false));
        round_trip(Pbr { base_color: Vec3::new(0.8, 0.5, 0.1), metallic: 0.7, roughness: 0.4 });
    }
}
