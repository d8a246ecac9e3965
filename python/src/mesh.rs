//! Meshes: loaded from a file by `bvseg_io::load`, or from arrays by `bvseg_io::load_arrays`
//! (the readers' own last step: weld, drop degenerate triangles, turn outward, report).
use std::path::PathBuf;
use std::sync::Arc;

use bvseg_io::{LoadOptions, LoadedMesh};
use glam::DVec3;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::errors::{mesh_io, MeshError};

/// A mesh as bvseg sees it: welded, without degenerate triangles, facing outward.
#[pyclass(frozen, name = "Mesh", module = "bvseg")]
pub struct PyMesh {
    pub loaded: Arc<LoadedMesh>,
    pub name: String,
}

impl PyMesh {
    pub fn mesh(&self) -> &bvseg_core::Mesh {
        &self.loaded.mesh
    }
}

/// `n x 3` rows as a numpy array.
fn rows<'py, T: numpy::Element + Copy>(
    py: Python<'py>,
    rows: impl ExactSizeIterator<Item = [T; 3]>,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    let n = rows.len();
    let mut flat = Vec::with_capacity(3 * n);
    for r in rows {
        flat.extend_from_slice(&r);
    }
    PyArray1::from_vec(py, flat).reshape([n, 3])
}

#[pymethods]
impl PyMesh {
    /// The vertices, float64, one row per vertex (a new array on each access).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows(py, self.mesh().vertices().iter().map(|v| v.to_array()))
    }

    /// The triangles, int64 vertex indices, one row per triangle (a new array on each access).
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        rows(py, self.mesh().triangles().iter().map(|t| t.map(i64::from)))
    }

    /// What error messages call the mesh: the path as given, or the name given with arrays.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// Indices, among the triangles given (a file's after fanning polygons), of those
    /// dropped as degenerate after welding, increasing.
    #[getter]
    fn dropped<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let d: Vec<i64> = self.loaded.dropped.iter().map(|&i| i as i64).collect();
        PyArray1::from_vec(py, d)
    }

    /// What loading changed or found that a user should know, one line each (what the
    /// command line prints as warnings).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.loaded.warnings()
    }

    /// What loading did: vertices_read, welded, triangles_read, degenerate.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.loaded.stats;
        let d = PyDict::new(py);
        d.set_item("vertices_read", s.vertices_read)?;
        d.set_item("welded", s.welded)?;
        d.set_item("triangles_read", s.triangles_read)?;
        d.set_item("degenerate", s.degenerate)?;
        Ok(d)
    }

    /// What the mesh is like (what `bvseg info` prints): triangles, vertices, components,
    /// edges, open_edges, non_manifold_edges, duplicate_faces, flipped, volume, bbox_min,
    /// bbox_max.
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.loaded.report;
        let d = PyDict::new(py);
        d.set_item("triangles", r.triangles)?;
        d.set_item("vertices", r.vertices)?;
        d.set_item("components", r.components)?;
        d.set_item("edges", r.edges)?;
        d.set_item("open_edges", r.open_edges)?;
        d.set_item("non_manifold_edges", r.non_manifold_edges)?;
        d.set_item("duplicate_faces", r.duplicate_faces)?;
        d.set_item("flipped", r.flipped)?;
        d.set_item("volume", r.volume)?;
        d.set_item("bbox_min", r.bbox_min.to_array().to_vec())?;
        d.set_item("bbox_max", r.bbox_max.to_array().to_vec())?;
        Ok(d)
    }

    /// Whether the surface encloses a volume (relative to its bounding box); a mesh that
    /// does not cannot be segmented.
    #[getter]
    fn encloses_volume(&self) -> bool {
        !self.loaded.encloses_no_volume()
    }

    /// `vertices, faces = mesh`.
    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pair = PyTuple::new(
            py,
            [self.vertices(py)?.into_any(), self.faces(py)?.into_any()],
        )?;
        Ok(pair.try_iter()?.into_any())
    }

    fn __repr__(&self) -> String {
        format!(
            "<bvseg.Mesh {:?}: {} vertices, {} triangles>",
            self.name,
            self.mesh().vertices().len(),
            self.mesh().triangles().len()
        )
    }
}

/// Loads a mesh file (.obj, .gltf, .glb, .stl) as `bvseg segment` does.
#[pyfunction]
#[pyo3(signature = (path, *, object = None, mesh = None))]
pub fn load_mesh(
    py: Python<'_>,
    path: PathBuf,
    object: Option<String>,
    mesh: Option<String>,
) -> PyResult<PyMesh> {
    let options = LoadOptions { object, mesh };
    let name = path.display().to_string();
    let loaded = py
        .detach(|| bvseg_io::load(&path, &options))
        .map_err(mesh_io)?;
    Ok(PyMesh {
        loaded: Arc::new(loaded),
        name,
    })
}

/// A mesh from arrays of vertices (float64, n x 3) and faces (int64, m x 3), through the
/// loader's last step.
#[pyfunction]
#[pyo3(signature = (vertices, faces, name))]
pub fn mesh_from_arrays(
    py: Python<'_>,
    vertices: PyReadonlyArray2<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
    name: String,
) -> PyResult<PyMesh> {
    let bad = |m: String| MeshError::new_err(format!("{name}: {m}"));
    if vertices.shape()[1] != 3 {
        return Err(bad(format!(
            "vertices must have shape (n, 3), got {:?}",
            vertices.shape()
        )));
    }
    if faces.shape()[1] != 3 {
        return Err(bad(format!(
            "faces must have shape (m, 3) (triangles), got {:?}",
            faces.shape()
        )));
    }
    let v = vertices.as_array();
    let n = v.nrows();
    let f = faces.as_array();
    // As the OBJ reader (tobj) does: the vertices the faces use, renumbered in the order
    // they first use them, so that the arrays of an OBJ file in file order (trimesh's, say)
    // give the very mesh, hence the very bytes, that the file gives. Idempotent: the arrays
    // of a loaded OBJ or STL mesh come back unchanged.
    let mut new_index = vec![usize::MAX; n];
    let mut positions: Vec<DVec3> = Vec::with_capacity(n);
    let mut triangles = Vec::with_capacity(f.nrows());
    for (index, r) in f.rows().into_iter().enumerate() {
        let mut t = [0usize; 3];
        for j in 0..3 {
            let i = usize::try_from(r[j])
                .ok()
                .filter(|&i| i < n)
                .ok_or_else(|| {
                    bad(format!(
                        "triangle {index} refers to vertex {}, but the mesh has only {n} vertices",
                        r[j]
                    ))
                })?;
            if new_index[i] == usize::MAX {
                new_index[i] = positions.len();
                positions.push(DVec3::new(v[[i, 0]], v[[i, 1]], v[[i, 2]]));
            }
            t[j] = new_index[i];
        }
        triangles.push(t);
    }
    let loaded = py
        .detach(|| bvseg_io::load_arrays(positions, triangles, &name))
        .map_err(mesh_io)?;
    Ok(PyMesh {
        loaded: Arc::new(loaded),
        name,
    })
}
