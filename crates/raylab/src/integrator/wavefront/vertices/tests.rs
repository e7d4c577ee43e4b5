//! The lanes of every BSDF kind against the scalar path's steps, lane by lane, on every
//! instruction set.

use glam::{Affine3A, Vec2, Vec3};

use super::super::super::path::PathState;
use super::super::super::{PathScalar, PathSettings};
use super::*;
use crate::bvh::Bvh;
use crate::material::{
    Bsdf, Conductor, Dielectric, Diffuse, Ggx, Material, Pbr, Plastic, RoughConductor,
    RoughDielectric,
};
use crate::material::{BsdfKind, with_bsdf_type};
use crate::mesh::Mesh;
use crate::sampling::Pcg32;
use crate::scene::Scene;
use crate::{Geometry, PointLight};

/// A floor, a square emitter above it facing down, a point light, a spot light and, where
/// `sky`, the environment and a sun: the lanes' triangles and environment and the lights the
/// scalar code samples for them (delta lights, one outside whose cone many points lie, and a
/// sun of 0.01°) all get picked (without the sky, the chunks take the lanes' code without the
/// environment's).
fn scene(sky: bool) -> Scene {
    let quad = |y: f32, half: f32, flip: bool| Mesh {
        name: "quad".into(),
        positions: [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
            .iter()
            .map(|&(x, z)| Vec3::new(x * half, y, z * half))
            .collect(),
        triangles: if flip { vec![[0, 2, 1], [2, 3, 1]] } else { vec![[0, 1, 2], [2, 1, 3]] },
        ..Mesh::default()
    };
    let mut geometry = Geometry::new();
    geometry.add_mesh(&quad(0.0, 4.0, false), &Affine3A::IDENTITY, |_| 0);
    geometry.add_mesh(&quad(2.0, 0.5, true), &Affine3A::IDENTITY, |_| 1);
    let mut lamp = Material::diffuse("lamp", Vec3::ZERO);
    lamp.emission = Vec3::new(8.0, 6.0, 4.0);
    let materials = vec![Material::diffuse("floor", Vec3::splat(0.5)), lamp];
    let light = PointLight { position: Vec3::new(1.0, 1.5, 0.0), power: Vec3::splat(30.0) };
    let mut scene = Scene::new("lanes", geometry, materials, light);
    let spot = crate::light::SpotLight::new(
        Vec3::new(-1.0, 1.8, 0.5),
        Vec3::new(0.2, -1.0, 0.1),
        Vec3::splat(20.0),
        0.5,
        0.3,
        crate::light::SpotProfile::Mitsuba,
    );
    scene.lights.push(crate::Light::Spot(spot.expect("a spot")));
    if sky {
        scene.lights.push(crate::Light::Environment { radiance: Vec3::new(0.3, 0.5, 0.9) });
        let sun = crate::light::SunLight::new(
            Vec3::new(0.3, -1.0, 0.2),
            0.01f32.to_radians(),
            Vec3::splat(2e5),
        );
        scene.lights.push(crate::Light::Sun(sun.expect("a sun")));
    }
    scene
}

/// A hostile float: ordinary, zero of either sign, tiny, huge, or exactly an edge.
fn hostile(rng: &mut Pcg32, scale: f32, shift: f32) -> f32 {
    let ordinary = rng.next_f32() * scale + shift;
    match rng.next_u32() % 16 {
        0 => 0.0,
        1 => -0.0,
        2 => f32::MIN_POSITIVE,
        3 => 3e38,
        4 => -1e-30,
        _ => ordinary,
    }
}

fn unit(rng: &mut Pcg32) -> Vec3 {
    let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
    v.try_normalize().unwrap_or(Vec3::Y)
}

fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn same3(a: Vec3, b: Vec3) -> bool {
    same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z)
}

/// A BSDF of each kind with hostile parameters: zero and huge colours, roughnesses at the
/// clamp and anisotropic, indices of refraction above and below 1.
fn hostile_bsdf(rng: &mut Pcg32, kind: BsdfKind) -> Bsdf {
    let colour = |rng: &mut Pcg32| {
        Vec3::new(hostile(rng, 1.0, 0.0), rng.next_f32(), hostile(rng, 1.0, 0.0)).abs()
    };
    let alpha = |rng: &mut Pcg32| match rng.next_u32() % 4 {
        0 => 0.0,
        _ => rng.next_f32() * 0.8,
    };
    let eta = |rng: &mut Pcg32| match rng.next_u32() % 3 {
        0 => 1.0 / (1.0 + rng.next_f32()),
        _ => 1.0 + rng.next_f32(),
    };
    let conductor = |rng: &mut Pcg32| Conductor {
        eta: Vec3::new(0.2, 0.4, 1.4) * (0.5 + rng.next_f32()),
        k: Vec3::new(3.4, 2.3, 1.8) * rng.next_f32(),
        specular_reflectance: colour(rng),
    };
    match kind {
        BsdfKind::Diffuse => Bsdf::Diffuse(Diffuse { reflectance: colour(rng) }),
        BsdfKind::Conductor => Bsdf::Conductor(conductor(rng)),
        BsdfKind::RoughConductor => Bsdf::RoughConductor(RoughConductor {
            conductor: conductor(rng),
            distribution: Ggx::new(alpha(rng), alpha(rng)),
        }),
        BsdfKind::Dielectric => Bsdf::Dielectric(Dielectric { eta: eta(rng) }),
        BsdfKind::RoughDielectric => Bsdf::RoughDielectric(RoughDielectric {
            eta: eta(rng),
            distribution: Ggx::new(alpha(rng), alpha(rng)),
        }),
        BsdfKind::Plastic => Bsdf::Plastic(Plastic::new(
            colour(rng),
            colour(rng),
            eta(rng),
            rng.next_u32().is_multiple_of(2),
        )),
        BsdfKind::Pbr => Bsdf::Pbr(Pbr {
            base_color: colour(rng),
            metallic: rng.next_f32(),
            roughness: alpha(rng),
        }),
    }
}

/// On every instruction set this CPU has, for every BSDF kind, each lane gives the scalar
/// path's shadow ray, contribution, next ray, throughput, density, η and delta flag to the bit,
/// for hostile vertices: directions at and below the horizon, zero and huge throughputs and
/// colours, anisotropic frames, points far off (whose offsets overflow: those lanes must say
/// they are not exact), numbers at 0 and just below 1, and lights picked of both kinds.
#[test]
fn lanes_are_the_scalar_paths_bits_on_every_instruction_set() {
    for kind in BsdfKind::ALL {
        with_bsdf_type!(kind, B => lanes_match_the_scalar_path::<B>(kind));
    }
}

fn lanes_match_the_scalar_path<B: LaneBsdf>(kind: BsdfKind) {
    for sky in [true, false] {
        lanes_match_the_scalar_path_in::<B>(kind, sky);
    }
}

fn lanes_match_the_scalar_path_in<B: LaneBsdf>(kind: BsdfKind, sky: bool) {
    let scene = scene(sky);
    let bvh = Bvh::new(&scene.vertices());
    let path = PathScalar::new(&scene, &bvh, PathSettings::default());
    let mut rng = Pcg32::new(27, 16 + kind as u64);
    let below_one = 1.0 - f32::EPSILON / 2.0;
    let mut cases = Vec::new();
    for _ in 0..2000 {
        let number = |rng: &mut Pcg32| match rng.next_u32() % 8 {
            0 => 0.0,
            1 => below_one,
            _ => rng.next_f32(),
        };
        let p = Vec3::new(
            hostile(&mut rng, 6.0, -3.0),
            // Some above the lamp, which faces down: they see its back.
            rng.next_f32() * 2.6,
            rng.next_f32() * 6.0 - 3.0,
        );
        let normal = unit(&mut rng);
        // Now and then an error bound so large that the offset point overflows.
        let error = Vec3::splat(if rng.next_u32().is_multiple_of(32) { 3e38 } else { 1e-6 });
        let point = crate::ray::SurfacePoint { p, error, normal };
        let shading_normal = unit(&mut rng);
        // Arrivals of any length, now and then along the surface (the horizon: `wi.z` 0).
        let mut arrival = unit(&mut rng) * hostile(&mut rng, 4.0, 1e-3);
        if rng.next_u32().is_multiple_of(8) {
            arrival = shading_normal.any_orthonormal_vector() * 3.0;
        }
        let two_sided = rng.next_u32().is_multiple_of(2);
        let bsdf = hostile_bsdf(&mut rng, kind);
        // `shading_frame`'s frame: `dp/du`'s (now and then along the normal) where the BSDF
        // is anisotropic.
        let tangent = bsdf.is_anisotropic().then(|| match rng.next_u32() % 8 {
            0 => shading_normal * 2.0,
            _ => unit(&mut rng) * 0.3,
        });
        let frame = match tangent {
            Some(dp_du) => Frame::new(shading_normal, dp_du),
            None => Frame::about(shading_normal),
        };
        let (frame, flip, wi) = facing(two_sided, arrival, frame);
        assert_eq!(bsdf.kind(), kind);
        let surface = LaneSurface {
            point,
            normal: shading_normal,
            two_sided,
            tangent,
            bsdf: Cow::Owned(bsdf.clone()),
        };
        let vertex = Vertex { point, frame, flip, wi, bsdf: Cow::Owned(bsdf) };
        let mut state = PathState::new(&Ray::new(Vec3::ZERO, Vec3::Z));
        state.throughput = Vec3::new(hostile(&mut rng, 0.0, 1.0), rng.next_f32(), 0.7);
        state.eta = hostile(&mut rng, 0.0, 1.5);
        state.depth = rng.next_u32() % 8;
        let u = [(); 6].map(|_| number(&mut rng));
        cases.push((vertex, state, u, (surface, arrival)));
    }
    type Case<'a> = (Vertex<'a>, PathState, [f32; 6], (LaneSurface<'a>, Vec3));
    let lane_vertex = |(_, state, _, (_, arrival)): &Case| LaneVertex {
        arrival: *arrival,
        throughput: state.throughput,
        eta: state.eta,
        roulette: state.depth + 1 >= PathSettings::default().rr_depth,
    };
    let lane_draws = |u: &[f32; 6], point: &crate::ray::SurfacePoint| {
        let (u_point, u_direction) = (Vec2::new(u[0], u[1]), Vec2::new(u[3], u[4]));
        let light = path.lights().pick_for_lanes(u_point);
        // As the wavefront's stage gives them: the scalar code's sample of a light the lanes
        // do not sample.
        let given = (B::SMOOTH && light.role() == LaneRole::Other)
            .then(|| path.lights().sample(point, u_point))
            .flatten();
        LaneDraws { light, given, u_point, u_lobe: u[2], u_direction, u_roulette: u[5] }
    };
    // In order, then in reverse into the same lanes: their rows must not keep anything of the
    // vertex a lane held before.
    let forward: Vec<usize> = (0..cases.len()).collect();
    let backward: Vec<usize> = forward.iter().rev().copied().collect();
    for isa in Isa::ALL.into_iter().filter(|isa| isa.is_supported()) {
        let mut lanes = VertexLanes::default();
        for order in [&forward, &backward] {
            lanes.clear();
            for (i, &c) in order.iter().enumerate() {
                lanes.push(&cases[c].3.0, &lane_vertex(&cases[c]));
                lanes.set_draws(i, &lane_draws(&cases[c].2, &cases[c].0.point));
            }
            lanes.shade::<B>(isa);
            let (mut exact, mut shadows, mut skies, mut backs, mut bounces) = (0, 0, 0, 0, 0);
            let mut given = 0;
            for (lane, &c) in order.iter().enumerate() {
                let (vertex, state, u, _) = &cases[c];
                let result = lanes.result(lane);
                // The scalar steps' vertex made from the lane is the scalar path's own.
                let rebuilt = lanes.vertex::<B>(lane);
                // (Bit for bit: a huge colour gives a plastic a NaN weight, which `==` refuses.)
                let bits = |bsdf: &Bsdf| {
                    let mut rows = [[0.0; LANES]; PARAMS];
                    crate::material::lanes::store(bsdf, &mut rows, 0);
                    rows.map(|row| row[0].to_bits())
                };
                assert!(bits(&rebuilt.bsdf) == bits(&vertex.bsdf) && rebuilt.flip == vertex.flip);
                assert!(
                    same3(rebuilt.wi, vertex.wi)
                        && same3(rebuilt.frame.tangent, vertex.frame.tangent)
                );
                if !result.exact {
                    continue;
                }
                exact += 1;
                let light = path.lights().pick_for_lanes(Vec2::new(u[0], u[1]));
                let expected =
                    path.sample_light_with(vertex, Vec2::new(u[0], u[1]), state.throughput);
                let lamp = light.role() == LaneRole::Triangle;
                match (light.role(), result.shadow) {
                    (_, None) => {
                        assert!(expected.is_none(), "{kind:?} {isa:?} lane {lane}: {expected:?}");
                        backs += usize::from(lamp && vertex.point.p.y > 2.0);
                    }
                    (_, Some((ray, contribution))) => {
                        let (want, want_contribution) = expected.expect("a shadow ray");
                        shadows += 1;
                        skies += usize::from(ray.t_max == f32::INFINITY);
                        given += usize::from(light.role() == LaneRole::Other);
                        assert!(
                            same3(ray.origin, want.origin)
                                && same3(ray.direction, want.direction)
                                && same(ray.t_max, want.t_max)
                                && same3(contribution, want_contribution),
                            "{kind:?} {isa:?} lane {lane}: {ray:?} {contribution} against {want:?} {want_contribution}"
                        );
                    }
                }
                let mut scalar = *state;
                let goes_on = path.bounce(&mut scalar, vertex, u[2], Vec2::new(u[3], u[4]))
                    && path.survives_roulette(&mut scalar, u[5]);
                assert_eq!(result.next.is_some(), goes_on, "{kind:?} {isa:?} lane {lane}");
                if let Some(next) = result.next {
                    bounces += 1;
                    assert!(
                        same3(next.ray.origin, scalar.ray.origin)
                            && same3(next.ray.direction, scalar.ray.direction)
                            && same3(next.throughput, scalar.throughput)
                            && same(next.pdf, scalar.previous_pdf)
                            && same(next.eta, scalar.eta)
                            && next.delta == scalar.previous_delta,
                        "{kind:?} {isa:?} lane {lane}: {next:?} against {scalar:?}"
                    );
                }
            }
            // The comparisons were made, not skipped (delta BSDFs sample no lights; without the
            // sky, no shadow ray leaves the scene).
            let smooth = usize::from(B::SMOOTH);
            let (least_skies, least_backs) = (smooth * usize::from(sky) * 50, smooth * 10);
            assert!(
                exact > 1800
                    && shadows >= smooth * 100
                    && skies >= least_skies
                    && (sky || skies == 0)
                    && backs >= least_backs
                    && bounces > 400
                    && given >= smooth * 50,
                "{kind:?} {sky}: {exact} {shadows} {skies} {backs} {bounces} {given}"
            );
            assert!(exact < cases.len(), "some far points must have been left to the scalar code");
        }
    }
}
