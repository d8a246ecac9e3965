//! The mesh as the checks read it: validated positions and index triples.
use glam::DVec3;

use crate::{VerifyError, MAX_COORDINATE};

/// A validated mesh: finite positions within [`MAX_COORDINATE`], at least one triangle,
/// every index in range.
pub(crate) struct MeshRef<'a> {
    vertices: Vec<DVec3>,
    triangles: &'a [[u32; 3]],
}

impl<'a> MeshRef<'a> {
    pub(crate) fn new(
        vertices: &[[f64; 3]],
        triangles: &'a [[u32; 3]],
    ) -> Result<Self, VerifyError> {
        if triangles.is_empty() {
            return Err(VerifyError::NoTriangles);
        }
        let vertices: Vec<DVec3> = vertices.iter().map(|&p| DVec3::from_array(p)).collect();
        if let Some(index) = vertices
            .iter()
            .position(|v| !v.is_finite() || v.abs().max_element() > MAX_COORDINATE)
        {
            return Err(VerifyError::BadVertex { index });
        }
        let count = vertices.len();
        for (index, t) in triangles.iter().enumerate() {
            if let Some(&vertex) = t.iter().find(|&&v| v as usize >= count) {
                return Err(VerifyError::BadIndex {
                    index,
                    vertex,
                    count,
                });
            }
        }
        Ok(Self {
            vertices,
            triangles,
        })
    }

    pub(crate) fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    pub(crate) fn triangles(&self) -> &[[u32; 3]] {
        self.triangles
    }

    /// The three corners of triangle `t`.
    #[inline]
    pub(crate) fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// Axis-aligned bounding box of the vertices that triangles use.
    pub(crate) fn bbox(&self) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for t in self.triangles {
            for &v in t {
                let p = self.vertices[v as usize];
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (lo, hi)
    }
}
