//! Todd–Yildirim: Khachiyan's coordinate ascent on the dual weights, with away and drop
//! steps, started from the Kumar–Yildirim core set; it finishes and certifies the fit.
// Small dense matrix code (N <= 4, K <= 10) reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use crate::math;

use super::barrier::barrier;
use crate::linalg::dense::{invert, quad};

/// Todd–Yildirim: dual weights and the inverse of `M(u) = sum u_i q_i q_i^T` over an active
/// set. The
/// active points are kept in contiguous arrays, since every iteration sweeps them all, and the
/// weights and `omega`s carry a common factor so that a step touches each point only once.
pub(super) struct WaTy<const N: usize> {
    /// Input index and lifted point of each active point.
    idx: Vec<usize>,
    q: Vec<[f64; N]>,
    /// Weights `u = w * ws` and `omega = q^T M^-1 q = o * os`.
    w: Vec<f64>,
    ws: f64,
    o: Vec<f64>,
    os: f64,
    minv: [[f64; N]; N],
}

impl<const N: usize> WaTy<N> {
    /// Weights for the lifted points `q`; `K = N (N + 1) / 2`.
    ///
    /// Not inlined in WebAssembly: see [`barrier`].
    #[cfg_attr(target_arch = "wasm32", inline(never))]
    pub(super) fn run<const K: usize>(q: &[[f64; N]], eps: f64) -> Option<Vec<f64>> {
        let core = core_set(q);
        let mut u0 = vec![0.0; q.len()];
        for &i in &core {
            u0[i] = 1.0 / core.len() as f64;
        }
        let n = N as f64;
        // The interior-point solve goes first, to about the target duality gap, and
        // coordinate steps certify `eps` from its weights (see the module docs). Should it
        // fail, coordinate steps start from the core set alone and grow an active set from
        // the most violated points.
        let gap = n * math::ln(1.0 + eps);
        let (idx, w) = match barrier::<N, K>(q, &u0, gap) {
            Some(u) => ((0..q.len()).collect(), u),
            None => (core.clone(), vec![1.0 / core.len() as f64; core.len()]),
        };
        let mut s = Self {
            q: idx.iter().map(|&i| q[i]).collect(),
            w,
            ws: 1.0,
            o: Vec::new(),
            os: 1.0,
            idx,
            minv: [[0.0; N]; N],
        };
        let mut active = vec![false; q.len()];
        for &i in &s.idx {
            active[i] = true;
        }
        // Each round solves on the active set, then admits the points it leaves out the most.
        // Points only join, and at most all of them, so this ends; the cap on iterations
        // guards against stagnation in floating point.
        let mut budget = 20_000 + 200 * q.len();
        loop {
            s.refresh()?;
            budget = budget.saturating_sub(s.iterate(eps, budget)?);
            s.refresh()?;
            let mut out = s.violators(q, &active, eps);
            if out.is_empty() || budget == 0 {
                let mut u = vec![0.0; q.len()];
                for (&i, &w) in s.idx.iter().zip(&s.w) {
                    u[i] = w * s.ws;
                }
                return Some(u);
            }
            // Most violated first; index breaks ties so the result is deterministic.
            out.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            for &(_, i) in out.iter().take(4 * N) {
                active[i] = true;
                s.idx.push(i);
                s.q.push(q[i]);
                s.w.push(0.0);
            }
        }
    }

    /// The inactive points with `omega > N (1 + eps)`, with their `omega`.
    fn violators(&self, q: &[[f64; N]], active: &[bool], eps: f64) -> Vec<(f64, usize)> {
        let lim = N as f64 * (1.0 + eps);
        (0..q.len())
            .filter(|&i| !active[i])
            .map(|i| (quad(&self.minv, &q[i]), i))
            .filter(|&(om, _)| om > lim)
            .collect()
    }

    /// Recomputes `M^-1` and `omega` from the weights, clearing accumulated round-off.
    fn refresh(&mut self) -> Option<()> {
        let total: f64 = self.w.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        for w in self.w.iter_mut() {
            *w /= total;
        }
        self.ws = 1.0;
        let mut m = [[0.0; N]; N];
        for (qi, &ui) in self.q.iter().zip(&self.w) {
            for a in 0..N {
                for b in 0..N {
                    m[a][b] += ui * qi[a] * qi[b];
                }
            }
        }
        self.minv = invert(m)?;
        self.o = self.q.iter().map(|qi| quad(&self.minv, qi)).collect();
        self.os = 1.0;
        Some(())
    }

    /// The active points with the largest `omega`, and with the smallest among those of
    /// positive weight (`usize::MAX` if none).
    fn extremes(&self) -> (usize, usize) {
        let (mut j, mut k) = (0, usize::MAX);
        let (mut jo, mut ko) = (f64::NEG_INFINITY, f64::INFINITY);
        for (a, (&o, &w)) in self.o.iter().zip(&self.w).enumerate() {
            if o > jo {
                (j, jo) = (a, o);
            }
            if w > 0.0 && o < ko {
                (k, ko) = (a, o);
            }
        }
        (j, k)
    }

    /// Toward and away steps on the active set until it is `eps`-primal feasible; returns the
    /// number of iterations used.
    ///
    /// Not inlined in WebAssembly: see [`barrier`].
    #[cfg_attr(target_arch = "wasm32", inline(never))]
    fn iterate(&mut self, eps: f64, budget: usize) -> Option<usize> {
        let n = N as f64;
        let (mut j, mut k) = self.extremes();
        for it in 0..budget {
            let omj = self.o[j] * self.os;
            let eps_plus = omj / n - 1.0;
            if eps_plus <= eps {
                return Some(it);
            }
            let (omk, uk) = if k == usize::MAX {
                (n, 1.0)
            } else {
                (self.o[k] * self.os, self.w[k] * self.ws)
            };
            let eps_minus = 1.0 - omk / n;
            let (a, tau, drop) = if eps_plus > eps_minus || uk >= 1.0 - 1e-12 {
                (j, (omj - n) / (n * (omj - 1.0)), false)
            } else {
                // Away from the least needed point, at most down to a zero weight.
                let t = (omk - n) / (n * math::max(omk - 1.0, 1e-300));
                let tmin = -uk / (1.0 - uk);
                if t <= tmin {
                    (k, tmin, true)
                } else {
                    (k, t, false)
                }
            };
            (j, k) = self.step(a, tau, drop)?;
            if it % 256 == 255 {
                self.refresh()?;
                (j, k) = self.extremes();
            }
        }
        Some(budget)
    }

    /// `u <- (1 - tau) u + tau e_a`, with rank-one updates of `M^-1` and `omega`; returns the
    /// new [`WaTy::extremes`], found in the same sweep.
    fn step(&mut self, a: usize, tau: f64, drop: bool) -> Option<(usize, usize)> {
        let qa = self.q[a];
        let mut v = [0.0; N];
        for (r, vr) in v.iter_mut().enumerate() {
            *vr = (0..N).map(|c| self.minv[r][c] * qa[c]).sum();
        }
        let denom = 1.0 - tau + tau * self.o[a] * self.os;
        let keep = 1.0 - tau;
        if !(denom > 0.0 && keep > 0.0) {
            return None;
        }
        // M' = keep M + tau q q^T, so M'^-1 = (M^-1 - g v v^T) / keep (Sherman–Morrison).
        let g = tau / denom;
        let inv_keep = 1.0 / keep;
        for r in 0..N {
            for c in 0..N {
                self.minv[r][c] = (self.minv[r][c] - g * v[r] * v[c]) * inv_keep;
            }
        }
        self.ws *= keep;
        if drop {
            self.w[a] = 0.0;
        } else {
            self.w[a] += tau / self.ws;
        }
        let go = g / self.os;
        self.os *= inv_keep;
        let (mut j, mut k) = (0, usize::MAX);
        let (mut jo, mut ko) = (f64::NEG_INFINITY, f64::INFINITY);
        for (b, ((o, qi), &w)) in self.o.iter_mut().zip(&self.q).zip(&self.w).enumerate() {
            let mut qv = 0.0;
            for c in 0..N {
                qv += qi[c] * v[c];
            }
            *o -= go * qv * qv;
            if *o > jo {
                (j, jo) = (b, *o);
            }
            if w > 0.0 && *o < ko {
                (k, ko) = (b, *o);
            }
        }
        Some((j, k))
    }
}

/// Kumar–Yildirim initial core set: the extreme points along `d` mutually orthogonal
/// directions, each chosen orthogonal to the spans of the previous pairs. At most `2d` points
/// whose lifted second-moment matrix is non-singular for a full-dimensional set.
pub(super) fn core_set<const N: usize>(q: &[[f64; N]]) -> Vec<usize> {
    let d = N - 1;
    let mut basis: Vec<[f64; N]> = Vec::new();
    let mut out = Vec::new();
    let dot = |a: &[f64; N], b: &[f64; N]| (0..d).map(|i| a[i] * b[i]).sum::<f64>();
    let project_out = |x: &mut [f64; N], basis: &[[f64; N]]| {
        for b in basis {
            let t = dot(x, b);
            for i in 0..d {
                x[i] -= t * b[i];
            }
        }
    };
    for _ in 0..d {
        // The coordinate axis least in the span so far.
        let mut dir = [0.0; N];
        let mut best = -1.0;
        for e in 0..d {
            let mut x = [0.0; N];
            x[e] = 1.0;
            project_out(&mut x, &basis);
            let l = dot(&x, &x);
            if l > best {
                best = l;
                dir = x;
            }
        }
        let (mut lo, mut hi) = ((f64::INFINITY, 0), (f64::NEG_INFINITY, 0));
        for (i, p) in q.iter().enumerate() {
            let t = dot(p, &dir);
            if t < lo.0 {
                lo = (t, i);
            }
            if t > hi.0 {
                hi = (t, i);
            }
        }
        out.extend([lo.1, hi.1]);
        let mut w = [0.0; N];
        for i in 0..d {
            w[i] = q[hi.1][i] - q[lo.1][i];
        }
        project_out(&mut w, &basis);
        let l = dot(&w, &w).sqrt();
        if l > 0.0 {
            basis.push(w.map(|x| x / l));
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}
