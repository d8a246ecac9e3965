//! The paper's section 6.1: a skeleton seeds the start with one part per link, and binds
//! every part to a bone.
//!
//! - [`seeds`]: the start, each sample given to the link nearest to it, kept connected, then
//!   optimised for that k.
//! - [`bones`]: which bone each part moves with: the bone carrying most of its triangles'
//!   skin weight, or without a skin, the bone whose link is nearest most of its samples
//!   (for a part the skeleton seeded, the link that seeded it).
//! - [`auto`]: an approximate curve skeleton of the solid, for meshes that have none.
pub mod auto;
pub mod bones;
pub mod seeds;

use glam::DVec3;

use crate::geometry::closest_on_segment;
use crate::partition::Solid;
use crate::Skeleton;

/// A link of the skeleton as a segment in the lattice's units ([`Solid::q`]), with the joint
/// (the bone) it belongs to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Link {
    /// The joint the link starts at: its bone.
    pub bone: usize,
    /// The segment's ends.
    pub a: DVec3,
    /// See `a`.
    pub b: DVec3,
}

impl Link {
    /// Squared distance from `q` to the segment.
    #[inline]
    pub fn dist2(&self, q: DVec3) -> f64 {
        (q - closest_on_segment(q, self.a, self.b)).length_squared()
    }
}

/// The links of `skeleton` in the lattice units of `solid`; a skeleton of joints without
/// links gives each joint a point link of its own, so that a lone joint still binds parts.
pub fn links(skeleton: &Skeleton, solid: &Solid) -> Vec<Link> {
    let g = &solid.grid;
    let off = DVec3::new(
        solid.offset[0] as f64,
        solid.offset[1] as f64,
        solid.offset[2] as f64,
    );
    let q = |p: DVec3| (p - g.origin) / g.h - off;
    let pairs = skeleton.links();
    if pairs.is_empty() {
        return skeleton
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| Link {
                bone: i,
                a: q(j.position()),
                b: q(j.position()),
            })
            .collect();
    }
    pairs
        .into_iter()
        .map(|(p, c)| Link {
            bone: p,
            a: q(skeleton.joints[p].position()),
            b: q(skeleton.joints[c].position()),
        })
        .collect()
}

/// The index into `links` of the link nearest `q` (the first on ties).
pub fn nearest(links: &[Link], q: DVec3) -> usize {
    let mut best = (f64::INFINITY, 0);
    for (i, l) in links.iter().enumerate() {
        let d = l.dist2(q);
        if d < best.0 {
            best = (d, i);
        }
    }
    best.1
}
