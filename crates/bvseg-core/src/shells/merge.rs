//! Bottom-up: two clusters become one while the one volume still keeps within the
//! tolerance (or, for a cluster that no volume holds within it, protrudes no more than the
//! cluster did), cheapest first (the merge that adds the least volume); past the part
//! budget, the merges that protrude least, whatever they protrude.
use std::collections::BTreeMap;

use super::bound::Bounder;
use super::split::{Cluster, Cluster as C};
use super::Atom;

/// Each cluster is tried with this many nearest others (by the gap between their boxes).
const NEAREST: usize = 6;

/// Merge `clusters` as the module says, down to at most `max_k`.
pub fn merge(
    b: &Bounder,
    atoms: &[Atom],
    mut clusters: Vec<Cluster>,
    max_k: usize,
) -> Vec<Cluster> {
    // Candidate merges by pair of cluster ids; ids are never reused, so a cached merge of
    // two live clusters is still valid.
    let mut ids: Vec<usize> = (0..clusters.len()).collect();
    let mut next_id = clusters.len();
    let mut cache: BTreeMap<(usize, usize), C> = BTreeMap::new();
    loop {
        let forced = clusters.len() > max_k;
        let pairs = near_pairs(&clusters, b.tol, forced);
        // Fit the merges not yet fitted, in parallel.
        let todo: Vec<(usize, usize)> = pairs
            .iter()
            .copied()
            .filter(|&(i, j)| !cache.contains_key(&(ids[i], ids[j])))
            .collect();
        let fitted = crate::parallel::map(&todo, |&(i, j)| {
            let (x, y) = (&clusters[i], &clusters[j]);
            let mut members = x.atoms.clone();
            members.extend_from_slice(&y.atoms);
            members.sort_unstable();
            let bone = bone_of(atoms, x, y);
            // Of one bone (or none), the hull of the two hulls is the merge's; across bones,
            // the corners must be carried back by the one bone.
            let fit = if x.bone == y.bone {
                b.fit_both(&x.fit, &y.fit)
            } else {
                b.fit(&super::split::triangles(atoms, &members), bone)
            };
            Cluster {
                atoms: members,
                bone,
                fit,
            }
        });
        for (&(i, j), c) in todo.iter().zip(fitted) {
            cache.insert((ids[i], ids[j]), c);
        }
        // Cheapest first by the volume a merge adds; the first within the tolerance wins
        // (its protrusion is measured only now, and kept with the cached fit).
        let size = |c: &Cluster| c.fit.volume.volume();
        let mut ranked: Vec<(f64, usize, usize)> = pairs
            .iter()
            .map(|&(i, j)| {
                let m = &cache[&(ids[i], ids[j])];
                (size(m) - size(&clusters[i]) - size(&clusters[j]), i, j)
            })
            .collect();
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
        let best = if forced {
            pairs
                .iter()
                .map(|&(i, j)| (cache[&(ids[i], ids[j])].fit.protrusion(b), i, j))
                .min_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))))
        } else {
            // A cluster already out of tolerance (a triangle no volume holds within it) may
            // take neighbours that do not make it protrude more.
            let limit = |c: &Cluster| {
                if c.fit.within(b) {
                    b.tol
                } else {
                    c.fit.protrusion(b)
                }
            };
            ranked.into_iter().find(|&(_, i, j)| {
                let m = &cache[&(ids[i], ids[j])].fit;
                let l = crate::math::max(limit(&clusters[i]), limit(&clusters[j]));
                if l <= b.tol {
                    m.within(b)
                } else {
                    m.protrusion(b) <= l
                }
            })
        };
        let Some((_, i, j)) = best else {
            return clusters;
        };
        let Some(merged) = cache.remove(&(ids[i], ids[j])) else {
            // Every pair ranked was fitted above.
            return clusters;
        };
        // j > i: remove j first.
        clusters.remove(j);
        ids.remove(j);
        clusters[i] = merged;
        ids[i] = next_id;
        next_id += 1;
    }
}

/// The bone of a merge: that of the cluster with more triangles (a volume fitted with a bone
/// holds triangles of any bone in every pose; it is tightest on its own bone's).
fn bone_of(atoms: &[Atom], a: &Cluster, b: &Cluster) -> Option<usize> {
    let n = |c: &Cluster| {
        c.atoms
            .iter()
            .map(|&x| atoms[x].triangles.len())
            .sum::<usize>()
    };
    if n(b) > n(a) {
        b.bone
    } else {
        a.bone
    }
}

/// Pairs `(i, j)`, `i < j`, worth trying: of one bone unless `forced`, each cluster with its
/// [`NEAREST`] nearest, and (unless forced) only those whose boxes are within `2 tol`.
fn near_pairs(clusters: &[Cluster], tol: f64, forced: bool) -> Vec<(usize, usize)> {
    let boxes: Vec<_> = clusters.iter().map(|c| c.fit.volume.aabb()).collect();
    let gap = |i: usize, j: usize| {
        let (a, b) = (boxes[i], boxes[j]);
        (a.0 - b.1).max(b.0 - a.1).max(glam::DVec3::ZERO).length()
    };
    let mut out = Vec::new();
    for i in 0..clusters.len() {
        let mut near: Vec<(f64, usize)> = (0..clusters.len())
            .filter(|&j| j != i && (forced || clusters[i].bone == clusters[j].bone))
            .map(|j| (gap(i, j), j))
            .filter(|&(g, _)| forced || g <= 2.0 * tol)
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        out.extend(
            near.iter()
                .take(NEAREST)
                .map(|&(_, j)| (i.min(j), i.max(j))),
        );
    }
    out.sort_unstable();
    out.dedup();
    out
}
