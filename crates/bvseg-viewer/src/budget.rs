//! How much core work a frame may do during a run (and, for a run in the background, how
//! often a frame looks at it).
//!
//! Drawing a frame costs little on a GPU but a lot in a software renderer (a browser without
//! GPU draws WebGL on the CPU, on the same cores as the core). A fixed budget would let the
//! drawing dominate there; so the budget follows the measured cost of the rest of the frame,
//! keeping the drawing to about a ninth of the run's time, within bounds that keep the UI
//! responsive (a frame at least every 0.3 s while a run is live).
use web_time::{Duration, Instant};

/// The smallest budget (also the first frame's).
pub const MIN_BUDGET: Duration = Duration::from_millis(30);
/// The largest budget: a frame at least about three times a second.
pub const MAX_BUDGET: Duration = Duration::from_millis(300);
/// Core work per unit of frame overhead. Half of it (and 200 ms at most) left a sixth of the
/// page's run to drawing in a software renderer.
pub const RATIO: u32 = 8;

/// How often a frame takes the news of a run in the background (the page's threaded build),
/// which needs no frames of its own. A frame that shows news costs the drawing of two or
/// three (egui lays out again the panels that changed): taking news every frame, the page's
/// run of `spot` drew 14 to 19 frames and its core shared the machine with the drawing; at
/// 500 ms it draws 8, as many as a stepped run.
pub const NEWS_INTERVAL: Duration = Duration::from_millis(500);

/// [`NEWS_INTERVAL`] when WebGL draws on the CPU (a software renderer: no GPU, or a blocked
/// one), on the cores the run needs. There each frame costs tens of milliseconds of the
/// cores: taking news every 500 ms left a sixth of the page's run to drawing, every 2 s a few
/// hundredths.
pub const SOFTWARE_NEWS_INTERVAL: Duration = Duration::from_secs(2);

/// How often the app looks, between frames, whether a run in the background has ended (see
/// [`crate::platform::repaint_when_set`]): a look costs a timer and an atomic load, whereas
/// waiting for the next news frame showed a run's end up to [`SOFTWARE_NEWS_INTERVAL`] late.
pub const END_WATCH_INTERVAL: Duration = Duration::from_millis(20);

/// How often a frame takes the news of a run in the background, drawn by a software renderer
/// or not.
pub fn news_interval(software_renderer: bool) -> Duration {
    if software_renderer {
        SOFTWARE_NEWS_INTERVAL
    } else {
        NEWS_INTERVAL
    }
}

/// The budget for a frame whose drawing and event handling take `overhead`.
pub fn budget_for(overhead: Duration) -> Duration {
    (overhead * RATIO).clamp(MIN_BUDGET, MAX_BUDGET)
}

/// Tracks the frames of a run to size each frame's core work.
#[derive(Debug, Default, Clone)]
pub struct FrameBudget {
    last_start: Option<Instant>,
    last_work: Duration,
    /// Smoothed time a frame spends outside the core.
    overhead: Option<Duration>,
}

impl FrameBudget {
    /// A frame of the run starts at `now`: returns how long it may work.
    pub fn start(&mut self, now: Instant) -> Duration {
        if let Some(prev) = self.last_start {
            let outside = now
                .saturating_duration_since(prev)
                .saturating_sub(self.last_work);
            self.overhead = Some(match self.overhead {
                Some(o) => (o * 7 + outside * 3) / 10,
                None => outside,
            });
        }
        self.last_start = Some(now);
        self.last_work = Duration::ZERO;
        self.overhead.map_or(MIN_BUDGET, budget_for)
    }

    /// The frame worked for `d`.
    pub fn worked(&mut self, d: Duration) {
        self.last_work = d;
    }

    /// A frame without a run: the gap to the next run frame is idle time, not overhead.
    pub fn idle(&mut self) {
        self.last_start = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    #[test]
    fn news_come_less_often_on_a_software_renderer() {
        assert_eq!(news_interval(false), NEWS_INTERVAL);
        assert_eq!(news_interval(true), SOFTWARE_NEWS_INTERVAL);
        assert!(SOFTWARE_NEWS_INTERVAL > NEWS_INTERVAL);
    }

    #[test]
    fn budget_follows_the_frame_overhead_within_bounds() {
        assert_eq!(budget_for(Duration::ZERO), MIN_BUDGET);
        assert_eq!(budget_for(20 * MS), 160 * MS);
        assert_eq!(budget_for(Duration::from_secs(1)), MAX_BUDGET);

        let mut b = FrameBudget::default();
        let t0 = Instant::now();
        assert_eq!(b.start(t0), MIN_BUDGET);
        b.worked(30 * MS);
        // The frame took 80 ms in all: 50 ms outside the core.
        assert_eq!(b.start(t0 + 80 * MS), MAX_BUDGET);
        b.worked(200 * MS);
        // A fast renderer: 5 ms outside; the smoothed overhead falls.
        let later = b.start(t0 + 285 * MS);
        assert!(later < MAX_BUDGET && later > MIN_BUDGET, "{later:?}");
        // After an idle gap the next frame measures nothing, and keeps the smoothed value.
        b.idle();
        assert_eq!(b.start(t0 + Duration::from_secs(60)), later);
    }
}
