//! Stage 3: initial partitions.
//!
//! - [`cvt`]: a centroidal Voronoi tessellation (Euclidean k-means on the samples, seeded by
//!   k-means++ and kept connected by flooding), the paper's CVT start.
//! - [`split`]: split one part of an optimised partition, seeding the new part at the
//!   part's sample farthest from its centre (the paper's refinement step).
use crate::math;
use glam::DVec3;

use crate::assignment::{assign, PartMetric, Rule};
use crate::flooding::make_connected;
use crate::moments::Moments;
use crate::partition::{Partition, Solid};
use crate::rng::Rng;

/// Euclidean k-means iterations of the CVT start.
const CVT_ITERATIONS: usize = 20;

/// k-means++ seeds, at least one in each component of the solid when `k` allows (largest
/// components first), so that no part has to span two disjoint pieces.
fn seeds(solid: &Solid, k: usize, rng: &mut Rng) -> Vec<usize> {
    let (comps, ncomp) = (&solid.components, solid.pieces);
    let n = solid.len();
    let mut seeds = Vec::with_capacity(k);
    let mut sizes = vec![0usize; ncomp];
    for &c in comps.iter() {
        sizes[c as usize] += 1;
    }
    let mut order: Vec<usize> = (0..ncomp).collect();
    order.sort_by(|&a, &b| sizes[b].cmp(&sizes[a]).then(a.cmp(&b)));
    let mut first_of = vec![usize::MAX; ncomp];
    for (s, &c) in comps.iter().enumerate() {
        if first_of[c as usize] == usize::MAX {
            first_of[c as usize] = s;
        }
    }
    if ncomp > 1 {
        for &c in order.iter().take(k) {
            // The component's sample nearest its centroid (a deterministic interior seed).
            let members = (0..n).filter(|&s| comps[s] as usize == c);
            let mean = members.clone().map(|s| solid.q[s]).sum::<DVec3>() / sizes[c] as f64;
            let s = members
                .min_by(|&a, &b| {
                    (solid.q[a] - mean)
                        .length_squared()
                        .total_cmp(&(solid.q[b] - mean).length_squared())
                })
                .unwrap_or(first_of[c]);
            seeds.push(s);
        }
    } else {
        seeds.push(rng.below(n));
    }
    let mut d2: Vec<f64> = solid
        .q
        .iter()
        .map(|&x| {
            seeds
                .iter()
                .map(|&s| (x - solid.q[s]).length_squared())
                .fold(f64::INFINITY, math::min)
        })
        .collect();
    while seeds.len() < k {
        let total: f64 = d2.iter().sum();
        let next = if total > 0.0 {
            let mut r = rng.next_f64() * total;
            let mut pick = n - 1;
            for (s, &d) in d2.iter().enumerate() {
                if r < d {
                    pick = s;
                    break;
                }
                r -= d;
            }
            pick
        } else {
            rng.below(n)
        };
        seeds.push(next);
        let c = solid.q[next];
        for (s, d) in d2.iter_mut().enumerate() {
            *d = math::min(*d, (solid.q[s] - c).length_squared());
        }
    }
    seeds
}

/// A connected CVT partition with `k` parts (`k <= samples`).
pub fn cvt(solid: &Solid, k: usize, seed: u64) -> Partition {
    let n = solid.len();
    let k = k.clamp(1, n);
    let mut rng = Rng::new(seed);
    let seeds = seeds(solid, k, &mut rng);
    let all: Vec<u32> = (0..n as u32).collect();
    let cand: Vec<u32> = (0..k as u32).collect();
    let mut metrics: Vec<PartMetric> = seeds
        .iter()
        .map(|&s| {
            let mut m = Moments::default();
            m.add(solid.q[s]);
            PartMetric::new(&m)
        })
        .collect();
    let mut labels = assign(solid, &all, &metrics, &cand, Rule::Euclidean);
    let mut part = Partition::from_labels(solid, labels.clone(), k);
    for _ in 0..CVT_ITERATIONS {
        make_connected(&solid.grid, &mut labels, &solid.components, None, |s, j| {
            metrics[j as usize].cost_of(solid, s, Rule::Euclidean)
        });
        let next = Partition::from_labels(solid, labels.clone(), k);
        let stable = next == part;
        part = next;
        if stable || part.has_empty_part() {
            break;
        }
        metrics = part.parts.iter().map(PartMetric::new).collect();
        labels = assign(solid, &all, &metrics, &cand, Rule::Euclidean);
    }
    drop_empty_parts(&mut part);
    part
}

/// Remove parts that lost every sample (possible only on tiny inputs).
pub fn drop_empty_parts(part: &mut Partition) {
    let mut i = part.k();
    while i > 0 {
        i -= 1;
        if part.parts[i].n < 1.0 && part.k() > 1 {
            part.remove_empty_part(i);
        }
    }
}

/// Split part `i` of `part` in two: the new part (label `k`) is seeded at the sample of part
/// `i` farthest from its centre, and the two halves are formed by a few 2-means steps
/// within part `i`, kept connected. Returns `None` when part `i` has fewer than 2 samples.
pub fn split(solid: &Solid, part: &Partition, i: usize) -> Option<Partition> {
    let members: Vec<u32> = (0..solid.len() as u32)
        .filter(|&s| part.labels[s as usize] == i as u32)
        .collect();
    if members.len() < 2 {
        return None;
    }
    let mu = part.parts[i].mean();
    let far = |from: DVec3| {
        *members
            .iter()
            .max_by(|&&a, &&b| {
                (solid.q[a as usize] - from)
                    .length_squared()
                    .total_cmp(&(solid.q[b as usize] - from).length_squared())
                    .then(b.cmp(&a))
            })
            .unwrap_or(&members[0])
    };
    let a = far(mu);
    let b = far(solid.q[a as usize]);
    let mut ca = solid.q[a as usize];
    let mut cb = solid.q[b as usize];
    let k = part.k();
    let mut labels = part.labels.clone();
    for _ in 0..10 {
        let mut ma = Moments::default();
        let mut mb = Moments::default();
        for &s in &members {
            let x = solid.q[s as usize];
            if (x - cb).length_squared() < (x - ca).length_squared() {
                labels[s as usize] = k as u32;
                mb.add(x);
            } else {
                labels[s as usize] = i as u32;
                ma.add(x);
            }
        }
        if ma.n < 1.0 || mb.n < 1.0 {
            return None;
        }
        let (na, nb) = (ma.mean(), mb.mean());
        if na == ca && nb == cb {
            break;
        }
        ca = na;
        cb = nb;
    }
    let (cai, cbi) = (ca, cb);
    make_connected(
        &solid.grid,
        &mut labels,
        &solid.components,
        Some(&members),
        |s, j| {
            let x = solid.q[s];
            if j as usize == k {
                (x - cbi).length_squared()
            } else if j as usize == i {
                (x - cai).length_squared()
            } else {
                f64::INFINITY
            }
        },
    );
    let next = Partition::from_labels(solid, labels, k + 1);
    if next.has_empty_part() {
        return None;
    }
    Some(next)
}
