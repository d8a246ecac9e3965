//! Stage 5: minimising F for a fixed number of parts.
//!
//! 1. Lloyd-like sweeps ([`crate::assignment`] then [`crate::flooding`]): a sweep is kept only
//!    if the exact F drops. When the paper's rule stops improving, the corrected first-order
//!    rule (`e (d - 3)`) is tried before giving up: the exact F decides.
//! 2. Boundary moves ([`move_boundary_samples`]): single boundary samples move to a neighbouring part when the exact
//!    change of F (from rank-one updated moments) is negative and the move keeps the part it
//!    leaves connected, until no such move remains.
use crate::assignment::{assign, assign_local, PartMetric, Rule};
use crate::flooding::make_connected;
use crate::partition::{Partition, Solid, CELL_VAR};
use crate::sampling::NONE;

/// What an optimisation did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OptStats {
    /// Lloyd sweeps kept.
    pub sweeps: usize,
    /// Boundary samples moved by [`move_boundary_samples`].
    pub moves: usize,
    /// F before.
    pub f_before: f64,
    /// F after.
    pub f_after: f64,
}

/// Relative decrease of F below which a sweep counts as no progress.
const MIN_GAIN: f64 = 1e-7;

/// Optimise `part` in place: Lloyd sweeps over the parts `lloyd_parts`, then the boundary
/// sample moves over `move_parts` (`None`: all parts). Only samples of those parts move, and
/// only among them; the refinement uses this to re-optimise locally after a split.
pub fn optimize(
    solid: &Solid,
    part: &mut Partition,
    lloyd_parts: Option<&[u32]>,
    move_parts: Option<&[u32]>,
    max_sweeps: usize,
) -> OptStats {
    let f_before = part.f();
    let sweeps = lloyd(solid, part, lloyd_parts, max_sweeps);
    let moves = move_boundary_samples(solid, part, move_parts);
    OptStats {
        sweeps,
        moves,
        f_before,
        f_after: part.f(),
    }
}

/// Lloyd sweeps; returns how many were kept.
pub fn lloyd(
    solid: &Solid,
    part: &mut Partition,
    active: Option<&[u32]>,
    max_sweeps: usize,
) -> usize {
    let k = part.k();
    let candidates: Vec<u32> = match active {
        Some(a) => a.to_vec(),
        None => (0..k as u32).collect(),
    };
    let mut is_active = vec![active.is_none(); k];
    for &c in &candidates {
        is_active[c as usize] = true;
    }
    let samples: Vec<u32> = (0..solid.len() as u32)
        .filter(|&s| is_active[part.labels[s as usize] as usize])
        .collect();
    let mut f = part.f();
    let mut kept = 0;
    let mut rule = Rule::Paper;
    // Previous label of each sample touched in the current sweep (NONE: untouched).
    let mut prev = vec![NONE; solid.len()];
    // Whether each sample touches another part, kept up to date from the samples that moved.
    let mut is_boundary = vec![false; solid.len()];
    for &s in &samples {
        is_boundary[s as usize] = on_boundary(&solid.grid, &part.labels, &is_active, s);
    }
    let mut last_touched: Vec<u32> = Vec::new();
    for sweep in 0..max_sweeps {
        let metrics: Vec<PartMetric> = part.parts.iter().map(PartMetric::new).collect();
        // The first sweep looks at every candidate part; later ones only at the parts that
        // touch a sample's own part (and itself), where a connected partition can move it.
        // After the first sweeps, samples only change part near the boundaries between parts:
        // re-assign the band of samples within two steps of one.
        let (band, pairs) = if sweep >= 1 {
            // Only samples that changed part, and their neighbours, can change boundary status.
            let g = &solid.grid;
            for &s in &last_touched {
                is_boundary[s as usize] = on_boundary(g, &part.labels, &is_active, s);
                for &t in g.neighbors(s as usize) {
                    if t != NONE {
                        is_boundary[t as usize] = on_boundary(g, &part.labels, &is_active, t);
                    }
                }
            }
            boundary_band(solid, &part.labels, &samples, &is_active, &is_boundary)
        } else {
            (samples.clone(), Vec::new())
        };
        let band = if sweep >= 2 { band } else { samples.clone() };
        let best = if sweep == 0 || candidates.len() <= 4 {
            assign(solid, &band, &metrics, &candidates, rule)
        } else {
            let mut near: Vec<Vec<u32>> = (0..k as u32).map(|i| vec![i]).collect();
            for (a, b) in pairs {
                if is_active[a as usize] && is_active[b as usize] {
                    near[a as usize].push(b);
                    near[b as usize].push(a);
                }
            }
            assign_local(solid, &band, &part.labels, &metrics, &near, rule)
        };
        let mut touched = Vec::new();
        for (&s, &l) in band.iter().zip(&best) {
            let su = s as usize;
            if part.labels[su] != l {
                prev[su] = part.labels[su];
                touched.push(s);
                part.labels[su] = l;
            }
        }
        // Most moves provably keep their parts connected; only the parts of the others need
        // the (whole-part) repair.
        let repair = parts_to_repair(&solid.grid, &part.labels, &prev, &touched, k);
        let scope: Vec<u32> = if repair.iter().any(|&r| r) {
            samples
                .iter()
                .copied()
                .filter(|&s| repair[part.labels[s as usize] as usize])
                .collect()
        } else {
            Vec::new()
        };
        let fixed = if scope.is_empty() {
            Vec::new()
        } else {
            make_connected(
                &solid.grid,
                &mut part.labels,
                &solid.components,
                Some(&scope),
                |s, j| {
                    if is_active[j as usize] {
                        metrics[j as usize].cost_of(solid, s, rule)
                    } else {
                        f64::INFINITY
                    }
                },
            )
        };
        for (s, before) in fixed {
            if prev[s as usize] == NONE {
                prev[s as usize] = before;
                touched.push(s);
            }
        }
        let saved = part.parts.clone();
        let mut moved = 0usize;
        for &s in &touched {
            let su = s as usize;
            let (from, to) = (prev[su], part.labels[su]);
            if from != to {
                solid.remove(&mut part.parts[from as usize], su);
                solid.add(&mut part.parts[to as usize], su);
                moved += 1;
            }
        }
        let nf = if part.has_empty_part() {
            f64::INFINITY
        } else {
            part.f()
        };
        let accept = moved > 0 && nf < f * (1.0 - MIN_GAIN);
        if accept {
            f = nf;
            kept += 1;
        } else {
            part.parts = saved;
        }
        for &s in &touched {
            if !accept {
                part.labels[s as usize] = prev[s as usize];
            }
            prev[s as usize] = NONE;
        }
        last_touched = touched;
        // Few samples moved: the sweep has converged, the boundary moves finish the job.
        let converged = accept && (moved as f64) < 1e-3 * samples.len() as f64;
        if converged {
            break;
        }
        if !accept {
            if rule == Rule::Paper {
                rule = Rule::Corrected;
            } else {
                break;
            }
        }
    }
    kept
}

/// The parts that moving every sample `s` of `moved` from part `prev[s]` to `labels[s]` (all
/// at once) may have split: `true` for each part that needs a connectivity repair. Parts
/// connected before stay connected when each of their moves passes a local test:
/// - a sample leaving part `a` has a face neighbour still in `a`, no face neighbour that
///   left `a` too, and its face neighbours still in `a` are connected through samples of `a`
///   within its 3x3x3 neighbourhood: every path through it then has a detour;
/// - a sample joining part `b` has a face neighbour that was in `b` and stayed there.
fn parts_to_repair(
    grid: &crate::sampling::Grid,
    labels: &[u32],
    prev: &[u32],
    moved: &[u32],
    k: usize,
) -> Vec<bool> {
    let mut repair = vec![false; k];
    for &s in moved {
        let (a, b) = (prev[s as usize], labels[s as usize]);
        if a == b || !leaves_safely(grid, labels, prev, s, a) {
            repair[a as usize] = true;
            repair[b as usize] = true;
            continue;
        }
        let joins = grid
            .neighbors(s as usize)
            .iter()
            .any(|&t| t != NONE && labels[t as usize] == b && prev[t as usize] == NONE);
        if !joins {
            repair[a as usize] = true;
            repair[b as usize] = true;
        }
    }
    repair
}

/// The test of [`parts_to_repair`] for sample `s` leaving part `a`.
fn leaves_safely(
    grid: &crate::sampling::Grid,
    labels: &[u32],
    prev: &[u32],
    s: u32,
    a: u32,
) -> bool {
    for &t in grid.neighbors(s as usize) {
        if t != NONE && prev[t as usize] == a && labels[t as usize] != a {
            return false;
        }
    }
    if grid.side(s as usize) > 1 {
        return shell_connected(grid, s as usize, |t| labels[t as usize] == a) == Some(true);
    }
    // Cell (x, y, z) of the 3x3x3 neighbourhood is bit x + 3 y + 9 z (centre 13).
    let [i, j, l] = grid.coords[s as usize].map(|c| c as i64);
    let mut in_a = 0u32;
    for z in 0..3 {
        for y in 0..3 {
            for x in 0..3 {
                let t = grid.sample_at(i + x - 1, j + y - 1, l + z - 1);
                if t != NONE && labels[t as usize] == a {
                    in_a |= 1 << (x + 3 * y + 9 * z);
                }
            }
        }
    }
    in_a &= !(1 << 13);
    const FACES: u32 = (1 << 4) | (1 << 10) | (1 << 12) | (1 << 14) | (1 << 16) | (1 << 22);
    let faces = in_a & FACES;
    if faces == 0 {
        return false;
    }
    // Flood within the neighbourhood from one face neighbour.
    let mut seen = 1u32 << faces.trailing_zeros();
    loop {
        let mut grown = seen;
        let mut bits = seen;
        while bits != 0 {
            let c = bits.trailing_zeros();
            bits &= bits - 1;
            let (x, y, z) = (c % 3, (c / 3) % 3, c / 9);
            if x > 0 {
                grown |= 1 << (c - 1);
            }
            if x < 2 {
                grown |= 1 << (c + 1);
            }
            if y > 0 {
                grown |= 1 << (c - 3);
            }
            if y < 2 {
                grown |= 1 << (c + 3);
            }
            if z > 0 {
                grown |= 1 << (c - 9);
            }
            if z < 2 {
                grown |= 1 << (c + 9);
            }
        }
        grown &= in_a;
        if grown == seen {
            break;
        }
        seen = grown;
    }
    faces & !seen == 0
}

/// Whether sample `s` has a face neighbour in another active part (samples only move
/// between active parts, so a boundary with an inactive one is not where they move).
fn on_boundary(g: &crate::sampling::Grid, labels: &[u32], is_active: &[bool], s: u32) -> bool {
    let l = labels[s as usize];
    g.neighbors(s as usize).iter().any(|&t| {
        t != NONE && {
            let m = labels[t as usize];
            m != l && is_active[m as usize]
        }
    })
}

/// The samples of `scope` within two grid steps of a sample of another active part (sorted),
/// and the pairs of active parts that touch there. `is_boundary` tells which samples touch
/// another active part.
fn boundary_band(
    solid: &Solid,
    labels: &[u32],
    scope: &[u32],
    is_active: &[bool],
    is_boundary: &[bool],
) -> (Vec<u32>, Vec<(u32, u32)>) {
    let k = is_active.len();
    let g = &solid.grid;
    let mut mark = vec![false; labels.len()];
    let mut ring = Vec::new();
    // Touching pairs as a k x k bit set: sorting every sighting would cost more than the rest.
    let mut touch = vec![0u64; (k * k).div_ceil(64)];
    for &s in scope {
        if !is_boundary[s as usize] {
            continue;
        }
        let l = labels[s as usize];
        for &t in g.neighbors(s as usize) {
            if t != NONE && labels[t as usize] != l && is_active[labels[t as usize] as usize] {
                let m = labels[t as usize];
                let bit = l.min(m) as usize * k + l.max(m) as usize;
                touch[bit / 64] |= 1 << (bit % 64);
            }
        }
        mark[s as usize] = true;
        ring.push(s);
    }
    for _ in 0..2 {
        let mut next = Vec::new();
        for &s in &ring {
            let l = labels[s as usize];
            for &t in g.neighbors(s as usize) {
                // Rings stay within the scope: a neighbour in the same part is in it.
                if t != NONE && !mark[t as usize] && labels[t as usize] == l {
                    mark[t as usize] = true;
                    next.push(t);
                }
            }
        }
        ring = next;
    }
    let band = scope
        .iter()
        .copied()
        .filter(|&s| mark[s as usize])
        .collect();
    let mut pairs = Vec::new();
    for (w, &word) in touch.iter().enumerate() {
        let mut bits = word;
        while bits != 0 {
            let bit = w * 64 + bits.trailing_zeros() as usize;
            pairs.push(((bit / k) as u32, (bit % k) as u32));
            bits &= bits - 1;
        }
    }
    (band, pairs)
}

/// Whether removing sample `s` from `label` keeps that part connected, judged within the
/// 3x3x3 block around it: every face neighbour of `s` in the part must be reachable from the
/// others through the block without passing through `s`. This is sufficient (any path
/// through `s` can be rerouted inside the block) and cheap.
fn removable(solid: &Solid, labels: &[u32], s: usize, label: u32) -> bool {
    let grid = &solid.grid;
    if grid.side(s) > 1 {
        return shell_connected(grid, s, |t| labels[t as usize] == label) != Some(false);
    }
    let [ci, cj, ck] = grid.coords[s];
    let (ci, cj, ck) = (ci as i64, cj as i64, ck as i64);
    // Block cells in the part, indexed (dx+1) + 3 (dy+1) + 9 (dz+1).
    let mut inside = [false; 27];
    for dz in -1..=1i64 {
        for dy in -1..=1i64 {
            for dx in -1..=1i64 {
                if dx == 0 && dy == 0 && dz == 0 {
                    continue;
                }
                let t = grid.sample_at(ci + dx, cj + dy, ck + dz);
                if t != NONE && labels[t as usize] == label {
                    inside[((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)) as usize] = true;
                }
            }
        }
    }
    let faces = [4usize, 22, 10, 16, 12, 14];
    let mut present = faces.iter().copied().filter(|&f| inside[f]);
    let Some(first) = present.next() else {
        return true;
    };
    if present.next().is_none() {
        // A leaf of the part (or its last sample, which the caller refuses anyway).
        return true;
    }
    // A flood over the 27 cells, in fixed arrays: this runs for every boundary sample of
    // every call of `move_boundary_samples`, where a heap allocation per call showed in the profile.
    let mut seen = [false; 27];
    let mut stack = [0usize; 27];
    let mut top = 1;
    stack[0] = first;
    seen[first] = true;
    while top > 0 {
        top -= 1;
        let c = stack[top];
        let (x, y, z) = ((c % 3) as i64, ((c / 3) % 3) as i64, (c / 9) as i64);
        for (dx, dy, dz) in [
            (-1, 0, 0),
            (1, 0, 0),
            (0, -1, 0),
            (0, 1, 0),
            (0, 0, -1),
            (0, 0, 1),
        ] {
            let (nx, ny, nz) = (x + dx, y + dy, z + dz);
            if !(0..3).contains(&nx) || !(0..3).contains(&ny) || !(0..3).contains(&nz) {
                continue;
            }
            let nc = (nx + 3 * ny + 9 * nz) as usize;
            if inside[nc] && !seen[nc] {
                seen[nc] = true;
                stack[top] = nc;
                top += 1;
            }
        }
    }
    faces.iter().all(|&f| !inside[f] || seen[f])
}

/// The test of [`removable`] and [`leaves_safely`] for a block of adaptive sampling: within
/// the shell of cells one deep around the block, whether the cells across its faces whose
/// samples `in_part` accepts are all connected through such cells (`None` when there are
/// none). Any path through the block enters and leaves through such cells, so when they are
/// connected around it, the block can leave the part without cutting it. (For a single cell
/// this is the 3x3x3 test the callers run on bit masks.)
fn shell_connected(
    grid: &crate::sampling::Grid,
    s: usize,
    in_part: impl Fn(u32) -> bool,
) -> Option<bool> {
    let b = i64::from(grid.side(s));
    let w = (b + 2) as usize;
    let c = grid.coords[s].map(i64::from);
    let at = |x: usize, y: usize, z: usize| x + w * (y + w * z);
    let in_block = |v: i64| (1..=b).contains(&v);
    let mut cell = vec![false; w * w * w];
    let mut faces = Vec::new();
    for z in 0..w {
        for y in 0..w {
            for x in 0..w {
                let o = [x as i64, y as i64, z as i64];
                let inner = o.iter().filter(|&&v| in_block(v)).count();
                if inner == 3 {
                    continue;
                }
                let t = grid.sample_at(c[0] + o[0] - 1, c[1] + o[1] - 1, c[2] + o[2] - 1);
                if t != NONE && t as usize != s && in_part(t) {
                    cell[at(x, y, z)] = true;
                    if inner == 2 {
                        faces.push(at(x, y, z));
                    }
                }
            }
        }
    }
    let &first = faces.first()?;
    let mut seen = vec![false; w * w * w];
    let mut stack = vec![first];
    seen[first] = true;
    while let Some(i) = stack.pop() {
        let (x, y, z) = (i % w, (i / w) % w, i / (w * w));
        let mut visit = |j: usize| {
            if cell[j] && !seen[j] {
                seen[j] = true;
                stack.push(j);
            }
        };
        if x > 0 {
            visit(at(x - 1, y, z));
        }
        if x + 1 < w {
            visit(at(x + 1, y, z));
        }
        if y > 0 {
            visit(at(x, y - 1, z));
        }
        if y + 1 < w {
            visit(at(x, y + 1, z));
        }
        if z > 0 {
            visit(at(x, y, z - 1));
        }
        if z + 1 < w {
            visit(at(x, y, z + 1));
        }
    }
    Some(faces.iter().all(|&f| seen[f]))
}

/// Moves single boundary samples to a neighbouring part while the exact change of F is
/// negative and the part left stays connected; returns the number of moves.
pub fn move_boundary_samples(solid: &Solid, part: &mut Partition, active: Option<&[u32]>) -> usize {
    let k = part.k();
    let mut is_active = vec![active.is_none(); k];
    if let Some(a) = active {
        for &c in a {
            is_active[c as usize] = true;
        }
    }
    let grid = &solid.grid;
    let n = solid.len();
    let mut queued = vec![false; n];
    let mut queue = std::collections::VecDeque::new();
    for s in 0..n {
        let l = part.labels[s];
        if is_active[l as usize]
            && grid
                .neighbors(s)
                .iter()
                .any(|&t| t != NONE && part.labels[t as usize] != l)
        {
            queued[s] = true;
            queue.push_back(s);
        }
    }
    let mut terms: Vec<f64> = part.parts.iter().map(|m| m.f_term(CELL_VAR, 1.0)).collect();
    let mut moves = 0;
    // Each move lowers F strictly, so this terminates; the cap bounds pathological cases.
    let cap = 20 * n + 1000;
    while let Some(s) = queue.pop_front() {
        queued[s] = false;
        if moves >= cap {
            break;
        }
        let a = part.labels[s];
        if !is_active[a as usize] || part.parts[a as usize].n <= f64::from(grid.weight(s)) {
            continue;
        }
        let mut from = part.parts[a as usize];
        solid.remove(&mut from, s);
        let from_term = from.f_term(CELL_VAR, 1.0);
        let mut best = None;
        let mut best_gain = 0.0;
        for &t in grid.neighbors(s) {
            if t == NONE {
                continue;
            }
            let b = part.labels[t as usize];
            if b == a || !is_active[b as usize] {
                continue;
            }
            let mut to = part.parts[b as usize];
            solid.add(&mut to, s);
            let to_term = to.f_term(CELL_VAR, 1.0);
            let gain = terms[a as usize] + terms[b as usize] - from_term - to_term;
            // A relative threshold keeps round-off from cycling samples back and forth.
            if gain > best_gain && gain > 1e-10 * (terms[a as usize] + terms[b as usize]) {
                best_gain = gain;
                best = Some((b, to_term));
            }
        }
        let Some((b, to_term)) = best else { continue };
        if !removable(solid, &part.labels, s, a) {
            continue;
        }
        part.move_sample(solid, s, b);
        terms[a as usize] = from_term;
        terms[b as usize] = to_term;
        moves += 1;
        for &t in grid.neighbors(s).iter() {
            if t != NONE && !queued[t as usize] {
                queued[t as usize] = true;
                queue.push_back(t as usize);
            }
        }
        if !queued[s] {
            queued[s] = true;
            queue.push_back(s);
        }
    }
    moves
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flooding::is_connected;
    use crate::initialization::cvt;
    use crate::sampling::Grid;
    use glam::DVec3;

    /// An L-shaped solid made of two boxes: its best 2-partition is the two boxes.
    fn l_shape() -> Grid {
        Grid::from_inside_fn(DVec3::ZERO, DVec3::new(3.0, 3.0, 1.0), 0.1, |p| {
            let in_a = p.x <= 3.0 && p.y <= 1.0;
            let in_b = p.x <= 1.0 && p.y <= 3.0;
            p.x >= 0.0 && p.y >= 0.0 && p.z >= 0.0 && p.z <= 1.0 && (in_a || in_b)
        })
    }

    /// Whether the samples labelled `l` form one connected piece (or none).
    fn part_connected(g: &Grid, labels: &[u32], l: u32) -> bool {
        let members: Vec<u32> = (0..labels.len() as u32)
            .filter(|&s| labels[s as usize] == l)
            .collect();
        let (piece, _, _) = crate::flooding::pieces_in(g, labels, members.iter().copied());
        members.iter().all(|&s| piece[s as usize] == 0)
    }

    /// A slab with a few pillars of holes: parts can break in many ways around them. With
    /// `blocks`, sampled finer and adaptively, so that blocks fill the slab between the holes.
    fn holey_slab(blocks: bool) -> Grid {
        let h = if blocks { 0.025 } else { 0.1 };
        let g = Grid::from_inside_fn(DVec3::ZERO, DVec3::new(2.0, 2.0, 0.5), h, |p| {
            let hole = ((p.x * 5.0) as i64 % 3 == 1) && ((p.y * 5.0) as i64 % 3 == 1);
            (0.0..=2.0).contains(&p.x)
                && (0.0..=2.0).contains(&p.y)
                && (0.0..=0.5).contains(&p.z)
                && !hole
        });
        if blocks {
            let g = g.into_blocks();
            assert!(g.has_blocks());
            g
        } else {
            g
        }
    }

    /// The 3x3x3 test of [`removable`] on single cells is a flood over the block without its
    /// centre: checked against a plain flood over the samples themselves, on random labels.
    #[test]
    fn removable_is_the_block_flood() {
        let g = Grid::from_inside_fn(DVec3::ZERO, DVec3::splat(0.5), 0.1, |_| true);
        let solid = Solid::new(g);
        let g = &solid.grid;
        let centre = g.sample_at(2, 2, 2) as usize;
        let block: Vec<u32> = (0..g.len() as u32)
            .filter(|&t| {
                let (c, d) = (g.coords[t as usize], g.coords[centre]);
                t as usize != centre && (0..3).all(|a| c[a].abs_diff(d[a]) <= 1)
            })
            .collect();
        assert_eq!(block.len(), 26);
        let mut rng = crate::rng::Rng::new(7);
        let (mut yes, mut no) = (0, 0);
        for _ in 0..3000 {
            let mut labels: Vec<u32> = (0..g.len()).map(|_| (rng.below(3) == 0) as u32).collect();
            labels[centre] = 0;
            let faces: Vec<u32> = g
                .neighbors(centre)
                .iter()
                .copied()
                .filter(|&t| t != NONE && labels[t as usize] == 0)
                .collect();
            let expected = faces.len() <= 1 || {
                let mut seen = vec![faces[0]];
                let mut stack = vec![faces[0]];
                while let Some(x) = stack.pop() {
                    for &t in g.neighbors(x as usize) {
                        if block.contains(&t) && labels[t as usize] == 0 && !seen.contains(&t) {
                            seen.push(t);
                            stack.push(t);
                        }
                    }
                }
                faces.iter().all(|f| seen.contains(f))
            };
            assert_eq!(removable(&solid, &labels, centre, 0), expected);
            if expected {
                yes += 1;
            } else {
                no += 1;
            }
        }
        assert!(yes > 100 && no > 100, "both answers tried: {yes} and {no}");
    }

    /// The local test that lets the Lloyd sweeps skip most connectivity repairs must never
    /// pass a part that came apart: random batches of boundary moves on a holey solid.
    #[test]
    fn parts_the_local_test_passes_stay_connected() {
        local_test_passes_only_connected_parts(holey_slab(false));
    }

    /// The same on adaptive sampling, whose blocks take the general shell test.
    #[test]
    fn parts_the_local_test_passes_stay_connected_with_blocks() {
        local_test_passes_only_connected_parts(holey_slab(true));
    }

    fn local_test_passes_only_connected_parts(g: Grid) {
        let solid = Solid::new(g);
        let g = &solid.grid;
        let mut rng = crate::rng::Rng::new(7);
        let (mut passed, mut flagged, mut blocks_moved) = (0, 0, 0);
        // About as many moves per part on the finer adaptive slab as on the regular one.
        let rate = if g.has_blocks() { 60 } else { 25 };
        for round in 0..200 {
            let k = 3 + round % 6;
            let part = cvt(&solid, k, round as u64);
            let mut labels = part.labels.clone();
            let mut prev = vec![NONE; labels.len()];
            let mut moved = Vec::new();
            // Move a random share of the boundary samples to a random neighbouring part.
            for s in 0..labels.len() as u32 {
                let l = part.labels[s as usize];
                let others: Vec<u32> = g
                    .neighbors(s as usize)
                    .iter()
                    .filter(|&&t| t != NONE && part.labels[t as usize] != l)
                    .map(|&t| part.labels[t as usize])
                    .collect();
                if !others.is_empty() && rng.below(rate) == 0 {
                    labels[s as usize] = others[rng.below(others.len())];
                    prev[s as usize] = l;
                    moved.push(s);
                    blocks_moved += usize::from(g.side(s as usize) > 1);
                }
            }
            let repair = parts_to_repair(g, &labels, &prev, &moved, k);
            for l in 0..k as u32 {
                let was = part_connected(g, &part.labels, l);
                if was && !repair[l as usize] {
                    passed += 1;
                    assert!(part_connected(g, &labels, l), "round {round}, part {l}");
                } else {
                    flagged += 1;
                }
            }
        }
        // The test is only worth something if both outcomes occur often.
        assert!(
            passed > 100 && flagged > 100,
            "{passed} passed, {flagged} flagged"
        );
        assert_eq!(
            g.has_blocks(),
            blocks_moved > 50,
            "{blocks_moved} blocks moved"
        );
    }

    /// The shell test on a block: a block that is the only link of a bar through it may not
    /// leave the bar's part; a block at the edge of a half-space part may.
    #[test]
    fn a_block_that_links_a_bar_cannot_leave_it() {
        let g = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), 0.05, |p| {
            p.abs().max_element() <= 0.95
        })
        .into_blocks();
        let solid = Solid::new(g);
        let g = &solid.grid;
        let nx = g.dims[0];
        let s = (0..g.len())
            .filter(|&s| g.side(s) == 2)
            .min_by_key(|&s| {
                g.coords[s]
                    .map(|c| (c as i64 - nx as i64 / 2).abs())
                    .iter()
                    .sum::<i64>()
            })
            .unwrap();
        let [_, cy, cz] = g.coords[s];
        let bar = |t: usize| {
            g.cells_of(t)
                .any(|[_, y, z]| (cy..cy + 2).contains(&y) && (cz..cz + 2).contains(&z))
        };
        let labels: Vec<u32> = (0..g.len()).map(|t| u32::from(!bar(t))).collect();
        assert!(!removable(&solid, &labels, s, 0));
        let prev = vec![NONE; labels.len()];
        assert!(!leaves_safely(g, &labels, &prev, s as u32, 0));
        // The whole half below the block's top, block included: the rest holds together
        // around it.
        let below = |t: usize| g.cells_of(t).any(|[_, _, z]| z < cz + 2);
        let labels: Vec<u32> = (0..g.len()).map(|t| u32::from(!below(t))).collect();
        assert_eq!(labels[s], 0);
        assert!(removable(&solid, &labels, s, 0));
        assert!(leaves_safely(g, &labels, &prev, s as u32, 0));
    }

    #[test]
    fn optimisation_never_raises_f_and_keeps_parts_connected() {
        optimisation_keeps_its_promises(Solid::new(l_shape()));
    }

    /// The same on adaptive sampling: blocks move whole, moments stay exact.
    #[test]
    fn optimisation_keeps_its_promises_with_blocks() {
        optimisation_keeps_its_promises(Solid::new(holey_slab(true)));
    }

    fn optimisation_keeps_its_promises(solid: Solid) {
        for seed in 0..4 {
            let mut part = cvt(&solid, 5, seed);
            let stats = optimize(&solid, &mut part, None, None, 100);
            assert!(stats.f_after <= stats.f_before, "{stats:?}");
            assert!(stats.f_after >= 1.0);
            assert_eq!(part.k(), 5);
            assert!(is_connected(&solid.grid, &part.labels, &solid.components));
            // Moments stay exactly those of the labels.
            let fresh = Partition::from_labels(&solid, part.labels.clone(), 5);
            assert_eq!(fresh, part);
        }
    }

    #[test]
    fn two_parts_of_an_l_are_its_two_arms() {
        let solid = Solid::new(l_shape());
        let mut part = cvt(&solid, 2, 1);
        optimize(&solid, &mut part, None, None, 100);
        // Box-like parts: F close to a box's e (1.127), far below the single-part F.
        let one = Partition::from_labels(&solid, vec![0; solid.len()], 1);
        assert!(
            part.f() < 1.16 && one.f() > 1.25,
            "{} vs {}",
            part.f(),
            one.f()
        );
    }
}
