//! Stage 10: a bounding-volume hierarchy over the parts (paper section 5.3).
//!
//! Bottom-up and greedy: among the pairs of current nodes that touch, merge the pair whose
//! parent volume is smallest, until one node is left. Nodes carry the convex-hull points of
//! their parts, so a parent is fitted to few points. Pairs that never touch (a solid made of
//! several pieces) are merged last, by the same rule.
//!
//! A parent's volume holds the convex hull of its points, so that hull's volume bounds it
//! from below: a pair is fitted only once no pair fitted so far is smaller than its bound
//! (most pairs of large nodes never are, as their nodes merge with others first).
use crate::math;
use std::collections::{BTreeMap, BTreeSet};

use glam::DVec3;

use crate::bounding::hull::convex_hull;
use crate::{BoundingVolume, HierarchyNode};

/// A candidate parent of a pair of nodes.
struct Candidate {
    /// The convex hull of the pair's points: its vertices, and its volume (less a hair for
    /// round-off), a lower bound on the parent's volume.
    hull: Vec<DVec3>,
    bound: f64,
    /// The fitted volume, once fitted.
    volume: Option<BoundingVolume>,
}

/// Build the hierarchy from each part's hull points, its volume, and the pairs of touching
/// parts. `fit` fits a volume to points. Leaves come first (node `i` is part `i`), the root
/// last.
pub fn build(
    hulls: Vec<Vec<DVec3>>,
    volumes: &[BoundingVolume],
    adjacency: &[(u32, u32)],
    fit: impl Fn(&[DVec3]) -> BoundingVolume + Sync + Send,
) -> Vec<HierarchyNode> {
    let k = hulls.len();
    let mut nodes: Vec<HierarchyNode> = volumes
        .iter()
        .enumerate()
        .map(|(i, v)| HierarchyNode {
            volume: v.clone(),
            part: Some(i),
            children: None,
        })
        .collect();
    let mut points = hulls;
    let mut alive: BTreeSet<usize> = (0..k).collect();
    let mut touching: BTreeSet<(usize, usize)> = adjacency
        .iter()
        .map(|&(a, b)| (a as usize, b as usize))
        .collect();
    // Candidate parents by pair: the hull of their points, its volume, and the fitted
    // volume once fitted.
    let mut cache: BTreeMap<(usize, usize), Candidate> = BTreeMap::new();
    while alive.len() > 1 {
        let mut pairs: Vec<(usize, usize)> = touching
            .iter()
            .copied()
            .filter(|(a, b)| alive.contains(a) && alive.contains(b))
            .collect();
        if pairs.is_empty() {
            let a: Vec<usize> = alive.iter().copied().collect();
            pairs = a
                .iter()
                .enumerate()
                .flat_map(|(i, &x)| a[i + 1..].iter().map(move |&y| (x, y)))
                .collect();
        }
        let missing: Vec<(usize, usize)> = pairs
            .iter()
            .copied()
            .filter(|p| !cache.contains_key(p))
            .collect();
        let hulls = crate::parallel::map(&missing, |&(a, b)| {
            let mut p = points[a].clone();
            p.extend_from_slice(&points[b]);
            let hull = convex_hull(&p);
            Candidate {
                bound: hull.volume() * (1.0 - 1e-9),
                hull: hull.vertices,
                volume: None,
            }
        });
        cache.extend(missing.into_iter().zip(hulls));
        // Fit, in parallel rounds, every pair whose bound is below the smallest volume fitted
        // so far; the first round fits the pairs of the smallest bounds.
        let mut by_bound = pairs.clone();
        by_bound.sort_by(|p, q| cache[p].bound.total_cmp(&cache[q].bound));
        loop {
            let smallest = pairs
                .iter()
                .filter_map(|p| cache[p].volume.as_ref().map(BoundingVolume::volume))
                .fold(f64::INFINITY, math::min);
            let mut todo: Vec<(usize, usize)> = by_bound
                .iter()
                .copied()
                .filter(|p| cache[p].volume.is_none() && cache[p].bound <= smallest)
                .collect();
            if smallest == f64::INFINITY {
                todo.truncate(crate::parallel::threads().max(1));
            }
            if todo.is_empty() {
                break;
            }
            let fitted = crate::parallel::map(&todo, |p| fit(&cache[p].hull));
            for (p, v) in todo.into_iter().zip(fitted) {
                if let Some(c) = cache.get_mut(&p) {
                    c.volume = Some(v);
                }
            }
        }
        // The smallest fitted volume, the first pair of it in pair order; a pair not fitted
        // has a bound, so a volume, above it.
        let mut best: Option<(f64, usize, usize)> = None;
        for &(a, b) in &pairs {
            let Some(vol) = cache[&(a, b)].volume.as_ref().map(BoundingVolume::volume) else {
                continue;
            };
            if best.is_none_or(|x| vol < x.0) {
                best = Some((vol, a, b));
            }
        }
        let Some((_, a, b)) = best else {
            break;
        };
        let Some(Candidate {
            hull,
            volume: Some(v),
            ..
        }) = cache.remove(&(a, b))
        else {
            break;
        };
        let id = nodes.len();
        nodes.push(HierarchyNode {
            volume: v,
            part: None,
            children: Some([a, b]),
        });
        points.push(hull);
        alive.remove(&a);
        alive.remove(&b);
        let neighbours: Vec<usize> = touching
            .iter()
            .filter(|(x, y)| *x == a || *x == b || *y == a || *y == b)
            .map(|&(x, y)| if x == a || x == b { y } else { x })
            .filter(|n| alive.contains(n))
            .collect();
        for n in neighbours {
            touching.insert((n.min(id), n.max(id)));
        }
        alive.insert(id);
    }
    nodes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounding::hull::hull_points;
    use crate::rng::Rng;

    /// The greedy rule applied naively: fit every touching pair, merge the smallest.
    fn eager(
        hulls: Vec<Vec<DVec3>>,
        adjacency: &[(u32, u32)],
        fit: impl Fn(&[DVec3]) -> BoundingVolume,
    ) -> Vec<[usize; 2]> {
        let mut points = hulls;
        let mut alive: BTreeSet<usize> = (0..points.len()).collect();
        let mut touching: BTreeSet<(usize, usize)> = adjacency
            .iter()
            .map(|&(a, b)| (a as usize, b as usize))
            .collect();
        let mut merges = Vec::new();
        while alive.len() > 1 {
            let mut pairs: Vec<(usize, usize)> = touching
                .iter()
                .copied()
                .filter(|(a, b)| alive.contains(a) && alive.contains(b))
                .collect();
            if pairs.is_empty() {
                let a: Vec<usize> = alive.iter().copied().collect();
                pairs = a
                    .iter()
                    .enumerate()
                    .flat_map(|(i, &x)| a[i + 1..].iter().map(move |&y| (x, y)))
                    .collect();
            }
            let mut best: Option<(f64, usize, usize)> = None;
            for (a, b) in pairs {
                let mut p = points[a].clone();
                p.extend_from_slice(&points[b]);
                let vol = fit(&hull_points(&p)).volume();
                if best.is_none_or(|x| vol < x.0) {
                    best = Some((vol, a, b));
                }
            }
            let (_, a, b) = best.unwrap();
            let id = points.len();
            let mut p = points[a].clone();
            p.extend_from_slice(&points[b]);
            points.push(hull_points(&p));
            merges.push([a, b]);
            alive.remove(&a);
            alive.remove(&b);
            let nb: Vec<usize> = touching
                .iter()
                .filter(|(x, y)| *x == a || *x == b || *y == a || *y == b)
                .map(|&(x, y)| if x == a || x == b { y } else { x })
                .filter(|n| alive.contains(n))
                .collect();
            for n in nb {
                touching.insert((n.min(id), n.max(id)));
            }
            alive.insert(id);
        }
        merges
    }

    #[test]
    fn fitting_only_the_pairs_that_can_win_merges_as_fitting_them_all() {
        let mut rng = Rng::new(3);
        for round in 0..6 {
            // Blobs of points along a bent chain, some pieces apart (no adjacency between
            // them), of varied sizes.
            let k = 12 + round;
            let mut hulls = Vec::new();
            for i in 0..k {
                let c = DVec3::new(i as f64, (i as f64 * 0.7).sin() * 2.0, 0.3 * i as f64);
                let r = 0.2 + rng.next_f64();
                let pts: Vec<DVec3> = (0..40)
                    .map(|_| {
                        c + DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * r
                            - DVec3::splat(0.5 * r)
                    })
                    .collect();
                hulls.push(hull_points(&pts));
            }
            let adjacency: Vec<(u32, u32)> = (0..k as u32 - 1)
                .filter(|i| i % 5 != 4)
                .map(|i| (i, i + 1))
                .collect();
            let fit = |p: &[DVec3]| crate::bounding::fit(crate::Shape::Ellipsoid, p, 1e-6, 32);
            let volumes: Vec<BoundingVolume> = hulls.iter().map(|h| fit(h)).collect();
            let nodes = build(hulls.clone(), &volumes, &adjacency, fit);
            let merges: Vec<[usize; 2]> = nodes.iter().filter_map(|n| n.children).collect();
            assert_eq!(merges, eager(hulls, &adjacency, fit), "round {round}");
            assert_eq!(nodes.len(), 2 * k - 1);
        }
    }
}
