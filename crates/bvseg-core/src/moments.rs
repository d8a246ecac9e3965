//! Stage 2: moments and e-tightness.
//!
//! A part is summarised by its sample count and the first and second moments of its sample
//! positions, relative to a fixed reference point (the grid centre) so that sums of squares
//! do not lose precision far from the origin. Adding or removing a sample is O(1), and the
//! covariance, the Legendre ellipsoid and e(S) follow in O(1).
use crate::math;
use glam::{DMat3, DVec3};

/// `20 sqrt(5) pi / 3`: vol(Legendre ellipsoid) = this * sqrt(det C).
pub const LEGENDRE_VOLUME: f64 = 20.0 * 2.236_067_977_499_79 * std::f64::consts::PI / 3.0;

/// Raw moments of a set of equal-weight samples (positions relative to a reference point).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Moments {
    /// Number of samples.
    pub n: f64,
    /// Sum of positions.
    pub s: DVec3,
    /// Sum of x x^T, packed (xx, yy, zz, xy, xz, yz).
    pub ss: [f64; 6],
}

impl Moments {
    /// Add one sample at (reference-relative) position `p`.
    #[inline]
    pub fn add(&mut self, p: DVec3) {
        self.n += 1.0;
        self.s += p;
        self.ss[0] += p.x * p.x;
        self.ss[1] += p.y * p.y;
        self.ss[2] += p.z * p.z;
        self.ss[3] += p.x * p.y;
        self.ss[4] += p.x * p.z;
        self.ss[5] += p.y * p.z;
    }

    /// Remove one sample at position `p` (which must have been added).
    #[inline]
    pub fn remove(&mut self, p: DVec3) {
        self.n -= 1.0;
        self.s -= p;
        self.ss[0] -= p.x * p.x;
        self.ss[1] -= p.y * p.y;
        self.ss[2] -= p.z * p.z;
        self.ss[3] -= p.x * p.y;
        self.ss[4] -= p.x * p.z;
        self.ss[5] -= p.y * p.z;
    }

    /// Add the `b x b x b` cells of a block centred at `c` (a cell centre when `b` is odd,
    /// a cell corner when even): the exact sums over its cells, integers for integer cell
    /// positions, so the moments stay those of the cells one by one.
    #[inline]
    pub fn add_block(&mut self, c: DVec3, b: u32) {
        let (n, s, ss) = block_sums(c, b);
        self.n += n;
        self.s += s;
        for (a, x) in self.ss.iter_mut().zip(ss) {
            *a += x;
        }
    }

    /// Remove a block added by [`Moments::add_block`].
    #[inline]
    pub fn remove_block(&mut self, c: DVec3, b: u32) {
        let (n, s, ss) = block_sums(c, b);
        self.n -= n;
        self.s -= s;
        for (a, x) in self.ss.iter_mut().zip(ss) {
            *a -= x;
        }
    }

    /// Sum of two sets' moments.
    #[inline]
    pub fn merged(&self, o: &Moments) -> Moments {
        let mut ss = self.ss;
        for (a, b) in ss.iter_mut().zip(o.ss) {
            *a += b;
        }
        Moments {
            n: self.n + o.n,
            s: self.s + o.s,
            ss,
        }
    }

    /// Mean (reference-relative).
    #[inline]
    pub fn mean(&self) -> DVec3 {
        self.s / self.n
    }

    /// Covariance of the union of the samples' cells: the point covariance plus
    /// `cell_var = h^2 / 12` on the diagonal (a uniform cube's own covariance). Packed as in
    /// [`Moments::ss`].
    #[inline]
    pub fn cov_packed(&self, cell_var: f64) -> [f64; 6] {
        let m = self.s / self.n;
        let inv = 1.0 / self.n;
        [
            self.ss[0] * inv - m.x * m.x + cell_var,
            self.ss[1] * inv - m.y * m.y + cell_var,
            self.ss[2] * inv - m.z * m.z + cell_var,
            self.ss[3] * inv - m.x * m.y,
            self.ss[4] * inv - m.x * m.z,
            self.ss[5] * inv - m.y * m.z,
        ]
    }

    /// Covariance as a matrix (see [`Moments::cov_packed`]).
    pub fn cov(&self, cell_var: f64) -> DMat3 {
        let c = self.cov_packed(cell_var);
        DMat3::from_cols(
            DVec3::new(c[0], c[3], c[4]),
            DVec3::new(c[3], c[1], c[5]),
            DVec3::new(c[4], c[5], c[2]),
        )
    }

    /// `det C`, clamped at zero.
    #[inline]
    pub fn det_cov(&self, cell_var: f64) -> f64 {
        math::max(det_packed(&self.cov_packed(cell_var)), 0.0)
    }

    /// This part's term of F, in units of the cell volume: `n * e = vol(K) / h^3`
    /// = `LEGENDRE_VOLUME * sqrt(det C) / h^3`. Summing it over parts and dividing by the
    /// total sample count gives F.
    #[inline]
    pub fn f_term(&self, cell_var: f64, inv_cell_volume: f64) -> f64 {
        if self.n <= 0.0 {
            return 0.0;
        }
        LEGENDRE_VOLUME * self.det_cov(cell_var).sqrt() * inv_cell_volume
    }

    /// e-tightness: vol(Legendre ellipsoid) / vol(part), with each sample standing for a cell
    /// of volume `cell_volume`.
    pub fn e(&self, cell_var: f64, cell_volume: f64) -> f64 {
        self.f_term(cell_var, 1.0 / cell_volume) / self.n
    }
}

/// Count, sum and packed sum of `x x^T` over the cells of a `b x b x b` block centred at
/// `c`: with the cell offsets `o` in `-(b-1)/2 ..= (b-1)/2` along each axis, `sum o = 0` and
/// `sum o^2 = b (b^2 - 1) / 12` per axis, so the sums are `b^3 c`, `b^3 c c^T` plus that
/// spread on the diagonal, all exact for block centres on the half-integer lattice.
#[inline]
fn block_sums(c: DVec3, b: u32) -> (f64, DVec3, [f64; 6]) {
    let b = f64::from(b);
    let n = b * b * b;
    let spread = b * b * (b * (b * b - 1.0) / 12.0);
    (
        n,
        n * c,
        [
            n * c.x * c.x + spread,
            n * c.y * c.y + spread,
            n * c.z * c.z + spread,
            n * c.x * c.y,
            n * c.x * c.z,
            n * c.y * c.z,
        ],
    )
}

/// Determinant of a packed symmetric matrix.
#[inline]
pub fn det_packed(c: &[f64; 6]) -> f64 {
    let [xx, yy, zz, xy, xz, yz] = *c;
    xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz)
}

/// Inverse of a packed symmetric matrix (packed the same way), or `None` if singular.
#[inline]
pub fn inv_packed(c: &[f64; 6]) -> Option<[f64; 6]> {
    let [xx, yy, zz, xy, xz, yz] = *c;
    let a00 = yy * zz - yz * yz;
    let a01 = xz * yz - xy * zz;
    let a02 = xy * yz - xz * yy;
    let det = xx * a00 + xy * a01 + xz * a02;
    if det.is_nan() || det <= 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    Some([
        a00 * inv,
        (xx * zz - xz * xz) * inv,
        (xx * yy - xy * xy) * inv,
        a01 * inv,
        a02 * inv,
        (xy * xz - xx * yz) * inv,
    ])
}

/// Quadratic form `d^T M d` of a packed symmetric matrix.
#[inline]
pub fn quad_packed(m: &[f64; 6], d: DVec3) -> f64 {
    m[0] * d.x * d.x
        + m[1] * d.y * d.y
        + m[2] * d.z * d.z
        + 2.0 * (m[3] * d.x * d.y + m[4] * d.x * d.z + m[5] * d.y * d.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Grid;

    fn moments_of(g: &Grid) -> Moments {
        let mut m = Moments::default();
        for &p in &g.points {
            m.add(p);
        }
        m
    }

    /// A block's moments are those of its cells added one by one, bit for bit, and removing
    /// it restores the moments before.
    #[test]
    fn a_block_adds_its_cells_exactly() {
        for (c, b) in [
            (DVec3::new(3.5, -2.5, 10.5), 2),
            (DVec3::new(-41.5, 7.5, 0.5), 4),
            (DVec3::new(5.0, -6.0, 7.0), 1),
        ] {
            let mut base = Moments::default();
            base.add(DVec3::new(1.0, 2.0, -3.0));
            let mut cells = base;
            let half = 0.5 * f64::from(b - 1);
            for k in 0..b {
                for j in 0..b {
                    for i in 0..b {
                        let o = DVec3::new(f64::from(i), f64::from(j), f64::from(k)) - half;
                        cells.add(c + o);
                    }
                }
            }
            let mut block = base;
            block.add_block(c, b);
            assert_eq!(block, cells, "side {b}");
            block.remove_block(c, b);
            assert_eq!(block, base, "side {b}");
        }
    }

    #[test]
    fn e_of_box_and_ellipsoid() {
        let h = 0.05;
        let b = Grid::from_inside_fn(
            DVec3::new(-1.0, -0.5, -0.3),
            DVec3::new(1.0, 0.5, 0.3),
            h,
            |p| p.x.abs() <= 1.0 && p.y.abs() <= 0.5 && p.z.abs() <= 0.3,
        );
        let e = moments_of(&b).e(h * h / 12.0, h * h * h);
        assert!((e - 1.127).abs() < 0.01, "box e = {e}");
        let r = DVec3::new(1.0, 0.6, 0.4);
        let el = Grid::from_inside_fn(-r, r, h, |p| (p / r).length_squared() <= 1.0);
        let e = moments_of(&el).e(h * h / 12.0, h * h * h);
        assert!((e - 1.0).abs() < 0.02, "ellipsoid e = {e}");
    }

    #[test]
    fn e_is_affine_invariant() {
        // The same solid (a half-ball) under a shear-and-stretch map, sampled afresh: e agrees
        // within sampling error, while the volumes differ by det(A).
        let a = DMat3::from_cols(
            DVec3::new(2.0, 0.3, 0.0),
            DVec3::new(0.0, 0.7, 0.4),
            DVec3::new(0.5, 0.0, 1.3),
        );
        let ai = a.inverse();
        let inside = |p: DVec3| p.length() <= 1.0 && p.z >= -0.2;
        let h = 0.03;
        let g1 = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), h, inside);
        let lo = DVec3::splat(-4.0);
        let g2 = Grid::from_inside_fn(lo, -lo, h, |p| inside(ai * p));
        let e1 = moments_of(&g1).e(h * h / 12.0, h * h * h);
        let e2 = moments_of(&g2).e(h * h / 12.0, h * h * h);
        assert!((e1 - e2).abs() < 0.01, "{e1} vs {e2}");
        assert!(e1 > 1.05, "a half-ball is not an ellipsoid: {e1}");
        let ratio = g2.len() as f64 / g1.len() as f64;
        assert!((ratio - a.determinant()).abs() / a.determinant() < 0.02);
    }

    #[test]
    fn add_remove_roundtrip_and_inverse() {
        let mut m = Moments::default();
        let pts = [
            DVec3::new(0.1, 0.2, 0.3),
            DVec3::new(-1.0, 0.5, 2.0),
            DVec3::new(0.7, -0.4, 0.0),
            DVec3::new(0.0, 1.0, -1.0),
        ];
        for p in pts {
            m.add(p);
        }
        let before = m;
        m.add(DVec3::new(5.0, 5.0, 5.0));
        m.remove(DVec3::new(5.0, 5.0, 5.0));
        assert!((m.s - before.s).length() < 1e-12);
        let c = m.cov_packed(0.01);
        let ci = inv_packed(&c).unwrap();
        let a = m.cov(0.01);
        let ai = a.inverse();
        let d = DVec3::new(0.3, -0.2, 0.9);
        assert!((quad_packed(&ci, d) - d.dot(ai * d)).abs() < 1e-9);
        assert!((det_packed(&c) - a.determinant()).abs() < 1e-12);
    }
}
