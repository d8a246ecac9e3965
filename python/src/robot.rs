//! `robot`: a URDF or MJCF robot segmented link by link and written out, through the one
//! run the command line makes (`bvseg_io::robot::segment_robot`, `RobotRun::write`), with the
//! GIL released. The run goes on a thread of its own; this thread relays its progress to the
//! callback and watches for Ctrl-C, which only the main thread sees.
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use bvseg_core::{Cancel, Step};
use bvseg_io::robot::{
    segment_robot, MeshSource, PartBudget, RobotError, RobotEvent, RobotOptions, RobotRun,
    DEFAULT_PARTS_PER_LINK, DEFAULT_SPHERES_PER_LINK,
};
use pyo3::exceptions::{PyTimeoutError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::args::{size, Given};
use crate::errors;
use crate::run::{pool, step_dict, within, Timer};

/// What the run tells this thread.
enum Event {
    Step {
        link: String,
        spheres: bool,
        step: Step,
    },
}

/// The Python exception of a run's error (`timed_out`: the timer stopped it).
fn robot_error(e: RobotError, timed_out: bool, timeout: Option<f64>, path: &str) -> PyErr {
    match e {
        e if e.is_cancelled() && timed_out => PyTimeoutError::new_err(format!(
            "{path}: gave up after {} s (timeout)",
            timeout.unwrap_or_default()
        )),
        RobotError::Io(e) => errors::robot_io(e),
        RobotError::Options(m) => PyValueError::new_err(m),
        RobotError::Params(p) => PyValueError::new_err(p.to_string()),
        RobotError::Segment { file, link, source } => {
            errors::core(&format!("{file}: link {link:?}"), source)
        }
        e => pyo3::exceptions::PyRuntimeError::new_err(e.to_string()),
    }
}

/// One link of the result, as a dict.
fn link_dict<'py>(
    py: Python<'py>,
    run: &RobotRun,
    i: usize,
    out_dir: &std::path::Path,
) -> PyResult<Bound<'py, PyDict>> {
    let link = &run.robot.links[i];
    let result = run.links[i].as_ref();
    let d = PyDict::new(py);
    d.set_item("name", &link.name)?;
    d.set_item("parts", result.map_or(0, |r| r.parts.parts.len()))?;
    let shapes: Vec<&str> = result
        .into_iter()
        .flat_map(|r| r.parts.parts.iter().map(|p| p.volume.shape.as_str()))
        .collect();
    d.set_item("shapes", shapes)?;
    d.set_item("kept", link.kept.len())?;
    d.set_item("spheres", result.map_or(0, |r| r.spheres.parts.len()))?;
    d.set_item("meshes", link.meshes.len())?;
    d.set_item("triangles", result.map_or(0, |r| r.triangles))?;
    d.set_item("tolerances_met", result.and_then(|r| r.tolerances_met))?;
    let json = run
        .volumes_file(i)
        .map(|rel| out_dir.join(rel).display().to_string());
    d.set_item("volumes", json)?;
    Ok(d)
}

/// Segments every link of the robot at `path` and writes its outputs into `out_dir`; see
/// `bvseg.robot` for the arguments.
#[pyfunction]
#[pyo3(signature = (path, out_dir, *, source = "collision", max_parts = None, total_parts = None,
                    spheres_per_link = None, urdf_capsules = false, progress = None, **params))]
#[allow(clippy::too_many_arguments)]
pub fn robot<'py>(
    py: Python<'py>,
    path: PathBuf,
    out_dir: PathBuf,
    source: &str,
    max_parts: Option<Bound<'py, PyAny>>,
    total_parts: Option<Bound<'py, PyAny>>,
    spheres_per_link: Option<Bound<'py, PyAny>>,
    urdf_capsules: bool,
    progress: Option<Py<PyAny>>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let run = Given::from_kwargs("robot", params)?.resolve()?;
    if let Some(p) = &progress {
        if !p.bind(py).is_callable() {
            return Err(PyTypeError::new_err(
                "progress must be callable (it is called with a dict per refinement step)",
            ));
        }
    }
    let source = match source {
        "collision" => MeshSource::Collision,
        "visual" => MeshSource::Visual,
        s => {
            return Err(PyValueError::new_err(format!(
                "source must be 'collision' or 'visual', got {s:?}"
            )))
        }
    };
    let opt =
        |name: &str, v: &Option<Bound<'py, PyAny>>| v.as_ref().map(|v| size(name, v)).transpose();
    let parts = match (
        opt("max_parts", &max_parts)?,
        opt("total_parts", &total_parts)?,
    ) {
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(
                "max_parts and total_parts cannot be combined: give a budget per link or for \
                 the robot",
            ))
        }
        (_, Some(n)) => PartBudget::Total(n),
        (Some(n), None) => PartBudget::PerLink(n),
        (None, None) => PartBudget::PerLink(DEFAULT_PARTS_PER_LINK),
    };
    let options = RobotOptions {
        source,
        params: run.params.clone(),
        parts,
        spheres_per_link: opt("spheres_per_link", &spheres_per_link)?
            .unwrap_or(DEFAULT_SPHERES_PER_LINK),
        urdf_capsules,
    };
    let name = path.display().to_string();
    let cancel = Cancel::new();
    let timer = run.timeout.map(|t| Timer::start(t, cancel.clone()));
    let pool = pool(run.threads)?;
    let pool = pool.as_ref();
    let start = Instant::now();
    let (result, raised) = py.detach(|| {
        let (tx, rx) = mpsc::channel::<Event>();
        std::thread::scope(|s| {
            let worker = s.spawn(|| {
                let tx = tx;
                let mut current = (String::new(), false);
                within(pool, || {
                    segment_robot(&path, &options, &cancel, |e| match e {
                        RobotEvent::Start { link, spheres, .. } => {
                            current = (link.to_owned(), spheres);
                        }
                        RobotEvent::Step(step) => {
                            // The receiver is gone only once this thread is told to stop.
                            let _ = tx.send(Event::Step {
                                link: current.0.clone(),
                                spheres: current.1,
                                step: *step,
                            });
                        }
                        _ => {}
                    })
                })
            });
            let mut raised: Option<PyErr> = None;
            loop {
                let event = match rx.recv_timeout(Duration::from_millis(100)) {
                    Ok(event) => Some(event),
                    Err(mpsc::RecvTimeoutError::Timeout) => None,
                    Err(mpsc::RecvTimeoutError::Disconnected) => break,
                };
                if raised.is_some() {
                    continue; // drain until the run has stopped
                }
                let r = Python::attach(|py| -> PyResult<()> {
                    py.check_signals()?;
                    if let (
                        Some(cb),
                        Some(Event::Step {
                            link,
                            spheres,
                            step,
                        }),
                    ) = (&progress, &event)
                    {
                        let d = step_dict(py, step)?;
                        d.set_item("link", link)?;
                        d.set_item("spheres", spheres)?;
                        cb.call1(py, (d,))?;
                    }
                    Ok(())
                });
                if let Err(e) = r {
                    raised = Some(e);
                    cancel.cancel();
                }
            }
            let result = worker
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            (result, raised)
        })
    });
    let timed_out = timer
        .as_ref()
        .is_some_and(|t| t.fired.load(Ordering::Relaxed));
    drop(timer);
    if let Some(e) = raised {
        return Err(e);
    }
    let done = result.map_err(|e| robot_error(e, timed_out, run.timeout, &name))?;
    let written = py
        .detach(|| done.write(&out_dir))
        .map_err(errors::output_io)?;
    let seconds = start.elapsed().as_secs_f64();
    let d = PyDict::new(py);
    d.set_item("robot", &done.robot.name)?;
    d.set_item("name", &done.stem)?;
    d.set_item("format", format!("{:?}", done.robot.format).to_lowercase())?;
    d.set_item("out_dir", out_dir.display().to_string())?;
    let shown: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    let file = |ext: &str| {
        out_dir
            .join(format!("{}.{ext}", done.stem))
            .display()
            .to_string()
    };
    d.set_item("urdf", file("urdf"))?;
    d.set_item("mjcf", file("xml"))?;
    d.set_item("curobo", out_dir.join("curobo.yml").display().to_string())?;
    d.set_item(
        "manifest",
        out_dir
            .join(bvseg_io::robot::DONE_FILE)
            .display()
            .to_string(),
    )?;
    d.set_item("warnings", &done.warnings)?;
    let links = (0..done.robot.links.len())
        .map(|i| link_dict(py, &done, i, &out_dir))
        .collect::<PyResult<Vec<_>>>()?;
    d.set_item("links", links)?;
    d.set_item("files", shown)?;
    d.set_item("parts", done.total_parts())?;
    d.set_item("spheres", done.total_spheres())?;
    d.set_item("seconds", seconds)?;
    Ok(d)
}

/// `"urdf"` or `"mjcf"` for a file `bvseg.robot` would read as a robot (every `.urdf`; an
/// `.xml` whose root is `<mujoco>` and that bvseg did not write), else `None`.
#[pyfunction]
pub fn robot_format(path: PathBuf) -> Option<&'static str> {
    bvseg_io::robot::robot_format(&path).map(|f| match f {
        bvseg_io::robot::RobotFormat::Urdf => "urdf",
        bvseg_io::robot::RobotFormat::Mjcf => "mjcf",
    })
}

/// The files the robot at `path` uses besides itself (its mesh files, the MJCF files it
/// includes), as canonical paths; best effort.
#[pyfunction]
pub fn robot_uses(path: PathBuf) -> Vec<String> {
    bvseg_io::robot::robot_uses(&path)
        .iter()
        .map(|p| p.display().to_string())
        .collect()
}
