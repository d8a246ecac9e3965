//! The public run: the lattice route's phase machine, or the surface route's one step.
use crate::pipeline::Lattice;
use crate::{
    BoundingVolume, Cancel, Error, HierarchyNode, Mesh, Params, Route, Segmentation, Step,
};

/// The segmentation as a sequence of steps, for progress display and interactive use: call
/// [`Segmenter::step`] until it returns `None`, then [`Segmenter::finish`]. Each step is a
/// bounded amount of work (one split or merge with its re-optimisation), so a UI can run one
/// per frame.
///
/// ```
/// # use bvseg_core::{Mesh, Params, Segmenter};
/// # use glam::{DMat3, DVec3};
/// # let mesh = bvseg_core::shapes::ellipsoid(DVec3::ZERO, DVec3::new(2.0, 1.0, 1.0), DMat3::IDENTITY, 16);
/// let params = Params { samples: 2000, ..Params::default() };
/// let mut run = Segmenter::new(&mesh, &params)?;
/// while let Some(step) = run.step() {
///     println!("{:?}: k = {}, TOV = {:.3}", step.kind, step.k, step.tov);
/// }
/// let seg = run.finish()?;
/// assert!(seg.parts.len() >= 1);
/// # Ok::<(), bvseg_core::Error>(())
/// ```
pub struct Segmenter {
    run: Run,
}

// One per run: the size of the surface variant's result does not matter.
#[allow(clippy::large_enum_variant)]
enum Run {
    Lattice(Box<Lattice>),
    /// The surface route is computed whole by [`Segmenter::new`] (it is fast: no lattice);
    /// its one step reports it.
    Surface {
        result: Option<Result<Segmentation, Error>>,
        volumes: Vec<BoundingVolume>,
        stepped: bool,
        cancel: Cancel,
    },
}

impl Segmenter {
    /// Validate the input, choose the route ([`Params::route`]) and sample the solid (the
    /// lattice route) or bound the surface (the surface route). The remaining work happens
    /// in [`Segmenter::step`].
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParams`] when `params` fails [`Params::validate`], and the sampling's
    /// errors: [`Error::NoVolume`], [`Error::TooComplex`].
    pub fn new(mesh: &Mesh, params: &Params) -> Result<Self, Error> {
        Self::with_cancel(mesh, params, Cancel::new())
    }

    /// Like [`Segmenter::new`], stopping when `cancel` is set: [`Segmenter::step`] then
    /// returns `None` and [`Segmenter::finish`] [`Error::Cancelled`].
    ///
    /// # Errors
    ///
    /// As [`Segmenter::new`], and [`Error::Cancelled`] if `cancel` was set during sampling.
    pub fn with_cancel(mesh: &Mesh, params: &Params, cancel: Cancel) -> Result<Self, Error> {
        params.validate()?;
        cancel.check()?;
        let run = match crate::shells::route(mesh, params) {
            Route::Surface => {
                let seg = crate::shells::segment(mesh, params, &cancel)?;
                Run::Surface {
                    volumes: seg.parts.iter().map(|p| p.volume.clone()).collect(),
                    result: Some(Ok(seg)),
                    stepped: false,
                    cancel,
                }
            }
            _ => Run::Lattice(Box::new(Lattice::with_cancel(mesh, params, cancel)?)),
        };
        Ok(Self { run })
    }

    /// Number of interior samples the solid was sampled with (0 on the surface route).
    #[must_use]
    pub fn samples(&self) -> usize {
        match &self.run {
            Run::Lattice(l) => l.samples(),
            Run::Surface { .. } => 0,
        }
    }

    /// The refinement history so far.
    #[must_use]
    pub fn history(&self) -> &[Step] {
        match &self.run {
            Run::Lattice(l) => l.history(),
            Run::Surface {
                result: Some(Ok(s)),
                stepped: true,
                ..
            } => &s.history,
            Run::Surface { .. } => &[],
        }
    }

    /// The current part of each sample (empty before the first step, and on the surface
    /// route).
    #[must_use]
    pub fn labels(&self) -> &[u32] {
        match &self.run {
            Run::Lattice(l) => l.labels(),
            Run::Surface { .. } => &[],
        }
    }

    /// The current part of each input triangle (empty before the first step), by the rule
    /// [`Segmentation::triangle_parts`] follows.
    #[must_use]
    pub fn triangle_parts(&self) -> Vec<u32> {
        match &self.run {
            Run::Lattice(l) => l.triangle_parts(),
            Run::Surface {
                result: Some(Ok(s)),
                stepped: true,
                ..
            } => s.triangle_parts.clone(),
            Run::Surface { .. } => Vec::new(),
        }
    }

    /// The current refinement-time bounding volumes (empty before the first step).
    #[must_use]
    pub fn volumes(&self) -> &[BoundingVolume] {
        match &self.run {
            Run::Lattice(l) => l.volumes(),
            Run::Surface {
                volumes,
                stepped: true,
                ..
            } => volumes,
            Run::Surface { .. } => &[],
        }
    }

    /// The bounding-volume hierarchy over the current parts (after the last step, those of
    /// the result), as [`Segmentation::hierarchy`] holds it when [`Params::hierarchy`] is on:
    /// for a run made without it whose user turns out to want it (the viewer builds it only
    /// for a JSON export). Empty before the first step; on the surface route, the result's.
    #[must_use]
    pub fn hierarchy(&self) -> Vec<HierarchyNode> {
        match &self.run {
            Run::Lattice(l) => l.hierarchy(),
            Run::Surface {
                result: Some(Ok(s)),
                ..
            } => s.hierarchy.clone(),
            Run::Surface { .. } => Vec::new(),
        }
    }

    /// Whether [`Segmenter::step`] has returned `None`.
    #[must_use]
    pub fn is_done(&self) -> bool {
        match &self.run {
            Run::Lattice(l) => l.is_done(),
            Run::Surface { stepped, .. } => *stepped,
        }
    }

    /// Do the next step and report it; `None` when the segmentation is complete.
    pub fn step(&mut self) -> Option<Step> {
        match &mut self.run {
            Run::Lattice(l) => l.step(),
            Run::Surface {
                result,
                stepped,
                cancel,
                ..
            } => {
                if *stepped || cancel.is_cancelled() {
                    *stepped = true;
                    return None;
                }
                *stepped = true;
                match result {
                    Some(Ok(s)) => s.history.last().copied(),
                    _ => None,
                }
            }
        }
    }

    /// Run any remaining steps and return the result.
    ///
    /// # Errors
    ///
    /// [`Error::Cancelled`] when the run's [`Cancel`] flag was set before it ended, and
    /// [`Error::Internal`] if the run broke one of its own invariants.
    pub fn finish(mut self) -> Result<Segmentation, Error> {
        self.take_result()
    }

    /// Like [`Segmenter::finish`], keeping the segmenter, so that [`Segmenter::hierarchy`]
    /// can still build the hierarchy of a run made without it. A second call returns
    /// [`Error::Internal`].
    ///
    /// # Errors
    ///
    /// As [`Segmenter::finish`].
    pub fn take_result(&mut self) -> Result<Segmentation, Error> {
        match &mut self.run {
            Run::Lattice(l) => l.take_result(),
            Run::Surface {
                result,
                stepped,
                cancel,
                ..
            } => {
                *stepped = true;
                if cancel.is_cancelled() {
                    return Err(Error::Cancelled);
                }
                let r = result
                    .take()
                    .ok_or_else(|| Error::Internal("the run ended without a result".into()))??;
                r.check()?;
                Ok(r)
            }
        }
    }
}
