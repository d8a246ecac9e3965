//! Each sample's distance to the solid's boundary: the exact Euclidean distance transform of
//! the lattice (Felzenszwalb and Huttenlocher's lower envelope of parabolas, one pass per
//! axis, linear in the cells).
//!
//! The distance of a sample is to the nearest lattice cell centre outside the solid (every
//! cell beyond the grid counts as outside), in cells: 1 for a sample on the boundary layer.
//! Squared distances between cell centres are integers, kept exactly in `u32`, so the
//! transform is the same bits on every platform.
use super::Grid;

/// Squared distance standing for "no outside cell on this line yet": larger than any sum of
/// three squared extents of a grid that fits in memory.
const FAR: u32 = u32::MAX / 4;

/// Each sample's distance to the nearest cell outside the solid, in cells (at least 1). A
/// block of adaptive sampling gets its nearest cell's distance plus half its side less one,
/// about its centre's.
pub fn boundary_distance(grid: &Grid) -> Vec<f64> {
    let depth = cell_depths(grid);
    let [nx, ny, _] = grid.dims;
    (0..grid.len())
        .map(|s| {
            let near = grid
                .cells_of(s)
                .map(|[i, j, k]| depth[i as usize + nx * (j as usize + ny * k as usize)])
                .min()
                .unwrap_or(0);
            f64::from(near).sqrt() + 0.5 * f64::from(grid.side(s) - 1)
        })
        .collect()
}

/// For every lattice cell (`i + nx (j + ny k)`), its squared distance to the nearest cell
/// outside the solid, in cells squared: 0 outside, 1 on the boundary layer.
pub fn cell_depths(grid: &Grid) -> Vec<u32> {
    let [nx, ny, nz] = grid.dims;
    // One layer of outside cells around the grid, so that the grid's border counts as
    // outside in every direction.
    let d = [nx + 2, ny + 2, nz + 2];
    let index = |i: usize, j: usize, k: usize| i + d[0] * (j + d[1] * k);
    let mut f = vec![0u32; d[0] * d[1] * d[2]];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                if grid.sample_of_cell[i + nx * (j + ny * k)] != super::NONE {
                    f[index(i + 1, j + 1, k + 1)] = FAR;
                }
            }
        }
    }
    let mut line = Vec::new();
    let mut out = Vec::new();
    let mut envelope = Envelope::default();
    for axis in 0..3 {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        for v in 0..d[b] {
            for u in 0..d[a] {
                let at = |t: usize| {
                    let mut c = [0usize; 3];
                    c[axis] = t;
                    c[a] = u;
                    c[b] = v;
                    index(c[0], c[1], c[2])
                };
                line.clear();
                line.extend((0..d[axis]).map(|t| f[at(t)]));
                if line.iter().all(|&x| x == 0) {
                    continue;
                }
                envelope.transform(&line, &mut out);
                for (t, &x) in out.iter().enumerate() {
                    f[at(t)] = x;
                }
            }
        }
    }
    let mut depth = vec![0u32; nx * ny * nz];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                depth[i + nx * (j + ny * k)] = f[index(i + 1, j + 1, k + 1)];
            }
        }
    }
    depth
}

/// The buffers of the one-dimensional transform.
#[derive(Default)]
struct Envelope {
    /// Positions of the parabolas in the lower envelope.
    v: Vec<usize>,
    /// Where each one starts to be the lowest.
    z: Vec<f64>,
}

impl Envelope {
    /// `out[t] = min_s (f[s] + (t - s)^2)` over the sites `s` with `f[s] < FAR`.
    fn transform(&mut self, f: &[u32], out: &mut Vec<u32>) {
        let n = f.len();
        out.clear();
        self.v.clear();
        self.z.clear();
        let sq = |x: usize| (x * x) as f64;
        for q in 0..n {
            if f[q] >= FAR {
                continue;
            }
            let fq = f64::from(f[q]);
            loop {
                let Some(&p) = self.v.last() else {
                    self.v.push(q);
                    self.z.push(f64::NEG_INFINITY);
                    break;
                };
                // Where the parabola of q falls below that of p.
                let s = ((fq + sq(q)) - (f64::from(f[p]) + sq(p))) / (2.0 * (q - p) as f64);
                if s <= self.z[self.z.len() - 1] {
                    self.v.pop();
                    self.z.pop();
                } else {
                    self.v.push(q);
                    self.z.push(s);
                    break;
                }
            }
        }
        if self.v.is_empty() {
            out.resize(n, FAR);
            return;
        }
        let mut j = 0;
        for t in 0..n {
            while j + 1 < self.v.len() && self.z[j + 1] < t as f64 {
                j += 1;
            }
            let p = self.v[j];
            let dt = t.abs_diff(p);
            out.push((f[p] as usize + dt * dt).min(FAR as usize) as u32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::NONE;
    use glam::DVec3;

    #[test]
    fn matches_brute_force_on_a_ball_with_a_hole() {
        let g = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), 0.1, |p| {
            let r = p.length();
            r < 0.9 && (p - DVec3::new(0.3, 0.0, 0.0)).length() > 0.25
        });
        let d = boundary_distance(&g);
        let [nx, ny, nz] = g.dims;
        let outside: Vec<[i64; 3]> = (-1..=nz as i64)
            .flat_map(|k| {
                (-1..=ny as i64).flat_map(move |j| (-1..=nx as i64).map(move |i| [i, j, k]))
            })
            .filter(|&[i, j, k]| g.sample_at(i, j, k) == NONE)
            .collect();
        for (s, c) in g.coords.iter().enumerate() {
            let c = c.map(i64::from);
            let best = outside
                .iter()
                .map(|o| (0..3).map(|a| (o[a] - c[a]).pow(2)).sum::<i64>())
                .min()
                .unwrap();
            assert_eq!(d[s], (best as f64).sqrt(), "sample {s}");
        }
        assert!(d.iter().all(|&x| x >= 1.0));
    }
}
