//! The geometry shared by the writers: unit sphere, cube and cylinder meshes, capsule and
//! hull meshes, the transform of a volume, and part colours.
use bvseg_core::{BoundingVolume, ShapeView};
use glam::{DMat3, DQuat, DVec3};

/// The rotation taking local Y to a capsule's or cylinder's axis (the convention of glTF's
/// `KHR_implicit_shapes`), and local X and Z to its other two axes.
pub fn y_up_rotation(v: &BoundingVolume) -> DQuat {
    // A cyclic permutation of a right-handed frame is right-handed.
    let axes = DMat3::from_cols(v.axes.y_axis, v.axes.z_axis, v.axes.x_axis);
    if axes.determinant() < 0.0 {
        return DQuat::from_mat3(&DMat3::from_cols(-axes.x_axis, axes.y_axis, axes.z_axis))
            .normalize();
    }
    DQuat::from_mat3(&axes).normalize()
}

/// The rotation taking the unit shape's axes to the volume's axes.
pub fn volume_rotation(v: &BoundingVolume) -> DQuat {
    let mut axes = v.axes;
    // The core's frames are right-handed; should one not be, flipping an axis of a shape
    // that is symmetric about its centre describes the same solid with a proper rotation.
    if axes.determinant() < 0.0 {
        axes.z_axis = -axes.z_axis;
    }
    DQuat::from_mat3(&axes).normalize()
}

/// A distinct, stable colour (linear RGB in [0, 1]) for part `i`: hues spaced by the golden
/// angle, so neighbouring indices differ strongly.
pub fn part_color(i: usize) -> [f64; 3] {
    let h = (i as f64 * 0.618_033_988_749_895).fract() * 6.0;
    let (s, v) = (0.65, 0.95);
    let c = v * s;
    let x = c * (1.0 - (h % 2.0 - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m]
}

/// A closed, outward triangle mesh.
pub(crate) struct UnitMesh {
    pub positions: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// The unit sphere as a UV sphere with `n` segments around and `n / 2` rings; its vertices
/// lie on the sphere.
pub(crate) fn unit_sphere(n: usize) -> UnitMesh {
    let rings = n / 2;
    let mut positions = vec![DVec3::NEG_Z];
    for r in 1..rings {
        let th = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..n {
            let ph = std::f64::consts::TAU * s as f64 / n as f64;
            positions.push(DVec3::new(
                th.sin() * ph.cos(),
                th.sin() * ph.sin(),
                -th.cos(),
            ));
        }
    }
    positions.push(DVec3::Z);
    let triangles = bvseg_core::shapes::stitch_rings(rings - 1, n, positions.len());
    UnitMesh {
        normals: positions.clone(),
        positions,
        triangles,
    }
}

/// A polyhedron that encloses the unit sphere: the UV sphere scaled so that its nearest
/// face plane touches the sphere. Any affine image of it encloses the same image of the
/// sphere, so scaled by the radii it encloses the ellipsoid.
pub(crate) fn enclosing_sphere_hull(n: usize) -> UnitMesh {
    let mut m = unit_sphere(n);
    let inradius = m
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            (b - a).cross(c - a).normalize().dot(a).abs()
        })
        .fold(f64::INFINITY, f64::min);
    for p in &mut m.positions {
        *p /= inradius;
    }
    m
}

/// The cube [-1, 1]^3 with flat faces (four vertices per face, for sharp normals).
pub(crate) fn unit_cube() -> UnitMesh {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let n = DVec3::from_array(std::array::from_fn(|j| if j == axis { sign } else { 0.0 }));
            // Two in-face directions with u x v = n.
            let u = DVec3::from_array(std::array::from_fn(|j| {
                if j == (axis + 1) % 3 {
                    1.0
                } else {
                    0.0
                }
            }));
            let v = n.cross(u);
            let base = positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push(n + u * a + v * b);
                normals.push(n);
            }
            triangles.push([base, base + 1, base + 2]);
            triangles.push([base, base + 2, base + 3]);
        }
    }
    UnitMesh {
        positions,
        normals,
        triangles,
    }
}

/// The cylinder of radius 1 along Y from -1 to 1, `n` segments around, flat caps.
pub(crate) fn unit_cylinder(n: usize) -> UnitMesh {
    let (mut positions, mut normals, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
    let around = |s: usize| {
        let ph = std::f64::consts::TAU * s as f64 / n as f64;
        DVec3::new(ph.cos(), 0.0, -ph.sin())
    };
    // The side: two rings with radial normals.
    for s in 0..n {
        let d = around(s);
        positions.extend([d - DVec3::Y, d + DVec3::Y]);
        normals.extend([d, d]);
    }
    for s in 0..n {
        let (a, b) = (2 * s as u32, 2 * ((s + 1) % n) as u32);
        triangles.push([a, b, b + 1]);
        triangles.push([a, b + 1, a + 1]);
    }
    // The caps: a fan around each centre.
    for sign in [-1.0, 1.0] {
        let base = positions.len() as u32;
        let up = DVec3::Y * sign;
        positions.push(up);
        normals.push(up);
        for s in 0..n {
            positions.push(around(s) + up);
            normals.push(up);
        }
        for s in 0..n as u32 {
            let (a, b) = (base + 1 + s, base + 1 + (s + 1) % n as u32);
            triangles.push(if sign > 0.0 {
                [base, a, b]
            } else {
                [base, b, a]
            });
        }
    }
    UnitMesh {
        positions,
        normals,
        triangles,
    }
}

/// A capsule of radius `r` around the segment from `-h` to `h` on Y, `n` segments around.
pub(crate) fn capsule_mesh(r: f64, h: f64, n: usize) -> UnitMesh {
    let sphere = unit_sphere(n);
    // The UV sphere's rings run along its Z: the lower half moves down by h, the upper up.
    let mut positions = Vec::with_capacity(sphere.positions.len());
    let mut normals = Vec::with_capacity(sphere.positions.len());
    for &p in &sphere.positions {
        let q = DVec3::new(p.x, p.z, -p.y);
        normals.push(q);
        positions.push(q * r + DVec3::Y * if q.y >= 0.0 { h } else { -h });
    }
    UnitMesh {
        positions,
        normals,
        triangles: sphere.triangles,
    }
}

/// A hull's triangles around its centre (world minus centre), with flat normals.
pub(crate) fn hull_mesh(v: &BoundingVolume) -> UnitMesh {
    let (mut positions, mut normals, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
    let Some(p) = v.polytope() else {
        return UnitMesh {
            positions,
            normals,
            triangles,
        };
    };
    let local = |t: DVec3| v.world(t) - v.center;
    for tri in p.triangles() {
        let [a, b, c] = tri.map(|i| local(p.vertices()[i as usize]));
        let n = (b - a).cross(c - a).normalize_or_zero();
        let base = positions.len() as u32;
        positions.extend([a, b, c]);
        normals.extend([n, n, n]);
        triangles.push([base, base + 1, base + 2]);
    }
    UnitMesh {
        positions,
        normals,
        triangles,
    }
}

/// A hull's distinct vertices around its centre and its triangles over them.
pub(crate) fn hull_vertices(v: &BoundingVolume) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    match v.polytope() {
        Some(p) => (
            p.vertices()
                .iter()
                .map(|&t| v.world(t) - v.center)
                .collect(),
            p.triangles().to_vec(),
        ),
        None => (Vec::new(), Vec::new()),
    }
}

/// The vertices, around the volume's centre (world minus centre), of the convex polyhedron
/// an engine gets for a kind it has no shape of: a hull's own vertices; for an ellipsoid an
/// enclosing polyhedron (a 12-segment UV sphere whose faces touch the ellipsoid from outside,
/// 62 vertices); empty for the other kinds, which engines take natively.
pub fn enclosing_points(v: &BoundingVolume) -> Vec<DVec3> {
    match v.view() {
        ShapeView::Hull { .. } => hull_vertices(v).0,
        ShapeView::Ellipsoid { axes, radii, .. } => enclosing_sphere_hull(12)
            .positions
            .iter()
            .map(|&p| axes * (p * radii))
            .collect(),
        ShapeView::Obb { .. }
        | ShapeView::Sphere { .. }
        | ShapeView::Capsule { .. }
        | ShapeView::Cylinder { .. } => Vec::new(),
    }
}

/// A display mesh of any volume in world space: positions and triangles (UV spheres for the
/// curved kinds, `n` segments around).
pub(crate) fn world_triangles(v: &BoundingVolume, n: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let placed = |m: UnitMesh, q: DQuat, scale: DVec3| {
        let p = m
            .positions
            .iter()
            .map(|&p| v.center + q * (p * scale))
            .collect();
        (p, m.triangles)
    };
    match v.view() {
        // A sphere is its frame with three equal radii: one mapping for the three kinds.
        ShapeView::Ellipsoid { .. } | ShapeView::Sphere { .. } => {
            let m = unit_sphere(n);
            (world_mesh(v, &m), m.triangles)
        }
        ShapeView::Obb { .. } => {
            let m = unit_cube();
            (world_mesh(v, &m), m.triangles)
        }
        ShapeView::Cylinder {
            half_length,
            radius,
            ..
        } => placed(
            unit_cylinder(n),
            y_up_rotation(v),
            DVec3::new(radius, half_length, radius),
        ),
        ShapeView::Capsule {
            half_length,
            radius,
            ..
        } => placed(
            capsule_mesh(radius, half_length, n),
            y_up_rotation(v),
            DVec3::ONE,
        ),
        ShapeView::Hull { .. } => {
            let (p, t) = hull_vertices(v);
            (p.into_iter().map(|p| p + v.center).collect(), t)
        }
    }
}

/// The mesh of `v`'s shape, mapped into world space.
pub(crate) fn world_mesh(v: &BoundingVolume, unit: &UnitMesh) -> Vec<DVec3> {
    let axes: DMat3 = v.axes;
    unit.positions
        .iter()
        .map(|&p| v.center + axes * (p * v.radii))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use bvseg_core::Shape;

    fn volume(m: &UnitMesh) -> f64 {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn unit_meshes_are_closed_and_outward() {
        assert!((volume(&unit_cube()) - 8.0).abs() < 1e-12);
        let s = volume(&unit_sphere(24));
        assert!(s > 4.0 && s < 4.0 / 3.0 * std::f64::consts::PI, "{s}");
        let h = enclosing_sphere_hull(12);
        assert!(volume(&h) > 4.0 / 3.0 * std::f64::consts::PI);
        // Every face plane is at distance >= 1 from the centre.
        for t in &h.triangles {
            let [a, b, c] = t.map(|i| h.positions[i as usize]);
            assert!((b - a).cross(c - a).normalize().dot(a) >= 1.0 - 1e-12);
        }
    }

    #[test]
    fn rotation_maps_unit_axes_to_volume_axes() {
        let axes = DMat3::from_quat(DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0));
        let v = BoundingVolume::frame(Shape::Obb, DVec3::ONE, axes, DVec3::new(1.0, 2.0, 3.0));
        let q = volume_rotation(&v);
        assert!((q * DVec3::X - axes.x_axis).length() < 1e-12);
        assert!((q * DVec3::Z - axes.z_axis).length() < 1e-12);
        assert_ne!(part_color(0), part_color(1));
        let c = BoundingVolume::capsule(DVec3::ONE, axes.x_axis, 1.0, 0.5);
        assert!((y_up_rotation(&c) * DVec3::Y - axes.x_axis).length() < 1e-12);
    }

    #[test]
    fn every_kind_has_a_closed_world_mesh_inside_or_on_it() {
        let axes = DMat3::from_quat(DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0));
        let pts: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new(
                    (i & 1) as f64,
                    ((i >> 1) & 1) as f64,
                    ((i >> 2) & 1) as f64 * 2.0,
                )
            })
            .collect();
        for v in [
            BoundingVolume::sphere(DVec3::ONE, 2.0),
            BoundingVolume::capsule(DVec3::ONE, axes.y_axis, 1.5, 0.5),
            BoundingVolume::cylinder(DVec3::ONE, axes.z_axis, 1.5, 0.5),
            BoundingVolume::hull(&pts).unwrap(),
        ] {
            let (p, t) = world_triangles(&v, 24);
            let vol: f64 = t
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| p[i as usize] - v.center);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum();
            // Outward, and a little smaller than the solid (vertices on its boundary).
            assert!(
                vol > 0.9 * v.volume() && vol <= v.volume() * (1.0 + 1e-9),
                "{:?}: {vol} vs {}",
                v.shape,
                v.volume()
            );
            assert!(p.iter().all(|&q| v.gauge(q) <= 1.0 + 1e-9), "{:?}", v.shape);
            assert!(p.iter().any(|&q| v.gauge(q) >= 1.0 - 1e-9), "{:?}", v.shape);
        }
    }
}
