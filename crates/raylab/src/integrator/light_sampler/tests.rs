use super::*;

/// What a ray leaving the scene along `direction` finds: the infinite lights' radiances and
/// densities, summed (one light's, or zeros).
fn escaped(lights: &LightSet, direction: Vec3) -> (Vec3, f32) {
    let mut sum = (Vec3::ZERO, 0.0);
    lights.escaped(direction, |e| sum = (sum.0 + e.radiance, sum.1 + e.pdf));
    sum
}

#[test]
fn several_environments_shine_as_their_sum() {
    let mut scene = Scene::built_in("cornell").unwrap();
    scene.lights = vec![
        Light::Environment { radiance: Vec3::new(1.0, 2.0, 3.0) },
        Light::Environment { radiance: Vec3::new(0.5, 0.5, 0.5) },
    ];
    let lights = LightSet::new(&scene);
    assert_eq!(lights.len(), 1);
    let (radiance, pdf) = escaped(&lights, Vec3::Z);
    assert_eq!(radiance, Vec3::new(1.5, 2.5, 3.5));
    assert!((pdf - 1.0 / (4.0 * PI)).abs() < 1e-7);
    // Light sampling sees the same sum, with the same density.
    let point = SurfacePoint { p: Vec3::ZERO, error: Vec3::ZERO, normal: Vec3::Z };
    let sample = lights.sample(&point, Vec2::new(0.2, 0.9)).unwrap();
    assert_eq!((sample.radiance, sample.pdf), (radiance, pdf));
}

/// With other lights, the environment takes half the picks whatever its power (none if it is
/// black); each light's share of a stratified row of first numbers, rescaled, is a
/// stratified row again.
#[test]
fn the_environment_takes_half_the_picks_and_each_light_keeps_its_points_stratified() {
    let mut scene = Scene::built_in("cornell").unwrap();
    assert!(matches!(scene.lights[..], [Light::Point(_)]), "{:?}", scene.lights);
    // A dim environment, then a bright one: half the picks either way.
    for radiance in [0.01, 100.0] {
        scene.lights.truncate(1);
        scene.lights.push(Light::Environment { radiance: Vec3::splat(radiance) });
        let lights = LightSet::new(&scene);
        let (_, pdf) = escaped(&lights, Vec3::Z);
        assert_eq!(pdf, 0.5 / (4.0 * PI), "radiance {radiance}");
        const N: usize = 1024;
        let mut rescaled: [Vec<f32>; 2] = Default::default();
        for k in 0..N {
            let u = Vec2::new((k as f32 + 0.5) / N as f32, 0.5);
            let (index, selection, v) = lights.pick(u).unwrap();
            assert_eq!((selection, v.y), (0.5, 0.5));
            rescaled[index].push(v.x);
        }
        for xs in &rescaled {
            assert_eq!(xs.len(), N / 2);
            for (k, &x) in xs.iter().enumerate() {
                let expected = (k as f32 + 0.5) / xs.len() as f32;
                assert!((x - expected).abs() < 1e-5, "{k}: {x} against {expected}");
            }
        }
    }
    // A black environment takes none.
    scene.lights.truncate(1);
    scene.lights.push(Light::Environment { radiance: Vec3::ZERO });
    let lights = LightSet::new(&scene);
    assert_eq!(escaped(&lights, Vec3::Z).1, 0.0);
    assert_eq!(lights.pick(Vec2::new(0.999, 0.5)).map(|(i, p, _)| (i, p)), Some((0, 1.0)));
    // Alone, the environment takes every pick.
    scene.lights.truncate(1);
    scene.lights.push(Light::Environment { radiance: Vec3::splat(0.3) });
    scene.lights.remove(0);
    let lights = LightSet::new(&scene);
    assert_eq!(escaped(&lights, Vec3::Z).1, 1.0 / (4.0 * PI));
}

/// `sample_each` (the maps' picks made together) gives `sample`'s samples to the bit, for a
/// scene with two environment maps, one sampled in step, a point light, a sun and its area
/// lights, from points all around, in groups of every size up to sixteen.
#[test]
fn sampling_together_is_sampling_one_by_one() {
    use crate::film::Film;
    use crate::light::{EnvironmentMap, SunLight};
    use crate::sampling::{Pcg32, SEARCH_LANES};
    let map = |w: u32, h: u32, bright: u32| {
        let pixels = (0..w * h)
            .map(|i| if i % bright == 0 { Vec3::splat(40.0) } else { Vec3::new(0.2, 0.3, 0.4) })
            .collect();
        let film = Film::from_pixels(w, h, pixels);
        Arc::new(EnvironmentMap::new("m", film, 1.0, glam::Mat3::IDENTITY).unwrap())
    };
    let mut scene = Scene::built_in("cornell").unwrap();
    let mut lamp = crate::material::Material::diffuse("lamp", Vec3::ZERO);
    lamp.emission = Vec3::splat(5.0);
    scene.materials[0] = lamp;
    scene.lights.push(Light::EnvironmentMap(map(32, 17, 7)));
    scene.lights.push(Light::EnvironmentMap(map(8, 5, 3)));
    scene
        .lights
        .push(Light::Sun(SunLight::new(Vec3::new(0.2, 1.0, 0.1), 0.01, Vec3::ONE).unwrap()));
    let lights = LightSet::new(&scene);
    let mut rng = Pcg32::new(48, 3);
    let mut kinds = [0usize; 2];
    for size in 1..=SEARCH_LANES {
        for _ in 0..60 {
            let points: Vec<SurfacePoint> = (0..size)
                .map(|_| SurfacePoint {
                    p: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0,
                    error: Vec3::splat(1e-6),
                    normal: Vec3::Y,
                })
                .collect();
            let us: Vec<Vec2> =
                (0..size).map(|_| Vec2::new(rng.next_f32(), rng.next_f32())).collect();
            let mut each = vec![None; size];
            lights.sample_each(&points, &us, &mut each);
            for ((point, u), got) in points.iter().zip(&us).zip(&each) {
                let want = lights.sample(point, *u);
                let bits = |s: &Option<LightSample>| {
                    s.map(|s| {
                        let v = |v: Vec3| v.to_array().map(f32::to_bits);
                        let r = s.shadow_ray;
                        (
                            v(s.direction),
                            v(s.radiance),
                            s.pdf.to_bits(),
                            s.delta,
                            v(r.origin),
                            v(r.direction),
                            r.t_max.to_bits(),
                        )
                    })
                };
                assert_eq!(bits(got), bits(&want), "{u} from {point:?}");
                kinds[usize::from(want.is_some_and(|s| s.shadow_ray.t_max == f32::INFINITY))] += 1;
            }
        }
    }
    // Both kinds were compared: lights at a finite distance and lights infinitely far away.
    assert!(kinds[0] > 500 && kinds[1] > 500, "{kinds:?}");
}

/// `escaped_each` finds, lane by lane and in the same order, what `escaped` finds: two maps
/// (one sampled uniformly), a sun of 0.5° (directions on it and off it) and the constant
/// environment, along directions at the poles, the seam and all around.
#[test]
fn escaping_together_is_escaping_one_by_one() {
    use crate::film::Film;
    use crate::light::{EnvironmentMap, SunLight};
    use crate::sampling::Pcg32;
    let map = |w: u32, h: u32| {
        let pixels = (0..w * h).map(|i| Vec3::new((i % 7) as f32, 0.5, (i % 3) as f32)).collect();
        let film = Film::from_pixels(w, h, pixels);
        Arc::new(EnvironmentMap::new("m", film, 1.0, glam::Mat3::IDENTITY).unwrap())
    };
    let sun_direction = Vec3::new(0.2, 1.0, 0.1).normalize();
    let mut scene = Scene::built_in("cornell").unwrap();
    scene.lights.push(Light::EnvironmentMap(map(32, 17)));
    scene
        .lights
        .push(Light::Sun(SunLight::new(sun_direction, 0.5f32.to_radians(), Vec3::ONE).unwrap()));
    scene.lights.push(Light::Environment { radiance: Vec3::splat(0.25) });
    scene.lights.push(Light::EnvironmentMap(map(8, 5)));
    for sampling in [EnvironmentSampling::Importance, EnvironmentSampling::Uniform] {
        let lights = LightSet::new(&scene).with_environment_sampling(sampling);
        let mut rng = Pcg32::new(48, 4);
        let mut directions: Vec<Vec3> = (0..200)
            .map(|_| {
                let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
                v.normalize()
            })
            .collect();
        directions.extend([Vec3::Y, -Vec3::Y, -Vec3::Z, Vec3::Z, -sun_direction, -sun_direction]);
        let mut found = vec![Vec::new(); directions.len()];
        let mut scratch = vec![Emission::NONE; directions.len()];
        lights.escaped_each(&directions, &mut scratch, |lane, e| found[lane].push(e));
        let mut suns = 0;
        for (direction, got) in directions.iter().zip(&found) {
            let mut want = Vec::new();
            lights.escaped(*direction, |e| want.push(e));
            let bits = |es: &Vec<Emission>| {
                es.iter()
                    .map(|e| (e.radiance.to_array().map(f32::to_bits), e.pdf.to_bits()))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(got), bits(&want), "{direction}");
            suns += usize::from(want.len() == 4);
        }
        assert!(suns >= 2, "the sun was seen: {suns}");
    }
}
