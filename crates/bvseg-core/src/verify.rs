//! An independent check of bounding volumes against a mesh: does their union enclose every
//! triangle, and how much do they stick out of the solid?
//!
//! Nothing here is shared with the segmentation's own sampling, enclosure or metrics, so a
//! bug there cannot hide itself: the inside test is its own signed ray count (not the
//! lattice's column sweep), the volumes are tested by their own formulas, and the outside
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
use glam::{DVec2, DVec3};

use crate::{BoundingVolume, Error, Mesh, Shape};

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
    /// Each volume's share of the solid, `vol(S_i) / vol(S)`, for the per-part outside
    /// volumes `OV_i`; `None` reports only `vol(V_i \ S) / vol(S)`.
    pub fractions: Option<Vec<f64>>,
}

impl Default for VerifyOptions {
    fn default() -> Self {
        Self {
            points: 2_000_000,
            seed: 0,
            tolerance: 1e-5,
            fractions: None,
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
}

impl VerifyReport {
    /// Whether no point of the mesh was found outside the union of the volumes.
    pub fn all_enclosed(&self) -> bool {
        self.unenclosed == 0
    }
}

/// Check `volumes` against `mesh` (see the module docs). Fails on invalid options or
/// volumes (non-finite or out of range values, radii not positive, fractions of the wrong
/// length) and when the mesh encloses no volume at the grid's resolution.
pub fn verify(
    mesh: &Mesh,
    volumes: &[BoundingVolume],
    opts: &VerifyOptions,
) -> Result<VerifyReport, Error> {
    check_inputs(volumes, opts)?;
    let vols: Vec<Vol> = volumes.iter().map(Vol::new).collect();
    let (mlo, mhi) = mesh.bbox();
    let diag = (mhi - mlo).length();
    let tris = triangle_enclosure(mesh, &vols, opts.tolerance * diag);
    let grid = grid_metrics(mesh, &vols, opts)?;

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
    if let Some(fr) = &opts.fractions {
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

fn check_inputs(volumes: &[BoundingVolume], opts: &VerifyOptions) -> Result<(), Error> {
    let bad = |s: String| Err(Error::Internal(s));
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
    if volumes.is_empty() {
        return bad("no volumes to verify".into());
    }
    for (i, v) in volumes.iter().enumerate() {
        let finite = v.center.is_finite() && v.axes.is_finite() && v.radii.is_finite();
        if !finite
            || v.center.abs().max_element() > crate::MAX_COORDINATE
            || v.radii.max_element() > crate::MAX_COORDINATE
        {
            return bad(format!("volume {i}: non-finite or out-of-range value"));
        }
        if v.radii.min_element() <= 0.0 {
            return bad(format!("volume {i}: radii must be positive"));
        }
    }
    if let Some(fr) = &opts.fractions {
        if fr.len() != volumes.len() {
            return bad(format!(
                "{} fractions for {} volumes",
                fr.len(),
                volumes.len()
            ));
        }
        if fr.iter().any(|f| !(f.is_finite() && *f > 0.0)) {
            return bad("fractions must be positive and finite".into());
        }
    }
    Ok(())
}

/// A volume with what the tests need precomputed: the frame as rows, the box around it.
struct Vol {
    obb: bool,
    center: DVec3,
    rows: [DVec3; 3],
    radii: [f64; 3],
    /// Radius of a sphere about the centre holding the volume (with room for the slack).
    rmax: f64,
    lo: DVec3,
    hi: DVec3,
}

/// Slack of the inside test on the normalised coordinates, as in the schema.
const SLACK: f64 = 1e-9;

impl Vol {
    fn new(v: &BoundingVolume) -> Self {
        let rows = [v.axes.x_axis, v.axes.y_axis, v.axes.z_axis];
        let radii = v.radii.to_array();
        let obb = v.shape == Shape::Obb;
        // World half-width along axis d: the support of the shape in direction e_d.
        let mut half = DVec3::ZERO;
        for d in 0..3 {
            let comp = DVec3::new(
                rows[0][d] * radii[0],
                rows[1][d] * radii[1],
                rows[2][d] * radii[2],
            );
            half[d] = if obb {
                comp.abs().element_sum()
            } else {
                comp.length()
            };
        }
        // The slack makes the shape slightly larger than its radii.
        let half = half * (1.0 + 2.0 * SLACK) + DVec3::splat(1e-300);
        Self {
            obb,
            center: v.center,
            rows,
            radii,
            rmax: if obb {
                v.radii.length()
            } else {
                v.radii.max_element()
            } * 1.000_001,
            lo: v.center - half,
            hi: v.center + half,
        }
    }

    /// Coordinates in the volume's frame (not normalised).
    #[inline]
    fn frame(&self, p: DVec3) -> [f64; 3] {
        let d = p - self.center;
        [
            self.rows[0].dot(d),
            self.rows[1].dot(d),
            self.rows[2].dot(d),
        ]
    }

    #[inline]
    fn contains(&self, p: DVec3) -> bool {
        let y = self.frame(p);
        let t = [
            y[0] / self.radii[0],
            y[1] / self.radii[1],
            y[2] / self.radii[2],
        ];
        if self.obb {
            t.iter().all(|x| x.abs() <= 1.0 + SLACK)
        } else {
            t[0] * t[0] + t[1] * t[1] + t[2] * t[2] <= 1.0 + SLACK
        }
    }

    /// Euclidean distance from `p` to the volume (0 inside, with the slack).
    fn distance(&self, p: DVec3) -> f64 {
        if self.contains(p) {
            return 0.0;
        }
        let y = self.frame(p);
        let r = self.radii;
        if self.obb {
            let e = DVec3::new(
                (y[0].abs() - r[0]).max(0.0),
                (y[1].abs() - r[1]).max(0.0),
                (y[2].abs() - r[2]).max(0.0),
            );
            return e.length();
        }
        // Closest point x_j = r_j² y_j / (r_j² + λ), where λ > 0 solves
        // Σ (r_j y_j / (r_j² + λ))² = 1; the left side falls with λ, so bisect.
        let g = |lam: f64| -> f64 {
            (0..3)
                .map(|j| (r[j] * y[j] / (r[j] * r[j] + lam)).powi(2))
                .sum()
        };
        let ylen = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
        let (mut lo, mut hi) = (0.0f64, ylen * r.iter().fold(0.0f64, |a, &b| a.max(b)));
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if g(mid) > 1.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let lam = 0.5 * (lo + hi);
        let mut d2 = 0.0;
        for j in 0..3 {
            let x = r[j] * r[j] * y[j] / (r[j] * r[j] + lam);
            d2 += (y[j] - x) * (y[j] - x);
        }
        d2.sqrt()
    }
}

// ---------------------------------------------------------------- triangle enclosure

/// Pieces examined per triangle before the search settles for what it has found.
const MAX_PIECES: usize = 50_000;

/// Relative precision of a triangle's largest escape distance.
const ESCAPE_PRECISION: f64 = 1e-3;

/// Status and largest escape distance (absolute) of every triangle.
fn triangle_enclosure(mesh: &Mesh, vols: &[Vol], tol: f64) -> Vec<(TriangleStatus, f64)> {
    let ids: Vec<usize> = (0..mesh.triangles().len()).collect();
    crate::parallel::map_chunked(&ids, 64, |&t| check_triangle(mesh.corners(t), vols, tol))
}

/// For each volume, a value `>= ` its distance from `p`, exact for the nearest volumes: the
/// distance to the centre stands in for volumes that cannot be the nearest (their bounding
/// sphere is farther than a volume already measured), which keeps both bounds of the search
/// valid and skips most of the costly ellipsoid distances.
fn distances(p: DVec3, vols: &[Vol]) -> Vec<f64> {
    let mut out: Vec<f64> = vols.iter().map(|v| (p - v.center).length()).collect();
    let mut order: Vec<(f64, usize)> = vols
        .iter()
        .enumerate()
        .map(|(j, v)| (out[j] - v.rmax, j))
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut nearest = f64::INFINITY;
    for (lower, j) in order {
        if lower > nearest {
            break;
        }
        out[j] = vols[j].distance(p);
        nearest = nearest.min(out[j]);
    }
    out
}

fn check_triangle(c: [DVec3; 3], vols: &[Vol], tol: f64) -> (TriangleStatus, f64) {
    if vols.iter().any(|v| c.iter().all(|&p| v.contains(p))) {
        return (TriangleStatus::Single, 0.0);
    }
    // Branch and bound on the largest distance to the union over the triangle. Each volume's
    // distance is convex, so over a piece it peaks at a corner: min over volumes of the
    // corners' largest distance bounds the piece from above, the corners' own distances to
    // the union bound it from below.
    let dist = |p: DVec3| -> Vec<f64> { distances(p, vols) };
    let mut best = 0.0f64;
    let mut unproven = false;
    let corner_d = [dist(c[0]), dist(c[1]), dist(c[2])];
    let mut stack = vec![(c, corner_d)];
    let mut pieces = 0usize;
    while let Some((p, d)) = stack.pop() {
        pieces += 1;
        let lower = (0..3)
            .map(|i| d[i].iter().fold(f64::INFINITY, |a, &b| a.min(b)))
            .fold(0.0f64, f64::max);
        best = best.max(lower);
        let upper = (0..vols.len())
            .map(|j| d[0][j].max(d[1][j]).max(d[2][j]))
            .fold(f64::INFINITY, f64::min);
        // Held by one volume, or unable to beat the escape found so far by more than its
        // relative precision (without that, a stretch of triangle at a near-constant
        // distance would be refined down to the tolerance all along).
        if upper == 0.0 || upper <= best * (1.0 + ESCAPE_PRECISION) {
            continue;
        }
        let size = (p[1] - p[0])
            .length()
            .max((p[2] - p[1]).length())
            .max((p[0] - p[2]).length());
        if size <= tol || pieces >= MAX_PIECES {
            unproven = true;
            continue;
        }
        let m = [
            0.5 * (p[0] + p[1]),
            0.5 * (p[1] + p[2]),
            0.5 * (p[2] + p[0]),
        ];
        let dm = [dist(m[0]), dist(m[1]), dist(m[2])];
        let [d0, d1, d2] = d;
        let [m0, m1, m2] = dm;
        stack.push(([p[0], m[0], m[2]], [d0, m0.clone(), m2.clone()]));
        stack.push(([m[0], p[1], m[1]], [m0.clone(), d1, m1.clone()]));
        stack.push(([m[2], m[1], p[2]], [m2.clone(), m1.clone(), d2]));
        stack.push(([m[0], m[1], m[2]], [m0, m1, m2]));
    }
    let status = if best > 0.0 {
        TriangleStatus::Escapes
    } else if unproven {
        TriangleStatus::WithinTolerance
    } else {
        TriangleStatus::Split
    };
    (status, best)
}

// ---------------------------------------------------------------- inside test

/// A triangle projected along a ray axis.
struct Projected {
    /// Corners in the plane across the axis.
    a: [DVec2; 3],
    /// Corners' coordinates along the axis.
    h: [f64; 3],
    /// Twice the projected signed area.
    area2: f64,
}

/// Triangles projected along one axis and bucketed on a 2D grid, for signed ray counts.
struct RayIndex {
    axis: usize,
    tris: Vec<Projected>,
    lo: DVec2,
    hi: DVec2,
    cell: DVec2,
    g: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

/// Sign of the edge function of `p` against the edge `p0 -> p1`, with ties broken by the
/// perturbation `p + (ε, ε²)`: consistent for all triangles at once, so a ray through an
/// edge or a vertex is counted exactly once by the triangles around it.
#[inline]
fn edge_sign(p0: DVec2, p1: DVec2, p: DVec2) -> f64 {
    let d = p1 - p0;
    let e = d.x * (p.y - p0.y) - d.y * (p.x - p0.x);
    if e != 0.0 {
        e.signum()
    } else if d.y != 0.0 {
        -d.y.signum()
    } else {
        d.x.signum()
    }
}

impl RayIndex {
    fn new(mesh: &Mesh, axis: usize) -> Self {
        let (u, v) = [(1, 2), (2, 0), (0, 1)][axis];
        let mut tris = Vec::new();
        for t in 0..mesh.triangles().len() {
            let c = mesh.corners(t);
            let a = c.map(|p| DVec2::new(p[u], p[v]));
            let area2 = (a[1] - a[0]).perp_dot(a[2] - a[0]);
            // Triangles seen edge-on cover no area: no ray crosses them (up to measure zero).
            if area2 != 0.0 && area2.is_finite() {
                tris.push(Projected {
                    a,
                    h: c.map(|p| p[axis]),
                    area2,
                });
            }
        }
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for t in &tris {
            for p in t.a {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let n = tris.len();
        let mut g = ((1.5 * (n as f64).sqrt()) as usize).clamp(8, 2048);
        // Long thin triangles could span many cells each: coarsen until the index is small.
        loop {
            let cell = ((hi - lo) / g as f64).max(DVec2::splat(f64::MIN_POSITIVE));
            let entries: usize = tris
                .iter()
                .map(|t| {
                    let (c0, c1) = Self::span(t, lo, cell, g);
                    (c1[0] - c0[0] + 1) * (c1[1] - c0[1] + 1)
                })
                .sum();
            if entries <= 8 * n + 4_000_000 || g <= 1 {
                break;
            }
            g /= 2;
        }
        let cell = ((hi - lo) / g as f64).max(DVec2::splat(f64::MIN_POSITIVE));
        let mut count = vec![0u32; g * g + 1];
        for t in &tris {
            let (c0, c1) = Self::span(t, lo, cell, g);
            for x in c0[0]..=c1[0] {
                for y in c0[1]..=c1[1] {
                    count[x * g + y + 1] += 1;
                }
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let start = count.clone();
        let mut fill = count;
        let mut items = vec![0u32; start[g * g] as usize];
        for (ti, t) in tris.iter().enumerate() {
            let (c0, c1) = Self::span(t, lo, cell, g);
            for x in c0[0]..=c1[0] {
                for y in c0[1]..=c1[1] {
                    let b = x * g + y;
                    items[fill[b] as usize] = ti as u32;
                    fill[b] += 1;
                }
            }
        }
        Self {
            axis,
            tris,
            lo,
            hi,
            cell,
            g,
            start,
            items,
        }
    }

    fn bucket(p: DVec2, lo: DVec2, cell: DVec2, g: usize) -> [usize; 2] {
        let q = (p - lo) / cell;
        let clamp = |x: f64| (x.max(0.0) as usize).min(g - 1);
        [clamp(q.x), clamp(q.y)]
    }

    fn span(t: &Projected, lo: DVec2, cell: DVec2, g: usize) -> ([usize; 2], [usize; 2]) {
        let tlo = t.a[0].min(t.a[1]).min(t.a[2]);
        let thi = t.a[0].max(t.a[1]).max(t.a[2]);
        (
            Self::bucket(tlo, lo, cell, g),
            Self::bucket(thi, lo, cell, g),
        )
    }

    /// Half the signed crossings above `p` minus half those below: the winding number of a
    /// closed mesh, the two-ray average of an open one.
    fn crossings(&self, p: DVec3) -> f64 {
        let (u, v) = [(1, 2), (2, 0), (0, 1)][self.axis];
        let q = DVec2::new(p[u], p[v]);
        if !(q.cmpge(self.lo).all() && q.cmple(self.hi).all()) || self.tris.is_empty() {
            return 0.0;
        }
        let [bx, by] = Self::bucket(q, self.lo, self.cell, self.g);
        let b = bx * self.g + by;
        let mut w = 0.0;
        for &ti in &self.items[self.start[b] as usize..self.start[b + 1] as usize] {
            let t = &self.tris[ti as usize];
            let s = t.area2.signum();
            let s0 = edge_sign(t.a[1], t.a[2], q) * s;
            let s1 = edge_sign(t.a[2], t.a[0], q) * s;
            let s2 = edge_sign(t.a[0], t.a[1], q) * s;
            if s0 < 0.0 || s1 < 0.0 || s2 < 0.0 {
                continue;
            }
            // Barycentric height of the crossing.
            let l0 = (t.a[2] - t.a[1]).perp_dot(q - t.a[1]);
            let l1 = (t.a[0] - t.a[2]).perp_dot(q - t.a[2]);
            let l2 = (t.a[1] - t.a[0]).perp_dot(q - t.a[0]);
            let h = (l0 * t.h[0] + l1 * t.h[1] + l2 * t.h[2]) / t.area2;
            w += if h > p[self.axis] { 0.5 * s } else { -0.5 * s };
        }
        w
    }
}

/// The inside test of S: signed crossings along z (closed) or the average over x, y, z.
struct InsideTest {
    rays: Vec<RayIndex>,
    /// +1 or -1: the mesh's orientation, so that inward-facing meshes count as solids.
    orient: f64,
    lo: DVec3,
    hi: DVec3,
}

impl InsideTest {
    fn new(mesh: &Mesh, closed: bool, orient: f64) -> Self {
        let axes: &[usize] = if closed { &[2] } else { &[0, 1, 2] };
        let (lo, hi) = mesh.bbox();
        Self {
            rays: axes.iter().map(|&a| RayIndex::new(mesh, a)).collect(),
            orient,
            lo,
            hi,
        }
    }

    fn inside(&self, p: DVec3) -> bool {
        if !(p.cmpge(self.lo).all() && p.cmple(self.hi).all()) {
            return false;
        }
        let w: f64 = self.rays.iter().map(|r| r.crossings(p)).sum::<f64>() / self.rays.len() as f64;
        w * self.orient > 0.5
    }
}

/// Whether every directed edge is matched by its reverse, vertices compared by position.
fn is_closed(mesh: &Mesh) -> bool {
    let vs = mesh.vertices();
    let mut order: Vec<u32> = (0..vs.len() as u32).collect();
    let key = |i: u32| {
        let p = vs[i as usize];
        // +0.0 and -0.0 are the same position.
        [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits)
    };
    order.sort_by_key(|&i| key(i));
    let mut canon = vec![0u32; vs.len()];
    let mut id = 0u32;
    for (n, &i) in order.iter().enumerate() {
        if n > 0 && key(order[n - 1]) != key(i) {
            id += 1;
        }
        canon[i as usize] = id;
    }
    let mut fwd = Vec::with_capacity(3 * mesh.triangles().len());
    let mut rev = Vec::with_capacity(3 * mesh.triangles().len());
    for t in mesh.triangles() {
        let c = t.map(|v| canon[v as usize]);
        for e in 0..3 {
            let (a, b) = (c[e], c[(e + 1) % 3]);
            fwd.push((a, b));
            rev.push((b, a));
        }
    }
    fwd.sort_unstable();
    rev.sort_unstable();
    fwd == rev
}

/// Signed volume by tetrahedra from the centroid of the vertices used.
fn signed_volume(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.bbox();
    let c = 0.5 * (lo + hi);
    let mut sum = 0.0;
    for t in 0..mesh.triangles().len() {
        let [a, b, d] = mesh.corners(t);
        sum += (a - c).dot((b - c).cross(d - c));
    }
    sum / 6.0
}

// ---------------------------------------------------------------- grid metrics

struct GridMetrics {
    closed: bool,
    volume: f64,
    volume_grid: f64,
    volume_grid_se: f64,
    dims: [usize; 3],
    tov: f64,
    tov_se: f64,
    outside: Vec<f64>,
    outside_se: Vec<f64>,
    coverage_interior: f64,
}

/// Counts over a slab of two x-layers of the grid.
#[derive(Default)]
struct Counts {
    inside: u64,
    inside_diff: u64,
    outside_union: u64,
    outside_union_diff: u64,
    covered_inside: u64,
    /// Per volume: grid points in the volume and outside S, and their pair differences.
    outside: Vec<u64>,
    outside_diff: Vec<u64>,
}

/// SplitMix64's finaliser: a deterministic hash, so each cell's jitter depends only on the
/// seed and the cell, never on the order or thread it is computed in.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[inline]
fn unit(z: u64) -> f64 {
    (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Cells per axis for about `n` cells over a box of extents `l`, with an even count along
/// x (for the pairs of the error estimate). Axes too thin for one cell get one, and the
/// others share the budget.
fn grid_shape(l: DVec3, n: usize) -> [usize; 3] {
    let mut dims = [1usize; 3];
    let mut free = [true; 3];
    loop {
        let nf = free.iter().filter(|&&f| f).count();
        if nf == 0 {
            break;
        }
        let prod: f64 = (0..3).filter(|&d| free[d]).map(|d| l[d]).product();
        let h = (prod / n as f64).powf(1.0 / nf as f64);
        let mut clamped = false;
        for d in 0..3 {
            if free[d] {
                let c = (l[d] / h).round();
                if c < 1.0 {
                    free[d] = false;
                    dims[d] = 1;
                    clamped = true;
                } else {
                    dims[d] = c.min(n as f64) as usize;
                }
            }
        }
        if !clamped {
            break;
        }
    }
    dims[0] += dims[0] % 2;
    dims
}

fn grid_metrics(mesh: &Mesh, vols: &[Vol], opts: &VerifyOptions) -> Result<GridMetrics, Error> {
    let closed = is_closed(mesh);
    let sv = signed_volume(mesh);
    let orient = if sv < 0.0 { -1.0 } else { 1.0 };
    let inside = InsideTest::new(mesh, closed, orient);

    let (mut lo, mut hi) = mesh.bbox();
    for v in vols {
        lo = lo.min(v.lo);
        hi = hi.max(v.hi);
    }
    let ext = hi - lo;
    let dims = grid_shape(ext, opts.points);
    let [nx, ny, nz] = dims;
    let h = ext / DVec3::new(nx as f64, ny as f64, nz as f64);
    let w_cell = h.x * h.y * h.z;
    let k = vols.len();
    let seed = mix(opts.seed ^ 0x05EE_D0FB_75E6);

    let slabs: Vec<usize> = (0..nx / 2).collect();
    let parts = crate::parallel::map(&slabs, |&a| {
        let mut c = Counts {
            outside: vec![0; k],
            outside_diff: vec![0; k],
            ..Counts::default()
        };
        let mut cand: Vec<usize> = Vec::new();
        let mut in_v = vec![[false; 2]; k];
        let x0 = lo.x + (2 * a) as f64 * h.x;
        let x1 = x0 + 2.0 * h.x;
        for j in 0..ny {
            let y0 = lo.y + j as f64 * h.y;
            let y1 = y0 + h.y;
            cand.clear();
            cand.extend((0..k).filter(|&i| {
                let v = &vols[i];
                v.lo.x <= x1 && v.hi.x >= x0 && v.lo.y <= y1 && v.hi.y >= y0
            }));
            for kz in 0..nz {
                let mut in_s = [false; 2];
                let mut in_u = [false; 2];
                for (e, ix) in [2 * a, 2 * a + 1].into_iter().enumerate() {
                    let cell = (ix + nx * (j + ny * kz)) as u64;
                    let r = mix(seed ^ cell.wrapping_mul(0xD1B5_4A32_D192_ED03));
                    let p = DVec3::new(
                        lo.x + (ix as f64 + unit(r)) * h.x,
                        lo.y + (j as f64 + unit(mix(r ^ 1))) * h.y,
                        lo.z + (kz as f64 + unit(mix(r ^ 2))) * h.z,
                    );
                    in_s[e] = inside.inside(p);
                    for &i in &cand {
                        let v = &vols[i];
                        let hit = p.z >= v.lo.z && p.z <= v.hi.z && v.contains(p);
                        in_v[i][e] = hit;
                        in_u[e] |= hit;
                    }
                }
                c.inside += in_s[0] as u64 + in_s[1] as u64;
                c.inside_diff += (in_s[0] != in_s[1]) as u64;
                let out_u = [in_u[0] && !in_s[0], in_u[1] && !in_s[1]];
                c.outside_union += out_u[0] as u64 + out_u[1] as u64;
                c.outside_union_diff += (out_u[0] != out_u[1]) as u64;
                c.covered_inside += (in_u[0] && in_s[0]) as u64 + (in_u[1] && in_s[1]) as u64;
                for &i in &cand {
                    let o = [in_v[i][0] && !in_s[0], in_v[i][1] && !in_s[1]];
                    c.outside[i] += o[0] as u64 + o[1] as u64;
                    c.outside_diff[i] += (o[0] != o[1]) as u64;
                }
            }
        }
        c
    });
    // Integer sums, in slab order: the totals do not depend on the thread count.
    let mut t = Counts {
        outside: vec![0; k],
        outside_diff: vec![0; k],
        ..Counts::default()
    };
    for c in &parts {
        t.inside += c.inside;
        t.inside_diff += c.inside_diff;
        t.outside_union += c.outside_union;
        t.outside_union_diff += c.outside_union_diff;
        t.covered_inside += c.covered_inside;
        for i in 0..k {
            t.outside[i] += c.outside[i];
            t.outside_diff[i] += c.outside_diff[i];
        }
    }
    let volume_grid = t.inside as f64 * w_cell;
    let volume_grid_se = w_cell * (t.inside_diff as f64).sqrt();
    let volume = if closed { sv.abs() } else { volume_grid };
    if volume.is_nan() || volume <= 0.0 || t.inside == 0 {
        return Err(Error::NoVolume(
            "no point of the verification grid lies inside the mesh".into(),
        ));
    }
    let rel = |n: u64| n as f64 * w_cell / volume;
    let rel_se = |n: u64| w_cell * (n as f64).sqrt() / volume;
    Ok(GridMetrics {
        closed,
        volume,
        volume_grid,
        volume_grid_se,
        dims,
        tov: rel(t.outside_union),
        tov_se: rel_se(t.outside_union_diff),
        outside: t.outside.iter().map(|&n| rel(n)).collect(),
        outside_se: t.outside_diff.iter().map(|&n| rel_se(n)).collect(),
        coverage_interior: t.covered_inside as f64 / t.inside as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;
    use glam::DMat3;

    fn obb(c: DVec3, half: DVec3, rot: DMat3) -> BoundingVolume {
        BoundingVolume {
            shape: Shape::Obb,
            center: c,
            axes: rot,
            radii: half,
        }
    }

    fn opts(points: usize) -> VerifyOptions {
        VerifyOptions {
            points,
            ..VerifyOptions::default()
        }
    }

    #[test]
    fn box_in_its_own_box_and_in_its_circumscribed_ellipsoid() {
        let rot = DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let c = DVec3::new(0.4, -1.3, 2.2);
        let half = DVec3::new(1.0, 0.5, 0.25);
        let mesh = shapes::cuboid(c, half, rot);
        let r = verify(&mesh, &[obb(c, half, rot)], &opts(200_000)).unwrap();
        assert!(r.closed && r.all_enclosed() && r.single == 12);
        assert!((r.volume - 1.0).abs() < 1e-12);
        assert!(r.tov < 1e-3, "{}", r.tov);
        assert!(r.coverage_interior > 0.999);

        let e = BoundingVolume {
            shape: Shape::Ellipsoid,
            radii: half * 3f64.sqrt(),
            ..obb(c, half, rot)
        };
        let o = VerifyOptions {
            fractions: Some(vec![1.0]),
            ..opts(400_000)
        };
        let r = verify(&mesh, &[e], &o).unwrap();
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
        let mesh = shapes::cuboid(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.5), DMat3::IDENTITY);
        let v = obb(
            DVec3::new(-0.5, 0.0, 0.0),
            DVec3::splat(0.5),
            DMat3::IDENTITY,
        );
        let r = verify(&mesh, &[v], &opts(50_000)).unwrap();
        assert!(!r.all_enclosed());
        // The farthest point, a corner at x = 1, is 1 away from the volume; the diagonal is
        // sqrt(6).
        assert!((r.max_escape_rel - 1.0 / 6f64.sqrt()).abs() < 1e-12);
        assert!((r.coverage_interior - 0.5).abs() < 0.02);
        assert!(r.tov < 1e-3);
    }

    #[test]
    fn a_triangle_covered_by_two_volumes_is_split_exactly() {
        let mesh = shapes::cuboid(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.5), DMat3::IDENTITY);
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
        let r = verify(&mesh, &[a, b], &opts(20_000)).unwrap();
        assert!(r.all_enclosed(), "{r:?}");
        assert!(r.split > 0 && r.single > 0 && r.within_tolerance == 0);
        assert_eq!(r.max_escape_rel, 0.0);
    }

    #[test]
    fn ellipsoid_distance_matches_a_dense_search() {
        let v = Vol::new(&BoundingVolume {
            shape: Shape::Ellipsoid,
            center: DVec3::new(0.2, -0.1, 0.3),
            axes: DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1),
            radii: DVec3::new(1.5, 0.7, 0.3),
        });
        let p = DVec3::new(2.0, 1.0, -1.0);
        let d = v.distance(p);
        let mut best = f64::INFINITY;
        let n = 800;
        for i in 0..=n {
            let th = std::f64::consts::PI * i as f64 / n as f64;
            for j in 0..2 * n {
                let ph = std::f64::consts::PI * j as f64 / n as f64;
                let u = DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                let local = u * DVec3::new(1.5, 0.7, 0.3);
                let rows = v.rows;
                let w = v.center + rows[0] * local.x + rows[1] * local.y + rows[2] * local.z;
                best = best.min((w - p).length());
            }
        }
        assert!(d <= best + 1e-12 && best - d < 2e-3, "{d} vs {best}");
    }

    #[test]
    fn inward_and_open_meshes_and_torus_hole() {
        // Inward: same figures as outward.
        let m = shapes::cuboid(DVec3::ZERO, DVec3::splat(1.0), DMat3::IDENTITY);
        let flipped = Mesh::new(
            m.vertices().to_vec(),
            m.triangles().iter().map(|t| [t[0], t[2], t[1]]).collect(),
        )
        .unwrap();
        let v = obb(DVec3::ZERO, DVec3::splat(1.2), DMat3::IDENTITY);
        let a = verify(&m, &[v], &opts(100_000)).unwrap();
        let b = verify(&flipped, &[v], &opts(100_000)).unwrap();
        assert_eq!(a.tov, b.tov);
        assert!((a.tov - (1.2f64.powi(3) - 1.0)).abs() < 4.0 * a.tov_se + 2e-3);
        // Open (one triangle dropped): the six-ray average still sees the solid.
        let open = Mesh::new(m.vertices().to_vec(), m.triangles()[1..].to_vec()).unwrap();
        let c = verify(&open, &[v], &opts(100_000)).unwrap();
        assert!(!c.closed && (c.volume - 8.0).abs() < 0.2, "{}", c.volume);
        // The torus's hole is outside.
        let t = shapes::torus(DVec3::ZERO, 2.0, 0.5, 48);
        let ball = BoundingVolume {
            shape: Shape::Ellipsoid,
            center: DVec3::ZERO,
            axes: DMat3::IDENTITY,
            radii: DVec3::new(2.6, 2.6, 1.0),
        };
        let r = verify(&t, &[ball], &opts(200_000)).unwrap();
        assert!(r.closed && r.all_enclosed());
        let vt = t.signed_volume();
        let want = ball.volume() / vt - 1.0;
        assert!(
            (r.tov - want).abs() < 4.0 * r.tov_se + 5e-3,
            "{} vs {want}",
            r.tov
        );
    }

    #[test]
    fn reports_are_deterministic_and_bad_input_is_refused() {
        let m = shapes::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 2.0, 0.5), DMat3::IDENTITY, 24);
        let v = obb(DVec3::ZERO, DVec3::new(1.0, 2.0, 0.5), DMat3::IDENTITY);
        let a = verify(&m, &[v], &opts(30_000)).unwrap();
        let b = verify(&m, &[v], &opts(30_000)).unwrap();
        assert_eq!(a, b);
        let mut bad = v;
        bad.radii.y = 0.0;
        assert!(verify(&m, &[bad], &opts(30_000)).is_err());
        bad.radii.y = f64::NAN;
        assert!(verify(&m, &[bad], &opts(30_000)).is_err());
        assert!(verify(&m, &[], &opts(30_000)).is_err());
        assert!(verify(&m, &[v], &opts(10)).is_err());
        let o = VerifyOptions {
            fractions: Some(vec![0.5, 0.5]),
            ..opts(30_000)
        };
        assert!(verify(&m, &[v], &o).is_err());
    }

    #[test]
    fn pruned_distances_bound_the_exact_ones_and_keep_the_nearest() {
        let mut rng = crate::rng::Rng::new(3);
        let mut r = || rng.next_f64() * 2.0 - 1.0;
        let vols: Vec<Vol> = (0..30)
            .map(|i| {
                let axes = DMat3::from_euler(glam::EulerRot::XYZ, r() * 3.0, r() * 3.0, r() * 3.0);
                Vol::new(&BoundingVolume {
                    shape: if i % 2 == 0 {
                        Shape::Obb
                    } else {
                        Shape::Ellipsoid
                    },
                    center: DVec3::new(r(), r(), r()) * 5.0,
                    axes,
                    radii: DVec3::new(r().abs(), r().abs(), r().abs()) * 2.0 + 0.01,
                })
            })
            .collect();
        for _ in 0..500 {
            let p = DVec3::new(r(), r(), r()) * 8.0;
            let fast = distances(p, &vols);
            let exact: Vec<f64> = vols.iter().map(|v| v.distance(p)).collect();
            let min_exact = exact.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            let min_fast = fast.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            assert_eq!(min_fast, min_exact);
            for (f, e) in fast.iter().zip(&exact) {
                assert!(f >= e);
            }
        }
    }

    #[test]
    fn grid_shape_handles_thin_boxes() {
        assert_eq!(grid_shape(DVec3::ONE, 1000), [10, 10, 10]);
        let d = grid_shape(DVec3::new(1.0, 1.0, 1e-12), 10_000);
        assert_eq!(d, [100, 100, 1]);
    }
}
