//! Top-down: a cluster that reaches too far past the surface is cut in two by a plane across
//! its principal axis of largest spread, at the median of its area.
use glam::{DMat3, DVec3};

use super::bound::{Bounder, Fit};
use super::Atom;
use crate::linalg::sym_eigen;

/// A set of atoms bound by one volume, moving with one bone.
#[derive(Debug, Clone)]
pub struct Cluster {
    pub atoms: Vec<usize>,
    pub bone: Option<usize>,
    pub fit: Fit,
}

impl Cluster {
    pub fn new(b: &Bounder, atoms: &[Atom], members: Vec<usize>, bone: Option<usize>) -> Self {
        let fit = b.fit(&triangles(atoms, &members), bone);
        Self {
            atoms: members,
            bone,
            fit,
        }
    }
}

/// The triangles of `members`, in order.
pub fn triangles(atoms: &[Atom], members: &[usize]) -> Vec<u32> {
    let mut t: Vec<u32> = members
        .iter()
        .flat_map(|&a| atoms[a].triangles.iter().copied())
        .collect();
    t.sort_unstable();
    t
}

/// The cut of `c` in two, or `None` when it is one atom.
pub fn split(b: &Bounder, atoms: &[Atom], c: &Cluster) -> Option<[Cluster; 2]> {
    if c.atoms.len() < 2 {
        return None;
    }
    let weight: f64 = c.atoms.iter().map(|&a| atoms[a].area).sum();
    let mean = c
        .atoms
        .iter()
        .map(|&a| atoms[a].area * atoms[a].centroid)
        .sum::<DVec3>()
        / weight;
    let mut cov = DMat3::ZERO;
    for &a in &c.atoms {
        let d = atoms[a].centroid - mean;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z) * atoms[a].area;
    }
    let (_, axes) = sym_eigen(cov);
    // Across the longest spread: slices of a closed piece hold its inside (strips along it
    // would leave the middle of a tube empty).
    let axis = axes.x_axis;
    let key = |a: usize| axis.dot(atoms[a].centroid);
    let mut order = c.atoms.clone();
    order.sort_by(|&x, &y| key(x).total_cmp(&key(y)).then(x.cmp(&y)));
    // At the area's median: both sides get about half of the surface.
    let mut acc = 0.0;
    let mut at = 1;
    for (i, &a) in order.iter().enumerate() {
        acc += atoms[a].area;
        if acc >= 0.5 * weight {
            at = (i + 1).clamp(1, order.len() - 1);
            break;
        }
    }
    let (lo, hi) = order.split_at(at);
    Some([
        Cluster::new(b, atoms, lo.to_vec(), c.bone),
        Cluster::new(b, atoms, hi.to_vec(), c.bone),
    ])
}
