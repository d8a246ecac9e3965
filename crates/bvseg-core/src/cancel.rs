//! Stopping a run from outside: a shared flag that the pipeline checks between bounded
//! pieces of work.
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A flag that ends a run early when set: pass a clone to [`crate::Segmenter::with_cancel`]
/// and call [`Cancel::cancel`] from any thread, for example from a timer for a wall-time
/// budget. The run then ends with
/// [`crate::Error::Cancelled`] at its next check, within a fraction of a second on meshes of
/// ordinary size. Cloning shares the flag.
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A flag that is not set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets the flag: every run holding a clone stops at its next check.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether the flag is set.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// `Err(Cancelled)` once the flag is set.
    pub(crate) fn check(&self) -> Result<(), crate::Error> {
        if self.is_cancelled() {
            Err(crate::Error::Cancelled)
        } else {
            Ok(())
        }
    }
}
