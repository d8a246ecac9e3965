//! The input: a triangle mesh, validated once so that later stages can trust it.
mod weld;

#[cfg(test)]
pub(crate) use weld::edges_balance;
pub use weld::weld;

use std::sync::Arc;

use glam::{DVec3, Vec3};

use crate::{MeshError, Rig, RigError};

/// Coordinates beyond this magnitude are rejected: products of three of them (volumes) must
/// stay far from f64 overflow.
pub const MAX_COORDINATE: f64 = 1e100;

/// A triangle mesh: positions and vertex-index triples. The solid is what the surface
/// encloses; orientation may be outward or inward, and several shells are allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    rig: Option<Arc<Rig>>,
}

impl Mesh {
    /// Build a mesh, checking that it has triangles, that every coordinate is finite and
    /// below [`MAX_COORDINATE`] in magnitude, and that every index is in range.
    ///
    /// # Errors
    ///
    /// The first of these checks that fails, as a [`MeshError`].
    pub fn new(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if triangles.is_empty() {
            return Err(MeshError::NoTriangles);
        }
        if let Some(index) = vertices
            .iter()
            .position(|v| !v.is_finite() || v.abs().max_element() > MAX_COORDINATE)
        {
            return Err(MeshError::BadVertex { index });
        }
        // Every loader ends here, so this is where reading a file's triangles is counted.
        crate::work::add(triangles.len());
        let count = vertices.len();
        for (index, t) in triangles.iter().enumerate() {
            if let Some(&vertex) = t.iter().find(|&&v| v as usize >= count) {
                return Err(MeshError::BadIndex {
                    index,
                    vertex,
                    count,
                });
            }
        }
        Ok(Self {
            vertices,
            triangles,
            rig: None,
        })
    }

    /// The mesh with a rig: a skeleton to seed parts from and, for a skinned mesh, the poses
    /// its volumes must follow ([`Rig`]). The mesh's vertices are the rest pose.
    ///
    /// # Errors
    ///
    /// [`Rig::validate`]'s, against this mesh's vertex and triangle counts.
    pub fn with_rig(mut self, rig: Rig) -> Result<Self, RigError> {
        rig.validate(self.vertices.len(), self.triangles.len())?;
        self.rig = Some(Arc::new(rig));
        Ok(self)
    }

    /// The mesh's rig, if it has one.
    pub fn rig(&self) -> Option<&Rig> {
        self.rig.as_deref()
    }

    /// Like [`Mesh::new`] from single-precision positions, as most engines store them.
    ///
    /// # Errors
    ///
    /// As [`Mesh::new`].
    pub fn from_f32(vertices: &[Vec3], triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        Self::new(vertices.iter().map(|v| v.as_dvec3()).collect(), triangles)
    }

    /// Vertex positions.
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// Triangles as vertex-index triples.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The three corners of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// Axis-aligned bounding box of the vertices that triangles use.
    pub fn bbox(&self) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for t in &self.triangles {
            for &v in t {
                let p = self.vertices[v as usize];
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (lo, hi)
    }

    /// Signed volume by the divergence theorem (positive for outward-facing closed meshes).
    /// Computed relative to the box centre to limit cancellation.
    pub fn signed_volume(&self) -> f64 {
        let (lo, hi) = self.bbox();
        let c = 0.5 * (lo + hi);
        self.triangles
            .iter()
            .enumerate()
            .map(|(t, _)| {
                let [a, b, d] = self.corners(t);
                (a - c).dot((b - c).cross(d - c)) / 6.0
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_input() {
        assert_eq!(Mesh::new(vec![], vec![]), Err(MeshError::NoTriangles));
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::new(f64::NAN, 0.0, 0.0)];
        assert_eq!(
            Mesh::new(v, vec![[0, 1, 2]]),
            Err(MeshError::BadVertex { index: 2 })
        );
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!(matches!(
            Mesh::new(v, vec![[0, 1, 3]]),
            Err(MeshError::BadIndex { vertex: 3, .. })
        ));
    }
}
