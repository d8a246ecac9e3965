//! A count of the work done, for the tests that check that costs grow linearly with the
//! input: a counter, unlike a timing, is exact and repeatable whatever else the machine
//! does. Each stage whose cost depends on the input adds what it processed (lattice columns
//! scanned, points fitted, cells counted, vertices welded and triangles checked). Not part
//! of the API.
use std::sync::atomic::{AtomicU64, Ordering};

static UNITS: AtomicU64 = AtomicU64::new(0);

/// Counts `n` more units of work.
#[inline]
pub fn add(n: usize) {
    UNITS.fetch_add(n as u64, Ordering::Relaxed);
}

/// The units counted in this process so far.
pub fn total() -> u64 {
    UNITS.load(Ordering::Relaxed)
}
