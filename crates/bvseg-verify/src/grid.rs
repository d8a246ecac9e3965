//! The outside volumes, the grid estimate of vol(S) and the interior coverage, on a jittered
//! grid over the box of the mesh and the volumes.
use glam::DVec3;

use crate::inside::{is_closed, signed_volume, InsideTest};
use crate::mesh::MeshRef;
use crate::parallel;
use crate::vol::Vol;
use crate::{VerifyError, VerifyOptions};

pub(crate) struct GridMetrics {
    pub(crate) closed: bool,
    pub(crate) volume: f64,
    pub(crate) volume_grid: f64,
    pub(crate) volume_grid_se: f64,
    pub(crate) dims: [usize; 3],
    pub(crate) tov: f64,
    pub(crate) tov_se: f64,
    pub(crate) outside: Vec<f64>,
    pub(crate) outside_se: Vec<f64>,
    pub(crate) coverage_interior: f64,
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

pub(crate) fn grid_metrics(
    mesh: &MeshRef<'_>,
    vols: &[Vol],
    opts: &VerifyOptions,
    threads: usize,
) -> Result<GridMetrics, VerifyError> {
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

    let parts = parallel::map_range(nx / 2, 1, threads, |a| {
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
        return Err(VerifyError::NoVolume {
            points: nx * ny * nz,
        });
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

    #[test]
    fn grid_shape_handles_thin_boxes() {
        assert_eq!(grid_shape(DVec3::ONE, 1000), [10, 10, 10]);
        let d = grid_shape(DVec3::new(1.0, 1.0, 1e-12), 10_000);
        assert_eq!(d, [100, 100, 1]);
    }
}
