//! The independent verifier (`bvseg-verify`, which depends on neither the core nor the I/O
//! crate) on a segmentation: the mesh goes over as plain arrays, the volumes through the
//! file the product writes (`bvseg_io::to_json_string`, read back by the verifier's own
//! parser), which also tests the file contract. Shared by the tests and the fuzz targets.
#![allow(dead_code)]
use bvseg_core::{Mesh, Segmentation};
use bvseg_verify::{VerifyError, VerifyOptions, VerifyReport, Volumes};

/// The mesh's positions as the verifier takes them.
pub fn vertices(mesh: &Mesh) -> Vec<[f64; 3]> {
    mesh.vertices().iter().map(|v| v.to_array()).collect()
}

/// The volumes of `seg`, with their fractions, as the verifier reads them from the written
/// file. Panics when the verifier refuses what bvseg writes.
pub fn volumes(seg: &Segmentation) -> Volumes {
    let text = bvseg_io::to_json_string(seg);
    match Volumes::from_json(&text) {
        Ok(v) => v,
        Err(e) => panic!("the verifier refuses the written volumes file: {e}"),
    }
}

/// [`bvseg_verify::verify`] on `mesh`.
pub fn verify(
    mesh: &Mesh,
    volumes: &Volumes,
    opts: &VerifyOptions,
) -> Result<VerifyReport, VerifyError> {
    bvseg_verify::verify(&vertices(mesh), mesh.triangles(), volumes, opts)
}

/// [`bvseg_verify::verify`] on `mesh` and the written volumes of `seg`.
pub fn verify_segmentation(
    mesh: &Mesh,
    seg: &Segmentation,
    opts: &VerifyOptions,
) -> Result<VerifyReport, VerifyError> {
    verify(mesh, &volumes(seg), opts)
}
