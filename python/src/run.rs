//! `segment`: the run as the command line's `run_segmentation` does it (a local rayon pool
//! for `threads`, a `Cancel` flag set by a timer for `timeout`), with the GIL released, and
//! its result with the command line's writers.
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use bvseg_core::{Cancel, Params, Segmentation, Segmenter, Step, BUDGET_WARNING};
use bvseg_io::export::{write_labels, write_output, ExportOptions, OutputFormat};
use bvseg_io::{CliSummary, RunSummary};
use numpy::PyArray1;
use pyo3::exceptions::{PyRuntimeError, PyTimeoutError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::args::Given;
use crate::errors::{self, MeshError};
use crate::mesh::PyMesh;

/// The result of `segment` (wrapped by `bvseg.Segmentation`).
#[pyclass(frozen, name = "NativeSegmentation", module = "bvseg._bvseg")]
pub struct PySegmentation {
    seg: Segmentation,
    params: Params,
    mesh: Py<PyMesh>,
    seconds: f64,
    warnings: Vec<String>,
}

/// One refinement step as the JSON file's `history` writes it.
pub fn step_dict<'py>(py: Python<'py>, s: &Step) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("step", s.kind.as_str())?;
    d.set_item("k", s.k)?;
    d.set_item("f", s.f)?;
    d.set_item("tov", s.tov)?;
    d.set_item("mov", s.mov)?;
    d.set_item("protrusion", s.protrusion)?;
    Ok(d)
}

/// Sets a [`Cancel`] flag when its time is up, unless dropped first (the command line's
/// timer, less ending the process: the caller's interpreter is not ours to end).
pub struct Timer {
    _disarm: mpsc::Sender<()>,
    pub fired: Arc<AtomicBool>,
}

impl Timer {
    pub fn start(seconds: f64, cancel: Cancel) -> Self {
        let (tx, rx) = mpsc::channel::<()>();
        let fired = Arc::new(AtomicBool::new(false));
        let flag = fired.clone();
        let limit = Duration::from_secs_f64(seconds);
        std::thread::spawn(move || {
            if rx.recv_timeout(limit) == Err(mpsc::RecvTimeoutError::Timeout) {
                flag.store(true, Ordering::Relaxed);
                cancel.cancel();
            }
        });
        Self { _disarm: tx, fired }
    }
}

/// A pool of `threads` when given (as the command line's `in_pool`); `None`: rayon's global
/// pool.
pub fn pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    threads
        .map(|n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}")))
        })
        .transpose()
}

/// Runs `work` in `pool`, or in the global pool.
pub fn within<T: Send>(pool: Option<&rayon::ThreadPool>, work: impl FnOnce() -> T + Send) -> T {
    match pool {
        Some(p) => p.install(work),
        None => work(),
    }
}

/// How a run ended, before the GIL is taken back.
struct Outcome {
    result: Result<Segmentation, bvseg_core::Error>,
    /// What the progress callback raised (or a pending KeyboardInterrupt).
    raised: Option<PyErr>,
    seconds: f64,
}

/// Segments `mesh`; see `bvseg.segment` for the arguments.
#[pyfunction]
#[pyo3(signature = (mesh, *, progress = None, **params))]
pub fn segment<'py>(
    py: Python<'py>,
    mesh: Bound<'py, PyMesh>,
    progress: Option<Py<PyAny>>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<PySegmentation> {
    let run = Given::from_kwargs("segment", params)?.resolve()?;
    if let Some(p) = &progress {
        if !p.bind(py).is_callable() {
            return Err(pyo3::exceptions::PyTypeError::new_err(
                "progress must be callable (it is called with a dict per refinement step)",
            ));
        }
    }
    let m = mesh.get();
    let name = m.name.clone();
    let loaded = m.loaded.clone();
    // As the command line's load_solid: the one line that matters, before any warning.
    if loaded.encloses_no_volume() {
        let r = &loaded.report;
        return Err(MeshError::new_err(format!(
            "{name}: the mesh encloses no volume (flat, open or degenerate: {} triangles, {} open edges)",
            r.triangles, r.open_edges
        )));
    }
    let params = run.params;
    let cancel = Cancel::new();
    let timer = run.timeout.map(|t| Timer::start(t, cancel.clone()));
    let pool = pool(run.threads)?;
    let pool = pool.as_ref();
    // Each piece of work runs in the pool; the loop itself stays on this thread, so that the
    // callback and Ctrl-C (which only the main thread sees) are handled here.
    let outcome = py.detach(|| {
        let start = Instant::now();
        let mut raised = None;
        let result = within(pool, || {
            Segmenter::with_cancel(&loaded.mesh, &params, cancel.clone())
        })
        .and_then(|mut s| {
            while let Some(step) = within(pool, || s.step()) {
                let r = Python::attach(|py| -> PyResult<()> {
                    // Ctrl-C: the interpreter only sees it here, between steps.
                    py.check_signals()?;
                    if let Some(cb) = &progress {
                        cb.call1(py, (step_dict(py, &step)?,))?;
                    }
                    Ok(())
                });
                if let Err(e) = r {
                    raised = Some(e);
                    cancel.cancel();
                    break;
                }
            }
            within(pool, || s.finish())
        });
        Outcome {
            result,
            raised,
            seconds: start.elapsed().as_secs_f64(),
        }
    });
    let timed_out = timer
        .as_ref()
        .is_some_and(|t| t.fired.load(Ordering::Relaxed));
    drop(timer);
    if let Some(e) = outcome.raised {
        return Err(e);
    }
    let seg = match outcome.result {
        Ok(seg) => seg,
        Err(bvseg_core::Error::Cancelled) if timed_out => {
            return Err(PyTimeoutError::new_err(format!(
                "{name}: gave up after {} s (timeout)",
                run.timeout.unwrap_or_default()
            )))
        }
        Err(e) => return Err(errors::core(&name, e)),
    };
    let mut warnings = loaded.warnings();
    if seg.budget_exhausted {
        warnings.push(BUDGET_WARNING.to_owned());
    }
    Ok(PySegmentation {
        seg,
        params,
        mesh: mesh.unbind(),
        seconds: outcome.seconds,
        warnings,
    })
}

#[pymethods]
impl PySegmentation {
    /// The `bvseg.volumes` document, as `bvseg segment -o FILE.json` writes it.
    fn to_json(&self) -> String {
        bvseg_io::to_json_string(&self.seg)
    }

    /// Writes the volumes to `path` in the format its extension names, atomically, as
    /// `bvseg segment -o PATH [--with-mesh]` does.
    #[pyo3(signature = (path, *, with_mesh = false))]
    fn save(&self, py: Python<'_>, path: PathBuf, with_mesh: bool) -> PyResult<()> {
        let format = OutputFormat::from_path(&path).map_err(errors::output_io)?;
        if with_mesh && format != OutputFormat::Glb {
            return Err(PyValueError::new_err(format!(
                "{}: with_mesh applies to a .glb output",
                path.display()
            )));
        }
        let loaded = &self.mesh.get().loaded;
        let options = ExportOptions {
            mesh: with_mesh.then_some(&loaded.mesh),
            skinning: loaded.skinning.as_deref(),
            ..ExportOptions::default()
        };
        py.detach(|| write_output(&path, &self.seg, &options))
            .map_err(errors::output_io)
    }

    /// Writes one part index per triangle given (-1 for those dropped as degenerate), one
    /// per line, as `bvseg segment --labels PATH` does.
    fn save_labels(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let dropped = &self.mesh.get().loaded.dropped;
        py.detach(|| write_labels(&path, &self.seg, dropped))
            .map_err(errors::output_io)
    }

    /// The summary `bvseg segment --json` prints (keys sorted), less the outputs.
    fn summary_json(&self) -> String {
        let m = self.mesh.get();
        let summary = RunSummary {
            cli: Some(CliSummary::new(
                &self.seg,
                &self.params,
                m.mesh().triangles().len(),
                self.seconds,
                Vec::new(),
                self.warnings.clone(),
            )),
            ..RunSummary::new(&m.name, &self.seg)
        };
        summary.to_json_sorted()
    }

    /// Number of parts.
    #[getter]
    fn k(&self) -> usize {
        self.seg.metrics.k
    }

    /// For each triangle of the mesh (welded, without the dropped ones), the part whose
    /// volume encloses it.
    #[getter]
    fn triangle_parts<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_slice(py, &self.seg.triangle_parts)
    }

    /// For each interior sample, its part.
    #[getter]
    fn sample_parts<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_slice(py, &self.seg.sample_parts)
    }

    /// For each triangle given, its part, or -1 for one dropped as degenerate.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let dropped = &self.mesh.get().loaded.dropped;
        let total = self.seg.triangle_parts.len() + dropped.len();
        let mut out = Vec::with_capacity(total);
        let mut parts = self.seg.triangle_parts.iter();
        let mut d = dropped.iter().peekable();
        for i in 0..total {
            if d.next_if(|&&x| x == i).is_some() {
                out.push(-1);
            } else if let Some(&p) = parts.next() {
                out.push(i64::from(p));
            }
        }
        PyArray1::from_vec(py, out)
    }

    /// Whether a tolerance-mode run met its tolerances; `None` with a fixed k.
    #[getter]
    fn tolerances_met(&self) -> Option<bool> {
        self.seg.tolerances_met(&self.params)
    }

    /// The tolerances a tolerance-mode run left unmet: `(name, value, tolerance)` with name
    /// `"tov"`, `"protrusion"` (in mesh units) or `"mov"`.
    #[getter]
    fn unmet(&self) -> Vec<(&'static str, f64, f64)> {
        self.seg
            .unmet(&self.params)
            .into_iter()
            .map(|u| (u.tolerance.name(), u.value, u.limit))
            .collect()
    }

    /// For each part, the bone its volume moves with, as a dict (`joint`: the index into the
    /// skeleton, `name`, `node`: the glTF node index or None, `parent`: the parent joint's
    /// index or None), or None for a mesh without a skeleton.
    #[getter]
    fn bones<'py>(&self, py: Python<'py>) -> PyResult<Vec<Option<Bound<'py, PyDict>>>> {
        let joints = self.seg.skeleton.as_ref().map(|s| s.joints.as_slice());
        self.seg
            .parts
            .iter()
            .map(|p| {
                let Some((b, j)) = p.bone.zip(joints).and_then(|(b, j)| Some((b, j.get(b)?)))
                else {
                    return Ok(None);
                };
                let d = PyDict::new(py);
                d.set_item("joint", b)?;
                d.set_item("name", &j.name)?;
                d.set_item("node", j.node)?;
                d.set_item("parent", j.parent)?;
                Ok(Some(d))
            })
            .collect()
    }

    /// Whether the run's bound on work cut it short.
    #[getter]
    fn budget_exhausted(&self) -> bool {
        self.seg.budget_exhausted
    }

    /// Wall time of the run, in seconds.
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The mesh's warnings and the run's, one line each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// The mesh that was segmented.
    #[getter]
    fn mesh(&self, py: Python<'_>) -> Py<PyMesh> {
        self.mesh.clone_ref(py)
    }

    /// The parameters of the run (the keyword arguments' values, defaults filled in).
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = &self.params;
        let d = PyDict::new(py);
        d.set_item("k", p.k)?;
        d.set_item("tov", p.tov)?;
        d.set_item("max_protrusion", p.max_protrusion)?;
        d.set_item("max_protrusion_abs", p.max_protrusion_abs)?;
        d.set_item("mov", p.mov)?;
        d.set_item("max_k", p.max_k)?;
        d.set_item("kinds", p.kinds.to_string())?;
        d.set_item("max_hull_vertices", p.max_hull_vertices)?;
        d.set_item("samples", p.samples)?;
        d.set_item("seed", p.seed)?;
        d.set_item("merge", p.merge)?;
        d.set_item("tighten", p.tighten)?;
        d.set_item("margin", p.margin)?;
        Ok(d)
    }
}
