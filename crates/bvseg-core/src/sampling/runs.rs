//! The inside cells of one lattice as runs along its columns.
//!
//! Choosing a part's kind counts each candidate volume's outside cells, and a volume covers
//! many cells per column but meets each column in one interval. With the inside cells of a
//! column stored as a few runs, the count of a column is its interval's length minus the
//! runs' overlap with it: the cost follows the columns, not the cells (a thousand-fold less
//! for the hierarchy's large volumes at a million samples).

/// The inside cells of a lattice of dimensions `[nx, ny, nz]`, per column `(i, j)` a sorted
/// list of disjoint runs `k0..=k1`.
#[derive(Debug, Clone, Default)]
pub struct InsideRuns {
    nx: usize,
    ny: usize,
    /// Runs of column `c = i + nx j` are `runs[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    runs: Vec<[u32; 2]>,
}

impl InsideRuns {
    /// The runs of a lattice of `dims` whose cell `i + nx (j + ny k)` is inside iff
    /// `inside(that index)`.
    pub fn new(dims: [usize; 3], inside: impl Fn(usize) -> bool) -> Self {
        let [nx, ny, nz] = dims;
        let mut start = Vec::with_capacity(nx * ny + 1);
        let mut runs = Vec::new();
        let stride = nx * ny;
        for c in 0..stride {
            start.push(runs.len() as u32);
            let mut open: Option<u32> = None;
            for k in 0..nz {
                match (inside(c + stride * k), open) {
                    (true, None) => open = Some(k as u32),
                    (false, Some(k0)) => {
                        runs.push([k0, k as u32 - 1]);
                        open = None;
                    }
                    _ => {}
                }
            }
            if let Some(k0) = open {
                runs.push([k0, nz as u32 - 1]);
            }
        }
        start.push(runs.len() as u32);
        Self {
            nx,
            ny,
            start,
            runs,
        }
    }

    /// Number of inside cells `(i, j, k)` with `k0 <= k <= k1` (none beyond the lattice).
    #[inline]
    pub fn count(&self, [i, j]: [i64; 2], [k0, k1]: [i64; 2]) -> usize {
        if i < 0 || j < 0 || i >= self.nx as i64 || j >= self.ny as i64 || k1 < k0 {
            return 0;
        }
        let c = i as usize + self.nx * j as usize;
        let runs = &self.runs[self.start[c] as usize..self.start[c + 1] as usize];
        let mut n = 0;
        for &[a, b] in runs {
            let (a, b) = (i64::from(a), i64::from(b));
            if a > k1 {
                break;
            }
            let (lo, hi) = (a.max(k0), b.min(k1));
            if lo <= hi {
                n += (hi - lo + 1) as usize;
            }
        }
        n
    }

    /// Call `f(a, b)` for each maximal range `a..=b` of `k0..=k1`, in order, whose cells
    /// `(i, j, k)` are not inside (every cell beyond the lattice is outside): the gaps between
    /// the column's runs, so the cost follows the gaps, not the cells.
    #[inline]
    pub fn for_each_gap(&self, [i, j]: [i64; 2], [k0, k1]: [i64; 2], mut f: impl FnMut(i64, i64)) {
        if k1 < k0 {
            return;
        }
        if i < 0 || j < 0 || i >= self.nx as i64 || j >= self.ny as i64 {
            f(k0, k1);
            return;
        }
        let c = i as usize + self.nx * j as usize;
        let mut next = k0;
        for &[a, b] in &self.runs[self.start[c] as usize..self.start[c + 1] as usize] {
            let (a, b) = (i64::from(a), i64::from(b));
            if a > k1 {
                break;
            }
            if next < a {
                f(next, a - 1);
            }
            next = next.max(b + 1);
        }
        if next <= k1 {
            f(next, k1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_gaps_match_a_cell_by_cell_walk() {
        let dims = [5, 4, 23];
        // A pattern with runs at both ends of columns, single cells and empty columns.
        let inside = |c: usize| {
            let (col, k) = (c % 20, c / 20);
            col % 7 != 3 && ((k * 7 + col * 3) % 11 < 5 || k == 0 || k == 22)
        };
        let runs = InsideRuns::new(dims, inside);
        for j in -1..5i64 {
            for i in -1..6i64 {
                for k0 in -3..26i64 {
                    for k1 in k0 - 1..27 {
                        let walk = (k0..=k1)
                            .filter(|&k| {
                                (0..5).contains(&i)
                                    && (0..4).contains(&j)
                                    && (0..23).contains(&k)
                                    && inside((i + 5 * (j + 4 * k)) as usize)
                            })
                            .count();
                        assert_eq!(runs.count([i, j], [k0, k1]), walk, "{i} {j} {k0} {k1}");
                        let mut gaps = Vec::new();
                        let mut last = i64::MIN;
                        runs.for_each_gap([i, j], [k0, k1], |a, b| {
                            // Maximal, ordered, non-empty ranges.
                            assert!(a <= b && a > last.saturating_add(1), "{a} {b} {last}");
                            last = b;
                            gaps.extend(a..=b);
                        });
                        let outside: Vec<i64> = (k0..=k1)
                            .filter(|&k| {
                                !((0..5).contains(&i)
                                    && (0..4).contains(&j)
                                    && (0..23).contains(&k)
                                    && inside((i + 5 * (j + 4 * k)) as usize))
                            })
                            .collect();
                        assert_eq!(gaps, outside, "{i} {j} {k0} {k1}");
                    }
                }
            }
        }
    }
}
