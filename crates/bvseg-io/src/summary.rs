//! The summary of one segmentation run as one JSON object: what `bvseg segment --json` prints,
//! and the start of what the viewer reports to its page (the viewer flattens a [`RunSummary`]
//! into its own summary, followed by its own fields).
//!
//! Every front end fills the same [`RunSummary`]; its serializer names and formats every key
//! (numbers as `serde_json` prints them, non-finite ones as `null`), and whether the
//! tolerances were met is always [`Segmentation::tolerances_met`].
use bvseg_core::{Params, Segmentation};
use serde::Serialize;

/// The summary of a finished run. The figures every front end has come first, led by the
/// viewer's page contract `k`, `tov`, `mov`, `f`; then `mesh`, `samples` and `kind`; then
/// the fields only the command line has ([`CliSummary`]), present only when given.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunSummary {
    /// Number of parts.
    pub k: usize,
    /// Total outside volume TOV.
    pub tov: f64,
    /// Largest per-part outside volume MOV.
    pub mov: f64,
    /// The objective F.
    pub f: f64,
    /// The protrusion (one-way Hausdorff distance from the union's boundary to the surface),
    /// in mesh units.
    pub protrusion: f64,
    /// The protrusion as a fraction of the bounding box's diagonal.
    pub protrusion_rel: f64,
    /// The mesh, as the front end names it.
    pub mesh: String,
    /// Interior samples used.
    pub samples: usize,
    /// The kinds of volume the run could choose from (`ellipsoid`, `mixed`, or a comma list
    /// such as `ellipsoid,obb,sphere,capsule,cylinder`).
    pub kind: String,
    /// What the command line adds, after the shared figures.
    #[serde(flatten)]
    pub cli: Option<CliSummary>,
}

/// The fields of [`RunSummary`] that `bvseg segment --json` adds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CliSummary {
    /// Triangles of the mesh (after welding and dropping degenerate ones).
    pub triangles: usize,
    /// The tolerances of a tolerance-mode run; `null` with a fixed k.
    pub tolerances: Option<Tolerances>,
    /// Whether the tolerances were met; `null` with a fixed k.
    pub tolerances_met: Option<bool>,
    /// Wall time of the segmentation, in seconds.
    pub seconds: f64,
    /// The files written, as given.
    pub outputs: Vec<String>,
    /// Warnings about the mesh and the run, one line each.
    pub warnings: Vec<String>,
}

/// The tolerances of a tolerance-mode run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tolerances {
    /// Tolerance on TOV.
    pub tov: f64,
    /// Tolerance on the protrusion, in mesh units.
    pub protrusion: f64,
    /// The same, as a fraction of the bounding box's diagonal.
    pub protrusion_rel: f64,
    /// Tolerance on MOV; `null` when MOV is not checked (the default).
    pub mov: Option<f64>,
}

impl Tolerances {
    /// The tolerances `params` set for the run `seg`, `None` with a fixed k (which has none).
    pub fn of(params: &Params, seg: &Segmentation) -> Option<Self> {
        let d = seg.metrics.diagonal;
        let protrusion = params.protrusion_tolerance(d);
        params.k.is_none().then_some(Self {
            tov: params.tov,
            protrusion,
            protrusion_rel: protrusion / d.max(f64::MIN_POSITIVE),
            mov: params.mov,
        })
    }
}

impl RunSummary {
    /// The shared figures of `seg`, a run of the mesh called `mesh`, with neither front end's
    /// fields.
    pub fn new(mesh: &str, seg: &Segmentation) -> Self {
        let m = &seg.metrics;
        Self {
            k: m.k,
            tov: m.tov,
            mov: m.mov,
            f: m.f,
            protrusion: m.protrusion,
            protrusion_rel: m.protrusion_rel,
            mesh: mesh.to_owned(),
            samples: m.samples,
            kind: seg.kinds.to_string(),
            cli: None,
        }
    }

    /// One line of JSON with the keys in the order of the fields: the page contract (`k`,
    /// `tov`, `mov`, `f`) first.
    // Strings, numbers (non-finite ones become null) and string-keyed maps: serde_json
    // cannot fail on them.
    #[allow(clippy::expect_used)]
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a RunSummary always serializes")
    }

    /// One line of JSON with the keys sorted, as `bvseg segment --json` prints it.
    #[allow(clippy::expect_used)]
    pub fn to_json_sorted(&self) -> String {
        let mut v = serde_json::to_value(self).expect("a RunSummary always serializes");
        v.sort_all_objects();
        v.to_string()
    }
}

impl CliSummary {
    /// The command line's fields for `seg`, a run with `params`.
    pub fn new(
        seg: &Segmentation,
        params: &Params,
        triangles: usize,
        seconds: f64,
        outputs: Vec<String>,
        warnings: Vec<String>,
    ) -> Self {
        Self {
            triangles,
            tolerances: Tolerances::of(params, seg),
            tolerances_met: seg.tolerances_met(params),
            seconds,
            outputs,
            warnings,
        }
    }
}
