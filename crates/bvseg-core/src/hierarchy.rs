//! Stage 10: a bounding-volume hierarchy over the parts (paper section 5.3).
//!
//! Bottom-up and greedy: among the pairs of current nodes that touch, merge the pair whose
//! parent volume is smallest, until one node is left. Nodes carry the convex-hull points of
//! their parts, so a parent is fitted to few points. Pairs that never touch (a solid made of
//! several pieces) are merged last, by the same rule.
use std::collections::{BTreeMap, BTreeSet};

use glam::DVec3;

use crate::bounding::hull::hull_points;
use crate::{BoundingVolume, HierarchyNode};

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
    // Candidate parents by pair: (fitted volume, hull points).
    let mut cache: BTreeMap<(usize, usize), (BoundingVolume, Vec<DVec3>)> = BTreeMap::new();
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
        // Fit the new candidates in parallel; the choice below runs in pair order.
        let missing: Vec<(usize, usize)> = pairs
            .iter()
            .copied()
            .filter(|p| !cache.contains_key(p))
            .collect();
        let fitted = crate::parallel::map(&missing, |&(a, b)| {
            let mut p = points[a].clone();
            p.extend_from_slice(&points[b]);
            let hull = hull_points(&p);
            (fit(&hull), hull)
        });
        cache.extend(missing.into_iter().zip(fitted));
        let mut best: Option<(f64, usize, usize)> = None;
        for (a, b) in pairs {
            let vol = cache[&(a, b)].0.volume();
            if best.is_none_or(|x| vol < x.0) {
                best = Some((vol, a, b));
            }
        }
        let Some((_, a, b)) = best else {
            break;
        };
        let Some((v, hull)) = cache.remove(&(a, b)) else {
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
