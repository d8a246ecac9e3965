//! A cell of one of the two lattices the outside volume is counted on.
//!
//! The sampling lattice and the one offset from it by half a cell share one list per volume,
//! so a cell carries its lattice in its coordinates: an offset cell has [`OFFSET_TAG`] added
//! to its first one (far beyond any real index). The encoding stays in this file.

/// Added to the first coordinate of a cell of the offset lattice.
const OFFSET_TAG: i32 = 1 << 29;
/// Largest magnitude of a first coordinate: beyond it, both lattices would meet.
const FIRST_MAX: i64 = (1 << 28) - 1;

/// A cell of the sampling lattice or of the offset lattice (see [`crate::metrics`]). Ordered
/// and hashed by its encoded coordinates.
///
/// Twelve bytes, as the fit cache keeps lists of many of them. Lattices stay far below the
/// coordinate range (the sampling keeps them under `64 n + 10^6` cells); a coordinate beyond
/// it, which only an absurdly large volume could reach, is clamped to its end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell([i32; 3]);

/// `c` clamped into the encoding's range.
#[inline]
fn narrow([i, j, k]: [i64; 3]) -> [i32; 3] {
    let wide = |x: i64| x.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
    [i.clamp(-FIRST_MAX, FIRST_MAX) as i32, wide(j), wide(k)]
}

impl Cell {
    /// Cell `c` of the sampling lattice.
    #[inline]
    pub fn sampling(c: [i64; 3]) -> Self {
        Cell(narrow(c))
    }

    /// Cell `c` of the offset lattice (centres at `origin + h (c + 1/2)`).
    #[inline]
    pub fn offset(c: [i64; 3]) -> Self {
        let [i, j, k] = narrow(c);
        Cell([i + OFFSET_TAG, j, k])
    }

    /// Cell `c` of the offset lattice if `offset`, else of the sampling one.
    #[inline]
    pub fn of(offset: bool, c: [i64; 3]) -> Self {
        if offset {
            Self::offset(c)
        } else {
            Self::sampling(c)
        }
    }

    /// Whether the cell belongs to the offset lattice.
    #[inline]
    pub fn is_offset(&self) -> bool {
        self.0[0] >= OFFSET_TAG / 2
    }

    /// The cell `d` above this one in its column (within the encoding's range).
    #[inline]
    pub fn up(self, d: u32) -> Self {
        let [i, j, k] = self.0;
        Cell([i, j, k.saturating_add_unsigned(d)])
    }

    /// The cell's indices in its own lattice.
    #[inline]
    pub fn index(&self) -> [i64; 3] {
        let [i, j, k] = self.0.map(i64::from);
        if self.is_offset() {
            [i - i64::from(OFFSET_TAG), j, k]
        } else {
            [i, j, k]
        }
    }
}

/// Cells of one lattice, as consecutive runs along its columns (the third index): a volume's
/// outside cells, which fill a few intervals of each column it meets. Twelve bytes per run
/// plus four for its length, instead of twelve per cell: at a million samples, the lists the
/// fit cache keeps were half the run's memory as cells.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Cells {
    runs: Vec<(Cell, u32)>,
    len: usize,
}

impl Cells {
    /// Add the cells `(i, j, a..=b)` of the sampling lattice (`offset` false) or the offset
    /// one (nothing when `b < a`).
    pub fn push_run(&mut self, offset: bool, [i, j]: [i64; 2], [a, b]: [i64; 2]) {
        let mut a = a;
        while a <= b {
            // Runs longer than a u32 only for absurd volumes: split them.
            let n = (b - a + 1).min(i64::from(u32::MAX));
            self.runs.push((Cell::of(offset, [i, j, a]), n as u32));
            self.len += n as usize;
            a += n;
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The runs: a first cell and the number of cells from it up its column.
    pub fn runs(&self) -> &[(Cell, u32)] {
        &self.runs
    }

    /// The cells, run by run.
    pub fn iter(&self) -> impl Iterator<Item = Cell> + '_ {
        self.runs
            .iter()
            .flat_map(|&(c, n)| (0..n).map(move |d| c.up(d)))
    }

    /// Free the room the list grew into beyond its runs.
    pub fn shrink_to_fit(&mut self) {
        self.runs.shrink_to_fit();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattices_stay_apart_and_indices_round_trip() {
        for c in [
            [0, 0, 0],
            [-5, 7, 1 << 20],
            [(1 << 28) - 1, -3, 2],
            [1 - (1 << 28), 4, -9],
        ] {
            let (s, o) = (Cell::sampling(c), Cell::offset(c));
            assert!(!s.is_offset() && o.is_offset());
            assert_eq!((s.index(), o.index()), (c, c));
            assert_ne!(s, o);
        }
        // Negative offset indices (cells beyond the lattice's low corner) stay offset, and
        // coordinates out of range are clamped, not wrapped.
        assert!(Cell::offset([-1000, 0, 0]).is_offset());
        assert!(Cell::offset([-(1 << 40), 0, 0]).is_offset());
        assert!(!Cell::sampling([1 << 40, 0, 0]).is_offset());
        assert_eq!(
            Cell::sampling([0, 1 << 40, 0]).index()[1],
            i64::from(i32::MAX)
        );
    }
}
