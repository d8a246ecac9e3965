//! Triangle enclosure: is every point of every triangle in some volume?
use glam::DVec3;

use crate::mesh::MeshRef;
use crate::parallel;
use crate::vol::{distances, Vol};
use crate::TriangleStatus;

/// Pieces examined per triangle before the search settles for what it has found.
const MAX_PIECES: usize = 50_000;

/// Relative precision of a triangle's largest escape distance.
const ESCAPE_PRECISION: f64 = 1e-3;

/// Triangles handed to a thread at a time.
const BLOCK: usize = 64;

/// Status and largest escape distance (absolute) of every triangle, in triangle order.
pub(crate) fn triangle_enclosure(
    mesh: &MeshRef<'_>,
    vols: &[Vol],
    tol: f64,
    threads: usize,
) -> Vec<(TriangleStatus, f64)> {
    parallel::map_range(mesh.triangles().len(), BLOCK, threads, |t| {
        check_triangle(mesh.corners(t), vols, tol)
    })
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
