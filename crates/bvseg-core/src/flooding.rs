//! Stage 4b: keep every part one connected region of the grid's face-neighbour graph.
//!
//! The Lloyd step assigns each sample to its best part independently, which can leave
//! islands. As in the paper's "distortion-minimising flooding", islands are re-grown from
//! their surroundings in order of increasing cost: each part keeps its largest connected
//! piece, and the orphaned samples are flooded from the neighbouring parts through a
//! priority queue on the assignment cost.
use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::sampling::{Grid, NONE};

/// Connected pieces of the labelling among the samples of `scope`: for each sample, the id of
/// its piece (pieces are numbered in order of their first sample in `scope`; [`NONE`] outside
/// the scope), the size of each piece, and its first sample. A piece never leaves its part,
/// so `scope` must hold every sample of each part it touches.
pub fn pieces_in(
    grid: &Grid,
    labels: &[u32],
    scope: impl IntoIterator<Item = u32>,
) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let mut piece = vec![NONE; labels.len()];
    let mut sizes = Vec::new();
    let mut firsts = Vec::new();
    let mut stack = Vec::new();
    for start in scope {
        if piece[start as usize] != NONE {
            continue;
        }
        let id = sizes.len() as u32;
        let l = labels[start as usize];
        let mut size = 0u32;
        piece[start as usize] = id;
        stack.push(start);
        while let Some(s) = stack.pop() {
            size += 1;
            for &t in grid.neighbors(s as usize) {
                if t != NONE && piece[t as usize] == NONE && labels[t as usize] == l {
                    piece[t as usize] = id;
                    stack.push(t);
                }
            }
        }
        sizes.push(size);
        firsts.push(start);
    }
    (piece, sizes, firsts)
}

/// Connected pieces of the whole labelling (see [`pieces_in`]): piece of each sample, sizes.
pub fn pieces(grid: &Grid, labels: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let (piece, sizes, _) = pieces_in(grid, labels, 0..labels.len() as u32);
    (piece, sizes)
}

/// Whether every part (label) forms one connected piece on the samples it owns, ignoring
/// parts that lie in several connected components of the solid itself (`solid_components`
/// gives the component of each sample; a part is then checked per component).
pub fn is_connected(grid: &Grid, labels: &[u32], solid_components: &[u32]) -> bool {
    let (piece, _) = pieces(grid, labels);
    // A part is connected iff it has exactly one piece per solid component it touches.
    let mut first: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    labels
        .iter()
        .enumerate()
        .all(|(s, &l)| *first.entry((l, solid_components[s])).or_insert(piece[s]) == piece[s])
}

/// The pairs among `pairs` whose merge keeps every part connected within each component of
/// the solid: wherever both parts own samples in one component, they must share a face
/// there. (Two parts of one piece whose volumes merely overlap would otherwise merge into
/// a part of two separate regions.)
pub fn connected_merges(
    grid: &Grid,
    labels: &[u32],
    solid_components: &[u32],
    pairs: &[(u32, u32)],
) -> Vec<(u32, u32)> {
    use std::collections::HashSet;
    let mut owns: HashSet<(u32, u32)> = HashSet::new();
    let mut touch: HashSet<(u32, u32, u32)> = HashSet::new();
    for (s, &l) in labels.iter().enumerate() {
        // Face neighbours are always in the same component.
        let c = solid_components[s];
        owns.insert((l, c));
        for &t in grid.neighbors(s) {
            if t != NONE && labels[t as usize] != l {
                let m = labels[t as usize];
                touch.insert((l.min(m), l.max(m), c));
            }
        }
    }
    let mut comps_of: Vec<Vec<u32>> = Vec::new();
    for &(l, c) in &owns {
        if comps_of.len() <= l as usize {
            comps_of.resize(l as usize + 1, Vec::new());
        }
        comps_of[l as usize].push(c);
    }
    pairs
        .iter()
        .copied()
        .filter(|&(a, b)| {
            comps_of.get(a as usize).is_none_or(|cs| {
                cs.iter()
                    .all(|&c| !owns.contains(&(b, c)) || touch.contains(&(a.min(b), a.max(b), c)))
            })
        })
        .collect()
}

#[derive(PartialEq)]
struct Item {
    cost: f64,
    sample: u32,
    part: u32,
}

impl Eq for Item {}

impl Ord for Item {
    fn cmp(&self, o: &Self) -> Ordering {
        // Min-heap on cost; ties broken by indices so the order is deterministic.
        o.cost
            .total_cmp(&self.cost)
            .then_with(|| o.sample.cmp(&self.sample))
            .then_with(|| o.part.cmp(&self.part))
    }
}

impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Make every part connected (within each component of the solid), re-flooding orphaned
/// samples by increasing `cost(sample, part)`. Returns the samples that changed part, each
/// with its previous part.
///
/// Only the samples in `scope` (all when `None`) are examined and may change: a part
/// whose samples are all outside the scope is assumed connected already. `solid_components`
/// gives the connected component of the solid each sample is in: a part keeps its largest
/// piece in each component it owns, so a part that spans several components (possible only
/// when k is smaller than their number) is left alone there.
pub fn make_connected(
    grid: &Grid,
    labels: &mut [u32],
    solid_components: &[u32],
    scope: Option<&[u32]>,
    cost: impl Fn(usize, u32) -> f64,
) -> Vec<(u32, u32)> {
    let all: Vec<u32>;
    let scope = match scope {
        Some(s) => s,
        None => {
            all = (0..labels.len() as u32).collect();
            &all
        }
    };
    // Pieces of the labelling within the scope (BFS never leaves a part, and every sample of
    // a part in scope is in scope).
    let (piece, sizes, firsts) = pieces_in(grid, labels, scope.iter().copied());
    // For each (part, solid component), its largest piece (the first one on ties).
    let mut best: std::collections::BTreeMap<(u32, u32), u32> = std::collections::BTreeMap::new();
    for (p, &first) in firsts.iter().enumerate() {
        let key = (labels[first as usize], solid_components[first as usize]);
        let e = best.entry(key).or_insert(p as u32);
        if sizes[p] > sizes[*e as usize] {
            *e = p as u32;
        }
    }
    if best.len() == sizes.len() {
        return Vec::new();
    }
    let mut keep = vec![false; sizes.len()];
    for &p in best.values() {
        keep[p as usize] = true;
    }
    let mut orphans = Vec::new();
    let mut original = Vec::new();
    for &s in scope {
        let su = s as usize;
        if !keep[piece[su] as usize] {
            original.push(labels[su]);
            labels[su] = NONE;
            orphans.push(s);
        }
    }
    let mut heap = BinaryHeap::new();
    for &s in &orphans {
        for &t in grid.neighbors(s as usize) {
            if t != NONE && labels[t as usize] != NONE {
                let part = labels[t as usize];
                heap.push(Item {
                    cost: cost(s as usize, part),
                    sample: s,
                    part,
                });
            }
        }
    }
    while let Some(Item { sample, part, .. }) = heap.pop() {
        let s = sample as usize;
        if labels[s] != NONE {
            continue;
        }
        labels[s] = part;
        for &t in grid.neighbors(s) {
            if t != NONE && labels[t as usize] == NONE {
                heap.push(Item {
                    cost: cost(t as usize, part),
                    sample: t,
                    part,
                });
            }
        }
    }
    // The flood reaches every orphan (each touches a kept piece through its component);
    // the original label is only a guard.
    let mut changed = Vec::new();
    for (&s, &o) in orphans.iter().zip(&original) {
        if labels[s as usize] == NONE {
            labels[s as usize] = o;
        }
        if labels[s as usize] != o {
            changed.push((s, o));
        }
    }
    changed
}

/// Connected components of the solid itself (of the full sample graph).
pub fn solid_components(grid: &Grid) -> (Vec<u32>, usize) {
    let zeros = vec![0u32; grid.len()];
    let (piece, sizes) = pieces(grid, &zeros);
    (piece, sizes.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn islands_are_reflooded() {
        let g = Grid::from_inside_fn(DVec3::ZERO, DVec3::new(9.0, 0.0, 0.0), 1.0, |p| {
            (0.0..=9.0).contains(&p.x) && p.y.abs() < 0.5 && p.z.abs() < 0.5
        });
        assert_eq!(g.len(), 10);
        // Part 0 on the left, part 1 on the right, with a part-1 island inside part 0.
        let mut labels = vec![0, 0, 1, 0, 0, 1, 1, 1, 1, 1];
        let (comp, _) = solid_components(&g);
        assert!(!is_connected(&g, &labels, &comp));
        let changed = make_connected(&g, &mut labels, &comp, None, |_, _| 0.0);
        assert_eq!(changed, vec![(2, 1)]);
        assert_eq!(labels, vec![0, 0, 0, 0, 0, 1, 1, 1, 1, 1]);
        assert!(is_connected(&g, &labels, &comp));
    }
}
