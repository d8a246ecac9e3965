//! One segmentation run, advanced a bounded amount at a time.
//!
//! The browser has no threads, so the run cannot go off to a worker: [`Session::advance`] does
//! whole core steps until a time budget is spent and then returns, and the app calls it once
//! per frame. Cancelling is dropping the session. Every step leaves a [`Snapshot`], so the
//! history can be stepped back through after (and during) the run.
use std::sync::Arc;

use bvseg_core::{BoundingVolume, Error, Mesh, Params, Segmentation, Segmenter, Step, StepKind};
use web_time::{Duration, Instant};

/// Part label of a triangle whose part is not known (drawn in the plain mesh colour).
pub const UNKNOWN_PART: u16 = u16::MAX;

/// Above this many triangles, snapshots keep no per-triangle colouring (only the final state
/// has it), so that long histories of big meshes stay small in memory.
pub const MAX_SNAPSHOT_TRIANGLES: usize = 250_000;

/// The state after one refinement step.
#[derive(Debug, Clone)]
pub struct Snapshot {
    /// The step and its figures.
    pub step: Step,
    /// The bounding volumes after the step (for a backtrack, those of the state it returned to).
    pub volumes: Arc<Vec<BoundingVolume>>,
    /// Each triangle's part, or [`UNKNOWN_PART`]; empty when not kept.
    pub triangle_parts: Arc<Vec<u16>>,
    /// Each part's share of the samples.
    pub fractions: Arc<Vec<f64>>,
}

/// Where a run is.
enum Stage {
    /// Nothing done yet: the next call samples the solid.
    Sampling,
    /// Stepping.
    Stepping(Box<Segmenter>),
    /// Finished; the segmenter is kept, until asked for, to build the hierarchy the run went
    /// without (see [`Session::result_with_hierarchy`]).
    Done(Box<Segmentation>, Option<Box<Segmenter>>),
    /// The core refused the input.
    Failed(Error),
}

/// A run of the core on one mesh with one set of parameters.
pub struct Session {
    mesh: Arc<Mesh>,
    /// The mesh's bounding-box diagonal (asked for every frame by the plot).
    diagonal: f64,
    params: Params,
    stage: Stage,
    samples: usize,
    snapshots: Vec<Snapshot>,
    /// Time spent inside the core so far (not counting the frames in between).
    busy: Duration,
    /// Calls of [`Session::advance`] (frames of the run).
    calls: usize,
    started: Instant,
    wall: Option<Duration>,
}

/// What [`Session::advance`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// More to do.
    Running,
    /// The run has just finished or had finished before.
    Done,
    /// The run failed (see [`Session::error`]).
    Failed,
}

impl Session {
    /// A run that has not started; [`Session::advance`] does the work.
    pub fn new(mesh: Arc<Mesh>, params: Params) -> Self {
        let (lo, hi) = mesh.bbox();
        Self {
            diagonal: (hi - lo).length(),
            mesh,
            params,
            stage: Stage::Sampling,
            samples: 0,
            snapshots: Vec::new(),
            busy: Duration::ZERO,
            calls: 0,
            started: Instant::now(),
            wall: None,
        }
    }

    /// Do at least one unit of work (sampling, or one core step), and more while `budget` lasts.
    pub fn advance(&mut self, budget: Duration) -> Progress {
        let t0 = Instant::now();
        self.calls += 1;
        loop {
            let p = self.advance_one();
            if p != Progress::Running || t0.elapsed() >= budget {
                self.busy += t0.elapsed();
                if p != Progress::Running && self.wall.is_none() {
                    self.wall = Some(self.started.elapsed());
                }
                return p;
            }
        }
    }

    fn advance_one(&mut self) -> Progress {
        match &mut self.stage {
            Stage::Sampling => {
                match Segmenter::new(&self.mesh, &self.params) {
                    Ok(seg) => {
                        self.samples = seg.samples();
                        self.stage = Stage::Stepping(Box::new(seg));
                    }
                    Err(e) => {
                        self.stage = Stage::Failed(e);
                        return Progress::Failed;
                    }
                }
                Progress::Running
            }
            Stage::Stepping(seg) => match seg.step() {
                Some(step) => {
                    let snap = self.snapshot(step);
                    self.snapshots.push(snap);
                    Progress::Running
                }
                None => {
                    let Stage::Stepping(mut seg) =
                        std::mem::replace(&mut self.stage, Stage::Sampling)
                    else {
                        unreachable!("matched above");
                    };
                    let result = match seg.take_result() {
                        Ok(r) => r,
                        Err(e) => {
                            self.stage = Stage::Failed(e);
                            return Progress::Failed;
                        }
                    };
                    if let Some(last) = self.snapshots.last_mut() {
                        if last.step.kind == StepKind::Final {
                            // The final colouring: the part whose volume encloses each triangle.
                            last.triangle_parts = Arc::new(
                                result
                                    .triangle_parts
                                    .iter()
                                    .map(|&p| u16::try_from(p).unwrap_or(UNKNOWN_PART))
                                    .collect(),
                            );
                        }
                    }
                    let keep = (!self.params.hierarchy).then_some(seg);
                    self.stage = Stage::Done(Box::new(result), keep);
                    Progress::Done
                }
            },
            Stage::Done(..) => Progress::Done,
            Stage::Failed(_) => Progress::Failed,
        }
    }

    fn snapshot(&self, step: Step) -> Snapshot {
        let Stage::Stepping(seg) = &self.stage else {
            unreachable!("snapshots are taken while stepping");
        };
        // A backtrack leaves the current state as it was: share the previous snapshot's data.
        if step.kind == StepKind::Backtrack {
            if let Some(prev) = self.snapshots.last() {
                return Snapshot {
                    step,
                    ..prev.clone()
                };
            }
        }
        let labels = seg.labels();
        let volumes = seg.volumes().to_vec();
        let mut counts = vec![0usize; volumes.len()];
        for &l in labels {
            if let Some(c) = counts.get_mut(l as usize) {
                *c += 1;
            }
        }
        let n = labels.len().max(1) as f64;
        // The core's own rule (each triangle goes with its nearest sample), so that the colours
        // during the run are those of the result.
        let triangle_parts = if self.mesh.triangles().len() <= MAX_SNAPSHOT_TRIANGLES {
            seg.triangle_parts()
                .into_iter()
                .map(|l| u16::try_from(l).unwrap_or(UNKNOWN_PART))
                .collect()
        } else {
            Vec::new()
        };
        Snapshot {
            step,
            volumes: Arc::new(volumes),
            triangle_parts: Arc::new(triangle_parts),
            fractions: Arc::new(counts.iter().map(|&c| c as f64 / n).collect()),
        }
    }

    /// The mesh being segmented.
    pub fn mesh(&self) -> &Arc<Mesh> {
        &self.mesh
    }

    /// The parameters of the run.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// One snapshot per step so far.
    pub fn snapshots(&self) -> &[Snapshot] {
        &self.snapshots
    }

    /// The result, once done. Its hierarchy is empty when the parameters went without it.
    pub fn result(&self) -> Option<&Segmentation> {
        match &self.stage {
            Stage::Done(s, _) => Some(s),
            _ => None,
        }
    }

    /// The result with its hierarchy, built now if the run went without it (the app runs
    /// without, as only the JSON export carries it).
    pub fn result_with_hierarchy(&mut self) -> Option<&Segmentation> {
        let Stage::Done(res, run) = &mut self.stage else {
            return None;
        };
        if let Some(run) = run.take() {
            res.hierarchy = run.hierarchy();
        }
        Some(res)
    }

    /// The core's error, if the run failed.
    pub fn error(&self) -> Option<&Error> {
        match &self.stage {
            Stage::Failed(e) => Some(e),
            _ => None,
        }
    }

    /// Whether the run is over (done or failed).
    pub fn is_over(&self) -> bool {
        matches!(self.stage, Stage::Done(..) | Stage::Failed(_))
    }

    /// Number of interior samples (0 before sampling).
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Time spent in the core.
    pub fn busy(&self) -> Duration {
        self.busy
    }

    /// Number of [`Session::advance`] calls so far (the frames of the run).
    pub fn calls(&self) -> usize {
        self.calls
    }

    /// The diagonal of the mesh's bounding box (the protrusion is shown relative to it).
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// Wall-clock time from the start to the end of the run, or so far.
    pub fn wall(&self) -> Duration {
        self.wall.unwrap_or_else(|| self.started.elapsed())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::meshes::{load_bundled, BUNDLED};

    #[test]
    fn advance_runs_to_the_end_with_one_snapshot_per_step() {
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let params = Params {
            samples: 3000,
            k: Some(4),
            ..Params::default()
        };
        let mut s = Session::new(mesh.clone(), params.clone());
        let mut calls = 0;
        // A zero budget still makes progress: one unit of work per call.
        while s.advance(Duration::ZERO) == Progress::Running {
            calls += 1;
            assert!(calls < 10_000);
        }
        let res = s.result().unwrap();
        assert_eq!(res.metrics.k, 4);
        assert_eq!(s.snapshots().len(), res.history.len());
        assert!(calls >= res.history.len());
        let last = s.snapshots().last().unwrap();
        assert_eq!(last.step.kind, StepKind::Final);
        assert_eq!(last.volumes.len(), 4);
        assert_eq!(last.triangle_parts.len(), mesh.triangles().len());
        assert!(last.triangle_parts.iter().all(|&p| p < 4));
        // The colours follow the core's triangle rule: at the end, the result's parts.
        let expect: Vec<u16> = res.triangle_parts.iter().map(|&p| p as u16).collect();
        assert_eq!(*last.triangle_parts, expect);
        // Stepping gives what the one-call API gives.
        let direct = bvseg_core::segment(&mesh, &params).unwrap();
        assert_eq!(direct.metrics, res.metrics);
    }

    #[test]
    fn a_run_without_the_hierarchy_builds_it_when_asked() {
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let params = Params {
            samples: 3000,
            k: Some(4),
            ..Params::default()
        };
        let direct = bvseg_core::segment(&mesh, &params).unwrap();
        let mut s = Session::new(
            mesh,
            Params {
                hierarchy: false,
                ..params
            },
        );
        while s.advance(Duration::from_secs(1)) == Progress::Running {}
        assert!(s.result().unwrap().hierarchy.is_empty());
        assert_eq!(s.result_with_hierarchy(), Some(&direct));
        assert_eq!(s.result(), Some(&direct));
    }

    #[test]
    fn invalid_parameters_fail_the_run() {
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let params = Params {
            samples: 10,
            ..Params::default()
        };
        let mut s = Session::new(mesh, params);
        assert_eq!(s.advance(Duration::from_secs(1)), Progress::Failed);
        assert!(s.error().unwrap().to_string().contains("samples"));
        assert!(s.is_over() && s.result().is_none());
    }
}
