//! A count of the work done, for the tests that check that costs grow linearly with the
//! input: a counter, unlike a timing, is exact and repeatable whatever else the machine
//! does. Each stage whose cost depends on the input adds what it processed (lattice columns
//! scanned, points fitted, cells counted, vertices welded and triangles checked). Not part
//! of the API.
//!
//! The count is per thread, so that work done by other threads (another test of the same
//! binary, say) never adds to it. To count a whole run, run it on one thread: with the
//! `parallel` feature, in a one-thread rayon pool that uses the calling thread
//! (`ThreadPoolBuilder::new().num_threads(1).use_current_thread()`).
use std::cell::Cell;

thread_local! {
    static UNITS: Cell<u64> = const { Cell::new(0) };
}

/// Counts `n` more units of work on this thread.
#[inline]
pub fn add(n: usize) {
    UNITS.with(|u| u.set(u.get() + n as u64));
}

/// The units counted on this thread so far.
pub fn total() -> u64 {
    UNITS.with(Cell::get)
}
