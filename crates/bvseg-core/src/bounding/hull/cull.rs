//! The cheap tests that spare most points the exact ones: an ellipsoid inside the initial
//! polytope, whose points are dropped at once, and a map from directions to the faces a ray
//! may leave through, so that each other point is tested against a few faces, not all.
use crate::math;
use glam::{DMat3, DVec3};

/// An ellipsoid inside a polytope: centred at `c`, shaped like the covariance of the polytope's
/// vertices, as large as the nearest face plane allows. Membership costs a few multiplications.
pub(super) struct InnerEllipsoid {
    c: DVec3,
    /// Rows of the whitening map `Lambda^-1/2 V^T`.
    w: [DVec3; 3],
    /// Squared scale, with a margin; negative when unusable.
    s2: f64,
}

impl InnerEllipsoid {
    pub(super) fn new(
        verts: &[DVec3],
        c: DVec3,
        planes: impl Iterator<Item = (DVec3, DVec3)>,
    ) -> Self {
        let mut cov = DMat3::ZERO;
        for &v in verts {
            let d = v - c;
            cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        let (vals, vecs) = crate::linalg::sym_eigen(cov);
        let unusable = Self {
            c,
            w: [DVec3::ZERO; 3],
            s2: -1.0,
        };
        if vals.z.is_nan() || vals.z <= vals.x * 1e-12 {
            return unusable;
        }
        let w = [0, 1, 2].map(|k| vecs.col(k) / vals[k].sqrt());
        let mut s2 = f64::INFINITY;
        for (n, a) in planes {
            // Support of the unit ellipsoid in direction n is |Lambda^1/2 V^T n|.
            let vn = vecs.transpose() * n;
            let support = (vn * vals.map(f64::sqrt)).length();
            let t = n.dot(a - c) / support;
            if t.is_nan() || t <= 0.0 {
                return unusable;
            }
            s2 = math::min(s2, t * t);
        }
        // A relative margin far above the rounding of `contains`.
        Self {
            c,
            w,
            s2: s2 * (1.0 - 1e-9),
        }
    }

    #[inline]
    pub(super) fn contains(&self, x: DVec3) -> bool {
        let d = x - self.c;
        let t = DVec3::new(self.w[0].dot(d), self.w[1].dot(d), self.w[2].dot(d));
        t.length_squared() < self.s2
    }
}

/// For rays from a point `c` strictly inside a polytope: a cube map of directions whose cells
/// list every face the ray may leave through. Seen from `c`, a face covers a convex cone of
/// directions; within one side of the cube that cone is the face clipped to the side's cone,
/// and its central projection on the side's plane is the convex polygon of the clipped
/// corners' projections. The face is listed in every cell of that polygon's bounding box,
/// widened by a margin far above rounding, which is conservative.
pub(super) struct DirMap {
    g: usize,
    start: Vec<u32>,
    list: Vec<u32>,
}

impl DirMap {
    /// Relative widening of the side cones and of the projected boxes.
    const MARGIN: f64 = 1e-7;

    pub(super) fn new(c: DVec3, faces: impl ExactSizeIterator<Item = [DVec3; 3]>) -> Self {
        // Cells about as many as the faces, so that few faces are listed in each.
        let g = ((faces.len() as f64 / 6.0).sqrt() * 2.0)
            .ceil()
            .clamp(1.0, 32.0) as usize;
        let ncell = 6 * g * g;
        let gh = 0.5 * g as f64;
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        // Faces too close to `c` to project reliably: listed for every direction.
        let mut global = Vec::new();
        for (k, t) in faces.enumerate() {
            let t = t.map(|v| v - c);
            // A face whose plane passes (nearly) through `c` would project to infinity.
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let scale = t.iter().map(|v| v.length()).fold(0.0f64, math::max);
            let dist = n.dot(t[0]);
            let far_enough = dist.abs() > 1e-6 * n.length() * scale;
            if !far_enough {
                global.push(k as u32);
                continue;
            }
            // A triangle whose corners are well inside one side's cone stays in it (the cone
            // is convex); any other is clipped to each side's slightly widened cone.
            let sides = t.map(Self::side_of);
            let one = (sides[0].is_some() && sides[0] == sides[1] && sides[1] == sides[2])
                .then_some(sides[0])
                .flatten();
            for side in 0..6 {
                let mut poly = [DVec3::ZERO; 8];
                let len = match one {
                    Some(s) if s == side => {
                        poly[..3].copy_from_slice(&t);
                        3
                    }
                    Some(_) => 0,
                    None => Self::clip(&t, side, &mut poly),
                };
                if len == 0 {
                    continue;
                }
                let (m, sg) = (side / 2, if side & 1 == 0 { 1.0 } else { -1.0 });
                let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
                for p in &poly[..len] {
                    let w = sg * p[m];
                    for (a, ax) in [(m + 1) % 3, (m + 2) % 3].into_iter().enumerate() {
                        let u = p[ax] / w;
                        lo[a] = math::min(lo[a], u);
                        hi[a] = math::max(hi[a], u);
                    }
                }
                if !(lo.iter().chain(&hi).all(|x| x.is_finite())) {
                    global.push(k as u32);
                    break;
                }
                let cell = |u: f64| ((u + 1.0) * gh).clamp(0.0, (g - 1) as f64) as usize;
                let (i0, i1) = (cell(lo[0] - Self::MARGIN), cell(hi[0] + Self::MARGIN));
                let (j0, j1) = (cell(lo[1] - Self::MARGIN), cell(hi[1] + Self::MARGIN));
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        pairs.push((((side * g + i) * g + j) as u32, k as u32));
                    }
                }
            }
        }
        global.dedup();
        for &k in &global {
            pairs.extend((0..ncell as u32).map(|cell| (cell, k)));
        }
        // Bucket by cell (a stable counting sort keeps each cell's faces in face order).
        let mut start = vec![0u32; ncell + 1];
        for &(cell, _) in &pairs {
            start[cell as usize + 1] += 1;
        }
        for i in 0..ncell {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut list = vec![0u32; pairs.len()];
        for &(cell, f) in &pairs {
            list[fill[cell as usize] as usize] = f;
            fill[cell as usize] += 1;
        }
        Self { g, start, list }
    }

    /// The cube side whose (widened) cone alone holds direction `d`, if exactly one does.
    fn side_of(d: DVec3) -> Option<usize> {
        let a = d.abs();
        let m = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (b, c) = (a[(m + 1) % 3], a[(m + 2) % 3]);
        // Near a side's edge, the widened cones of both sides hold it.
        (b < a[m] * (1.0 - 4.0 * Self::MARGIN) && c < a[m] * (1.0 - 4.0 * Self::MARGIN))
            .then_some(2 * m + usize::from(d[m] < 0.0))
    }

    /// Clips triangle `t` to the cone of cube side `side`, widened by `MARGIN`: the polygon's
    /// length in `out`.
    fn clip(t: &[DVec3; 3], side: usize, out: &mut [DVec3; 8]) -> usize {
        let (m, sg) = (side / 2, if side & 1 == 0 { 1.0 } else { -1.0 });
        let mut cur = [DVec3::ZERO; 8];
        cur[..3].copy_from_slice(t);
        let mut n = 3;
        for (ax, s) in [
            ((m + 1) % 3, 1.0),
            ((m + 1) % 3, -1.0),
            ((m + 2) % 3, 1.0),
            ((m + 2) % 3, -1.0),
        ] {
            // Keep sg * p[m] * (1 + MARGIN) - s * p[ax] >= 0.
            let f = |p: &DVec3| sg * p[m] * (1.0 + Self::MARGIN) - s * p[ax];
            let mut k = 0;
            for i in 0..n {
                let (p, q) = (cur[i], cur[(i + 1) % n]);
                let (fp, fq) = (f(&p), f(&q));
                if fp >= 0.0 {
                    out[k] = p;
                    k += 1;
                }
                if (fp >= 0.0) != (fq >= 0.0) && k < 8 {
                    out[k] = p + (q - p) * (fp / (fp - fq));
                    k += 1;
                }
            }
            n = k;
            if n == 0 {
                return 0;
            }
            cur[..n].copy_from_slice(&out[..n]);
        }
        n
    }

    #[inline]
    fn cell_of(g: usize, d: DVec3) -> usize {
        let a = d.abs();
        let m = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let s = a[m];
        if s.is_nan() || s <= 0.0 {
            return 0;
        }
        let side = 2 * m + usize::from(d[m] < 0.0);
        let k = 0.5 * g as f64 / s;
        let i = ((d[(m + 1) % 3] * k + 0.5 * g as f64) as usize).min(g - 1);
        let j = ((d[(m + 2) % 3] * k + 0.5 * g as f64) as usize).min(g - 1);
        (side * g + i) * g + j
    }

    /// The faces a ray from `c` in direction `d` may leave through.
    #[inline]
    pub(super) fn faces(&self, d: DVec3) -> &[u32] {
        let cell = Self::cell_of(self.g, d);
        &self.list[self.start[cell] as usize..self.start[cell + 1] as usize]
    }
}
