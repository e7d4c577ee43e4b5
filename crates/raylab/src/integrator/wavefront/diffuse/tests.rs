//! The diffuse lanes against the scalar path's steps, lane by lane, on every instruction set.

use glam::{Affine3A, Vec2, Vec3};

use super::super::super::path::PathState;
use super::super::super::{Path, PathSettings};
use super::*;
use crate::bvh::Bvh;
use crate::material::{Bsdf, Material};
use crate::mesh::Mesh;
use crate::sampling::Pcg32;
use crate::scene::Scene;
use crate::{Geometry, PointLight};

/// A floor, a square emitter above it and a point light: the lanes' triangles and the
/// scalar code's point light both get picked.
fn scene() -> Scene {
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
    Scene::new("lanes", geometry, materials, light)
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

/// On every instruction set this CPU has, each lane gives the scalar path's shadow ray,
/// contribution, next ray, throughput and density to the bit, for hostile vertices:
/// directions at and below the horizon, zero and huge throughputs and reflectances, points
/// far off (whose offsets overflow: those lanes must say they are not exact), numbers at 0
/// and just below 1, and lights picked of both kinds.
#[test]
fn lanes_are_the_scalar_paths_bits_on_every_instruction_set() {
    let scene = scene();
    let bvh = Bvh::new(&scene.vertices());
    let path = Path::new(&scene, &bvh, PathSettings::default());
    let mut rng = Pcg32::new(27, 16);
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
            rng.next_f32() * 1.9,
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
        let reflectance =
            Vec3::new(hostile(&mut rng, 1.0, 0.0), rng.next_f32(), hostile(&mut rng, 1.0, 0.0));
        let surface = DiffuseSurface { point, normal: shading_normal, two_sided, reflectance };
        // The scalar path's vertex there (`Path::vertex`'s frame for a diffuse BSDF).
        let (frame, flip, wi) = facing(two_sided, arrival, Frame::about(shading_normal));
        let vertex = Vertex {
            point,
            frame,
            flip,
            wi,
            bsdf: Cow::Owned(Bsdf::Diffuse(Diffuse { reflectance })),
        };
        let mut state = PathState::new(&Ray::new(Vec3::ZERO, Vec3::Z));
        state.throughput = Vec3::new(hostile(&mut rng, 0.0, 1.0), rng.next_f32(), 0.7);
        state.eta = hostile(&mut rng, 0.0, 1.5);
        state.depth = rng.next_u32() % 8;
        let u = [(); 6].map(|_| number(&mut rng));
        cases.push((vertex, state, u, (surface, arrival)));
    }
    type Case<'a> = (Vertex<'a>, PathState, [f32; 6], (DiffuseSurface, Vec3));
    let lane_vertex = |(_, state, _, (surface, arrival)): &Case| LaneVertex {
        surface: *surface,
        arrival: *arrival,
        throughput: state.throughput,
        eta: state.eta,
        roulette: state.depth + 1 >= PathSettings::default().rr_depth,
    };
    let lane_draws = |u: &[f32; 6]| {
        let (u_point, u_direction) = (Vec2::new(u[0], u[1]), Vec2::new(u[3], u[4]));
        let light = path.lights().pick_for_lanes(u_point);
        LaneDraws { light, u_point, u_direction, u_roulette: u[5] }
    };
    for isa in Isa::ALL.into_iter().filter(|isa| isa.is_supported()) {
        let mut lanes = DiffuseLanes::default();
        for (i, case) in cases.iter().enumerate() {
            lanes.push(&lane_vertex(case));
            lanes.set_draws(i, &lane_draws(&case.2));
        }
        lanes.shade(isa);
        let (mut exact, mut shadows, mut bounces) = (0, 0, 0);
        for (lane, (vertex, state, u, _)) in cases.iter().enumerate() {
            let result = lanes.result(lane);
            if !result.exact {
                continue;
            }
            exact += 1;
            let light = path.lights().pick_for_lanes(Vec2::new(u[0], u[1]));
            let expected = path.sample_light_with(vertex, Vec2::new(u[0], u[1]), state.throughput);
            match (light, result.shadow) {
                (LanePick::Other, shadow) => assert!(shadow.is_none(), "{isa:?} lane {lane}"),
                (_, None) => assert!(expected.is_none(), "{isa:?} lane {lane}: {expected:?}"),
                (_, Some((ray, contribution))) => {
                    let (want, want_contribution) = expected.expect("a shadow ray");
                    shadows += 1;
                    assert!(
                        same3(ray.origin, want.origin)
                            && same3(ray.direction, want.direction)
                            && same(ray.t_max, want.t_max)
                            && same3(contribution, want_contribution),
                        "{isa:?} lane {lane}: {ray:?} {contribution} against {want:?} {want_contribution}"
                    );
                }
            }
            let mut scalar = *state;
            let goes_on = path.bounce(&mut scalar, vertex, u[2], Vec2::new(u[3], u[4]))
                && path.survives_roulette(&mut scalar, u[5]);
            assert_eq!(result.next.is_some(), goes_on, "{isa:?} lane {lane}");
            if let Some((ray, throughput, pdf)) = result.next {
                bounces += 1;
                assert!(
                    same3(ray.origin, scalar.ray.origin)
                        && same3(ray.direction, scalar.ray.direction)
                        && same3(throughput, scalar.throughput)
                        && same(pdf, scalar.previous_pdf),
                    "{isa:?} lane {lane}: {ray:?} {throughput} {pdf} against {:?} {} {}",
                    scalar.ray,
                    scalar.throughput,
                    scalar.previous_pdf
                );
            }
        }
        // The comparisons were made, not skipped.
        assert!(exact > 1800 && shadows > 100 && bounces > 500, "{exact} {shadows} {bounces}");
        assert!(exact < cases.len(), "some far points must have been left to the scalar code");
    }
}
