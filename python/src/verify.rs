//! `verify`: the independent check `bvseg verify` runs (the `bvseg-verify` crate), with the
//! same validation of the document first (`bvseg_io::parse_volumes`) and the same report.
use bvseg_verify::{ReportContext, VerifyError, VerifyOptions, Volumes};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::MeshError;
use crate::mesh::PyMesh;

/// The verifier's threads by default: as many as rayon's global pool would take
/// (`RAYON_NUM_THREADS` when set, else one per core), as `bvseg verify` does.
fn default_threads() -> Option<usize> {
    std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|s| s.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
}

fn verify_error(mesh: &str, volumes: &str, e: VerifyError) -> PyErr {
    match e {
        VerifyError::NoTriangles
        | VerifyError::BadVertex { .. }
        | VerifyError::BadIndex { .. }
        | VerifyError::NoVolume { .. } => MeshError::new_err(format!("{mesh}: {e}")),
        VerifyError::Document(_) => PyValueError::new_err(format!("{volumes}: {e}")),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// Checks the volumes document `text` (called `volumes_name` in messages) against `mesh`;
/// returns the report as the JSON `bvseg verify --json` prints.
#[pyfunction]
#[pyo3(signature = (mesh, text, volumes_name, *, points = VerifyOptions::default().points, seed = 0, threads = None))]
pub fn verify(
    py: Python<'_>,
    mesh: Bound<'_, PyMesh>,
    text: String,
    volumes_name: String,
    points: usize,
    seed: u64,
    threads: Option<usize>,
) -> PyResult<String> {
    if threads == Some(0) {
        return Err(PyValueError::new_err("threads must be at least 1, got 0"));
    }
    let m = mesh.get();
    // Validated by bvseg-io's reader first, as everywhere (its checks and messages), then
    // read by the verifier's own parser.
    let file = bvseg_io::parse_volumes(text.as_bytes(), &volumes_name)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let volumes = Volumes::from_json(&text).map_err(|e| verify_error(&m.name, &volumes_name, e))?;
    let mesh = m.mesh();
    let vertices: Vec<[f64; 3]> = mesh.vertices().iter().map(|v| v.to_array()).collect();
    let opts = VerifyOptions {
        points,
        seed,
        threads: threads.or_else(default_threads),
        ..VerifyOptions::default()
    };
    let r = py
        .detach(|| bvseg_verify::verify(&vertices, mesh.triangles(), &volumes, &opts))
        .map_err(|e| verify_error(&m.name, &volumes_name, e))?;
    // The same JSON as `bvseg verify --json`.
    Ok(r.to_json(&ReportContext {
        mesh: &m.name,
        volumes_file: &volumes_name,
        kind: &file.kind,
        k: file.volumes.len(),
        reported_protrusion_rel: file.reported.protrusion_rel,
        reported_tov: file.reported.tov,
        reported_mov: file.reported.mov,
        seed,
    }))
}

/// The defaults of `verify`'s options.
#[pyfunction]
pub fn verify_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = VerifyOptions::default();
    let out = PyDict::new(py);
    out.set_item("points", d.points)?;
    out.set_item("seed", d.seed)?;
    out.set_item("threads", py.None())?;
    Ok(out)
}
