//! Stage 4a: the Lloyd-like assignment step.
//!
//! With each part's mean, covariance and e-tightness frozen, every sample goes to the part
//! minimising `h_j(x) = e(S_j) * d_M(x, S_j)`, the first-order change of F when `x` joins
//! `S_j` (paper section 4). Samples are independent, so this runs in parallel; each result
//! depends only on its own sample, so the output is the same for any thread count.
use glam::DVec3;

use crate::moments::{inv_packed, quad_packed, Moments};
use crate::partition::{Solid, CELL_VAR};

/// Which first-order rule ranks the parts for a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// The paper's `e_j d_M(x, S_j)`.
    Paper,
    /// The expansion that keeps the covariance rescaling: `e_j (d_M(x, S_j) - 3)`.
    Corrected,
    /// Euclidean distance to the part's mean (k-means / CVT).
    Euclidean,
}

/// A part's frozen metric during one sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartMetric {
    /// Mean (lattice units).
    pub mu: DVec3,
    /// Inverse covariance (packed symmetric).
    pub inv: [f64; 6],
    /// e-tightness.
    pub e: f64,
}

impl PartMetric {
    /// The metric of a part from its moments (cell covariance included). Empty parts get a
    /// metric that no sample prefers.
    pub fn new(m: &Moments) -> Self {
        if m.n < 1.0 {
            return Self {
                mu: DVec3::ZERO,
                inv: [0.0; 6],
                e: f64::INFINITY,
            };
        }
        let c = m.cov_packed(CELL_VAR);
        // The cell term keeps C positive definite; the fallback only guards round-off.
        let inv = inv_packed(&c).unwrap_or([12.0, 12.0, 12.0, 0.0, 0.0, 0.0]);
        Self {
            mu: m.mean(),
            inv,
            e: m.e(CELL_VAR, 1.0),
        }
    }

    /// Squared Mahalanobis distance of `q` to the part.
    #[inline]
    pub fn d(&self, q: DVec3) -> f64 {
        quad_packed(&self.inv, q - self.mu)
    }

    /// The cost of sample `s` of `solid` joining this part under `rule`, per cell: for a
    /// block of adaptive sampling, the mean of its cells' costs, whose Mahalanobis distances
    /// exceed its centre's by the block's spread along each axis.
    #[inline]
    pub fn cost_of(&self, solid: &Solid, s: usize, rule: Rule) -> f64 {
        let q = solid.q[s];
        match solid.grid.side(s) {
            1 => self.cost(q, rule),
            b => {
                let b = f64::from(b);
                let spread = (b * b - 1.0) / 12.0 * (self.inv[0] + self.inv[1] + self.inv[2]);
                match rule {
                    Rule::Paper => self.e * (self.d(q) + spread),
                    Rule::Corrected => self.e * (self.d(q) + spread - 3.0),
                    Rule::Euclidean => self.cost(q, rule),
                }
            }
        }
    }

    /// The cost of `q` joining this part under `rule`.
    #[inline]
    pub fn cost(&self, q: DVec3, rule: Rule) -> f64 {
        match rule {
            Rule::Paper => self.e * self.d(q),
            Rule::Corrected => self.e * (self.d(q) - 3.0),
            Rule::Euclidean => {
                if self.e.is_finite() {
                    (q - self.mu).length_squared()
                } else {
                    f64::INFINITY
                }
            }
        }
    }
}

/// For each sample in `samples`, the part of least cost among the candidates of its current
/// part: `candidates[labels[s]]` (ties: the first listed). Listing, for each part, itself and
/// the parts it touches confines the search to where a sample can go without leaving its
/// part's neighbourhood, which is all a connected partition allows anyway.
pub fn assign_local(
    solid: &Solid,
    samples: &[u32],
    labels: &[u32],
    metrics: &[PartMetric],
    candidates: &[Vec<u32>],
    rule: Rule,
) -> Vec<u32> {
    crate::parallel::map_chunked(samples, 1024, |&s| {
        let own = labels[s as usize];
        cheapest(solid, s as usize, &candidates[own as usize], metrics, rule).unwrap_or(own)
    })
}

/// For each sample in `samples`, the candidate part of least cost (ties: the first listed).
pub fn assign(
    solid: &Solid,
    samples: &[u32],
    metrics: &[PartMetric],
    candidates: &[u32],
    rule: Rule,
) -> Vec<u32> {
    crate::parallel::map_chunked(samples, 1024, |&s| {
        cheapest(solid, s as usize, candidates, metrics, rule).unwrap_or(candidates[0])
    })
}

/// The candidate of least finite cost for sample `s` (the first on ties), if any.
#[inline]
fn cheapest(
    solid: &Solid,
    s: usize,
    candidates: &[u32],
    metrics: &[PartMetric],
    rule: Rule,
) -> Option<u32> {
    let mut best = None;
    let mut best_cost = f64::INFINITY;
    for &j in candidates {
        let c = metrics[j as usize].cost_of(solid, s, rule);
        if c < best_cost {
            best_cost = c;
            best = Some(j);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mahalanobis_prefers_elongated_part() {
        // Part 0: long along x; part 1: round, nearer in Euclidean terms.
        let mut a = Moments::default();
        for i in -20..=20 {
            a.add(DVec3::new(i as f64, 0.0, 0.0));
        }
        let mut b = Moments::default();
        for dx in -1..=1 {
            for dy in -1..=1 {
                b.add(DVec3::new(25.0 + dx as f64, 8.0 + dy as f64, 0.0));
            }
        }
        let m = [PartMetric::new(&a), PartMetric::new(&b)];
        let q = DVec3::new(21.0, 0.0, 0.0);
        let best = |rule| {
            (0..2)
                .min_by(|&i: &usize, &j| m[i].cost(q, rule).total_cmp(&m[j].cost(q, rule)))
                .unwrap()
        };
        assert_eq!(best(Rule::Paper), 0);
        assert_eq!(best(Rule::Euclidean), 1);
    }
}
