//! Small meshes, volumes and a random source for the unit tests (the crate has no access to
//! the core's `shapes` or `rng`, by design).
use glam::{DMat3, DVec3};

use crate::Volume;

/// A mesh as [`crate::verify`] takes it.
pub(crate) use bvseg_testkit::geometry::Arrays;

/// A box with centre `c`, half extents `half` along the columns of `rot`, facing outward.
pub(crate) fn cuboid(c: DVec3, half: DVec3, rot: DMat3) -> Arrays {
    let v = (0..8)
        .map(|i| {
            let s = DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            (c + rot * (s * half)).to_array()
        })
        .collect();
    let t = bvseg_testkit::geometry::BOX_TRIANGLES.to_vec();
    (v, t)
}

/// A UV ellipsoid about the origin with semi-axes `radii`: `n` segments around, `n / 2`
/// rings, facing outward.
pub(crate) fn ellipsoid_mesh(radii: DVec3, n: usize) -> Arrays {
    let rings = n / 2;
    let mut v = vec![[0.0, 0.0, -radii.z]];
    for r in 1..rings {
        let th = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..n {
            let ph = std::f64::consts::TAU * s as f64 / n as f64;
            let u = DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), -th.cos());
            v.push((u * radii).to_array());
        }
    }
    v.push([0.0, 0.0, radii.z]);
    let m = rings - 1;
    let top = (v.len() - 1) as u32;
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
    (v, t)
}

/// A torus about the z axis: tube radius `small` at distance `big`, `n` segments around and
/// `n / 2` around the tube, facing outward.
pub(crate) fn torus(big: f64, small: f64, n: usize) -> Arrays {
    let m = n / 2;
    let mut v = Vec::new();
    for i in 0..n {
        let u = std::f64::consts::TAU * i as f64 / n as f64;
        for j in 0..m {
            let w = std::f64::consts::TAU * j as f64 / m as f64;
            let rr = big + small * w.cos();
            v.push([rr * u.cos(), rr * u.sin(), small * w.sin()]);
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
    (v, t)
}

/// A box volume whose frame is the columns of `rot` (the file's rows).
pub(crate) fn obb(c: DVec3, half: DVec3, rot: DMat3) -> Volume {
    Volume::Obb {
        center: c.to_array(),
        axes: [rot.x_axis, rot.y_axis, rot.z_axis].map(|a| a.to_array()),
        half_extents: half.to_array(),
    }
}

/// A ball volume.
pub(crate) fn sphere(c: DVec3, radius: f64) -> Volume {
    Volume::Sphere {
        center: c.to_array(),
        radius,
    }
}

/// A capsule volume about `axis` (normalised here).
pub(crate) fn capsule(c: DVec3, axis: DVec3, half_length: f64, radius: f64) -> Volume {
    Volume::Capsule {
        center: c.to_array(),
        axis: axis.normalize().to_array(),
        half_length,
        radius,
    }
}

/// A cylinder volume about `axis` (normalised here).
pub(crate) fn cylinder(c: DVec3, axis: DVec3, half_length: f64, radius: f64) -> Volume {
    Volume::Cylinder {
        center: c.to_array(),
        axis: axis.normalize().to_array(),
        half_length,
        radius,
    }
}

/// A hull volume of `points`.
pub(crate) fn hull_volume(points: &[DVec3]) -> Volume {
    Volume::Hull {
        points: points.iter().map(|p| p.to_array()).collect(),
    }
}

/// A closed surface of revolution about z: `profile` lists `(rho, z)` from the bottom pole
/// (rho = 0) to the top pole (rho = 0), `n` segments around, facing outward; then rotated by
/// `rot` and moved to `c`.
pub(crate) fn revolution(profile: &[(f64, f64)], n: usize, c: DVec3, rot: DMat3) -> Arrays {
    let m = profile.len() - 2;
    let place = |p: DVec3| (c + rot * p).to_array();
    let mut v = vec![place(DVec3::new(0.0, 0.0, profile[0].1))];
    for &(rho, z) in &profile[1..=m] {
        for s in 0..n {
            let ph = std::f64::consts::TAU * s as f64 / n as f64;
            v.push(place(DVec3::new(rho * ph.cos(), rho * ph.sin(), z)));
        }
    }
    v.push(place(DVec3::new(0.0, 0.0, profile[m + 1].1)));
    let top = (v.len() - 1) as u32;
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
    (v, t)
}

/// A capsule about the z axis of `rot`, centred at `c`: half length `h`, radius `r`, with
/// `rings` latitude steps per hemisphere and `n` segments around; every vertex on the
/// capsule's surface.
pub(crate) fn capsule_mesh(c: DVec3, rot: DMat3, h: f64, r: f64, rings: usize, n: usize) -> Arrays {
    let mut profile = Vec::new();
    let quarter = std::f64::consts::FRAC_PI_2;
    for k in 0..=rings {
        let phi = -quarter + quarter * k as f64 / rings as f64;
        profile.push((r * phi.cos(), -h + r * phi.sin()));
    }
    for k in 0..=rings {
        let phi = quarter * k as f64 / rings as f64;
        profile.push((r * phi.cos(), h + r * phi.sin()));
    }
    profile[0].0 = 0.0;
    let last = profile.len() - 1;
    profile[last].0 = 0.0;
    revolution(&profile, n, c, rot)
}

/// SplitMix64: a tiny deterministic random source.
pub(crate) struct SplitMix(u64);

impl SplitMix {
    pub(crate) fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub(crate) fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [-1, 1).
    pub(crate) fn signed(&mut self) -> f64 {
        2.0 * self.next_f64() - 1.0
    }
}
