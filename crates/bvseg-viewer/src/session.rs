//! One segmentation run, advanced a bounded amount at a time.
//!
//! The app calls [`Session::advance`] once per frame. A run goes one of two ways:
//! - **stepped** (natively, and in the page without threads): `advance` does whole core steps
//!   on the caller's thread until a time budget is spent, then returns;
//! - **in the background** (the page's threaded build, `threads`): the whole run goes to
//!   rayon's pool (Web Workers) at once, and `advance` only collects what it has done so far,
//!   without ever waiting: a page's main thread may not.
//!
//! Cancelling is dropping the session. Every step leaves a [`Snapshot`], so the history can be
//! stepped back through after (and during) the run.
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use bvseg_core::{
    BoundingVolume, Cancel, Error, Mesh, Params, Segmentation, Segmenter, Step, StepKind,
    TooComplex,
};
use web_time::{Duration, Instant};

/// Part label of a triangle whose part is not known (drawn in the plain mesh colour).
pub const UNKNOWN_PART: u16 = u16::MAX;

/// Above this many triangles, snapshots keep no per-triangle colouring (only the final state
/// has it), so that long histories of big meshes stay small in memory.
pub const MAX_SNAPSHOT_TRIANGLES: usize = 250_000;

/// Samples and largest number of parts of a [`Session::warm_up`] run: every stage and every
/// kind of fit runs, in about a fifth of a default run of spot natively.
pub const WARM_UP_SAMPLES: usize = 2000;
/// See [`WARM_UP_SAMPLES`].
pub const WARM_UP_MAX_K: usize = 16;

/// The state after one refinement step.
#[derive(Debug, Clone)]
pub struct Snapshot {
    /// The step and its figures.
    pub step: Step,
    /// The bounding volumes after the step (for a backtrack, those of the state it returned to).
    pub volumes: Arc<Vec<BoundingVolume>>,
    /// Each triangle's part, or [`UNKNOWN_PART`]; empty when not kept.
    pub triangle_parts: Arc<Vec<u16>>,
    /// Each part's share of the samples.
    pub fractions: Arc<Vec<f64>>,
}

/// Where a run is.
enum Stage {
    /// Nothing done yet: the next call samples the solid.
    Sampling,
    /// Stepping.
    Stepping(Box<Segmenter>),
    /// Running on the pool; what it did so far waits in the inbox. (Never, in the page
    /// without threads.)
    #[cfg_attr(
        all(target_arch = "wasm32", not(feature = "threads")),
        allow(dead_code)
    )]
    Background(Arc<Inbox>),
    /// Finished; the segmenter is kept, until asked for, to build the hierarchy the run went
    /// without (see [`Session::result_with_hierarchy`]).
    Done(Box<Segmentation>, Option<Box<Segmenter>>),
    /// The core refused the input.
    Failed(Error),
}

/// What a run in the background hands over, and how to stop it.
#[derive(Default)]
struct Inbox {
    cancel: Cancel,
    mail: Mutex<Mail>,
    /// Set once the run's end is in the mail (see [`Session::take_end_signal`]).
    ended: Arc<AtomicBool>,
}

/// The background run's news since the last collection.
#[derive(Default)]
struct Mail {
    samples: usize,
    snapshots: Vec<Snapshot>,
    /// Time spent in the core so far.
    busy: Duration,
    /// How the run ended, and when.
    end: Option<(Ending, Instant)>,
}

/// A run's result and the segmenter that made it (kept to build the hierarchy later), or the
/// core's error.
type Ending = Result<(Segmentation, Segmenter), Error>;

/// The first failure of a thread of rayon's pool, as the run's error will say it (see
/// [`note_pool_panic`] and [`note_worker_failure`]).
static POOL_FAILURE: Mutex<Option<String>> = Mutex::new(None);

/// Records a panic on a thread of rayon's pool. In the page's threaded build a panic aborts
/// its Web Worker without unwinding, so the run in the background would never end; the
/// session's next look turns this into the run's error instead (the pool is then a thread
/// short: the page must be reloaded).
pub fn note_pool_panic(message: &str) {
    let mut first = POOL_FAILURE
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    first.get_or_insert_with(|| format!("the core panicked ({message})"));
}

/// What the viewer says of a failed run: the core's error, and after an allocation that
/// failed, that the page must be reloaded first (the failure aborted one of its workers).
pub fn failure_message(e: &Error) -> String {
    match e {
        Error::TooComplex(TooComplex::OutOfMemory { .. }) => {
            format!("{e} (reload the page first)")
        }
        _ => e.to_string(),
    }
}

/// The size of an allocation that failed (0: none did). Running out of memory aborts the
/// thread without a panic, so in the page's threaded build the run would wait forever for
/// its dead worker; the page's allocator ([`NotingAllocator`]) notes the failure here first,
/// and the session's next look fails the run with it. Not a lock: a thread out of memory
/// cannot format a message, nor may the allocator wait. (A failure that the program handles,
/// as `Vec::try_reserve` lets it, would count too; nothing in bvseg makes one.)
static ALLOCATION_FAILED: AtomicUsize = AtomicUsize::new(0);

/// An allocator that notes its failures, for the session to read, before the runtime aborts
/// the thread: the page's threaded build wraps the system allocator in it.
pub struct NotingAllocator<A>(pub A);

// SAFETY: every call goes to the wrapped allocator unchanged; a null result is only noted.
unsafe impl<A: std::alloc::GlobalAlloc> std::alloc::GlobalAlloc for NotingAllocator<A> {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        noted(unsafe { self.0.alloc(layout) }, layout.size())
    }

    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: as above.
        noted(unsafe { self.0.alloc_zeroed(layout) }, layout.size())
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new: usize) -> *mut u8 {
        // SAFETY: as above.
        noted(unsafe { self.0.realloc(ptr, layout, new) }, new)
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: as above.
        unsafe { self.0.dealloc(ptr, layout) }
    }
}

fn noted(ptr: *mut u8, size: usize) -> *mut u8 {
    if ptr.is_null() {
        let _ = ALLOCATION_FAILED.compare_exchange(
            0,
            size.max(1),
            Ordering::Relaxed,
            Ordering::Relaxed,
        );
    }
    ptr
}

/// A run of the core on one mesh with one set of parameters.
pub struct Session {
    mesh: Arc<Mesh>,
    /// The mesh's bounding-box diagonal (asked for every frame by the plot).
    diagonal: f64,
    params: Params,
    stage: Stage,
    samples: usize,
    snapshots: Vec<Snapshot>,
    /// Time spent inside the core so far (not counting the frames in between).
    busy: Duration,
    /// Calls of [`Session::advance`] (frames of the run).
    calls: usize,
    started: Instant,
    wall: Option<Duration>,
    /// A run in the background's end signal, until taken.
    end_signal: Option<Arc<AtomicBool>>,
}

/// What [`Session::advance`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// More to do.
    Running,
    /// The run has just finished or had finished before.
    Done,
    /// The run failed (see [`Session::error`]).
    Failed,
}

impl Session {
    /// A run in the way this build runs them: in the background in the page's threaded
    /// build (see the module docs).
    #[cfg(feature = "threads")]
    pub fn new(mesh: Arc<Mesh>, params: Params) -> Self {
        Self::in_background(mesh, params)
    }

    /// A run in the way this build runs them: stepped, as the build has no `threads` (see
    /// the module docs).
    #[cfg(not(feature = "threads"))]
    pub fn new(mesh: Arc<Mesh>, params: Params) -> Self {
        Self::stepped(mesh, params)
    }

    /// A run that has not started; [`Session::advance`] does the work, a step at a time.
    pub fn stepped(mesh: Arc<Mesh>, params: Params) -> Self {
        let (lo, hi) = mesh.bbox();
        Self {
            diagonal: (hi - lo).length(),
            mesh,
            params,
            stage: Stage::Sampling,
            samples: 0,
            snapshots: Vec::new(),
            busy: Duration::ZERO,
            calls: 0,
            started: Instant::now(),
            wall: None,
            end_signal: None,
        }
    }

    /// A run started at once on rayon's pool; [`Session::advance`] collects its steps.
    #[cfg(any(feature = "threads", not(target_arch = "wasm32")))]
    pub fn in_background(mesh: Arc<Mesh>, params: Params) -> Self {
        let inbox = Arc::new(Inbox::default());
        let mut s = Self::stepped(mesh.clone(), params.clone());
        s.stage = Stage::Background(inbox.clone());
        s.end_signal = Some(inbox.ended.clone());
        rayon::spawn(move || {
            run_in_background(&mesh, &params, &inbox);
            inbox.ended.store(true, Ordering::Release);
        });
        s
    }

    /// A small run of `mesh` with `params` in the background whose result nobody looks at, or
    /// `None` in the page's build without threads (its core runs on the page's own thread).
    /// A browser first runs a WebAssembly module in baseline code and optimises each function
    /// only once it has run a while, so a page's first run is slower than its later ones
    /// (docs/viewer.md, "Size and speed", has the figures). Started as the page loads, this
    /// leaves the core's hot functions optimised before the user's first run. Dropping it
    /// stops it.
    pub fn warm_up(mesh: Arc<Mesh>, params: &Params) -> Option<Self> {
        let params = Params {
            samples: WARM_UP_SAMPLES,
            max_k: WARM_UP_MAX_K,
            k: None,
            ..params.clone()
        };
        #[cfg(any(feature = "threads", not(target_arch = "wasm32")))]
        return Some(Self::in_background(mesh, params));
        #[cfg(not(any(feature = "threads", not(target_arch = "wasm32"))))]
        {
            let _ = (mesh, params);
            None
        }
    }

    /// Stepped: do at least one unit of work (sampling, or one core step), and more while
    /// `budget` lasts. In the background: take what the run did since the last call, if it
    /// can be had without waiting (`budget` is not used).
    pub fn advance(&mut self, budget: Duration) -> Progress {
        let t0 = Instant::now();
        self.calls += 1;
        if let Stage::Background(inbox) = &self.stage {
            let inbox = inbox.clone();
            return self.collect(&inbox);
        }
        loop {
            let p = self.advance_one();
            if p != Progress::Running || t0.elapsed() >= budget {
                self.busy += t0.elapsed();
                if p != Progress::Running && self.wall.is_none() {
                    self.wall = Some(self.started.elapsed());
                }
                return p;
            }
        }
    }

    fn advance_one(&mut self) -> Progress {
        match &mut self.stage {
            Stage::Sampling => {
                match Segmenter::new(&self.mesh, &self.params) {
                    Ok(seg) => {
                        self.samples = seg.samples();
                        self.stage = Stage::Stepping(Box::new(seg));
                    }
                    Err(e) => {
                        self.stage = Stage::Failed(e);
                        return Progress::Failed;
                    }
                }
                Progress::Running
            }
            Stage::Stepping(seg) => match seg.step() {
                Some(step) => {
                    let snap = self.snapshot(step);
                    self.snapshots.push(snap);
                    Progress::Running
                }
                None => {
                    let Stage::Stepping(mut seg) =
                        std::mem::replace(&mut self.stage, Stage::Sampling)
                    else {
                        unreachable!("matched above");
                    };
                    let result = seg.take_result().map(|r| (r, *seg));
                    self.end(result)
                }
            },
            Stage::Background(_) => unreachable!("advance collects a background run"),
            Stage::Done(..) => Progress::Done,
            Stage::Failed(_) => Progress::Failed,
        }
    }

    fn snapshot(&self, step: Step) -> Snapshot {
        let Stage::Stepping(seg) = &self.stage else {
            unreachable!("snapshots are taken while stepping");
        };
        snapshot(seg, &self.mesh, step, self.snapshots.last())
    }

    /// Take the background run's news without waiting (the main thread of a page may not).
    fn collect(&mut self, inbox: &Inbox) -> Progress {
        // Out of memory is the input's size (the sample count), a panic a bug.
        let failed = match ALLOCATION_FAILED.load(Ordering::Relaxed) {
            0 => POOL_FAILURE
                .try_lock()
                .ok()
                .and_then(|p| p.clone())
                .map(|msg| Error::Internal(format!("{msg}; reload the page"))),
            size => Some(Error::TooComplex(TooComplex::OutOfMemory { bytes: size })),
        };
        if let Some(e) = failed {
            inbox.cancel.cancel();
            self.stage = Stage::Failed(e);
            return Progress::Failed;
        }
        let Ok(mut mail) = inbox.mail.try_lock() else {
            return Progress::Running;
        };
        self.samples = mail.samples;
        self.busy = mail.busy;
        self.snapshots.append(&mut mail.snapshots);
        let Some((result, at)) = mail.end.take() else {
            return Progress::Running;
        };
        drop(mail);
        self.wall = Some(at.saturating_duration_since(self.started));
        self.end(result)
    }

    /// The run has ended with `result` (and the segmenter that made it).
    fn end(&mut self, result: Ending) -> Progress {
        let (result, seg) = match result {
            Ok(r) => r,
            Err(e) => {
                self.stage = Stage::Failed(e);
                return Progress::Failed;
            }
        };
        if let Some(last) = self.snapshots.last_mut() {
            if last.step.kind == StepKind::Final {
                // The final colouring: the part whose volume encloses each triangle.
                last.triangle_parts = Arc::new(
                    result
                        .triangle_parts
                        .iter()
                        .map(|&p| u16::try_from(p).unwrap_or(UNKNOWN_PART))
                        .collect(),
                );
            }
        }
        let keep = (!self.params.hierarchy).then(|| Box::new(seg));
        self.stage = Stage::Done(Box::new(result), keep);
        Progress::Done
    }

    /// For a run in the background, once: a flag that its thread sets when the run has ended
    /// (with a result, an error or by cancelling), after which [`Session::advance`] sees the
    /// end. Between news frames nothing looks at the run, so the app hands this to
    /// [`crate::platform::repaint_when_set`] to show the end as soon as it comes. `None` for a
    /// stepped run, and after the first call.
    pub fn take_end_signal(&mut self) -> Option<Arc<AtomicBool>> {
        self.end_signal.take()
    }

    /// Whether a run in the background has ended, so that [`Session::advance`] would find the
    /// end: the app then takes it at once instead of at the next news frame. `false` for a
    /// stepped run.
    pub fn has_ended(&self) -> bool {
        matches!(&self.stage, Stage::Background(inbox) if inbox.ended.load(Ordering::Acquire))
    }

    /// Whether the run is going on in the background (see the module docs).
    pub fn is_background(&self) -> bool {
        matches!(self.stage, Stage::Background(_))
    }

    /// The mesh being segmented.
    pub fn mesh(&self) -> &Arc<Mesh> {
        &self.mesh
    }

    /// The parameters of the run.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// One snapshot per step so far.
    pub fn snapshots(&self) -> &[Snapshot] {
        &self.snapshots
    }

    /// The result, once done. Its hierarchy is empty when the parameters went without it.
    pub fn result(&self) -> Option<&Segmentation> {
        match &self.stage {
            Stage::Done(s, _) => Some(s),
            _ => None,
        }
    }

    /// The result with its hierarchy, built now if the run went without it (the app runs
    /// without, as only the JSON export carries it).
    pub fn result_with_hierarchy(&mut self) -> Option<&Segmentation> {
        let Stage::Done(res, run) = &mut self.stage else {
            return None;
        };
        if let Some(run) = run.take() {
            res.hierarchy = run.hierarchy();
        }
        Some(res)
    }

    /// The core's error, if the run failed.
    pub fn error(&self) -> Option<&Error> {
        match &self.stage {
            Stage::Failed(e) => Some(e),
            _ => None,
        }
    }

    /// Whether the run is over (done or failed).
    pub fn is_over(&self) -> bool {
        matches!(self.stage, Stage::Done(..) | Stage::Failed(_))
    }

    /// Number of interior samples (0 before sampling).
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Time spent in the core.
    pub fn busy(&self) -> Duration {
        self.busy
    }

    /// Number of [`Session::advance`] calls so far (the frames of the run).
    pub fn calls(&self) -> usize {
        self.calls
    }

    /// The diagonal of the mesh's bounding box (the protrusion is shown relative to it).
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// Wall-clock time from the start to the end of the run, or so far.
    pub fn wall(&self) -> Duration {
        self.wall.unwrap_or_else(|| self.started.elapsed())
    }
}

impl Drop for Session {
    /// A run in the background stops at its next step.
    fn drop(&mut self) {
        if let Stage::Background(inbox) = &self.stage {
            inbox.cancel.cancel();
        }
    }
}

/// The state of `seg` after `step`; `prev` is the snapshot before it.
fn snapshot(seg: &Segmenter, mesh: &Mesh, step: Step, prev: Option<&Snapshot>) -> Snapshot {
    // A backtrack leaves the current state as it was: share the previous snapshot's data.
    if step.kind == StepKind::Backtrack {
        if let Some(prev) = prev {
            return Snapshot {
                step,
                ..prev.clone()
            };
        }
    }
    let labels = seg.labels();
    let volumes = seg.volumes().to_vec();
    let mut counts = vec![0usize; volumes.len()];
    for &l in labels {
        if let Some(c) = counts.get_mut(l as usize) {
            *c += 1;
        }
    }
    let n = labels.len().max(1) as f64;
    // The core's own rule (each triangle goes with its nearest sample), so that the colours
    // during the run are those of the result.
    let triangle_parts = if mesh.triangles().len() <= MAX_SNAPSHOT_TRIANGLES {
        seg.triangle_parts()
            .into_iter()
            .map(|l| u16::try_from(l).unwrap_or(UNKNOWN_PART))
            .collect()
    } else {
        Vec::new()
    };
    Snapshot {
        step,
        volumes: Arc::new(volumes),
        triangle_parts: Arc::new(triangle_parts),
        fractions: Arc::new(counts.iter().map(|&c| c as f64 / n).collect()),
    }
}

/// The whole run, on a thread of rayon's pool, posting each step to `inbox`.
#[cfg(any(feature = "threads", not(target_arch = "wasm32")))]
fn run_in_background(mesh: &Mesh, params: &Params, inbox: &Inbox) {
    let t0 = Instant::now();
    // The pool's threads may wait for the lock (only the main thread may not).
    let post = |f: &mut dyn FnMut(&mut Mail)| {
        let mut mail = inbox
            .mail
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        mail.busy = t0.elapsed();
        f(&mut mail);
    };
    let mut seg = match Segmenter::with_cancel(mesh, params, inbox.cancel.clone()) {
        Ok(seg) => seg,
        Err(e) => return post(&mut |m| m.end = Some((Err(e.clone()), Instant::now()))),
    };
    post(&mut |m| m.samples = seg.samples());
    let mut last: Option<Snapshot> = None;
    while let Some(step) = seg.step() {
        let snap = snapshot(&seg, mesh, step, last.as_ref());
        last = Some(snap.clone());
        post(&mut |m| m.snapshots.push(snap.clone()));
    }
    let mut end = Some(seg.take_result().map(|r| (r, seg)));
    post(&mut |m| m.end = end.take().map(|e| (e, Instant::now())));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::meshes::{load_bundled, BUNDLED};

    #[test]
    fn advance_runs_to_the_end_with_one_snapshot_per_step() {
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let params = Params {
            samples: 3000,
            k: Some(4),
            ..Params::default()
        };
        let mut s = Session::new(mesh.clone(), params.clone());
        let mut calls = 0;
        // A zero budget still makes progress: one unit of work per call.
        while s.advance(Duration::ZERO) == Progress::Running {
            calls += 1;
            assert!(calls < 10_000);
        }
        let res = s.result().unwrap();
        assert_eq!(res.metrics.k, 4);
        assert_eq!(s.snapshots().len(), res.history.len());
        assert!(calls >= res.history.len());
        let last = s.snapshots().last().unwrap();
        assert_eq!(last.step.kind, StepKind::Final);
        assert_eq!(last.volumes.len(), 4);
        assert_eq!(last.triangle_parts.len(), mesh.triangles().len());
        assert!(last.triangle_parts.iter().all(|&p| p < 4));
        // The colours follow the core's triangle rule: at the end, the result's parts.
        let expect: Vec<u16> = res.triangle_parts.iter().map(|&p| p as u16).collect();
        assert_eq!(*last.triangle_parts, expect);
        // Stepping gives what the one-call API gives.
        let direct = bvseg_core::segment(&mesh, &params).unwrap();
        assert_eq!(direct.metrics, res.metrics);
    }

    /// The tests of runs in the background, one at a time: a panic noted on the pool fails
    /// every run in the background of the process.
    static BACKGROUND: Mutex<()> = Mutex::new(());

    fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
        BACKGROUND
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// The inbox of a run in the background.
    fn inbox_of(s: &Session) -> Arc<Inbox> {
        let Stage::Background(inbox) = &s.stage else {
            panic!("not in the background");
        };
        inbox.clone()
    }

    /// Collects a background run until it ends (natively the caller may wait in between).
    fn collect_all(s: &mut Session) -> Progress {
        for _ in 0..60_000 {
            match s.advance(Duration::ZERO) {
                Progress::Running => std::thread::sleep(Duration::from_millis(1)),
                p => return p,
            }
        }
        panic!("the background run did not end");
    }

    #[test]
    fn a_run_in_the_background_gives_the_stepped_runs_steps_and_result() {
        let _one = one_at_a_time();
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let params = Params {
            samples: 3000,
            max_k: 8,
            hierarchy: false,
            ..Params::default()
        };
        let mut stepped = Session::stepped(mesh.clone(), params.clone());
        while stepped.advance(Duration::ZERO) == Progress::Running {}
        let mut bg = Session::in_background(mesh, params);
        assert!(bg.is_background());
        assert_eq!(collect_all(&mut bg), Progress::Done);
        assert!(bg.result().is_some() && bg.result() == stepped.result());
        assert_eq!(bg.samples(), stepped.samples());
        let steps = |s: &Session| -> Vec<Step> { s.snapshots().iter().map(|x| x.step).collect() };
        assert!(steps(&bg).len() > 2);
        assert_eq!(steps(&bg), steps(&stepped));
        for (a, b) in bg.snapshots().iter().zip(stepped.snapshots()) {
            assert_eq!(a.volumes, b.volumes);
            assert_eq!(a.triangle_parts, b.triangle_parts);
        }
        assert!(bg.busy() > Duration::ZERO && bg.busy() <= bg.wall());
        // The hierarchy it went without is built on the main thread when asked.
        assert!(!bg.result_with_hierarchy().unwrap().hierarchy.is_empty());
    }

    #[test]
    fn a_background_run_signals_its_end_once_the_end_can_be_collected() {
        let _one = one_at_a_time();
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let params = Params {
            samples: 3000,
            max_k: 8,
            ..Params::default()
        };
        assert!(Session::stepped(mesh.clone(), params.clone())
            .take_end_signal()
            .is_none());
        for params in [
            params.clone(),
            Params {
                samples: 10,
                ..params
            },
        ] {
            let mut s = Session::in_background(mesh.clone(), params);
            let ended = s.take_end_signal().unwrap();
            assert!(s.take_end_signal().is_none(), "handed out once");
            let t0 = Instant::now();
            while !ended.load(Ordering::Acquire) {
                assert!(t0.elapsed() < Duration::from_secs(120), "no end signal");
                std::thread::sleep(Duration::from_millis(1));
            }
            // The first look after the signal finds the end (the result, or the error).
            assert!(s.has_ended());
            assert_ne!(s.advance(Duration::ZERO), Progress::Running);
        }
    }

    #[test]
    fn a_background_run_reports_the_cores_error_and_stops_when_dropped() {
        let _one = one_at_a_time();
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let bad = Params {
            samples: 10,
            ..Params::default()
        };
        let mut s = Session::in_background(mesh.clone(), bad);
        assert_eq!(collect_all(&mut s), Progress::Failed);
        assert!(s.error().unwrap().to_string().contains("samples"));
        // Dropped while running: the cancel flag stops it at its next step.
        let s = Session::in_background(mesh, Params::default());
        let inbox = inbox_of(&s);
        drop(s);
        assert!(inbox.cancel.is_cancelled());
        for _ in 0..60_000 {
            if inbox.mail.lock().unwrap().end.is_some() {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        let mail = inbox.mail.lock().unwrap();
        assert!(
            matches!(mail.end, Some((Err(Error::Cancelled), _))),
            "{:?}",
            mail.end.as_ref().map(|e| e.0.is_ok())
        );
    }

    #[test]
    fn a_panic_on_the_pool_fails_the_background_run() {
        let _one = one_at_a_time();
        let msg = failure_of_a_run_after(
            || note_pool_panic("index out of bounds"),
            || *POOL_FAILURE.lock().unwrap() = None,
        );
        assert!(msg.contains("panicked (index out of bounds)"), "{msg}");
    }

    /// The error of a default background run whose pool `fail`s as it starts (`reset` undoes
    /// that for the other tests): the run fails at once, is cancelled, and says to reload.
    fn failure_of_a_run_after(fail: impl FnOnce(), reset: impl FnOnce()) -> String {
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let mut s = Session::in_background(mesh, Params::default());
        let inbox = inbox_of(&s);
        fail();
        let failed = s.advance(Duration::ZERO);
        reset();
        assert_eq!(failed, Progress::Failed);
        let msg = failure_message(s.error().unwrap());
        assert!(msg.contains("reload"), "{msg}");
        assert!(inbox.cancel.is_cancelled(), "the run goes on");
        msg
    }

    /// An allocation that failed (as the page's allocator notes it) fails the run too, with
    /// what the allocator saw.
    #[test]
    fn running_out_of_memory_fails_the_background_run() {
        use std::alloc::{GlobalAlloc, Layout, System};
        /// An allocator with no memory above a megabyte.
        struct Small;
        // SAFETY: passes the calls it does not refuse on to the system allocator.
        unsafe impl GlobalAlloc for Small {
            unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
                if layout.size() > 1 << 20 {
                    return std::ptr::null_mut();
                }
                // SAFETY: the caller's contract, passed on.
                unsafe { System.alloc(layout) }
            }
            unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
                // SAFETY: as above (only the system allocator's blocks reach here).
                unsafe { System.dealloc(ptr, layout) }
            }
        }
        let _one = one_at_a_time();
        let noting = NotingAllocator(Small);
        let small = Layout::from_size_align(64, 8).unwrap();
        // SAFETY: a valid layout; the block is freed with it.
        unsafe {
            let p = noting.alloc(small);
            assert!(!p.is_null());
            noting.dealloc(p, small);
        }
        assert_eq!(
            ALLOCATION_FAILED.load(Ordering::Relaxed),
            0,
            "noted a success"
        );
        let msg = failure_of_a_run_after(
            || {
                // SAFETY: a valid layout; the null result is not used.
                let p = unsafe { noting.alloc(Layout::from_size_align(3 << 20, 8).unwrap()) };
                assert!(p.is_null());
            },
            || ALLOCATION_FAILED.store(0, Ordering::Relaxed),
        );
        assert!(
            msg.contains("ran out of memory (an allocation of 3.1 MB failed)"),
            "{msg}"
        );
    }

    #[test]
    fn a_run_without_the_hierarchy_builds_it_when_asked() {
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let params = Params {
            samples: 3000,
            k: Some(4),
            ..Params::default()
        };
        let direct = bvseg_core::segment(&mesh, &params).unwrap();
        let mut s = Session::new(
            mesh,
            Params {
                hierarchy: false,
                ..params
            },
        );
        while s.advance(Duration::from_secs(1)) == Progress::Running {}
        assert!(s.result().unwrap().hierarchy.is_empty());
        assert_eq!(s.result_with_hierarchy(), Some(&direct));
        assert_eq!(s.result(), Some(&direct));
    }

    #[test]
    fn invalid_parameters_fail_the_run() {
        let mesh = Arc::new(load_bundled(&BUNDLED[0]).unwrap());
        let params = Params {
            samples: 10,
            ..Params::default()
        };
        let mut s = Session::new(mesh, params);
        assert_eq!(s.advance(Duration::from_secs(1)), Progress::Failed);
        assert!(s.error().unwrap().to_string().contains("samples"));
        assert!(s.is_over() && s.result().is_none());
    }
}
