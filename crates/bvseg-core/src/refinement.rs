//! Stage 9: the refinement loop (placeholder until the pipeline lands).
use crate::{
    BoundingKind, Error, Mesh, Metrics, Params, Part, Segmentation, Step,
};

/// Steppable segmentation.
pub struct Segmenter {
    params: Params,
    tri: usize,
}

impl Segmenter {
    /// Start a segmentation.
    pub fn new(mesh: &Mesh, params: &Params) -> Result<Self, Error> {
        params.validate()?;
        Ok(Self { params: params.clone(), tri: mesh.triangles().len() })
    }

    /// Run one step; `None` when done.
    pub fn step(&mut self) -> Option<Step> {
        None
    }

    /// The result.
    pub fn finish(self) -> Segmentation {
        let _ = BoundingKind::Ellipsoid;
        let v = crate::bounding::mvee::mvee(&[glam::DVec3::ZERO], 1e-3, 1.0);
        Segmentation {
            kind: self.params.bounding,
            parts: vec![Part { volume: v, fraction: 1.0, samples: 1, ov: 0.0, e: 1.0 }],
            metrics: Metrics { k: 1, f: 1.0, tov: 0.0, mov: 0.0, samples: 1 },
            history: vec![],
            hierarchy: vec![],
            triangle_parts: vec![0; self.tri],
            sample_parts: vec![0],
            cell_size: 1.0,
        }
    }
}
