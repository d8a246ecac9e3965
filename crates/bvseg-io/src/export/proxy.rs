//! The geometry shared by the writers: unit sphere and cube meshes, the transform of a
//! volume, and part colours.
use bvseg_core::BoundingVolume;
use glam::{DMat3, DQuat, DVec3};

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
        let v = BoundingVolume {
            shape: bvseg_core::Shape::Obb,
            center: DVec3::ONE,
            axes,
            radii: DVec3::new(1.0, 2.0, 3.0),
        };
        let q = volume_rotation(&v);
        assert!((q * DVec3::X - axes.x_axis).length() < 1e-12);
        assert!((q * DVec3::Z - axes.z_axis).length() < 1e-12);
        assert_ne!(part_color(0), part_color(1));
    }
}
