//! The Python exceptions the errors of the crates become.
use bvseg_io::IoError;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::PyErr;

pyo3::create_exception!(
    bvseg,
    MeshError,
    PyValueError,
    "A mesh that cannot be segmented or verified: a file that does not parse, an unsupported \
     mesh format, non-finite or out-of-range coordinates, a face that refers to a vertex that \
     does not exist, no triangles, a surface that encloses no volume. A subclass of \
     ValueError; the message is one line naming the mesh."
);

pyo3::create_exception!(
    bvseg,
    RobotError,
    PyValueError,
    "A robot file that cannot be used: not well-formed XML, not a URDF or MJCF robot, a link \
     name used twice, a joint whose parent or child is not a link, an MJCF include cycle, an \
     unknown default class. A subclass of ValueError; the message is one line naming the \
     file. (A missing mesh file is a FileNotFoundError, an unreadable one a MeshError.)"
);

/// An `IoError` of reading a mesh: the operating system's errors as `OSError` (with its
/// `errno`, so that a missing file is a `FileNotFoundError`), everything else a `MeshError`.
pub fn mesh_io(e: IoError) -> PyErr {
    match &e {
        IoError::Io { .. } => os_error(&e),
        _ => MeshError::new_err(e.to_string()),
    }
}

/// An `IoError` of writing an output: the operating system's errors as `OSError`, an
/// unsupported extension or an unusable path as `ValueError`.
pub fn output_io(e: IoError) -> PyErr {
    match &e {
        IoError::Io { .. } => os_error(&e),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// An `IoError` of reading a robot: the operating system's errors as `OSError`, a mesh file
/// that is not there as `FileNotFoundError`, a link's mesh that cannot be used as
/// `MeshError`, everything else a `RobotError`.
pub fn robot_io(e: IoError) -> PyErr {
    match &e {
        IoError::Io { .. } => os_error(&e),
        IoError::MissingMesh { .. } => {
            pyo3::exceptions::PyFileNotFoundError::new_err(e.to_string())
        }
        IoError::Link { source, .. } if matches!(**source, IoError::Io { .. }) => {
            PyOSError::new_err(e.to_string())
        }
        IoError::Link { .. } => MeshError::new_err(e.to_string()),
        _ => RobotError::new_err(e.to_string()),
    }
}

/// `OSError(errno, message)`, which Python turns into the subclass of the errno
/// (`FileNotFoundError`, `PermissionError`, ...).
fn os_error(e: &IoError) -> PyErr {
    let errno = match e {
        IoError::Io { source, .. } => source.raw_os_error(),
        _ => None,
    };
    match errno {
        Some(code) => PyOSError::new_err((code, e.to_string())),
        None => PyOSError::new_err(e.to_string()),
    }
}

/// A core error that is not a cancellation, for the mesh called `name`: the mesh's and what
/// it encloses as `MeshError`, a parameter as `ValueError` (the core's message, which names
/// the parameter and its range), a bug as `RuntimeError`.
pub fn core(name: &str, e: bvseg_core::Error) -> PyErr {
    use bvseg_core::Error as E;
    match e {
        E::InvalidParams(p) => PyValueError::new_err(p.to_string()),
        E::Mesh(_) | E::NoVolume(_) | E::TooComplex(_) => {
            MeshError::new_err(format!("{name}: {e}"))
        }
        _ => PyRuntimeError::new_err(format!("{name}: {e}")),
    }
}
