//! The one JSON form of a [`VerifyReport`], written by `bvseg verify --json` and returned by
//! the Python package's `verify`, so that both give the same keys and values.
use serde_json::json;

use crate::VerifyReport;

/// What the JSON form of a report says besides the report itself: the files checked and
/// what the volumes file claimed of itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReportContext<'a> {
    /// The mesh's name (a path, or what the caller calls it).
    pub mesh: &'a str,
    /// The volumes file's name.
    pub volumes_file: &'a str,
    /// The file's `kind`: a shape's name or `mixed`.
    pub kind: &'a str,
    /// The number of volumes in the file.
    pub k: usize,
    /// The file's own `metrics.protrusion_rel`, if it has one.
    pub reported_protrusion_rel: Option<f64>,
    /// The file's own `metrics.tov`, if it has one.
    pub reported_tov: Option<f64>,
    /// The file's own `metrics.mov`, if it has one.
    pub reported_mov: Option<f64>,
    /// The seed the check ran with ([`crate::VerifyOptions::seed`]).
    pub seed: u64,
}

impl VerifyReport {
    /// The report as one line of JSON (an object; absent figures are `null`), with the
    /// files and claims of `about`. The keys are the report's fields under the names
    /// `bvseg verify --json` prints (docs/cli.md).
    #[must_use]
    pub fn to_json(&self, about: &ReportContext<'_>) -> String {
        let r = self;
        json!({
            "mesh": about.mesh,
            "volumes_file": about.volumes_file,
            "kind": about.kind,
            "k": about.k,
            "enclosed": r.all_enclosed(),
            "triangles": r.triangles,
            "triangles_single": r.single,
            "triangles_split": r.split,
            "triangles_within_tolerance": r.within_tolerance,
            "triangles_unenclosed": r.unenclosed,
            "max_escape_rel": r.max_escape_rel,
            "worst_triangle": r.worst_triangle,
            "closed": r.closed,
            "vol_mesh": r.volume,
            "vol_mesh_grid": r.volume_grid,
            "vol_mesh_grid_se": r.volume_grid_se,
            "tov": r.tov,
            "tov_se": r.tov_se,
            "mov": r.mov.map(|m| m.0),
            "mov_se": r.mov.map(|m| m.1),
            "mov_index": r.mov.map(|m| m.2),
            "ov": r.ov,
            "ov_se": r.ov_se,
            "coverage_interior": r.coverage_interior,
            "protrusion": r.protrusion,
            "protrusion_rel": r.protrusion_rel,
            "boundary_points": r.boundary_points,
            "reported_protrusion_rel": about.reported_protrusion_rel,
            "reported_tov": about.reported_tov,
            "reported_mov": about.reported_mov,
            "grid": r.grid,
            "grid_points": r.grid.iter().product::<usize>(),
            "seed": about.seed,
        })
        .to_string()
    }
}
