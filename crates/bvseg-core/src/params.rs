//! What the user controls.
use crate::Error;

/// Which bounding volume each part gets in the final output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum BoundingKind {
    /// Minimum-volume enclosing ellipsoid of each part.
    #[default]
    Ellipsoid,
    /// Tight oriented bounding box of each part.
    Obb,
    /// Per part, whichever of the two is smaller.
    Mixed,
}

impl BoundingKind {
    /// The name used in the `bvseg.volumes/1` JSON schema.
    pub fn as_str(self) -> &'static str {
        match self {
            BoundingKind::Ellipsoid => "ellipsoid",
            BoundingKind::Obb => "obb",
            BoundingKind::Mixed => "mixed",
        }
    }
}

/// Parameters of [`crate::segment`]. `Params::default()` is the paper's set-up: 20,000
/// samples, tolerances 0.3 (total) and 0.5 (per part), at most 64 parts, ellipsoids.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// Target number of interior samples (grid cells inside the solid).
    pub samples: usize,
    /// Seed of the initialisation; equal seeds give bit-identical results.
    pub seed: u64,
    /// Bounding volume of the output.
    pub bounding: BoundingKind,
    /// Fixed number of parts: skip the tolerance loop and return exactly this many parts
    /// (fewer only when the solid has fewer samples).
    pub k: Option<usize>,
    /// Tolerance on the total outside volume TOV (sigma_G in the paper).
    pub tov: f64,
    /// Tolerance on the largest per-part outside volume MOV (sigma_L in the paper).
    pub mov: f64,
    /// Upper bound on the number of parts in the tolerance loop.
    pub max_k: usize,
    /// Merge adjacent parts at the end of the tolerance loop while that lowers TOV.
    pub merge: bool,
    /// Beyond the paper: after optimising F, move boundary layers between neighbouring parts
    /// while that lowers the outside volume of the union of their bounding volumes
    /// ([`crate::tightening`]), then reshape the output ellipsoids to stick out of the solid
    /// less ([`crate::reshaping`]).
    pub polish: bool,
    /// Upper bound on Lloyd sweeps per optimisation.
    pub max_sweeps: usize,
    /// Grow every output volume (and every node of the hierarchy) outward by this distance,
    /// in mesh units (see [`crate::BoundingVolume::grown`]). The volumes enclose the mesh as
    /// given, in f64; an engine that stores them, or the mesh, in f32 moves each by up to an
    /// ulp or so of its coordinates, and a margin of that size (for example `1e-6` times the
    /// mesh's largest coordinate) keeps the enclosure. Default 0; finite and at least 0. The
    /// reported figures (TOV, MOV) are those of the grown volumes.
    pub margin: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            samples: 20_000,
            seed: 0,
            bounding: BoundingKind::Ellipsoid,
            k: None,
            tov: 0.3,
            mov: 0.5,
            max_k: 64,
            merge: true,
            polish: true,
            max_sweeps: 100,
            margin: 0.0,
        }
    }
}

/// Hard limit on the sample count: beyond it the grid would not fit comfortably in memory.
pub const MAX_SAMPLES: usize = 50_000_000;

impl Params {
    /// Check ranges; [`crate::segment`] calls this first.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |s: String| Err(Error::InvalidParams(s));
        if self.samples < 100 || self.samples > MAX_SAMPLES {
            return bad(format!(
                "samples must be between 100 and {MAX_SAMPLES}, got {}",
                self.samples
            ));
        }
        if let Some(k) = self.k {
            if k == 0 {
                return bad("k must be at least 1".into());
            }
            if k > self.samples / 8 {
                return bad(format!(
                    "k = {k} is too large for {} samples (at most samples / 8)",
                    self.samples
                ));
            }
        }
        if !(self.tov.is_finite() && self.tov >= 0.0 && self.mov.is_finite() && self.mov >= 0.0) {
            return bad("tolerances must be finite and non-negative".into());
        }
        if self.max_k == 0 || self.max_k > 4096 {
            return bad(format!(
                "max_k must be between 1 and 4096, got {}",
                self.max_k
            ));
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return bad(format!(
                "margin must be finite and at least 0, got {}",
                self.margin
            ));
        }
        if self.max_sweeps == 0 {
            return bad("max_sweeps must be at least 1".into());
        }
        Ok(())
    }
}
