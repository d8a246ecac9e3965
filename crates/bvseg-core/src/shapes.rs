//! Closed triangle meshes of simple solids, for tests, examples and demos.
//!
//! Every mesh is closed and outward-facing. [`union`] concatenates meshes into one (possibly
//! self-intersecting) mesh, which bvseg's inside test reads as the union of the solids.
//!
//! # Panics
//!
//! The builders panic when a parameter is not finite or beyond [`crate::MAX_COORDINATE`]
//! (they are for tests and demos; build a [`Mesh`] with [`Mesh::new`] from untrusted data).
use glam::{DMat3, DVec3};

use crate::Mesh;

#[allow(clippy::expect_used)]
fn mesh(v: Vec<DVec3>, t: Vec<[u32; 3]>) -> Mesh {
    // The generators below only produce in-range indices, and finite vertices from finite
    // parameters (see the module's docs).
    Mesh::new(v, t).expect("shape parameters must be finite")
}

/// An oriented box with centre `c`, half-extents `half` and rotation `rot`.
pub fn cuboid(c: DVec3, half: DVec3, rot: DMat3) -> Mesh {
    let v = (0..8)
        .map(|i| {
            let s = DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            c + rot * (s * half)
        })
        .collect();
    let t = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    mesh(v, t)
}

/// A UV ellipsoid with centre `c`, semi-axes `radii`, rotation `rot`, and `n` segments
/// around (`n / 2` rings).
pub fn ellipsoid(c: DVec3, radii: DVec3, rot: DMat3, n: usize) -> Mesh {
    let n = n.max(4);
    let rings = (n / 2).max(2);
    let mut v = vec![c + rot * DVec3::new(0.0, 0.0, -radii.z)];
    for r in 1..rings {
        let th = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..n {
            let ph = std::f64::consts::TAU * s as f64 / n as f64;
            let u = DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), -th.cos());
            v.push(c + rot * (u * radii));
        }
    }
    v.push(c + rot * DVec3::new(0.0, 0.0, radii.z));
    let t = stitch_rings(rings - 1, n, v.len());
    mesh(v, t)
}

/// Triangles closing a surface of revolution whose vertices are: the bottom pole (index 0),
/// `m` rings of `n` vertices from bottom to top, and the top pole (index `count - 1`).
pub fn stitch_rings(m: usize, n: usize, count: usize) -> Vec<[u32; 3]> {
    let top = (count - 1) as u32;
    let ring = |r: usize, s: usize| (1 + r * n + s % n) as u32;
    let mut t = Vec::new();
    for s in 0..n {
        t.push([0, ring(0, s + 1), ring(0, s)]);
        t.push([top, ring(m - 1, s), ring(m - 1, s + 1)]);
    }
    for r in 0..m - 1 {
        for s in 0..n {
            t.push([ring(r, s), ring(r, s + 1), ring(r + 1, s + 1)]);
            t.push([ring(r, s), ring(r + 1, s + 1), ring(r + 1, s)]);
        }
    }
    t
}

/// A capsule from `a` to `b` with radius `r` (`n` segments around).
pub fn capsule(a: DVec3, b: DVec3, r: f64, n: usize) -> Mesh {
    let n = n.max(4);
    let half = (n / 4).max(2);
    let axis = b - a;
    let len = axis.length();
    let z = if len > 0.0 { axis / len } else { DVec3::Z };
    let x = z.any_orthonormal_vector();
    let rot = DMat3::from_cols(x, z.cross(x), z);
    // Rings: the lower hemisphere around a, then the upper one around b.
    let mut rings: Vec<(f64, f64)> = Vec::new(); // (height along z, radius)
    for i in 1..=half {
        let th = std::f64::consts::FRAC_PI_2 * i as f64 / half as f64;
        rings.push((-r * th.cos(), r * th.sin()));
    }
    for i in 0..half {
        let th = std::f64::consts::FRAC_PI_2 * i as f64 / half as f64;
        rings.push((len + r * th.sin(), r * th.cos()));
    }
    let mut v = vec![a + rot * DVec3::new(0.0, 0.0, -r)];
    for &(hz, rr) in &rings {
        for s in 0..n {
            let ph = std::f64::consts::TAU * s as f64 / n as f64;
            v.push(a + rot * DVec3::new(rr * ph.cos(), rr * ph.sin(), hz));
        }
    }
    v.push(a + rot * DVec3::new(0.0, 0.0, len + r));
    let t = stitch_rings(rings.len(), n, v.len());
    mesh(v, t)
}

/// A torus around the z axis with major radius `big` and minor radius `small`.
pub fn torus(c: DVec3, big: f64, small: f64, n: usize) -> Mesh {
    let n = n.max(6);
    let m = (n / 2).max(4);
    let mut v = Vec::new();
    for i in 0..n {
        let u = std::f64::consts::TAU * i as f64 / n as f64;
        for j in 0..m {
            let w = std::f64::consts::TAU * j as f64 / m as f64;
            let rr = big + small * w.cos();
            v.push(c + DVec3::new(rr * u.cos(), rr * u.sin(), small * w.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % n) * m + j % m) as u32;
    let mut t = Vec::new();
    for i in 0..n {
        for j in 0..m {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    mesh(v, t)
}

/// All meshes in one (the union of the solids under the nonzero winding rule).
pub fn union(meshes: &[Mesh]) -> Mesh {
    let mut v = Vec::new();
    let mut t = Vec::new();
    for m in meshes {
        let base = v.len() as u32;
        v.extend_from_slice(m.vertices());
        t.extend(m.triangles().iter().map(|x| x.map(|i| i + base)));
    }
    mesh(v, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_meshes_are_closed_and_outward() {
        let pi = std::f64::consts::PI;
        let cases = [
            (
                cuboid(DVec3::ONE, DVec3::new(1.0, 2.0, 3.0), DMat3::IDENTITY),
                48.0,
                1e-9,
            ),
            (
                ellipsoid(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0), DMat3::IDENTITY, 64),
                4.0 / 3.0 * pi * 6.0,
                0.02,
            ),
            (
                capsule(DVec3::ZERO, DVec3::new(0.0, 0.0, 2.0), 0.5, 64),
                pi * 0.25 * 2.0 + 4.0 / 3.0 * pi * 0.125,
                0.02,
            ),
            (
                torus(DVec3::ZERO, 2.0, 0.5, 64),
                2.0 * pi * pi * 2.0 * 0.25,
                0.02,
            ),
        ];
        for (m, vol, tol) in cases {
            let v = m.signed_volume();
            assert!((v - vol).abs() / vol < tol, "{v} vs {vol}");
            // Closed: every directed edge has its reverse.
            let mut edges = std::collections::HashMap::new();
            for t in m.triangles() {
                for e in 0..3 {
                    *edges.entry((t[e], t[(e + 1) % 3])).or_insert(0) += 1;
                }
            }
            for (&(a, b), &c) in &edges {
                assert_eq!(edges.get(&(b, a)), Some(&c));
            }
        }
    }
}
