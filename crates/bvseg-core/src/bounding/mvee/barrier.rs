//! The primal log-barrier method that brings the duality gap near the target before
//! Todd–Yildirim certifies, and the Harman–Pronzato bound that drops points between centrings.
// Small dense matrix code (N <= 4, K <= 10) reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use crate::math;

use crate::linalg::dense::{cholesky_solve, dot, invert, log_det, quad};

/// Primal log-barrier method for the lifted MVEE of `q`: minimise `-log det H` subject to
/// `q_i^T H q_i <= 1`, over symmetric `H` (`N (N + 1) / 2` unknowns, so Newton steps are
/// cheap whatever the number of points), until the barrier's duality gap is below `gap`.
/// Starts from the ellipsoid of weights `u0` shrunk to be strictly feasible; returns the dual
/// weights of the central point reached. `None` on numerical failure.
// One function each in WebAssembly, not inlined into their one caller: the browser compiles
// the module's hot functions again while the page runs, and a giant one slowly (web/build.sh).
#[cfg_attr(target_arch = "wasm32", inline(never))]
pub(super) fn barrier<const N: usize, const K: usize>(
    q: &[[f64; N]],
    u0: &[f64],
    gap: f64,
) -> Option<Vec<f64>> {
    // Unknowns: the upper triangle of H, so that q^T H q = phi(q) . h.
    let pairs: [(usize, usize); K] = (0..N)
        .flat_map(|a| (a..N).map(move |b| (a, b)))
        .collect::<Vec<_>>()
        .try_into()
        .ok()?;
    // Stored by column, so that the sums over points below are plain dot products.
    let mut phi: [Vec<f64>; K] = std::array::from_fn(|p| {
        let (a, b) = pairs[p];
        let f = if a == b { 1.0 } else { 2.0 };
        q.iter().map(|x| f * x[a] * x[b]).collect()
    });
    // The data part of the Hessian, sum c_i phi_p(q_i) phi_r(q_i), only involves the
    // `C(N + 3, 4)` distinct monomials of degree 4 in the lifted coordinates: one weighted sum
    // per monomial instead of one per entry. `quartic[p][r]` is the monomial of entry (p, r).
    let mut monos: Vec<[usize; 4]> = Vec::new();
    for a in 0..N {
        for b in a..N {
            for c in b..N {
                for e in c..N {
                    monos.push([a, b, c, e]);
                }
            }
        }
    }
    let mut mono: Vec<Vec<f64>> = monos
        .iter()
        .map(|&[a, b, c, e]| q.iter().map(|x| x[a] * x[b] * x[c] * x[e]).collect())
        .collect();
    let quartic: [[usize; K]; K] = std::array::from_fn(|p| {
        std::array::from_fn(|r| {
            let mut k = [pairs[p].0, pairs[p].1, pairs[r].0, pairs[r].1];
            k.sort_unstable();
            monos.iter().position(|&m| m == k).unwrap_or(0)
        })
    });
    let pair_f: [f64; K] = pairs.map(|(a, b)| if a == b { 1.0 } else { 2.0 });
    let mut moment = vec![0.0; monos.len()];
    let to_mat = |h: &[f64; K]| {
        let mut m = [[0.0; N]; N];
        for (p, &(a, b)) in pairs.iter().enumerate() {
            m[a][b] = h[p];
            m[b][a] = h[p];
        }
        m
    };
    // Start: the ellipsoid of the weights `u0`, shrunk until every point is strictly inside.
    let mut m0 = [[0.0; N]; N];
    for (x, &u) in q.iter().zip(u0) {
        for a in 0..N {
            for b in 0..N {
                m0[a][b] += u * x[a] * x[b];
            }
        }
    }
    let w0 = invert(m0)?;
    let smax = q.iter().map(|x| quad(&w0, x)).fold(0.0, math::max);
    let mut h = pairs.map(|(a, b)| w0[a][b] / (smax * 1.05));
    // d/dh and d2/dh2 of -log det H: -tr(W E_p) and tr(W E_p W E_q), with E_p the
    // symmetric unit matrix of pair p = (a, b) (ones at (a, b) and (b, a)): with W symmetric,
    // f_p W_ab and f_p f_q (W_ad W_bc + W_ac W_bd) / 2 for q = (c, d), f the pair factors.
    let mut m = q.len() as f64;
    // Input index of each point still in the problem.
    let mut act: Vec<usize> = (0..q.len()).collect();
    let mut t = 10.0 * m;
    let mut s = vec![0.0; q.len()];
    let mut r = vec![0.0; q.len()];
    let mut c = vec![0.0; q.len()];
    let mut d = vec![0.0; q.len()];
    for _outer in 0..30 {
        for _newton in 0..50 {
            let wm = invert(to_mat(&h))?;
            s.fill(0.0);
            for (p, col) in phi.iter().enumerate() {
                for (si, f) in s.iter_mut().zip(col) {
                    *si += f * h[p];
                }
            }
            for ((ri, ci), si) in r.iter_mut().zip(c.iter_mut()).zip(&s) {
                *ri = 1.0 / (1.0 - si);
                *ci = *ri * *ri;
            }
            let mut g = [0.0; K];
            let mut hess = [[0.0; K]; K];
            for (mk, col) in moment.iter_mut().zip(&mono) {
                *mk = dot(&c, col);
            }
            for p in 0..K {
                g[p] = dot(&r, &phi[p]);
                for qq in 0..=p {
                    hess[p][qq] = pair_f[p] * pair_f[qq] * moment[quartic[p][qq]];
                }
            }
            for p in 0..K {
                let (a, b) = pairs[p];
                g[p] -= t * pair_f[p] * wm[a][b];
                for qq in 0..=p {
                    let (c, e) = pairs[qq];
                    let v = wm[a][e] * wm[b][c] + wm[a][c] * wm[b][e];
                    hess[p][qq] += 0.5 * t * pair_f[p] * pair_f[qq] * v;
                }
            }
            let step = cholesky_solve(&mut hess, &g)?;
            let lam2: f64 = g.iter().zip(&step).map(|(a, b)| a * b).sum();
            if lam2.is_nan() || lam2 <= 1e-6 {
                break;
            }
            // Within lambda < 1/4 the objective (self-concordant) is known to accept the full
            // step; otherwise backtrack along h - a step on t (-log det H) - sum log(1 - s).
            d.fill(0.0);
            for (p, col) in phi.iter().enumerate() {
                for (di, f) in d.iter_mut().zip(col) {
                    *di += f * step[p];
                }
            }
            let full: [f64; K] = std::array::from_fn(|p| h[p] - step[p]);
            let full_ok = lam2 < 0.0625
                && s.iter().zip(&d).all(|(si, di)| si - di < 1.0)
                && log_det(to_mat(&full)).is_some();
            let f = |a: f64| -> f64 {
                let hn: [f64; K] = std::array::from_fn(|p| h[p] - a * step[p]);
                let Some(ld) = log_det(to_mat(&hn)) else {
                    return f64::INFINITY;
                };
                let mut f = -t * ld;
                // Sum of logs as logs of products of 8 (slacks are at most about 1 and at
                // least 1e-38 or so in practice; a product out of range takes the slow way).
                for (sc, dc) in s.chunks(8).zip(d.chunks(8)) {
                    let mut prod = 1.0;
                    for (si, di) in sc.iter().zip(dc) {
                        let slack = 1.0 - si + a * di;
                        if slack.is_nan() || slack <= 0.0 {
                            return f64::INFINITY;
                        }
                        prod *= slack;
                    }
                    if prod.is_normal() && prod < 1e300 {
                        f -= math::ln(prod);
                    } else {
                        for (si, di) in sc.iter().zip(dc) {
                            f -= math::ln(1.0 - si + a * di);
                        }
                    }
                }
                f
            };
            let mut a = 1.0;
            if !full_ok {
                let f0 = f(0.0);
                while f(a) > f0 - 0.25 * a * lam2 {
                    a *= 0.5;
                    if a < 1e-12 {
                        return None;
                    }
                }
            }
            for p in 0..K {
                h[p] -= a * step[p];
            }
        }
        if m / t <= gap {
            break;
        }
        // Points that cannot support the optimal weights (Harman and Pronzato's bound on
        // their `omega` under the dual weights of the central point) leave the problem: the
        // optimum is unchanged, every later step is cheaper, and the duality gap bound
        // `m / t` shrinks with `m`.
        let keep = support_candidates::<N>(q, &act, &r);
        let kept = keep.iter().filter(|&&k| k).count();
        if kept < act.len() && kept >= N {
            let compact = |v: &mut Vec<f64>| {
                let mut j = 0;
                for i in 0..keep.len() {
                    if keep[i] {
                        v[j] = v[i];
                        j += 1;
                    }
                }
                v.truncate(j);
            };
            for v in phi.iter_mut().chain(mono.iter_mut()) {
                compact(v);
            }
            for v in [&mut s, &mut r, &mut c, &mut d] {
                compact(v);
            }
            let mut j = 0;
            for i in 0..keep.len() {
                if keep[i] {
                    act[j] = act[i];
                    j += 1;
                }
            }
            act.truncate(j);
            m = act.len() as f64;
        }
        t *= 20.0;
    }
    // On the central path, t H^-1 = sum q q^T / (1 - s): those are the dual weights.
    let total: f64 = r.iter().sum();
    let mut u = vec![0.0; q.len()];
    for (&i, &ri) in act.iter().zip(&r) {
        u[i] = ri / total;
    }
    (total > 0.0 && total.is_finite()).then_some(u)
}

/// Which of the points `q[act]` may still support the optimal weights, given positive weights
/// proportional to `r`: the others' `omega` is below the bound of Harman and Pronzato (2007),
/// `N (1 + e/2 - sqrt(e (4 + e - 4/N)) / 2)` with `N + e` the largest `omega`. All points
/// are kept if the moment matrix is singular.
pub(super) fn support_candidates<const N: usize>(
    q: &[[f64; N]],
    act: &[usize],
    r: &[f64],
) -> Vec<bool> {
    let total: f64 = r.iter().sum();
    let mut mu = [[0.0; N]; N];
    for (&i, &ri) in act.iter().zip(r) {
        let x = &q[i];
        let w = ri / total;
        for a in 0..N {
            for b in 0..N {
                mu[a][b] += w * x[a] * x[b];
            }
        }
    }
    let Some(mi) = invert(mu) else {
        return vec![true; act.len()];
    };
    let om: Vec<f64> = act.iter().map(|&i| quad(&mi, &q[i])).collect();
    let n = N as f64;
    let e = om.iter().fold(0.0, |a, &b| math::max(a, b)) - n;
    if !(e.is_finite() && e >= 0.0) {
        return vec![true; act.len()];
    }
    // A relative margin far above the rounding of `omega`.
    let bound =
        n * (1.0 + e / 2.0 - math::max(e * (4.0 + e - 4.0 / n), 0.0).sqrt() / 2.0) * (1.0 - 1e-9);
    om.iter().map(|&o| o >= bound).collect()
}
