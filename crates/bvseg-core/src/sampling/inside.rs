//! Which lattice cell centres lie inside the solid: signed ray crossings along grid columns.
//!
//! # Method
//!
//! The query points are not scattered: they are the centres of a regular lattice, so they
//! line up in columns parallel to each axis. One ray per column classifies every cell of the
//! column at once, which is far cheaper than a point-in-solid test per cell (generalised
//! winding numbers or a BVH ray per cell). Each crossing of the column with the surface
//! counts +1 when the ray enters (the face normal points against the ray) and -1 when it
//! leaves; the running sum along the column is the winding number of each cell, and a cell
//! is inside when it is nonzero (the nonzero rule). That rule is what makes the odd inputs
//! behave: an inward-facing mesh has winding -1 inside, a duplicated or self-overlapping
//! shell has winding 2 where it overlaps, an inner shell of opposite orientation carves a
//! cavity (winding 0) while an inner shell of the same orientation stays solid (winding 2).
//!
//! Each triangle only touches the columns its projection covers, so it is rasterised over
//! the column lattice (row by row, over the columns near its projection) and each crossing
//! is added to a difference array shaped like the lattice, with one extra layer along the
//! column axis for crossings past the far end. A prefix sum along the axis turns it into windings; the extra
//! layer then holds each column's total. Cost is O(triangles + covered columns + cells), with
//! no per-column allocation.
//!
//! # Watertightness
//!
//! Lattice columns often run exactly through mesh edges and vertices (both are on "nice"
//! coordinates), so a ray must count a shared edge or vertex exactly once. For each column,
//! vertices are translated so the column sits at the origin (each vertex rounded the same
//! way for every triangle that uses it), and the edge functions are 2D cross products of
//! translated vertices. Their signs are exact: rounding is monotone, so a rounded cross
//! product has the true sign or is zero, and zeros are settled with the `fma` error terms.
//! The two triangles that share an edge therefore see exactly opposite values (or equal ones
//! when they traverse it the same way), so the column falls on one side. What is left,
//! a column exactly on an edge line, is settled by simulation of simplicity: the cell centre
//! is treated as displaced by `(dx, dy, dz)`, infinitesimal with `dx >> dy >> dz > 0`, the
//! same displacement for all three column axes. Consequences: an axis-aligned box
//! `[a, b)^3` in lattice coordinates contains exactly the centres `a <= i < b`; projections
//! that are degenerate (vertical triangles) never contain the displaced point and drop out
//! with no special case; and on a closed mesh all axes agree (up to rounding of the crossing
//! position along the column).
//!
//! # Open and broken meshes
//!
//! On a closed mesh (every edge used equally often in each direction, after welding equal
//! positions) the windings along a column return to 0 at the far end, and one pass along z
//! is exact. Closedness is judged from the topology, not from the z columns returning to 0:
//! a tube open at both ends along z has no z crossing at all, so every z column "closes".
//! With holes, flipped triangles or unmatched non-manifold edges, a column that
//! passes through a defect gets a nonzero total and its answer depends on the end it is
//! counted from; other columns through the same cell usually miss the defect. So for such
//! meshes the pass runs along x, y and z, each column counted from both ends, and a cell is
//! inside when at least 3 of those 6 estimates say so (a column that misses the defects
//! gives two equal votes, so the rule is a majority over axes, and a tie leans inside so
//! that a hole does not punch a tunnel through the solid).

use crate::math;
use glam::DVec3;
#[cfg(feature = "parallel")]
use rayon::prelude::*;

use crate::parallel::{map, threads};
use crate::{Error, Mesh, TooComplex};

/// Lattice coordinates are clamped to this magnitude (far beyond any lattice that fits in
/// memory) so that products of two stay finite and roundings to `i64` cannot saturate,
/// whatever `origin` and `h` the caller passes. Clamping moves shared vertices together, so
/// a closed surface stays closed.
const COORD_LIMIT: f64 = 1e15;

/// The bound on the inside tests' work over a lattice of `cells` cells, in lattice columns
/// scanned by triangles (a triangle scans about the columns its projection covers, once per
/// pass): 20 per cell, plus 50 million. A closed mesh scans about four times the columns
/// of a pass per layer of surface it crosses, so this allows over a thousand layers at the
/// default sample count; beyond it the triangles overlap far more than any modelled surface
/// does (stacked copies, a fan of huge slivers), and the run is refused in a fraction of a
/// second instead of taking minutes.
pub fn column_budget(cells: f64) -> u64 {
    math::min(50e6 + SCANS_PER_CELL * math::max(cells, 0.0), 1e18) as u64
}

/// The scans per cell that [`column_budget`] allows.
const SCANS_PER_CELL: f64 = 20.0;

/// For every cell centre `origin + h * (i, j, k)` of a `dims` lattice, whether it lies inside
/// the solid bounded by `mesh`. Index `i + nx * (j + ny * k)`.
///
/// Inside means nonzero winding number, so inward-facing meshes, overlapping or duplicated
/// shells work, and an inner shell carves a cavity only when it is oriented opposite to its
/// outer shell. Centres exactly on the surface are decided by a consistent symbolic
/// perturbation (an axis-aligned box `[a, b)` in lattice units holds the centres
/// `a <= i < b`). Meshes with holes or inconsistent orientation get a majority vote over
/// rays along the three axes, counted from both ends. See the module docs of `sampling::inside`.
///
/// Returns all `false` when `h` is not a positive finite number or `origin` is not finite.
/// The result does not depend on the number of threads.
///
/// # Errors
///
/// [`Error::TooComplex`] when the triangles would scan more than `column_budget` lattice
/// columns.
pub fn inside_cells(
    mesh: &Mesh,
    origin: DVec3,
    h: f64,
    dims: [usize; 3],
) -> Result<Vec<bool>, Error> {
    let mut budget = column_budget((dims[0] * dims[1] * dims[2]) as f64);
    inside_cells_within(mesh, origin, h, dims, &mut budget)
}

/// [`inside_cells`], drawing its work from `budget` (in scanned columns), so that the
/// sampling's several lattices share one bound.
pub(crate) fn inside_cells_within(
    mesh: &Mesh,
    origin: DVec3,
    h: f64,
    dims: [usize; 3],
    budget: &mut u64,
) -> Result<Vec<bool>, Error> {
    let ncells = dims[0] * dims[1] * dims[2];
    if ncells == 0 || !(h > 0.0 && h.is_finite()) || !origin.is_finite() {
        return Ok(vec![false; ncells]);
    }
    let pts = lattice_coords(mesh, origin, h);
    let tris = weighted_triangles(mesh.triangles());
    let [x, y, z] = [0, 1, 2].map(|axis| Pass::new(axis, dims));
    // What each pass will cost is known before any of them runs.
    let mut spend = |scans: u64| {
        if scans > *budget {
            return Err(Error::TooComplex(TooComplex::LatticeScans {
                per_cell: SCANS_PER_CELL as u32,
            }));
        }
        *budget -= scans;
        crate::work::add(scans as usize);
        Ok(())
    };
    spend(z.scans(&pts, &tris))?;
    // The topology check costs about as much as the z pass; overlap them when possible.
    #[cfg(feature = "parallel")]
    let (wz, closed) = rayon::join(|| z.windings(&pts, &tris), || mesh.is_closed());
    #[cfg(not(feature = "parallel"))]
    let (wz, closed) = {
        let w = z.windings(&pts, &tris);
        let closed = z.all_columns_close(&w) && mesh.is_closed();
        (w, closed)
    };
    if closed && z.all_columns_close(&wz) {
        return Ok(wz[..ncells].iter().map(|&w| w != 0).collect());
    }
    spend(x.scans(&pts, &tris) + y.scans(&pts, &tris))?;
    let mut votes = vec![0u8; ncells];
    z.add_votes(&wz, &mut votes);
    // Keep at most one winding array alive at a time.
    drop(wz);
    for pass in [x, y] {
        let w = pass.windings(&pts, &tris);
        pass.add_votes(&w, &mut votes);
    }
    Ok(votes.into_iter().map(|v| v >= 3).collect())
}

/// The distinct index triples of `tris`, each with its number of copies, in order of first
/// appearance. Windings are sums over triangles and a copy crosses exactly the same columns
/// at exactly the same places, so rasterising each triple once with its count gives the
/// same windings at a fraction of the cost when a file repeats faces (a polygon fanned over
/// a few corners, stacked duplicates).
fn weighted_triangles(tris: &[[u32; 3]]) -> Vec<([u32; 3], i32)> {
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    order.sort_unstable_by_key(|&i| (tris[i as usize], i));
    let mut out: Vec<(u32, [u32; 3], i32)> = Vec::with_capacity(tris.len());
    for run in order.chunk_by(|&a, &b| tris[a as usize] == tris[b as usize]) {
        // Counts wrap like the windings they add to; a mesh has far fewer than 2^31 faces.
        out.push((run[0], tris[run[0] as usize], run.len() as i32));
    }
    out.sort_unstable_by_key(|e| e.0);
    out.into_iter().map(|(_, t, n)| (t, n)).collect()
}

/// Vertex positions in lattice units (cell centres at integers). Converted once per vertex,
/// so every triangle sharing a vertex sees the same rounded coordinates.
fn lattice_coords(mesh: &Mesh, origin: DVec3, h: f64) -> Vec<[f64; 3]> {
    let lim = DVec3::splat(COORD_LIMIT);
    mesh.vertices()
        .iter()
        .map(|&v| {
            // Overflow to infinity is clamped; NaN cannot arise from finite inputs with a
            // positive finite h, but is mapped somewhere harmless anyway.
            let q = ((v - origin) / h).clamp(-lim, lim);
            q.to_array().map(|x| if x.is_nan() { 0.0 } else { x })
        })
        .collect()
}

/// One family of parallel columns: the rays along axis `a`, one through each `(u, v)` lattice
/// position. Windings live in an array shaped like the lattice with `dims[a] + 1` layers
/// along `a`; the last layer receives crossings beyond the far end and, after the prefix sum,
/// holds each column's total.
struct Pass {
    /// Column axis.
    a: usize,
    /// The two other axes, `u < v` (the order matters for the tie-break).
    u: usize,
    v: usize,
    dims: [usize; 3],
    /// Extended dims (`dims` with one more layer along `a`).
    ext: [usize; 3],
    /// Strides of the extended array.
    stride: [usize; 3],
}

impl Pass {
    fn new(a: usize, dims: [usize; 3]) -> Self {
        let (u, v) = match a {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let mut ext = dims;
        ext[a] += 1;
        Self {
            a,
            u,
            v,
            dims,
            ext,
            stride: [1, ext[0], ext[0] * ext[1]],
        }
    }

    fn len(&self) -> usize {
        self.ext[0] * self.ext[1] * self.ext[2]
    }

    /// Columns the triangles scan in this pass (about the area of their projections, see
    /// [`Pass::rows`]): the cost of [`Pass::windings`].
    fn scans(&self, pts: &[[f64; 3]], tris: &[([u32; 3], i32)]) -> u64 {
        tris.iter()
            .map(|(t, _)| self.scans_of(&t.map(|i| pts[i as usize])))
            .sum()
    }

    /// Columns triangle `p` scans in this pass.
    #[inline]
    fn scans_of(&self, p: &[[f64; 3]; 3]) -> u64 {
        let mut n = 0;
        self.rows(p, |_, u0, u1| n += (u1 - u0 + 1) as u64);
        n
    }

    /// Winding number of every cell (and column totals in the extra layer).
    fn windings(&self, pts: &[[f64; 3]], tris: &[([u32; 3], i32)]) -> Vec<i32> {
        let mut w = vec![0i32; self.len()];
        let corners = |t: &[u32; 3]| t.map(|i| pts[i as usize]);
        // Runs of triangles scanning about CHUNK_SCANS columns each, rasterised a few runs
        // at a time into crossing lists that are added up before the next few: memory stays
        // bounded however large the triangles. Integer sums commute, so neither the runs nor
        // the thread count change the result. Indices fit in u32 (the lattice is capped far
        // below 2^32 cells), which halves the lists.
        const CHUNK_SCANS: u64 = 1 << 18;
        let mut runs = Vec::new();
        let (mut start, mut acc) = (0, 0);
        for (i, (t, _)) in tris.iter().enumerate() {
            acc += self.scans_of(&corners(t));
            if acc >= CHUNK_SCANS || i + 1 - start == 4096 {
                runs.push(start..i + 1);
                (start, acc) = (i + 1, 0);
            }
        }
        if start < tris.len() {
            runs.push(start..tris.len());
        }
        for batch in runs.chunks(4 * threads()) {
            let lists = map(batch, |run| {
                let mut out: Vec<(u32, i32)> = Vec::new();
                for (t, n) in &tris[run.clone()] {
                    self.rasterize(&corners(t), |i, s| out.push((i as u32, s * n)));
                }
                out
            });
            for (i, s) in lists.into_iter().flatten() {
                w[i as usize] = w[i as usize].wrapping_add(s);
            }
        }
        self.prefix_sum(&mut w);
        w
    }

    /// The lattice range `[first, last]` of the triangle's projection along axis `ax`, if
    /// it meets the lattice.
    #[inline]
    fn span(&self, p: &[[f64; 3]; 3], ax: usize) -> Option<(usize, usize)> {
        let lo = math::min(math::min(p[0][ax], p[1][ax]), p[2][ax]);
        let hi = math::max(math::max(p[0][ax], p[1][ax]), p[2][ax]);
        // The displaced centre sits just above an integer, so a column at the upper
        // bound is never covered; keeping it is harmless, the exact test rejects it.
        let first = ceil_i(lo).max(0);
        let last = floor_i(hi).min(self.dims[ax] as i64 - 1);
        (first <= last).then_some((first as usize, last as usize))
    }

    /// Emit `(index of the first cell after the crossing, +-1)` for every column that the
    /// triangle's projection covers.
    #[inline]
    fn rasterize(&self, p: &[[f64; 3]; 3], mut emit: impl FnMut(usize, i32)) {
        let (u, v) = (self.u, self.v);
        self.rows(p, |iv, u0, u1| {
            for iu in u0..=u1 {
                if let Some((k0, s)) = self.crossing(p, iu as f64, iv as f64) {
                    emit(
                        iu * self.stride[u] + iv * self.stride[v] + k0 * self.stride[self.a],
                        s,
                    );
                }
            }
        });
    }

    /// Calls `row(iv, u0, u1)` for every lattice row `iv` the triangle's projection meets,
    /// with a range of columns `u0..=u1` that holds every column of the row it covers.
    ///
    /// The range is where the row's line meets the projected triangle, widened by more than
    /// the rounding error of that intersection, so that only columns certainly outside are
    /// skipped: the exact test decides the rest, as if the whole bounding box were scanned.
    /// A sliver spanning the lattice then costs its rows, not its bounding box.
    #[inline]
    fn rows(&self, p: &[[f64; 3]; 3], mut row: impl FnMut(usize, usize, usize)) {
        let (u, v) = (self.u, self.v);
        let (Some((u0, u1)), Some((v0, v1))) = (self.span(p, u), self.span(p, v)) else {
            return;
        };
        let big = p
            .iter()
            .map(|q| math::max(q[u].abs(), q[v].abs()))
            .fold(0.0, math::max);
        let margin = 1.0 + 1e-12 * big;
        for iv in v0..=v1 {
            let y = iv as f64;
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for e in 0..3 {
                let (a, b) = (p[e], p[(e + 1) % 3]);
                if (a[v] - y) * (b[v] - y) > 0.0 {
                    continue;
                }
                let x = if a[v] == b[v] {
                    lo = math::min(lo, math::min(a[u], b[u]));
                    math::max(a[u], b[u])
                } else {
                    a[u] + (y - a[v]) * ((b[u] - a[u]) / (b[v] - a[v]))
                };
                lo = math::min(lo, x);
                hi = math::max(hi, x);
            }
            let (first, last) = if lo <= hi {
                (
                    ceil_i(lo - margin).max(u0 as i64) as usize,
                    floor_i(hi + margin).min(u1 as i64),
                )
            } else {
                // No edge found across the row (rounding): scan the whole bounding box row.
                (u0, u1 as i64)
            };
            if first as i64 <= last {
                row(iv, first, last as usize);
            }
        }
    }

    /// Whether the column through `(pu, pv)` crosses the triangle; if so, the first cell
    /// along the column that lies beyond the crossing (`dims[a]` if none) and the crossing's
    /// sign (+1 entering).
    #[inline]
    fn crossing(&self, p: &[[f64; 3]; 3], pu: f64, pv: f64) -> Option<(usize, i32)> {
        let (u, v, a) = (self.u, self.v, self.a);
        let q = [
            [p[0][u] - pu, p[0][v] - pv],
            [p[1][u] - pu, p[1][v] - pv],
            [p[2][u] - pu, p[2][v] - pv],
        ];
        // w[i]: edge function of the edge opposite vertex i (= twice the barycentric area).
        let w = [cross(q[1], q[2]), cross(q[2], q[0]), cross(q[0], q[1])];
        let pos = w.iter().any(|&x| x > 0.0);
        let neg = w.iter().any(|&x| x < 0.0);
        if pos && neg {
            return None;
        }
        let orient = if w.iter().all(|&x| x != 0.0) {
            if pos {
                1
            } else {
                -1
            }
        } else {
            let s = [
                exact_sign(w[0], q[1], q[2]),
                exact_sign(w[1], q[2], q[0]),
                exact_sign(w[2], q[0], q[1]),
            ];
            if s[0] == 0 || s[0] != s[1] || s[0] != s[2] {
                return None;
            }
            s[0]
        };

        // Position of the crossing along the column. The weights all have the sign of
        // `orient` (or are zero), so this is a convex combination; written relative to the
        // first vertex so that a face perpendicular to the column lands exactly on its
        // coordinate.
        let z = [p[0][a], p[1][a], p[2][a]];
        let sum = w[0] + w[1] + w[2];
        let zmin = math::min(math::min(z[0], z[1]), z[2]);
        let zmax = math::max(math::max(z[0], z[1]), z[2]);
        let mut t = if sum != 0.0 {
            z[0] + (w[1] * (z[1] - z[0]) + w[2] * (z[2] - z[0])) / sum
        } else {
            z[0]
        };
        t = t.clamp(zmin, zmax);

        // Sign of the a-component of the face normal, from the exact projected orientation:
        // (u, v, a) is a right-handed frame for a = x and z, left-handed for a = y.
        let normal_a = if a == 1 { -orient } else { orient };
        let f = floor_i(t);
        let first = if f as f64 != t {
            f + 1
        } else if self.tie_crossing_precedes(p, normal_a) {
            f
        } else {
            f + 1
        };
        let k0 = first.clamp(0, self.dims[a] as i64) as usize;
        Some((k0, -normal_a))
    }

    /// The crossing is exactly at a cell centre along the column: does it come before the
    /// displaced centre `c + (dx, dy, dz)`? At the displaced column the crossing moves by
    /// `g_u d_u + g_v d_v` (g = the plane's slopes), the centre by `d_a`; the largest
    /// displacement with a nonzero coefficient decides.
    #[cold]
    fn tie_crossing_precedes(&self, p: &[[f64; 3]; 3], normal_a: i32) -> bool {
        let e1 = DVec3::from_array(p[1]) - DVec3::from_array(p[0]);
        let e2 = DVec3::from_array(p[2]) - DVec3::from_array(p[0]);
        let n = e1.cross(e2).to_array();
        for (axis, &n_axis) in n.iter().enumerate() {
            if axis == self.a {
                return true;
            }
            // slope g = -n_axis / n_a; the crossing comes first when g < 0.
            if n_axis != 0.0 {
                return (n_axis > 0.0) == (normal_a > 0);
            }
        }
        true
    }

    /// Turn the difference array into windings by a prefix sum along the column axis.
    fn prefix_sum(&self, w: &mut [i32]) {
        let sa = self.stride[self.a];
        let layers = self.ext[self.a];
        let run = |b: &mut [i32]| {
            if sa == 1 {
                for t in 1..layers {
                    b[t] = b[t].wrapping_add(b[t - 1]);
                }
            } else {
                for t in 1..layers {
                    let (prev, cur) = b[(t - 1) * sa..(t + 1) * sa].split_at_mut(sa);
                    for (c, p) in cur.iter_mut().zip(prev.iter()) {
                        *c = c.wrapping_add(*p);
                    }
                }
            }
        };
        // Blocks of whole columns: rows for x, slabs for y, the whole array for z.
        let block = sa * layers;
        #[cfg(feature = "parallel")]
        w.par_chunks_mut(block).with_min_len(16).for_each(run);
        #[cfg(not(feature = "parallel"))]
        w.chunks_mut(block).for_each(run);
    }

    /// Whether every column's winding returns to 0 at the far end.
    fn all_columns_close(&self, w: &[i32]) -> bool {
        let sa = self.stride[self.a];
        let last = self.ext[self.a] - 1;
        w.chunks(sa * self.ext[self.a])
            .all(|b| b[last * sa..].iter().all(|&x| x == 0))
    }

    /// Add this pass's two estimates per cell (counted from the near end and from the far
    /// end) to `votes`.
    fn add_votes(&self, w: &[i32], votes: &mut [u8]) {
        let [nx, ny, _] = self.dims;
        let s = self.stride;
        let (a, na) = (self.a, self.dims[self.a]);
        let slab = |(k, out): (usize, &mut [u8])| {
            for j in 0..ny {
                for i in 0..nx {
                    let c = [i, j, k];
                    let e = i * s[0] + j * s[1] + k * s[2];
                    let total = w[e + (na - c[a]) * s[a]];
                    let near = w[e];
                    // From the far end the winding is near - total.
                    out[i + nx * j] += u8::from(near != 0) + u8::from(near != total);
                }
            }
        };
        #[cfg(feature = "parallel")]
        votes.par_chunks_mut(nx * ny).enumerate().for_each(slab);
        #[cfg(not(feature = "parallel"))]
        votes.chunks_mut(nx * ny).enumerate().for_each(slab);
    }
}

// `f64::floor` and `ceil` are library calls on baseline x86-64; these are exact for
// |x| < 2^63, which the coordinate clamp guarantees.
#[inline]
fn floor_i(x: f64) -> i64 {
    let t = x as i64;
    t - i64::from(t as f64 > x)
}

#[inline]
fn ceil_i(x: f64) -> i64 {
    let t = x as i64;
    t + i64::from((t as f64) < x)
}

#[inline]
fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Sign of `cross(a, b)` (whose rounded value is `w`) for the column displaced by
/// `(+e, +e^2)`. Antisymmetric in `(a, b)`, bit for bit, which is what makes shared edges
/// watertight.
#[inline]
fn exact_sign(w: f64, a: [f64; 2], b: [f64; 2]) -> i32 {
    if w > 0.0 {
        return 1;
    }
    if w < 0.0 {
        return -1;
    }
    // Rounded products equal: the exact difference is the difference of rounding errors.
    let p1 = a[0] * b[1];
    let p2 = a[1] * b[0];
    let e1 = a[0].mul_add(b[1], -p1);
    let e2 = a[1].mul_add(b[0], -p2);
    if e1 > e2 {
        return 1;
    }
    if e1 < e2 {
        return -1;
    }
    // Exactly on the line through a and b: cross(a - d, b - d) with d = (e, e^2) is
    // -e (b - a)_v + e^2 (b - a)_u.
    let (du, dv) = (b[0] - a[0], b[1] - a[1]);
    if dv != 0.0 {
        if dv > 0.0 {
            -1
        } else {
            1
        }
    } else if du > 0.0 {
        1
    } else if du < 0.0 {
        -1
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::edges_balance;
    use glam::DQuat;

    /// A triangle soup under construction; `finish` welds equal positions.
    #[derive(Clone, Default)]
    struct Soup {
        verts: Vec<DVec3>,
        tris: Vec<[u32; 3]>,
    }

    impl Soup {
        fn tri(&mut self, a: DVec3, b: DVec3, c: DVec3) {
            let n = self.verts.len() as u32;
            self.verts.extend([a, b, c]);
            self.tris.push([n, n + 1, n + 2]);
        }
        fn add(mut self, other: &Soup) -> Soup {
            let n = self.verts.len() as u32;
            self.verts.extend(&other.verts);
            self.tris
                .extend(other.tris.iter().map(|t| t.map(|i| i + n)));
            self
        }
        fn flipped(mut self) -> Soup {
            for t in &mut self.tris {
                t.swap(1, 2);
            }
            self
        }
        fn mapped(mut self, f: impl Fn(DVec3) -> DVec3) -> Soup {
            for v in &mut self.verts {
                *v = f(*v);
            }
            self
        }
        /// Indexed mesh with equal positions merged (so the topology is visible by index).
        fn welded(&self) -> Mesh {
            let (verts, remap) = crate::mesh::weld(&self.verts);
            let tris = self
                .tris
                .iter()
                .map(|t| t.map(|i| remap[i as usize]))
                .collect();
            Mesh::new(verts, tris).unwrap()
        }
        /// The unwelded soup as a mesh (every triangle has its own vertices).
        fn soup(&self) -> Mesh {
            Mesh::new(self.verts.clone(), self.tris.clone()).unwrap()
        }
    }

    /// Outward box `[lo, hi]`, each face split into `n x n` quads.
    fn cube(lo: DVec3, hi: DVec3, n: usize) -> Soup {
        let mut s = Soup::default();
        for axis in 0..3 {
            for side in [0.0, 1.0] {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let at = |a: usize, b: usize| {
                    let mut t = [0.0; 3];
                    t[axis] = side;
                    t[u] = a as f64 / n as f64;
                    t[v] = b as f64 / n as f64;
                    lo + (hi - lo) * DVec3::from_array(t)
                };
                for a in 0..n {
                    for b in 0..n {
                        let (p00, p10, p01, p11) =
                            (at(a, b), at(a + 1, b), at(a, b + 1), at(a + 1, b + 1));
                        // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
                        if side == 1.0 {
                            s.tri(p00, p10, p11);
                            s.tri(p00, p11, p01);
                        } else {
                            s.tri(p00, p11, p10);
                            s.tri(p00, p01, p11);
                        }
                    }
                }
            }
        }
        s
    }

    fn icosphere(subdiv: usize, r: f64, c: DVec3) -> Soup {
        let (v, tris) = bvseg_testkit::geometry::icosphere(subdiv, r, c.to_array());
        Soup {
            verts: v.into_iter().map(DVec3::from_array).collect(),
            tris,
        }
    }

    /// UV sphere with its poles on the z axis through `c` (fans of triangles meet there).
    fn uv_sphere(r: f64, c: DVec3, nu: usize, nv: usize) -> Soup {
        let mut s = Soup::default();
        let p = |i: usize, j: usize| {
            let th = std::f64::consts::PI * j as f64 / nv as f64;
            let ph = std::f64::consts::TAU * (i % nu) as f64 / nu as f64;
            if j == 0 {
                return c + DVec3::new(0.0, 0.0, r);
            }
            if j == nv {
                return c - DVec3::new(0.0, 0.0, r);
            }
            c + r * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())
        };
        for j in 0..nv {
            for i in 0..nu {
                if j > 0 {
                    s.tri(p(i, j), p(i, j + 1), p(i + 1, j));
                }
                if j + 1 < nv {
                    s.tri(p(i + 1, j), p(i, j + 1), p(i + 1, j + 1));
                }
            }
        }
        s
    }

    fn torus(big: f64, small: f64, nu: usize, nv: usize) -> Soup {
        let mut s = Soup::default();
        let p = |i: usize, j: usize| {
            let a = std::f64::consts::TAU * (i % nu) as f64 / nu as f64;
            let b = std::f64::consts::TAU * (j % nv) as f64 / nv as f64;
            let rr = big + small * b.cos();
            DVec3::new(rr * a.cos(), rr * a.sin(), small * b.sin())
        };
        for i in 0..nu {
            for j in 0..nv {
                s.tri(p(i, j), p(i + 1, j), p(i + 1, j + 1));
                s.tri(p(i, j), p(i + 1, j + 1), p(i, j + 1));
            }
        }
        s
    }

    /// A lattice of cell size `h` with a margin of about one cell around the mesh.
    fn lattice(mesh: &Mesh, h: f64) -> (DVec3, [usize; 3]) {
        let (lo, hi) = mesh.bbox();
        let n = ((hi - lo) / h).ceil() + 3.0;
        (lo - 1.3 * h, [n.x as usize, n.y as usize, n.z as usize])
    }

    fn count(mask: &[bool]) -> usize {
        mask.iter().filter(|&&b| b).count()
    }

    /// Cells whose lattice coordinates lie in one of the half-open boxes `[lo, hi)`.
    fn boxes_mask(dims: [usize; 3], boxes: &[([usize; 3], [usize; 3])]) -> Vec<bool> {
        let mut m = vec![false; dims[0] * dims[1] * dims[2]];
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let c = [i, j, k];
                    m[i + dims[0] * (j + dims[1] * k)] = boxes
                        .iter()
                        .any(|(lo, hi)| (0..3).all(|d| lo[d] <= c[d] && c[d] < hi[d]));
                }
            }
        }
        m
    }

    /// The two estimates (from the near and the far end) of the pass along `axis`, and
    /// whether all its columns close.
    fn pass_estimates(
        mesh: &Mesh,
        origin: DVec3,
        h: f64,
        dims: [usize; 3],
        axis: usize,
    ) -> (Vec<bool>, Vec<bool>, bool) {
        let pts = lattice_coords(mesh, origin, h);
        let pass = Pass::new(axis, dims);
        let w = pass.windings(&pts, &weighted_triangles(mesh.triangles()));
        let (mut near, mut far) = (Vec::new(), Vec::new());
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let c = [i, j, k];
                    let s = pass.stride;
                    let e = i * s[0] + j * s[1] + k * s[2];
                    let total = w[e + (dims[axis] - c[axis]) * s[axis]];
                    near.push(w[e] != 0);
                    far.push(w[e] != total);
                }
            }
        }
        (near, far, pass.all_columns_close(&w))
    }

    /// Every pass, counted from either end, gives `expected` exactly.
    fn assert_all_passes(mesh: &Mesh, origin: DVec3, h: f64, dims: [usize; 3], expected: &[bool]) {
        for axis in 0..3 {
            let (near, far, closed) = pass_estimates(mesh, origin, h, dims, axis);
            assert!(closed, "axis {axis}: a column does not close");
            assert!(near == expected, "axis {axis}: near-end estimate differs");
            assert!(far == expected, "axis {axis}: far-end estimate differs");
        }
    }

    #[test]
    fn aligned_cube_ties_on_faces_edges_and_vertices() {
        // Faces, edges, face diagonals and (for n > 1) interior vertices all lie exactly on
        // lattice columns and cell centres.
        let dims = [10, 11, 12];
        let expected = boxes_mask(dims, &[([2, 3, 1], [7, 8, 11])]);
        for n in [1, 5] {
            let s = cube(DVec3::new(2.0, 3.0, 1.0), DVec3::new(7.0, 8.0, 11.0), n);
            // The unwelded soup is closed only once equal positions are merged.
            assert!(!edges_balance(s.soup().triangles(), s.verts.len(), |i| i));
            assert!(s.soup().is_closed());
            for mesh in [s.welded(), s.soup(), s.clone().flipped().welded()] {
                let got = inside_cells(&mesh, DVec3::ZERO, 1.0, dims).unwrap();
                assert_eq!(count(&got), 5 * 5 * 10);
                assert!(got == expected);
                assert_all_passes(&mesh, DVec3::ZERO, 1.0, dims, &expected);
            }
        }
        // Same with a non-unit cell size and origin: lattice coordinates stay exact.
        let s = cube(DVec3::splat(0.5), DVec3::new(1.75, 1.5, 1.25), 4);
        let origin = DVec3::splat(-0.25);
        let dims = [10, 9, 8];
        let expected = boxes_mask(dims, &[([3, 3, 3], [8, 7, 6])]);
        let mesh = s.welded();
        assert!(inside_cells(&mesh, origin, 0.25, dims).unwrap() == expected);
        assert_all_passes(&mesh, origin, 0.25, dims, &expected);
    }

    #[test]
    fn octahedron_ties_on_inclined_faces_agree_across_axes() {
        // Faces |x| + |y| + |z| = 4 pass through many cell centres, where the crossing lands
        // exactly on a centre and the tie is broken by the slope of the face. The displaced
        // centre c + (dx, dy, dz) is inside exactly when |x| + |y| + |z| < 4, or = 4 with
        // x < 0 (the largest displacement dx then decreases the sum).
        let c = DVec3::splat(6.0);
        let mut s = Soup::default();
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                for sz in [-1.0, 1.0] {
                    let (a, b, d) = (
                        c + DVec3::new(4.0 * sx, 0.0, 0.0),
                        c + DVec3::new(0.0, 4.0 * sy, 0.0),
                        c + DVec3::new(0.0, 0.0, 4.0 * sz),
                    );
                    if sx * sy * sz > 0.0 {
                        s.tri(a, b, d);
                    } else {
                        s.tri(a, d, b);
                    }
                }
            }
        }
        let mesh = s.welded();
        assert!(mesh.signed_volume() > 0.0);
        let dims = [13, 13, 13];
        let mut expected = Vec::new();
        for k in 0..13 {
            for j in 0..13 {
                for i in 0..13 {
                    let (x, y, z) = (i as i64 - 6, j as i64 - 6, k as i64 - 6);
                    let l1 = x.abs() + y.abs() + z.abs();
                    expected.push(l1 < 4 || (l1 == 4 && x < 0));
                }
            }
        }
        assert!(inside_cells(&mesh, DVec3::ZERO, 1.0, dims).unwrap() == expected);
        assert_all_passes(&mesh, DVec3::ZERO, 1.0, dims, &expected);
    }

    #[test]
    fn rotated_cube_matches_volume() {
        let q = DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let mesh = cube(DVec3::splat(-0.5), DVec3::splat(0.5), 2)
            .mapped(|p| q * p + DVec3::new(0.01, 0.02, 0.03))
            .welded();
        let h = 1.0 / 30.0;
        let (origin, dims) = lattice(&mesh, h);
        let n = count(&inside_cells(&mesh, origin, h, dims).unwrap()) as f64;
        let expected = 1.0 / (h * h * h);
        assert!((n / expected - 1.0).abs() < 0.01, "{n} vs {expected}");
    }

    #[test]
    fn spheres_match_volume_and_orientation_does_not_matter() {
        let h = 0.04;
        let c = DVec3::ZERO;
        for s in [icosphere(3, 1.0, c), uv_sphere(1.0, c, 40, 20)] {
            let mesh = s.welded();
            // Centre the lattice on the sphere so that the poles sit on a column.
            let dims = [55, 55, 55];
            let origin = c - 27.0 * h * DVec3::ONE;
            let got = inside_cells(&mesh, origin, h, dims).unwrap();
            let expected = mesh.signed_volume() / (h * h * h);
            let n = count(&got) as f64;
            assert!((n / expected - 1.0).abs() < 0.01, "{n} vs {expected}");
            assert!(got[27 + 55 * (27 + 55 * 27)]);
            assert_all_passes(&mesh, origin, h, dims, &got);
            let flipped = s.clone().flipped().welded();
            assert!(mesh.signed_volume() < 0.0 || flipped.signed_volume() < 0.0);
            assert!(inside_cells(&flipped, origin, h, dims).unwrap() == got);
        }
    }

    #[test]
    fn several_components_nested_duplicated_and_overlapping_shells() {
        let dims = [12, 12, 12];
        let o = DVec3::ZERO;
        let b = |lo: f64, hi: f64| cube(DVec3::splat(lo), DVec3::splat(hi), 1);
        let box_ = |lo: usize, hi: usize| ([lo; 3], [hi; 3]);
        let check = |s: Soup, boxes: &[([usize; 3], [usize; 3])]| {
            let mesh = s.welded();
            let expected = boxes_mask(dims, boxes);
            assert!(inside_cells(&mesh, o, 1.0, dims).unwrap() == expected);
            assert_all_passes(&mesh, o, 1.0, dims, &expected);
        };
        // Two disjoint cubes.
        check(b(1.0, 4.0).add(&b(6.0, 10.0)), &[box_(1, 4), box_(6, 10)]);
        // Duplicated shell (winding 2) is the same as once.
        check(b(2.0, 9.0).add(&b(2.0, 9.0)), &[box_(2, 9)]);
        // Overlapping cubes (self-intersecting surface): the union.
        check(b(1.0, 6.0).add(&b(4.0, 10.0)), &[box_(1, 6), box_(4, 10)]);
        // Nested shell with opposite orientation: a cavity (winding 0 inside it).
        let hollow = b(1.0, 10.0).add(&b(4.0, 7.0).flipped());
        let mesh = hollow.welded();
        let got = inside_cells(&mesh, o, 1.0, dims).unwrap();
        assert_eq!(count(&got), 9 * 9 * 9 - 3 * 3 * 3);
        let cavity = boxes_mask(dims, &[box_(4, 7)]);
        let outer = boxes_mask(dims, &[box_(1, 10)]);
        for c in 0..got.len() {
            assert_eq!(got[c], outer[c] && !cavity[c]);
        }
        // Nested shell with the same orientation: the nonzero rule keeps it solid (winding 2).
        check(b(1.0, 10.0).add(&b(4.0, 7.0)), &[box_(1, 10)]);
        // Inverted outer shell with an inner shell facing out: still a cavity.
        let mesh = b(1.0, 10.0).flipped().add(&b(4.0, 7.0)).welded();
        assert!(inside_cells(&mesh, o, 1.0, dims).unwrap() == got);
    }

    #[test]
    fn holes_and_flipped_triangles_degrade_gracefully() {
        let h = 0.04;
        let s = icosphere(3, 1.0, DVec3::new(0.013, -0.007, 0.021));
        let closed = s.welded();
        let (origin, dims) = lattice(&closed, h);
        let reference = inside_cells(&closed, origin, h, dims).unwrap();
        let n_ref = count(&reference) as f64;

        // A few scattered triangles removed.
        let mut holed = s.clone();
        for t in [700, 300, 100, 1000, 5] {
            holed.tris.remove(t);
        }
        let holed = holed.welded();
        assert!(!holed.is_closed());
        let got = inside_cells(&holed, origin, h, dims).unwrap();
        let diff = got.iter().zip(&reference).filter(|(a, b)| a != b).count() as f64;
        assert!(diff / n_ref < 0.01, "{diff} cells differ out of {n_ref}");

        // A few triangles flipped (inconsistent orientation).
        let mut flipped = s.clone();
        for t in [3, 400, 900] {
            flipped.tris[t].swap(0, 1);
        }
        let flipped = flipped.welded();
        assert!(!flipped.is_closed());
        let got = inside_cells(&flipped, origin, h, dims).unwrap();
        let diff = got.iter().zip(&reference).filter(|(a, b)| a != b).count() as f64;
        assert!(diff / n_ref < 0.01, "{diff} cells differ out of {n_ref}");
    }

    #[test]
    fn tube_open_at_both_ends_is_filled_by_the_side_views() {
        // The z rays see nothing (all walls vertical), the x and y rays see a closed
        // square: two of three axes vote inside.
        let mut s = cube(DVec3::splat(2.0), DVec3::splat(7.0), 1);
        s.tris.retain(|t| {
            let z = t.map(|i| s.verts[i as usize].z);
            !(z[0] == z[1] && z[1] == z[2])
        });
        let mesh = s.welded();
        let dims = [10, 10, 10];
        let got = inside_cells(&mesh, DVec3::ZERO, 1.0, dims).unwrap();
        assert!(got == boxes_mask(dims, &[([2; 3], [7; 3])]));
    }

    #[test]
    fn torus_hole_is_empty() {
        let (big, small) = (1.0, 0.35);
        let mesh = torus(big, small, 64, 32).welded();
        let h = 0.03;
        let (origin, dims) = lattice(&mesh, h);
        let got = inside_cells(&mesh, origin, h, dims).unwrap();
        let expected = mesh.signed_volume() / (h * h * h);
        let n = count(&got) as f64;
        assert!((n / expected - 1.0).abs() < 0.015, "{n} vs {expected}");
        let mut in_hole = 0;
        let mut in_ring = 0;
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let p = origin + h * DVec3::new(i as f64, j as f64, k as f64);
                    let r = p.truncate().length();
                    let inside = got[i + dims[0] * (j + dims[1] * k)];
                    if r < big - small - 2.0 * h && inside {
                        in_hole += 1;
                    }
                    let tube = DVec3::new(r - big, p.z, 0.0).length();
                    if tube < small - 2.0 * h && !inside {
                        in_ring += 1;
                    }
                }
            }
        }
        assert_eq!((in_hole, in_ring), (0, 0));
    }

    #[test]
    fn rasterisation_matches_brute_force_over_all_columns() {
        // Irregular sphere: every triangle tested against every column must give the same
        // windings as the rasterised scan.
        let s = icosphere(2, 1.0, DVec3::ZERO)
            .mapped(|p| p * (1.0 + 0.15 * (7.0 * p.x).sin() * (5.0 * p.y + 1.0).cos()));
        let mesh = s.welded();
        let h = 0.09;
        let (origin, dims) = lattice(&mesh, h);
        let pts = lattice_coords(&mesh, origin, h);
        for axis in 0..3 {
            let pass = Pass::new(axis, dims);
            let fast = pass.windings(&pts, &weighted_triangles(mesh.triangles()));
            let mut slow = vec![0i32; pass.len()];
            for t in mesh.triangles() {
                let p = t.map(|i| pts[i as usize]);
                for iv in 0..dims[pass.v] {
                    for iu in 0..dims[pass.u] {
                        if let Some((k0, s)) = pass.crossing(&p, iu as f64, iv as f64) {
                            let e = iu * pass.stride[pass.u]
                                + iv * pass.stride[pass.v]
                                + k0 * pass.stride[axis];
                            slow[e] += s;
                        }
                    }
                }
            }
            pass.prefix_sum(&mut slow);
            assert!(fast == slow, "axis {axis}");
            assert!(pass.all_columns_close(&fast));
        }
    }

    #[test]
    fn odd_inputs_do_not_panic() {
        let tiny = cube(DVec3::splat(-1e-90), DVec3::splat(1e-90), 1).welded();
        let huge = cube(DVec3::splat(-1e100), DVec3::splat(1e100), 1).welded();
        let flat = Mesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).unwrap();
        let degenerate = Mesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y],
            vec![[0, 0, 0], [0, 1, 1], [1, 2, 1]],
        )
        .unwrap();
        for mesh in [&tiny, &huge, &flat, &degenerate] {
            for (origin, h) in [
                (DVec3::splat(-1.5), 0.5),
                (DVec3::splat(-1e100), 1e99),
                (DVec3::splat(-1e-90), 1e-91),
                (DVec3::ZERO, 1e-300),
                (DVec3::splat(1e300), 1e-300),
                (DVec3::ZERO, 0.0),
                (DVec3::ZERO, -1.0),
                (DVec3::ZERO, f64::NAN),
                (DVec3::splat(f64::INFINITY), 1.0),
            ] {
                for dims in [[8, 8, 8], [1, 1, 1], [0, 3, 3], [5, 1, 7]] {
                    let got = inside_cells(mesh, origin, h, dims).unwrap();
                    assert_eq!(got.len(), dims[0] * dims[1] * dims[2]);
                }
            }
        }
        // The scaled cubes still work at extreme scales (faces half a cell off the centres,
        // as rounding makes exact ties unlikely there).
        let got = inside_cells(&huge, DVec3::splat(-1.75e100), 0.5e100, [8, 8, 8]).unwrap();
        assert_eq!(count(&got), 4 * 4 * 4);
        let got = inside_cells(&tiny, DVec3::splat(-1.75e-90), 0.5e-90, [8, 8, 8]).unwrap();
        assert_eq!(count(&got), 4 * 4 * 4);
    }

    #[test]
    fn grid_from_mesh_uses_it() {
        let mesh = icosphere(4, 2.0, DVec3::new(5.0, -1.0, 3.0)).welded();
        let grid = crate::sampling::Grid::from_mesh(&mesh, 20_000).unwrap();
        let n = grid.len() as f64;
        assert!((n / 20_000.0 - 1.0).abs() < 0.3, "{n}");
        let expected = mesh.signed_volume() / grid.cell_volume();
        assert!((n / expected - 1.0).abs() < 0.02, "{n} vs {expected}");
        for p in &grid.points {
            assert!((*p - DVec3::new(5.0, -1.0, 3.0)).length() < 2.0);
        }
    }

    #[cfg(feature = "parallel")]
    #[test]
    fn same_result_for_any_thread_count() {
        let mut s = icosphere(4, 1.0, DVec3::ZERO);
        s.tris.truncate(s.tris.len() - 7); // open, so all three passes run
        let mesh = s.welded();
        let h = 0.03;
        let (origin, dims) = lattice(&mesh, h);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| inside_cells(&mesh, origin, h, dims).unwrap())
        };
        let one = run(1);
        assert!(run(2) == one);
        assert!(run(5) == one);
    }
}
