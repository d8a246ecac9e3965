//! How many volumes cover each outside cell: the union's outside volume, kept up to date as
//! volumes are swapped, so that a candidate move is judged without recounting the union.
use std::collections::HashMap;

use super::{Cell, Cells};
use crate::partition::Solid;

/// How many volumes cover each lattice cell outside the solid (of both lattices, see
/// [`crate::metrics`]), and how many such cells are covered at all.
#[derive(Debug, Clone)]
pub struct Coverage {
    lo: [i64; 3],
    n: [i64; 3],
    count: Vec<u16>,
    count_offset: Vec<u16>,
    extra: HashMap<Cell, u32>,
    /// Number of covered cells of both lattices (`LATTICES` times the union's outside volume
    /// in cells).
    pub union: usize,
}

impl Coverage {
    /// An empty coverage over the solid's lattices with a margin of a quarter of their size
    /// around them (cells beyond, where only volumes far larger than their parts reach, fall
    /// back to a hash map). Its arrays take 3.4 times as many cells as the lattice, against 8
    /// with half the size around them.
    pub fn new(solid: &Solid) -> Self {
        let d = solid.grid.dims;
        let m = [
            d[0] as i64 / 4 + 2,
            d[1] as i64 / 4 + 2,
            d[2] as i64 / 4 + 2,
        ];
        let lo = [-m[0], -m[1], -m[2]];
        let n = [
            d[0] as i64 + 2 * m[0],
            d[1] as i64 + 2 * m[1],
            d[2] as i64 + 2 * m[2],
        ];
        let len = (n[0] * n[1] * n[2]) as usize;
        Self {
            lo,
            n,
            count: vec![0; len],
            count_offset: vec![0; len],
            extra: HashMap::new(),
            union: 0,
        }
    }

    /// Index of cell `c` (tagged or not) in its lattice's dense array, if it is in range.
    #[inline]
    fn index(&self, c: &Cell) -> Option<(bool, usize)> {
        let offset = c.is_offset();
        let [x, y, z] = c.index();
        let r = [x - self.lo[0], y - self.lo[1], z - self.lo[2]];
        (0..3).all(|d| r[d] >= 0 && r[d] < self.n[d]).then(|| {
            (
                offset,
                // The third index fastest: a run of cells up a column is a slice.
                (r[2] + self.n[2] * (r[1] + self.n[1] * r[0])) as usize,
            )
        })
    }

    #[inline]
    fn slot(&mut self, c: &Cell) -> Option<&mut u16> {
        let (offset, i) = self.index(c)?;
        Some(if offset {
            &mut self.count_offset[i]
        } else {
            &mut self.count[i]
        })
    }

    /// Whether cell `c` is covered at least once.
    pub fn covered(&self, c: &Cell) -> bool {
        match self.index(c) {
            Some((true, i)) => self.count_offset[i] > 0,
            Some((false, i)) => self.count[i] > 0,
            None => self.extra.get(c).is_some_and(|&v| v > 0),
        }
    }

    /// Cover `cells` once more.
    pub fn add(&mut self, cells: &Cells) {
        self.count_each(cells, true);
    }

    /// The union after replacing the cells of `old` volumes by those of `new` ones; the
    /// coverage is left as it was.
    pub fn union_if(&mut self, old: [&Cells; 2], new: [&Cells; 2]) -> usize {
        self.replace(old, new);
        let union = self.union;
        self.replace(new, old);
        union
    }

    /// Replace the cells of `old` volumes by those of `new` ones.
    pub fn replace(&mut self, old: [&Cells; 2], new: [&Cells; 2]) {
        for c in old {
            self.remove(c);
        }
        for c in new {
            self.add(c);
        }
    }

    /// Undo one [`Coverage::add`] of `cells`.
    pub fn remove(&mut self, cells: &Cells) {
        self.count_each(cells, false);
    }

    /// Count each cell of `cells` once more (`add`) or once less, keeping
    /// [`Coverage::union`].
    fn count_each(&mut self, cells: &Cells, add: bool) {
        let mut moved = 0usize;
        for &(first, len) in cells.runs() {
            // A run whose first and last cells are in range lies in the dense array whole
            // (it goes up the third index).
            let dense = self
                .index(&first)
                .filter(|_| self.index(&first.up(len - 1)).is_some());
            if let Some((offset, i0)) = dense {
                let counts = if offset {
                    &mut self.count_offset
                } else {
                    &mut self.count
                };
                for v in &mut counts[i0..i0 + len as usize] {
                    moved += usize::from(count(v, add));
                }
            } else {
                for d in 0..len {
                    let c = first.up(d);
                    moved += usize::from(match self.slot(&c) {
                        Some(v) => count(v, add),
                        // A cell removed that was never added counts as added once.
                        None => count(self.extra.entry(c).or_insert(u32::from(!add)), add),
                    });
                }
            }
        }
        if add {
            self.union += moved;
        } else {
            self.union -= moved;
        }
    }
}

/// Count a cell once more (`add`) or once less; whether that moved it into or out of the
/// union.
#[inline]
fn count<T>(v: &mut T, add: bool) -> bool
where
    T: Copy + PartialEq + From<u8> + std::ops::AddAssign + std::ops::SubAssign,
{
    if add {
        *v += T::from(1);
        *v == T::from(1)
    } else {
        *v -= T::from(1);
        *v == T::from(0)
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use glam::DVec3;

    use super::*;
    use crate::sampling::Grid;

    #[test]
    fn runs_count_as_their_cells_in_and_beyond_the_dense_arrays() {
        let grid = Grid::from_inside_fn(DVec3::splat(-1.0), DVec3::splat(1.0), 0.2, |p| {
            p.length() < 1.0
        });
        let d = grid.dims.map(|x| x as i64);
        let solid = Solid::new(grid);
        // Runs inside the arrays, across their upper end, wholly beyond them, on both
        // lattices, overlapping one another.
        let lists: Vec<Cells> = (0..4i64)
            .map(|v| {
                let mut c = Cells::default();
                c.push_run(false, [v, 1], [0, d[2] + v]);
                c.push_run(true, [1, v], [d[2] - 2, 2 * d[2] + 3 * v]);
                c.push_run(false, [-d[0], v], [5 * d[2], 5 * d[2] + v]);
                c.push_run(v % 2 == 1, [2, 2], [-3, 3]);
                c
            })
            .collect();
        let mut cov = Coverage::new(&solid);
        let mut brute: BTreeMap<Cell, usize> = BTreeMap::new();
        let distinct = |b: &BTreeMap<Cell, usize>| b.values().filter(|&&n| n > 0).count();
        for c in &lists {
            cov.add(c);
            for x in c.iter() {
                *brute.entry(x).or_default() += 1;
            }
            assert_eq!(cov.union, distinct(&brute));
        }
        assert!(brute.keys().all(|x| cov.covered(x)));
        let before = cov.union;
        let none = Cells::default();
        let without = cov.union_if([&lists[0], &lists[3]], [&none, &none]);
        assert_eq!(cov.union, before, "union_if leaves the coverage as it was");
        for c in [&lists[0], &lists[3]] {
            cov.remove(c);
            for x in c.iter() {
                *brute.get_mut(&x).unwrap() -= 1;
            }
        }
        assert_eq!((cov.union, without), (distinct(&brute), distinct(&brute)));
        assert!(brute.iter().all(|(x, &n)| cov.covered(x) == (n > 0)));
    }
}
