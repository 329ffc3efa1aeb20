//! Progress reporting and cancellation of an [`unwrap`](crate::unwrap()).
//!
//! A [`Progress`] handed to the unwrap in [`UnwrapOptions`](crate::UnwrapOptions) is polled
//! between charts and between the iterations of the iterative methods (spectral, ABF, ARAP,
//! SLIM, MIPS, scaffold). Its callback receives `(charts_done, charts_total)` after every
//! chart and at every poll (callers throttle); returning `false` cancels.
//! [`Progress::cancel`] cancels from any thread. A cancelled unwrap returns
//! [`UvError::Cancelled`](crate::UvError::Cancelled) and no UVs.
//!
//! The iterative methods see the progress of the unwrap they run in through a thread-local
//! set by [`Progress::enter`] around each chart, so their signatures do not carry it: they
//! call [`cancelled`] once per iteration and stop early when it is true (their result is
//! discarded).

use std::cell::RefCell;
use std::fmt;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// Called after each chart with `(charts_done, charts_total)`; `false` cancels the unwrap.
/// It runs on the worker threads, possibly several at once.
pub type ProgressCallback = dyn Fn(usize, usize) -> bool + Send + Sync;

/// Progress callback and cancel flag of one unwrap (cheap to clone: shared state).
#[derive(Clone, Default)]
pub struct Progress {
    flag: Arc<AtomicBool>,
    callback: Option<Arc<ProgressCallback>>,
    /// (charts done, charts total) of the unwrap using this progress.
    counts: Arc<(AtomicUsize, AtomicUsize)>,
}

impl fmt::Debug for Progress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Progress")
            .field("cancelled", &self.is_cancelled())
            .field("callback", &self.callback.is_some())
            .finish()
    }
}

impl Progress {
    /// A cancel flag without a callback.
    pub fn new() -> Self {
        Progress::default()
    }

    /// A cancel flag and a callback called after each chart.
    pub fn with_callback(callback: impl Fn(usize, usize) -> bool + Send + Sync + 'static) -> Self {
        Progress { callback: Some(Arc::new(callback)), ..Progress::default() }
    }

    /// Start counting: `total` charts, none done.
    pub fn start(&self, total: usize) {
        self.counts.0.store(0, Ordering::Relaxed);
        self.counts.1.store(total, Ordering::Relaxed);
    }

    /// One more chart done: report it.
    pub fn chart_done(&self) {
        let done = self.counts.0.fetch_add(1, Ordering::Relaxed) + 1;
        self.report(done, self.counts.1.load(Ordering::Relaxed));
    }

    /// Charts done so far.
    pub fn charts_done(&self) -> usize {
        self.counts.0.load(Ordering::Relaxed)
    }

    /// Report the current counts (a poll from inside a chart); true when cancelled.
    pub fn poll(&self) -> bool {
        if !self.is_cancelled() {
            self.report(self.counts.0.load(Ordering::Relaxed), self.counts.1.load(Ordering::Relaxed));
        }
        self.is_cancelled()
    }

    /// Ask the unwrap to stop as soon as it polls (any thread).
    pub fn cancel(&self) {
        self.flag.store(true, Ordering::Relaxed);
    }

    /// Whether the unwrap was cancelled.
    pub fn is_cancelled(&self) -> bool {
        self.flag.load(Ordering::Relaxed)
    }

    /// Report `done` of `total` charts; cancels when the callback returns `false`.
    pub fn report(&self, done: usize, total: usize) {
        if let Some(cb) = &self.callback {
            if !cb(done, total) {
                self.cancel();
            }
        }
    }

    /// Make this progress the one [`cancelled`] polls on the current thread until the guard
    /// drops.
    pub fn enter(&self) -> ProgressGuard {
        let previous = CURRENT.with(|c| c.replace(Some(self.clone())));
        ProgressGuard { previous }
    }
}

thread_local! {
    static CURRENT: RefCell<Option<Progress>> = const { RefCell::new(None) };
}

/// Restores the previous thread-local progress when dropped (see [`Progress::enter`]).
pub struct ProgressGuard {
    previous: Option<Progress>,
}

impl Drop for ProgressGuard {
    fn drop(&mut self) {
        let previous = self.previous.take();
        CURRENT.with(|c| *c.borrow_mut() = previous);
    }
}

/// The progress [`Progress::enter`]ed on this thread, if any: work the unwrap hands to other
/// threads (a split chart's halves) enters it there, so its methods see a cancel too.
pub fn current() -> Option<Progress> {
    CURRENT.with(|c| c.borrow().clone())
}

/// Whether the unwrap running on this thread was cancelled (false outside any unwrap); also
/// gives its callback a chance to cancel. Polled by the iterative methods once per iteration.
pub fn cancelled() -> bool {
    // Cloned out of the cell so that a callback may itself run code that polls.
    let current = CURRENT.with(|c| c.borrow().clone());
    current.is_some_and(|p| p.poll())
}
