//! The one place that chooses between rayon and a plain loop, so that every stage maps in
//! parallel the same way and builds without rayon (for wasm32).

/// `items.iter().map(f).collect()`, in parallel with the `parallel` feature. The output order
/// is the input order either way, so results never depend on the thread count.
pub(crate) fn map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync + Send) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items.par_iter().with_min_len(1).map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        items.iter().map(f).collect()
    }
}

/// Like [`map`], for many cheap items: each task takes at least `min_len` of them.
pub(crate) fn map_chunked<T: Sync, R: Send>(
    items: &[T],
    min_len: usize,
    f: impl Fn(&T) -> R + Sync + Send,
) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items.par_iter().with_min_len(min_len).map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        let _ = min_len;
        items.iter().map(f).collect()
    }
}

/// Run `a` and `b`, in parallel with the `parallel` feature.
pub(crate) fn join<A: Send, B: Send>(
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B + Send,
) -> (A, B) {
    #[cfg(feature = "parallel")]
    {
        rayon::join(a, b)
    }
    #[cfg(not(feature = "parallel"))]
    {
        (a(), b())
    }
}

/// How many threads [`map`] and [`join`] run on.
pub(crate) fn threads() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}
