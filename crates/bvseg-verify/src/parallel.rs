//! A parallel map on scoped std threads (no thread pool, no dependency), whose output is in
//! input order whatever the thread count: every item is computed on its own, and the
//! results are put back in place before anything is combined.
use std::sync::atomic::{AtomicUsize, Ordering};

/// The thread count for `requested` (`None`: the available parallelism, one where that is
/// unknown, as on wasm32).
pub(crate) fn threads(requested: Option<usize>) -> usize {
    requested
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .max(1)
}

/// `(0..n).map(f).collect()`, on up to `threads` threads taking `block` consecutive items at
/// a time (blocks are handed out as threads become free, so uneven items balance out). The
/// calling thread works too; if no other thread can be started (wasm32), it does it all.
pub(crate) fn map_range<R: Send>(
    n: usize,
    block: usize,
    threads: usize,
    f: impl Fn(usize) -> R + Sync,
) -> Vec<R> {
    let block = block.max(1);
    let blocks = n.div_ceil(block);
    let threads = threads.min(blocks);
    if threads <= 1 {
        return (0..n).map(f).collect();
    }
    let next = AtomicUsize::new(0);
    let work = || {
        let mut done: Vec<(usize, Vec<R>)> = Vec::new();
        loop {
            let b = next.fetch_add(1, Ordering::Relaxed);
            if b >= blocks {
                break done;
            }
            let lo = b * block;
            let hi = (lo + block).min(n);
            done.push((b, (lo..hi).map(&f).collect()));
        }
    };
    let mut pieces: Vec<(usize, Vec<R>)> = std::thread::scope(|s| {
        let helpers: Vec<_> = (1..threads)
            .filter_map(|_| std::thread::Builder::new().spawn_scoped(s, work).ok())
            .collect();
        let mut all = work();
        for h in helpers {
            match h.join() {
                Ok(part) => all.extend(part),
                Err(panic) => std::panic::resume_unwind(panic),
            }
        }
        all
    });
    // Back in input order: the blocks are disjoint and cover 0..n.
    pieces.sort_unstable_by_key(|&(b, _)| b);
    let mut out = Vec::with_capacity(n);
    for (_, part) in pieces {
        out.extend(part);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_is_in_input_order_on_any_thread_count() {
        let want: Vec<usize> = (0..1000).map(|i| i * i).collect();
        for threads in [1, 2, 3, 7, 64] {
            for block in [1, 5, 64, 2000] {
                assert_eq!(map_range(1000, block, threads, |i| i * i), want);
            }
        }
        assert!(map_range(0, 4, 4, |i| i).is_empty());
        assert_eq!(threads(Some(3)), 3);
        assert!(threads(None) >= 1);
    }
}
