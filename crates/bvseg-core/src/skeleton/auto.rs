//! An approximate curve skeleton of the solid, for meshes without one (`SkeletonMode::Auto`):
//! a Reeb-style graph of the geodesic distance inside the solid.
//!
//! 1. Each piece of the solid is rooted at its thickest sample (largest distance to the
//!    boundary, [`crate::sampling::distance`]): the torso of a character, the palm of a
//!    hand.
//! 2. The geodesic distance from the root along the samples' face-neighbour graph cuts the
//!    piece into bands as wide as the root is thick; every connected region of a band is a
//!    joint at the region's centroid, and regions of neighbouring bands that touch are
//!    linked. A limb becomes a chain of joints along its length, and a band that meets
//!    several limbs gives one region, one branch, per limb.
//! 3. A region whose centroid lies within half a band of its parent's (the shell of a band
//!    around a thick root is one region centred on the root) and a region of a handful of
//!    samples are folded into their parent.
//!
//! The links of this skeleton seed the start as a given skeleton's would ([`super::seeds`]);
//! they bind no bones.
use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::{DMat4, DVec3};

use crate::partition::Solid;
use crate::sampling::NONE;
use crate::{Joint, Skeleton};

/// Fewest samples a region needs to be a joint of its own.
const MIN_REGION: usize = 8;

/// Narrowest band, in cells: narrower bands follow the lattice's staircase, not the shape.
const MIN_BAND: u32 = 3;

/// The approximate curve skeleton of `solid` (see the module's docs), in world coordinates.
pub fn curve_skeleton(solid: &Solid) -> Skeleton {
    let g = &solid.grid;
    let n = solid.len();
    if n == 0 {
        return Skeleton::default();
    }
    let thickness = g.boundary_distance();
    // The root of each piece: its thickest sample, the first on ties.
    let mut root = vec![usize::MAX; solid.pieces];
    for s in 0..n {
        let c = solid.components[s] as usize;
        if root[c] == usize::MAX || thickness[s] > thickness[root[c]] {
            root[c] = s;
        }
    }
    // Geodesic distance in half cells along the face-neighbour graph, from every piece's
    // root: a step between samples is as long as half their sides summed (one cell between
    // single cells, more to and from the blocks of adaptive sampling).
    let mut geo = vec![u32::MAX; n];
    let mut queue = BinaryHeap::new();
    for &r in root.iter().filter(|&&r| r != usize::MAX) {
        geo[r] = 0;
        queue.push(Reverse((0u32, r)));
    }
    while let Some(Reverse((d, s))) = queue.pop() {
        if d > geo[s] {
            continue;
        }
        for &t in g.neighbors(s) {
            if t == NONE {
                continue;
            }
            let t = t as usize;
            let to = d + g.side(s) + g.side(t);
            if to < geo[t] {
                geo[t] = to;
                queue.push(Reverse((to, t)));
            }
        }
    }
    let band_of = |s: usize| {
        let c = solid.components[s] as usize;
        let w = (thickness[root[c]].round() as u32).max(MIN_BAND);
        geo[s] / (2 * w)
    };
    let band: Vec<u32> = (0..n).map(band_of).collect();
    // The connected regions of each band, numbered by their first sample.
    let mut region = vec![u32::MAX; n];
    let mut members: Vec<Vec<u32>> = Vec::new();
    for s in 0..n {
        if region[s] != u32::MAX {
            continue;
        }
        let r = members.len() as u32;
        let mut list = vec![s as u32];
        region[s] = r;
        let mut at = 0;
        while at < list.len() {
            let x = list[at] as usize;
            at += 1;
            for &t in g.neighbors(x) {
                let t = t as usize;
                if t != NONE as usize && region[t] == u32::MAX && band[t] == band[x] {
                    region[t] = r;
                    list.push(t as u32);
                }
            }
        }
        members.push(list);
    }
    let regions = members.len();
    // Links from each region to the regions of the next band out that it touches.
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for s in 0..n {
        for &t in g.neighbors(s) {
            if t != NONE && band[t as usize] == band[s] + 1 {
                edges.push((region[s], region[t as usize]));
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    // A tree: each region's parent is the first region of the band before it that touches
    // it (the graph of a solid with handles has cycles; the tree drops their last links).
    let mut parent: Vec<Option<usize>> = vec![None; regions];
    let mut has_parent = vec![false; regions];
    for &(a, b) in &edges {
        if !has_parent[b as usize] {
            has_parent[b as usize] = true;
            parent[b as usize] = Some(a as usize);
        }
    }
    let centroid: Vec<DVec3> = members
        .iter()
        .map(|m| {
            let w = |s: u32| f64::from(g.weight(s as usize));
            let sum: DVec3 = m.iter().map(|&s| w(s) * g.points[s as usize]).sum();
            sum / m.iter().map(|&s| w(s)).sum::<f64>()
        })
        .collect();
    // Fold small regions and regions centred near their parent into the parent. Parents
    // come from earlier bands, so visiting regions by band folds each chain from its root.
    let mut order: Vec<usize> = (0..regions).collect();
    order.sort_by_key(|&r| (band[members[r][0] as usize], r));
    let mut kept_as: Vec<usize> = (0..regions).collect();
    for &r in &order {
        let Some(p) = parent[r] else { continue };
        let p = kept_as[p];
        let c = solid.components[members[r][0] as usize] as usize;
        let w = f64::from((thickness[root[c]].round() as u32).max(MIN_BAND)) * g.h;
        if members[r].len() < MIN_REGION || (centroid[r] - centroid[p]).length() < 0.5 * w {
            kept_as[r] = p;
        }
    }
    let mut joint_of = vec![usize::MAX; regions];
    let mut joints = Vec::new();
    for &r in &order {
        if kept_as[r] != r {
            continue;
        }
        joint_of[r] = joints.len();
        joints.push(Joint {
            name: format!("auto_{}", joints.len()),
            parent: parent[r].map(|p| joint_of[kept_as[p]]),
            rest: DMat4::from_translation(centroid[r]),
            node: None,
        });
    }
    Skeleton { joints }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Grid;

    #[test]
    fn a_star_gets_a_chain_per_arm() {
        // A ball with three long arms along +x, +y and -x.
        let g = Grid::from_inside_fn(
            DVec3::new(-3.0, -0.6, -0.6),
            DVec3::new(3.0, 3.0, 0.6),
            0.06,
            |p| {
                let ball = p.length() < 0.5;
                let tube = |d: DVec3| {
                    let t = p.dot(d);
                    t > 0.0 && t < 2.8 && (p - t * d).length() < 0.15
                };
                ball || tube(DVec3::X) || tube(DVec3::Y) || tube(-DVec3::X)
            },
        );
        let solid = Solid::new(g);
        let sk = curve_skeleton(&solid);
        assert_eq!(sk.validate(), Ok(()));
        assert_eq!(sk.joints.iter().filter(|j| j.parent.is_none()).count(), 1);
        // Three tips: leaves far out along each arm.
        let leaves: Vec<DVec3> = (0..sk.joints.len())
            .filter(|&i| sk.joints.iter().all(|j| j.parent != Some(i)))
            .map(|i| sk.joints[i].position())
            .collect();
        for d in [DVec3::X, DVec3::Y, -DVec3::X] {
            assert!(
                leaves.iter().any(|l| l.dot(d) > 2.0),
                "no tip along {d}: {leaves:?}"
            );
        }
        assert_eq!(leaves.len(), 3, "{leaves:?}");
        // Every joint lies near the solid's axis lines or the ball.
        for j in &sk.joints {
            let p = j.position();
            let near_axis = p.y.abs() < 0.2 || p.x.abs() < 0.2;
            assert!(near_axis && p.z.abs() < 0.2, "{p}");
        }
    }
}
