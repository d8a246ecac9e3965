//! Progress display: indicatif bars on a terminal, plain step lines otherwise (logs and
//! pipes), nothing with `--quiet`.
use std::io::IsTerminal;
use std::time::Duration;

use bvseg_core::{Params, Step};
use indicatif::{ProgressBar, ProgressStyle};

/// How a run reports its progress on stderr.
pub enum Progress {
    /// Nothing.
    Quiet,
    /// One line per refinement step.
    Lines,
    /// A spinner while sampling, then a bar over k with the live TOV and MOV.
    Bar(ProgressBar),
}

impl Progress {
    /// Bars on a terminal, lines elsewhere, nothing when `quiet`.
    pub fn new(quiet: bool) -> Self {
        if quiet {
            Progress::Quiet
        } else if std::io::stderr().is_terminal() {
            Progress::Bar(ProgressBar::hidden())
        } else {
            Progress::Lines
        }
    }

    pub fn sampling(&self) {
        if let Progress::Bar(bar) = self {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template("{spinner} sampling the interior {elapsed}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            bar.enable_steady_tick(Duration::from_millis(120));
        }
    }

    pub fn refining(&self, params: &Params) {
        if let Progress::Bar(bar) = self {
            bar.set_length(params.k.unwrap_or(params.max_k) as u64);
            bar.set_position(0);
            bar.set_style(
                ProgressStyle::with_template("refining [{bar:30}] k {pos}/{len} {msg} {elapsed}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
        }
    }

    pub fn step(&self, s: &Step) {
        match self {
            Progress::Quiet => {}
            Progress::Lines => eprintln!(
                "[{:<9}] k={:<3} F={:.6}  TOV={:.6}  MOV={:.6}  protrusion={:.6}",
                s.kind.as_str(),
                s.k,
                s.f,
                s.tov,
                s.mov,
                s.protrusion
            ),
            Progress::Bar(bar) => {
                bar.set_position(s.k as u64);
                bar.set_message(format!(
                    "TOV {:.3} MOV {:.3} ({})",
                    s.tov,
                    s.mov,
                    s.kind.as_str()
                ));
            }
        }
    }

    pub fn done(&self) {
        if let Progress::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}

/// A bar over the files of a batch (hidden when not on a terminal or quiet).
pub fn batch_bar(files: usize, quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(files as u64);
    bar.set_style(
        ProgressStyle::with_template("batch [{bar:30}] {pos}/{len} files {msg} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar
}
