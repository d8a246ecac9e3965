//! `bvseg._bvseg`: the native half of the Python package `bvseg` (the pure-Python half, in
//! `src/bvseg/`, turns the inputs it accepts into these calls and documents them).
//!
//! Everything goes through the crates the command line uses: meshes through
//! `bvseg_io::load` / `bvseg_io::load_arrays`, the run through the core's `Segmenter` (in a
//! local rayon pool when `threads` is given, with a `Cancel` flag for the timeout and the
//! progress callback), the outputs through `bvseg_io::to_json_string` and
//! `bvseg_io::export::write_output`, the check through `bvseg-verify`, robots through
//! `bvseg_io::robot::segment_robot`. The GIL is released while a mesh is loaded, segmented or
//! verified, and while a robot runs.

mod args;
mod errors;
mod mesh;
mod robot;
mod run;
mod verify;

use pyo3::prelude::*;

/// The native module.
#[pymodule]
fn _bvseg(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("MeshError", py.get_type::<errors::MeshError>())?;
    m.add("RobotError", py.get_type::<errors::RobotError>())?;
    m.add("ROBOT_DONE_FILE", bvseg_io::robot::DONE_FILE)?;
    m.add(
        "DEFAULT_SPHERES_PER_LINK",
        bvseg_io::robot::DEFAULT_SPHERES_PER_LINK,
    )?;
    m.add(
        "DEFAULT_PARTS_PER_LINK",
        bvseg_io::robot::DEFAULT_PARTS_PER_LINK,
    )?;
    m.add("GENERATOR", bvseg_io::GENERATOR)?;
    m.add("MESH_EXTENSIONS", bvseg_io::MESH_EXTENSIONS.to_vec())?;
    m.add("MAX_VOLUMES_BYTES", bvseg_io::MAX_VOLUMES_BYTES)?;
    m.add_class::<mesh::PyMesh>()?;
    m.add_class::<run::PySegmentation>()?;
    m.add_function(wrap_pyfunction!(mesh::load_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::mesh_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(args::defaults, m)?)?;
    m.add_function(wrap_pyfunction!(args::targets, m)?)?;
    m.add_function(wrap_pyfunction!(args::check_params, m)?)?;
    m.add_function(wrap_pyfunction!(run::segment, m)?)?;
    m.add_function(wrap_pyfunction!(verify::verify, m)?)?;
    m.add_function(wrap_pyfunction!(robot::robot, m)?)?;
    m.add_function(wrap_pyfunction!(robot::robot_format, m)?)?;
    m.add_function(wrap_pyfunction!(robot::robot_uses, m)?)?;
    m.add_function(wrap_pyfunction!(verify::verify_defaults, m)?)?;
    Ok(())
}
