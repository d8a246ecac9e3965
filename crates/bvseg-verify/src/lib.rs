//! # bvseg-verify
//!
//! An independent check of bounding volumes against a mesh: does their union enclose every
//! triangle, and how much do they stick out of the solid?
//!
//! This crate depends on neither `bvseg-core` nor `bvseg-io` (only on `glam` and
//! `serde_json`), so nothing here is shared with the segmentation's own sampling, enclosure,
//! metrics or file reader, and a bug there cannot hide itself: the volumes file is read by
//! its own parser ([`Volumes::from_json`]), the inside test is its own signed ray count (not
//! the lattice's column sweep), the volumes are tested by their own formulas, and the outside
//! volumes are estimated on an independent, finer, jittered grid with standard errors. The
//! definitions are those of the project's external judge (`shared/tools/bveval.py`):
//!
//! - `TOV = vol(∪V_i \ S) / vol(S)`, `OV_i = vol(V_i \ S) / (fraction_i · vol(S))`,
//!   `MOV = max_i OV_i`;
//! - `vol(S)` is the exact signed-tetrahedra volume when the mesh is closed (every directed
//!   edge matched by its reverse, vertices compared by position), else the grid estimate;
//! - inside S: the signed crossing count along ±z (closed meshes: the exact winding number),
//!   or averaged over ±x, ±y, ±z (open meshes), above 1/2, after orienting the mesh outward;
//! - one uniform point per cell of a grid over the box of the mesh and the volumes, and
//!   standard errors from the collapsed-strata estimator that pairs neighbouring cells
//!   along x: `Var ≈ w² Σ_pairs (y_a − y_b)²` (it can only overstate the error).
//!
//! Triangle enclosure is exact where one volume holds all three corners (volumes are
//! convex). Otherwise the triangle is subdivided, branch and bound, for the largest distance
//! of its points to the union of the volumes: a piece is settled when one volume holds its
//! corners, and refined until it is smaller than a tolerance; the largest escape is found
//! to a relative precision of 1e-3.
//!
//! The work is spread over [`VerifyOptions::threads`] threads; every figure is combined in a
//! fixed order, so the report is bit-identical whatever the thread count.
//!
//! ```
//! use bvseg_verify::{verify, VerifyOptions, Volumes};
//! // A unit cube, facing outward.
//! let v: Vec<[f64; 3]> = (0..8)
//!     .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
//!     .collect();
//! let t = [
//!     [0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
//!     [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5],
//! ];
//! let doc = r#"{"schema": "bvseg.volumes/1", "kind": "obb", "volumes": [
//!     {"shape": "obb", "center": [0.5, 0.5, 0.5], "axes": [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
//!      "radii": [0.5, 0.5, 0.5], "fraction": 1}]}"#;
//! let volumes = Volumes::from_json(doc)?;
//! let opts = VerifyOptions { points: 10_000, ..VerifyOptions::default() };
//! let report = verify(&v, &t, &volumes, &opts)?;
//! assert!(report.all_enclosed() && report.closed);
//! assert_eq!(report.volume, 1.0);
//! # Ok::<(), bvseg_verify::VerifyError>(())
//! ```
#![warn(missing_docs)]
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]
// Index loops over 3x3 matrices and parallel arrays read more clearly than iterator chains.
#![allow(clippy::needless_range_loop)]

mod enclosure;
mod error;
mod grid;
mod inside;
mod mesh;
mod parallel;
mod protrusion;
mod vol;
mod volumes;

#[cfg(test)]
mod test_support;

pub use error::VerifyError;
pub use volumes::{Volume, Volumes, MAX_VOLUMES, SCHEMA_V1, SCHEMA_V2};

use mesh::MeshRef;
use vol::Vol;

/// Largest magnitude of a coordinate, a centre or a radius, as in the schema (the judge
/// refuses larger ones): far enough from f64's range that squares and products stay finite.
const MAX_COORDINATE: f64 = 1e100;

/// Options of [`verify`].
#[derive(Debug, Clone, PartialEq)]
pub struct VerifyOptions {
    /// Number of grid points for the outside volumes (one per cell); 1000 to
    /// [`MAX_VERIFY_POINTS`].
    pub points: usize,
    /// Seed of the jitter; equal seeds give identical reports.
    pub seed: u64,
    /// Subdivision of a triangle stops at pieces smaller than this, relative to the mesh's
    /// bounding-box diagonal.
    pub tolerance: f64,
    /// Threads to run on, at least 1; `None`: [`std::thread::available_parallelism`] (one
    /// where that is unknown, as on wasm32). The report does not depend on it.
    pub threads: Option<usize>,
    /// Points on the union's boundary for the protrusion; 0 skips it.
    pub boundary_points: usize,
}

impl Default for VerifyOptions {
    fn default() -> Self {
        Self {
            points: 2_000_000,
            seed: 0,
            tolerance: 1e-5,
            threads: None,
            boundary_points: 40_000,
        }
    }
}

/// Largest [`VerifyOptions::points`].
pub const MAX_VERIFY_POINTS: usize = 200_000_000;

/// How a triangle relates to the union of the volumes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TriangleStatus {
    /// One volume holds all three corners, hence the whole triangle.
    Single,
    /// Subdivided into pieces, each held by one volume.
    Split,
    /// No point outside every volume was found, but pieces smaller than the tolerance were
    /// left unproven (they may stick out by less than their size).
    WithinTolerance,
    /// A point of the triangle lies outside every volume.
    Escapes,
}

/// What [`verify`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct VerifyReport {
    /// Number of triangles checked.
    pub triangles: usize,
    /// Triangles held by one volume.
    pub single: usize,
    /// Triangles held piecewise by several volumes.
    pub split: usize,
    /// Triangles with no escaping point found, down to the tolerance.
    pub within_tolerance: usize,
    /// Triangles with a point outside every volume.
    pub unenclosed: usize,
    /// Largest distance from a point of the mesh to the union, over the bounding-box
    /// diagonal (0 when everything is enclosed).
    pub max_escape_rel: f64,
    /// The triangle with that largest escape.
    pub worst_triangle: Option<usize>,
    /// Whether the mesh is closed (every directed edge matched by its reverse).
    pub closed: bool,
    /// vol(S): exact when closed, else the grid estimate.
    pub volume: f64,
    /// The grid estimate of vol(S) and its standard error.
    pub volume_grid: f64,
    /// Standard error of [`Self::volume_grid`].
    pub volume_grid_se: f64,
    /// Grid cells along x, y, z.
    pub grid: [usize; 3],
    /// Total outside volume and its standard error.
    pub tov: f64,
    /// Standard error of TOV.
    pub tov_se: f64,
    /// `vol(V_i \ S) / vol(S)` per volume.
    pub outside: Vec<f64>,
    /// Standard errors of [`Self::outside`].
    pub outside_se: Vec<f64>,
    /// `OV_i = vol(V_i \ S) / (fraction_i vol(S))` when the fractions were given.
    pub ov: Option<Vec<f64>>,
    /// Standard errors of [`Self::ov`].
    pub ov_se: Option<Vec<f64>>,
    /// `max_i OV_i`, its standard error and index, when the fractions were given.
    pub mov: Option<(f64, f64, usize)>,
    /// Share of the grid points inside S that lie in some volume.
    pub coverage_interior: f64,
    /// The protrusion: the largest distance to the mesh surface of the boundary points of
    /// the union (the one-way Hausdorff distance, sampled), in mesh units; 0 when skipped.
    pub protrusion: f64,
    /// [`Self::protrusion`] as a fraction of the mesh's bounding-box diagonal.
    pub protrusion_rel: f64,
    /// Boundary points the protrusion was taken over.
    pub boundary_points: usize,
}

impl VerifyReport {
    /// Whether no point of the mesh was found outside the union of the volumes.
    pub fn all_enclosed(&self) -> bool {
        self.unenclosed == 0
    }
}

/// Checks `volumes` against the mesh of `vertices` and `triangles` (vertex-index triples,
/// either orientation; see the crate docs). [`Volumes::fractions`], when present, give the
/// per-volume figures `OV_i` and `MOV`.
///
/// # Errors
///
/// - [`VerifyError::NoTriangles`], [`VerifyError::BadVertex`], [`VerifyError::BadIndex`]: the
///   mesh has no triangles, a non-finite coordinate or one above 1e100 in magnitude, or an
///   index out of range;
/// - [`VerifyError::InvalidParams`]: options out of range (points, tolerance, threads), no
///   volumes, a volume with non-finite or out-of-range values or radii not positive,
///   fractions of the wrong length or not positive;
/// - [`VerifyError::NoVolume`]: the mesh encloses no volume at the grid's resolution.
pub fn verify(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    volumes: &Volumes,
    opts: &VerifyOptions,
) -> Result<VerifyReport, VerifyError> {
    let mesh = MeshRef::new(vertices, triangles)?;
    check_inputs(volumes, opts)?;
    let threads = parallel::threads(opts.threads);
    let vols: Vec<Vol> = volumes.volumes.iter().map(Vol::new).collect();
    let (mlo, mhi) = mesh.bbox();
    let diag = (mhi - mlo).length();
    let tris = enclosure::triangle_enclosure(&mesh, &vols, opts.tolerance * diag, threads);
    let grid = grid::grid_metrics(&mesh, &vols, opts, threads)?;
    let (protrusion, boundary_points) = if opts.boundary_points > 0 {
        protrusion::protrusion(&mesh, &vols, opts.boundary_points, opts.seed, threads)
    } else {
        (0.0, 0)
    };

    let mut report = VerifyReport {
        triangles: tris.len(),
        single: 0,
        split: 0,
        within_tolerance: 0,
        unenclosed: 0,
        max_escape_rel: 0.0,
        worst_triangle: None,
        closed: grid.closed,
        volume: grid.volume,
        volume_grid: grid.volume_grid,
        volume_grid_se: grid.volume_grid_se,
        grid: grid.dims,
        tov: grid.tov,
        tov_se: grid.tov_se,
        outside: grid.outside,
        outside_se: grid.outside_se,
        ov: None,
        ov_se: None,
        mov: None,
        coverage_interior: grid.coverage_interior,
        protrusion,
        protrusion_rel: protrusion / diag.max(f64::MIN_POSITIVE),
        boundary_points,
    };
    for (t, &(status, escape)) in tris.iter().enumerate() {
        match status {
            TriangleStatus::Single => report.single += 1,
            TriangleStatus::Split => report.split += 1,
            TriangleStatus::WithinTolerance => report.within_tolerance += 1,
            TriangleStatus::Escapes => report.unenclosed += 1,
        }
        if escape > 0.0 && escape / diag > report.max_escape_rel {
            report.max_escape_rel = escape / diag;
            report.worst_triangle = Some(t);
        }
    }
    if let Some(fr) = &volumes.fractions {
        let ov: Vec<f64> = report.outside.iter().zip(fr).map(|(o, f)| o / f).collect();
        let se: Vec<f64> = report
            .outside_se
            .iter()
            .zip(fr)
            .map(|(o, f)| o / f)
            .collect();
        let mut best = 0;
        for i in 1..ov.len() {
            if ov[i] > ov[best] {
                best = i;
            }
        }
        report.mov = ov.get(best).map(|&m| (m, se[best], best));
        report.ov = Some(ov);
        report.ov_se = Some(se);
    }
    Ok(report)
}

fn check_inputs(volumes: &Volumes, opts: &VerifyOptions) -> Result<(), VerifyError> {
    let bad = |s: String| Err(VerifyError::InvalidParams(s));
    if !(1000..=MAX_VERIFY_POINTS).contains(&opts.points) {
        return bad(format!(
            "points must be between 1000 and {MAX_VERIFY_POINTS}, got {}",
            opts.points
        ));
    }
    if !(opts.tolerance.is_finite() && opts.tolerance > 0.0 && opts.tolerance <= 1.0) {
        return bad(format!(
            "tolerance must be in (0, 1], got {}",
            opts.tolerance
        ));
    }
    if opts.threads == Some(0) {
        return bad("threads must be at least 1".into());
    }
    let list = &volumes.volumes;
    if list.is_empty() {
        return bad("no volumes to verify".into());
    }
    for (i, v) in list.iter().enumerate() {
        let (center, axes, radii) = v.frame();
        let finite = center.iter().chain(axes.iter().flatten()).chain(&radii);
        if !finite.clone().all(|x| x.is_finite())
            || center.iter().any(|x| x.abs() > MAX_COORDINATE)
            || radii.iter().any(|&r| r > MAX_COORDINATE)
        {
            return bad(format!("volume {i}: non-finite or out-of-range value"));
        }
        if radii.iter().any(|&r| r <= 0.0) {
            return bad(format!("volume {i}: radii must be positive"));
        }
    }
    if let Some(fr) = &volumes.fractions {
        if fr.len() != list.len() {
            return bad(format!("{} fractions for {} volumes", fr.len(), list.len()));
        }
        if fr.iter().any(|f| !(f.is_finite() && *f > 0.0)) {
            return bad("fractions must be positive and finite".into());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{cuboid, ellipsoid_mesh, obb, torus, SplitMix};
    use glam::{DMat3, DVec3};

    fn opts(points: usize) -> VerifyOptions {
        VerifyOptions {
            points,
            ..VerifyOptions::default()
        }
    }

    fn one(v: Volume) -> Volumes {
        Volumes::new(vec![v])
    }

    #[test]
    fn box_in_its_own_box_and_in_its_circumscribed_ellipsoid() {
        let rot = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let c = DVec3::new(0.4, -1.3, 2.2);
        let half = DVec3::new(1.0, 0.5, 0.25);
        let (v, t) = cuboid(c, half, rot);
        let r = verify(&v, &t, &one(obb(c, half, rot)), &opts(200_000)).unwrap();
        assert!(r.closed && r.all_enclosed() && r.single == 12);
        assert!((r.volume - 1.0).abs() < 1e-12);
        assert!(r.tov < 1e-3, "{}", r.tov);
        assert!(r.coverage_interior > 0.999);

        let e = Volume::Ellipsoid {
            center: c.to_array(),
            axes: [rot.x_axis, rot.y_axis, rot.z_axis].map(|a| a.to_array()),
            radii: (half * 3f64.sqrt()).to_array(),
        };
        let vols = Volumes {
            fractions: Some(vec![1.0]),
            ..one(e)
        };
        let r = verify(&v, &t, &vols, &opts(400_000)).unwrap();
        let want = std::f64::consts::PI * 3f64.sqrt() / 2.0 - 1.0;
        assert!(r.all_enclosed());
        assert!(
            (r.tov - want).abs() < 4.0 * r.tov_se + 2e-3,
            "{} vs {want}",
            r.tov
        );
        assert_eq!(r.mov.unwrap().0, r.tov);
    }

    #[test]
    fn a_box_half_covered_escapes_by_the_exact_distance() {
        let (v, t) = cuboid(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.5), DMat3::IDENTITY);
        let b = obb(
            DVec3::new(-0.5, 0.0, 0.0),
            DVec3::splat(0.5),
            DMat3::IDENTITY,
        );
        let r = verify(&v, &t, &one(b), &opts(50_000)).unwrap();
        assert!(!r.all_enclosed());
        // The farthest point, a corner at x = 1, is 1 away from the volume; the diagonal is
        // sqrt(6).
        assert!((r.max_escape_rel - 1.0 / 6f64.sqrt()).abs() < 1e-12);
        assert!((r.coverage_interior - 0.5).abs() < 0.02);
        assert!(r.tov < 1e-3);
    }

    #[test]
    fn a_triangle_covered_by_two_volumes_is_split_exactly() {
        let (v, t) = cuboid(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.5), DMat3::IDENTITY);
        let a = obb(
            DVec3::new(-0.45, 0.0, 0.0),
            DVec3::new(0.6, 0.5, 0.5),
            DMat3::IDENTITY,
        );
        let b = obb(
            DVec3::new(0.45, 0.0, 0.0),
            DVec3::new(0.6, 0.5, 0.5),
            DMat3::IDENTITY,
        );
        let r = verify(&v, &t, &Volumes::new(vec![a, b]), &opts(20_000)).unwrap();
        assert!(r.all_enclosed(), "{r:?}");
        assert!(r.split > 0 && r.single > 0 && r.within_tolerance == 0);
        assert_eq!(r.max_escape_rel, 0.0);
    }

    #[test]
    fn inward_and_open_meshes_and_torus_hole() {
        // Inward: same figures as outward.
        let (v, t) = cuboid(DVec3::ZERO, DVec3::splat(1.0), DMat3::IDENTITY);
        let flipped: Vec<[u32; 3]> = t.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let b = one(obb(DVec3::ZERO, DVec3::splat(1.2), DMat3::IDENTITY));
        let a = verify(&v, &t, &b, &opts(100_000)).unwrap();
        let f = verify(&v, &flipped, &b, &opts(100_000)).unwrap();
        assert_eq!(a.tov, f.tov);
        assert!((a.tov - (1.2f64.powi(3) - 1.0)).abs() < 4.0 * a.tov_se + 2e-3);
        // Open (one triangle dropped): the six-ray average still sees the solid.
        let c = verify(&v, &t[1..], &b, &opts(100_000)).unwrap();
        assert!(!c.closed && (c.volume - 8.0).abs() < 0.2, "{}", c.volume);
        // The torus's hole is outside.
        let (v, t) = torus(2.0, 0.5, 48);
        let radii = [2.6, 2.6, 1.0];
        let ball = one(Volume::Ellipsoid {
            center: [0.0; 3],
            axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            radii,
        });
        let r = verify(&v, &t, &ball, &opts(200_000)).unwrap();
        assert!(r.closed && r.all_enclosed());
        // Closed: the report's volume is the mesh's exact one.
        let ball_volume = 4.0 / 3.0 * std::f64::consts::PI * radii.iter().product::<f64>();
        let want = ball_volume / r.volume - 1.0;
        assert!(
            (r.tov - want).abs() < 4.0 * r.tov_se + 5e-3,
            "{} vs {want}",
            r.tov
        );
    }

    #[test]
    fn reports_are_deterministic_and_bad_input_is_refused() {
        let (m, t) = ellipsoid_mesh(DVec3::new(1.0, 2.0, 0.5), 24);
        let b = obb(DVec3::ZERO, DVec3::new(1.0, 2.0, 0.5), DMat3::IDENTITY);
        let a = verify(&m, &t, &one(b.clone()), &opts(30_000)).unwrap();
        let again = verify(&m, &t, &one(b.clone()), &opts(30_000)).unwrap();
        assert_eq!(a, again);
        let with_radius_y = |y: f64| {
            let Volume::Obb {
                center,
                axes,
                mut half_extents,
            } = b.clone()
            else {
                unreachable!()
            };
            half_extents[1] = y;
            one(Volume::Obb {
                center,
                axes,
                half_extents,
            })
        };
        let err = |r: Result<VerifyReport, VerifyError>| r.unwrap_err().to_string();
        let e = err(verify(&m, &t, &with_radius_y(0.0), &opts(30_000)));
        assert!(e.contains("volume 0: radii must be positive"), "{e}");
        let e = err(verify(&m, &t, &with_radius_y(f64::NAN), &opts(30_000)));
        assert!(e.contains("volume 0: non-finite"), "{e}");
        let e = err(verify(&m, &t, &with_radius_y(1e101), &opts(30_000)));
        assert!(e.contains("out-of-range"), "{e}");
        assert!(verify(&m, &t, &Volumes::new(vec![]), &opts(30_000)).is_err());
        let e = err(verify(&m, &t, &one(b.clone()), &opts(10)));
        assert_eq!(
            e,
            "invalid parameter: points must be between 1000 and 200000000, got 10"
        );
        let o = VerifyOptions {
            tolerance: 0.0,
            ..opts(30_000)
        };
        assert!(verify(&m, &t, &one(b.clone()), &o).is_err());
        let o = VerifyOptions {
            threads: Some(0),
            ..opts(30_000)
        };
        assert!(verify(&m, &t, &one(b.clone()), &o).is_err());
        let two = Volumes {
            fractions: Some(vec![0.5, 0.5]),
            ..one(b.clone())
        };
        assert!(verify(&m, &t, &two, &opts(30_000)).is_err());
        let zero = Volumes {
            fractions: Some(vec![0.0]),
            ..one(b.clone())
        };
        assert!(verify(&m, &t, &zero, &opts(30_000)).is_err());
        // The mesh is checked too.
        let vb = one(b);
        assert_eq!(
            verify(&m, &[], &vb, &opts(30_000)),
            Err(VerifyError::NoTriangles)
        );
        assert_eq!(
            verify(&m, &[[0, 1, m.len() as u32]], &vb, &opts(30_000)),
            Err(VerifyError::BadIndex {
                index: 0,
                vertex: m.len() as u32,
                count: m.len()
            })
        );
        let mut nan = m.clone();
        nan[3][1] = f64::NAN;
        assert_eq!(
            verify(&nan, &t, &vb, &opts(30_000)),
            Err(VerifyError::BadVertex { index: 3 })
        );
        // A flat mesh encloses nothing.
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let e = verify(&flat, &[[0, 1, 2], [0, 2, 1]], &vb, &opts(30_000)).unwrap_err();
        assert!(matches!(e, VerifyError::NoVolume(_)), "{e}");
    }

    #[test]
    fn reports_are_identical_on_any_thread_count() {
        let mut rng = SplitMix::new(11);
        let (m, t) = ellipsoid_mesh(DVec3::new(1.0, 2.0, 0.5), 32);
        let vols: Vec<Volume> = (0..6)
            .map(|i| {
                let c = DVec3::new(rng.signed(), 2.0 * rng.signed(), 0.5 * rng.signed());
                let rot = DMat3::from_euler(
                    glam::EulerRot::XYZ,
                    rng.signed() * 3.0,
                    rng.signed() * 3.0,
                    rng.signed() * 3.0,
                );
                let r = DVec3::new(0.8, 1.2, 0.6) * (0.5 + rng.next_f64());
                if i % 2 == 0 {
                    obb(c, r, rot)
                } else {
                    Volume::Ellipsoid {
                        center: c.to_array(),
                        axes: [rot.x_axis, rot.y_axis, rot.z_axis].map(|a| a.to_array()),
                        radii: r.to_array(),
                    }
                }
            })
            .collect();
        let vols = Volumes {
            fractions: Some(vec![1.0 / 6.0; 6]),
            ..Volumes::new(vols)
        };
        let run = |threads| {
            let o = VerifyOptions {
                threads: Some(threads),
                seed: 5,
                ..opts(40_000)
            };
            verify(&m, &t, &vols, &o).unwrap()
        };
        let one_thread = run(1);
        assert!(one_thread.unenclosed > 0 && one_thread.split + one_thread.single > 0);
        for threads in [2, 3, 8] {
            let r = run(threads);
            assert_eq!(r, one_thread, "{threads} threads");
            // Bit for bit, not just ==.
            assert_eq!(r.tov.to_bits(), one_thread.tov.to_bits());
            assert_eq!(
                r.max_escape_rel.to_bits(),
                one_thread.max_escape_rel.to_bits()
            );
        }
    }
}
