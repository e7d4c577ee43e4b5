use super::*;
use crate::accel::Hit;
use crate::mesh::CornerAttribute;
use crate::ray::Ray;

fn quad(name: &str) -> Mesh {
    Mesh {
        name: name.into(),
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        ..Mesh::default()
    }
}

#[test]
fn meshes_append_with_offsets_transforms_and_materials() {
    let mut geometry = Geometry::new();
    geometry.add_mesh(&quad("a"), &Affine3A::IDENTITY, |_| 0);
    let moved = Affine3A::from_translation(Vec3::Z * 2.0);
    geometry.add_mesh(&quad("b"), &moved, |i| i as u32 + 1);
    assert_eq!(geometry.len(), 4);
    assert_eq!(
        geometry.triangle(3),
        [Vec3::Z * 2.0, Vec3::new(1.0, 1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)]
    );
    assert_eq!(geometry.material_ids(), &[0, 0, 1, 2]);
    assert_eq!(geometry.normal(2), Vec3::Z, "counter-clockwise seen from +z");
    assert_eq!(geometry.mesh_of(1).unwrap().name, "a");
    assert_eq!(geometry.mesh_of(2).unwrap().name, "b");
    assert!(geometry.mesh_of(4).is_none());
    assert_eq!(geometry.bounds(), Some((Vec3::ZERO, Vec3::new(1.0, 1.0, 2.0))));
    assert_eq!(geometry.area(0), 0.5);
}

#[test]
fn interactions_interpolate_normals_and_uvs() {
    let normals = CornerAttribute {
        values: vec![Vec3::Z, Vec3::new(1.0, 0.0, 1.0).normalize()],
        triangles: vec![[0, 1, 0], [0, 0, 0]],
    };
    let uvs = CornerAttribute {
        values: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
        triangles: quad("").triangles,
    };
    let mut geometry = Geometry::new();
    // A mesh without attributes first: it gets defaults when the second brings some.
    geometry.add_mesh(&quad("plain"), &Affine3A::IDENTITY, |_| 7);
    let scale = Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0));
    let smooth = Mesh { normals: Some(normals), uvs: Some(uvs), ..quad("smooth") };
    geometry.add_mesh(&smooth, &scale, |_| 3);
    let ray = Ray::new(Vec3::new(2.0, 0.0, 1.0), -Vec3::Z);
    // Triangle 2 is (0,0)-(2,0)-(2,1); the hit is its corner v1.
    let hit = Hit { t: 1.0, triangle: 2, b1: 1.0, b2: 0.0 };
    let si = geometry.interaction(&ray, &hit);
    assert_eq!(si.point.p, Vec3::new(2.0, 0.0, 0.0));
    assert_eq!(si.material, 3);
    assert_eq!(si.uv, Vec2::X);
    // u runs along x, over 2 units of the scaled quad: dp/du = (2, 0, 0).
    assert!((si.dp_du - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6, "{}", si.dp_du);
    // (1, 0, 1) through the inverse transpose of diag(2, 1, 1): (0.5, 0, 1), normalized.
    let expected = Vec3::new(0.5, 0.0, 1.0).normalize();
    assert!((si.shading_normal - expected).length() < 1e-6, "{}", si.shading_normal);
    // The plain mesh: geometric normal and barycentric uvs.
    let si = geometry.interaction(&ray, &Hit { t: 1.0, triangle: 0, b1: 0.25, b2: 0.5 });
    assert_eq!((si.shading_normal, si.uv, si.material), (Vec3::Z, Vec2::new(0.25, 0.5), 7));
    // Without UVs, Mitsuba's dp/du: the first edge.
    assert_eq!(si.dp_du, Vec3::X);
    assert!(si.point.error.max_element() < 1e-6);
}

/// The path tracer's shortcut gives the interaction's point, shading normal, material, texture
/// coordinates and `dp/du` exactly (bit for bit), with and without shading normals (interpolated,
/// unset and cancelling) and UVs, and no point through an instance.
#[test]
fn shaded_surface_points_are_the_interactions_on_unplaced_triangles() {
    let smooth = CornerAttribute {
        values: vec![
            Vec3::new(0.3, -0.2, 0.9).normalize(),
            Vec3::new(-0.5, 0.1, 0.8).normalize(),
            -Vec3::Z,
        ],
        triangles: vec![[0, 1, 2], [2, 1, 0]],
    };
    // Unset corners (zero) on the first triangle; normals that cancel at the second's centre.
    let partial = CornerAttribute {
        values: vec![Vec3::ZERO, Vec3::X, -Vec3::X, Vec3::Y],
        triangles: vec![[0, 0, 0], [1, 2, 3]],
    };
    let mut geometry = Geometry::new();
    geometry.add_mesh(&quad("plain"), &Affine3A::from_rotation_x(0.3), |i| 4 + i as u32);
    let uvs = CornerAttribute {
        values: vec![Vec2::new(0.1, 0.9), Vec2::new(3.7, -0.2), Vec2::new(0.4, 0.45), Vec2::ONE],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let smooth = Mesh { normals: Some(smooth), uvs: Some(uvs), ..quad("smooth") };
    geometry.add_mesh(&smooth, &Affine3A::IDENTITY, |_| 0);
    geometry.add_mesh(
        &Mesh { normals: Some(partial), ..quad("partial") },
        &Affine3A::IDENTITY,
        |_| 1,
    );
    let ray = Ray::new(Vec3::new(0.3, 0.2, 5.0), -Vec3::Z);
    let mut interpolated = 0;
    for triangle in 0..6 {
        for (b1, b2) in
            [(0.1f32, 0.7f32), (1.0, 0.0), (0.3, 0.3), (0.0, 0.5), (0.5, 0.5), (0.5, 0.0)]
        {
            let hit = Hit { t: 4.9, triangle, b1, b2 };
            let si = geometry.interaction(&ray, &hit);
            let expected = (si.point, si.shading_normal, si.material);
            assert_eq!(geometry.shaded_surface_point(&hit), Some(expected), "{hit:?}");
            let bits = |uv: Vec2| uv.to_array().map(f32::to_bits);
            assert_eq!(bits(geometry.uv(&hit)), bits(si.uv), "{hit:?}");
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            assert_eq!(bits(geometry.dp_du(&hit)), bits(si.dp_du), "{hit:?}");
            interpolated += usize::from(si.shading_normal != si.point.normal);
        }
    }
    assert!(interpolated >= 10, "the smooth quad's normals are interpolated: {interpolated}");
    // Through instances, one of them mirrored (its corners reordered): no shortcut point, and
    // the interaction's texture coordinates and `dp/du`.
    let mut instanced = Geometry::new();
    let mirrored = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let uvs = CornerAttribute {
        values: vec![Vec2::new(0.1, 0.9), Vec2::new(3.7, -0.2), Vec2::new(0.4, 0.45), Vec2::ONE],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let textured = Mesh { uvs: Some(uvs), ..quad("q") };
    instanced.add_instanced_mesh(&textured, &[Affine3A::IDENTITY, mirrored], |_| 0);
    for triangle in 0..4 {
        let hit = Hit { t: 1.0, triangle, b1: 0.2, b2: 0.3 };
        assert_eq!(instanced.shaded_surface_point(&hit), None);
        let si = instanced.interaction(&ray, &hit);
        let bits2 = |uv: Vec2| uv.to_array().map(f32::to_bits);
        let bits3 = |v: Vec3| v.to_array().map(f32::to_bits);
        assert_eq!(bits2(instanced.uv(&hit)), bits2(si.uv), "{hit:?}");
        assert_eq!(bits3(instanced.dp_du(&hit)), bits3(si.dp_du), "{hit:?}");
    }
}

#[test]
fn shading_normals_are_kept_as_the_mesh_gives_them() {
    let normals = CornerAttribute { values: vec![-Vec3::Z], triangles: vec![[0, 0, 0]; 2] };
    let mut geometry = Geometry::new();
    let flipped = Mesh { normals: Some(normals), ..quad("flipped") };
    geometry.add_mesh(&flipped, &Affine3A::IDENTITY, |_| 0);
    let si = geometry
        .interaction(&Ray::new(Vec3::Z, -Vec3::Z), &Hit { t: 1.0, triangle: 0, b1: 0.3, b2: 0.3 });
    assert_eq!(si.shading_normal, -Vec3::Z);
    assert_eq!(si.point.normal, Vec3::Z);
}

/// A quad with every corner attribute, drawn through placements (one a mirror) and flattened
/// (`Mesh::append_transformed`, which turns a mirrored copy's corners): scene triangle for scene
/// triangle, the same corners, normals and interactions.
#[test]
fn instances_look_like_their_flattened_copies() {
    use crate::mesh::CornerAttribute;
    let n = Vec3::new(0.2, 0.1, 1.0).normalize();
    let mesh = Mesh {
        normals: Some(CornerAttribute {
            values: vec![Vec3::Z, n, -n],
            triangles: vec![[0, 1, 2], [0, 2, 1]],
        }),
        uvs: Some(CornerAttribute {
            values: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
            triangles: quad("").triangles,
        }),
        tangents: Some(CornerAttribute {
            values: vec![Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 1.0, 0.0, -1.0)],
            triangles: vec![[0, 0, 1], [1, 0, 0]],
        }),
        ..quad("q")
    };
    let transforms = [
        Affine3A::from_scale_rotation_translation(
            Vec3::new(2.0, 0.5, 1.0),
            glam::Quat::from_rotation_x(0.7),
            Vec3::new(1.0, 2.0, 3.0),
        ),
        Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0)),
    ];
    let mut instanced = Geometry::new();
    instanced.add_mesh(&quad("plain"), &Affine3A::IDENTITY, |_| 9);
    instanced.add_instanced_mesh(&mesh, &transforms, |i| i as u32);
    let mut flat_mesh = Mesh::default();
    for t in &transforms {
        flat_mesh.append_transformed(&mesh, t);
    }
    let mut flat = Geometry::new();
    flat.add_mesh(&quad("plain"), &Affine3A::IDENTITY, |_| 9);
    flat.add_mesh(&flat_mesh, &Affine3A::IDENTITY, |i| i as u32 % 2);
    assert_eq!((instanced.len(), instanced.stored_len(), flat.len()), (6, 4, 6));
    for i in 0..6 {
        let (a, b) = (instanced.triangle(i), flat.triangle(i));
        assert!(a.iter().zip(&b).all(|(p, q)| p.abs_diff_eq(*q, 1e-6)), "{i}: {a:?} {b:?}");
        assert!(instanced.normal(i).abs_diff_eq(flat.normal(i), 1e-6), "{i}");
        assert_eq!(instanced.material_id(i), flat.material_id(i));
        let hit = Hit { t: 1.0, triangle: i as u32, b1: 0.2, b2: 0.3 };
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        let (x, y) = (instanced.interaction(&ray, &hit), flat.interaction(&ray, &hit));
        assert!(x.point.p.abs_diff_eq(y.point.p, 1e-6), "{i}");
        assert!(x.shading_normal.abs_diff_eq(y.shading_normal, 1e-6), "{i}");
        assert!(x.uv.abs_diff_eq(y.uv, 1e-6) && x.dp_du.abs_diff_eq(y.dp_du, 1e-5), "{i}");
        assert!(x.tangent.abs_diff_eq(y.tangent, 1e-6), "{i}: {} {}", x.tangent, y.tangent);
    }
    // The mirrored copy's front side is still +z seen through the mirror (x ↦ −x keeps z).
    assert_eq!(instanced.normal(4), Vec3::Z);
    assert_eq!(instanced.mesh_of(5).unwrap().name, "q");
    // Scaling the scene scales every copy.
    let scaled = instanced.scaled(3.0);
    for i in 0..6 {
        let (a, b) = (scaled.triangle(i), instanced.triangle(i));
        assert!(a.iter().zip(&b).all(|(p, q)| p.abs_diff_eq(*q * 3.0, 1e-5)), "{i}");
    }
    let ((lo, hi), (lo3, hi3)) = (instanced.bounds().unwrap(), scaled.bounds().unwrap());
    assert!(lo3.abs_diff_eq(lo * 3.0, 1e-5) && hi3.abs_diff_eq(hi * 3.0, 1e-5));
}
