//! How many volumes cover each outside cell: the union's outside volume, kept up to date as
//! volumes are swapped, so that a candidate move is judged without recounting the union.
use std::collections::HashMap;

use super::Cell;
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
    /// back to a hash map). Its arrays take 3.4 times as many cells as the lattice; with
    /// half the size around them it was 8 (132 MB at a million samples of the bunny).
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
                (r[0] + self.n[0] * (r[1] + self.n[1] * r[2])) as usize,
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
    pub fn add(&mut self, cells: &[Cell]) {
        for c in cells {
            let was = match self.slot(c) {
                Some(v) => {
                    *v += 1;
                    *v - 1
                }
                None => {
                    let v = self.extra.entry(*c).or_insert(0);
                    *v += 1;
                    (*v - 1) as u16
                }
            };
            if was == 0 {
                self.union += 1;
            }
        }
    }

    /// The union after replacing the cells of `old` volumes by those of `new` ones; the
    /// coverage is left as it was.
    pub fn union_if(&mut self, old: [&[Cell]; 2], new: [&[Cell]; 2]) -> usize {
        self.replace(old, new);
        let union = self.union;
        self.replace(new, old);
        union
    }

    /// Replace the cells of `old` volumes by those of `new` ones.
    pub fn replace(&mut self, old: [&[Cell]; 2], new: [&[Cell]; 2]) {
        for c in old {
            self.remove(c);
        }
        for c in new {
            self.add(c);
        }
    }

    /// Undo one [`Coverage::add`] of `cells`.
    pub fn remove(&mut self, cells: &[Cell]) {
        for c in cells {
            let now = match self.slot(c) {
                Some(v) => {
                    *v -= 1;
                    *v
                }
                None => {
                    let v = self.extra.entry(*c).or_insert(1);
                    *v -= 1;
                    *v as u16
                }
            };
            if now == 0 {
                self.union -= 1;
            }
        }
    }
}
