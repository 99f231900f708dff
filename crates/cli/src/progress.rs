//! The progress of a command's samples on standard error: a bar on a terminal (not with
//! `--quiet`), and the one-line estimate of a long command's wall time, said always.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::output::note;

/// Estimated totals at or below this many seconds go unsaid; the environment variable
/// [`ESTIMATE_THRESHOLD_VARIABLE`] sets another (the tests set it low).
const ESTIMATE_THRESHOLD_SECONDS: f64 = 60.0;

/// The environment variable that sets the threshold of the wall-time estimate, in seconds
/// (not documented for users: for the tests).
const ESTIMATE_THRESHOLD_VARIABLE: &str = "RVTOL_ESTIMATE_THRESHOLD_SECONDS";

/// Seconds after which the estimate is made even when the first chunks of every worker
/// have not all finished.
const ESTIMATE_SETTLE_SECONDS: f64 = 5.0;

/// Seconds of work before a command with a budget says how long the whole budget would
/// take.
const BUDGET_NOTE_SECONDS: f64 = 30.0;

/// A duration as a person says it: `45 s`, `12 min`, `10 h 12 min`, `3 days 4 h`.
fn human_duration(seconds: f64) -> String {
    let seconds = seconds.max(0.0).round() as u64;
    let (days, hours, minutes) = (seconds / 86_400, seconds / 3_600 % 24, seconds / 60 % 60);
    if seconds < 90 {
        format!("{seconds} s")
    } else if seconds < 90 * 60 {
        format!("{} min", (seconds + 30) / 60)
    } else if days == 0 {
        format!("{} h {minutes} min", seconds / 3_600)
    } else {
        format!("{days} day{} {hours} h", if days == 1 { "" } else { "s" })
    }
}

/// The progress of a command's samples: a bar on a terminal (not with --quiet), and, on
/// any stderr and with --quiet too, one line estimating the wall time when it will be
/// long: made once, from the pace of the first chunks (one per worker, or what is done
/// after a few seconds), and said when the total exceeds a minute. A run outside a
/// terminal (a batch job) would otherwise run for hours without a word.
pub struct Progress {
    bar: ProgressBar,
    command: &'static str,
    /// Whether the total is a budget that the command may stop well short of (a rare
    /// event's model evaluations), not its work.
    budget: bool,
    started: std::time::Instant,
    total: u64,
    done: AtomicU64,
    estimated: AtomicBool,
    /// Samples done when the pace is read: the first chunk of every worker.
    settled: u64,
    threshold_seconds: f64,
}

impl Progress {
    pub fn new(command: &'static str, samples: u64, quiet: bool, threads: usize) -> Progress {
        let bar = if quiet || !std::io::stderr().is_terminal() {
            ProgressBar::hidden()
        } else {
            let bar = ProgressBar::with_draw_target(Some(samples), ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {percent:>3}% {human_pos}/{human_len} samples, eta {eta}")
                    .expect("valid template"),
            );
            bar
        };
        let threshold_seconds = std::env::var(ESTIMATE_THRESHOLD_VARIABLE)
            .ok()
            .and_then(|text| text.trim().parse::<f64>().ok())
            .filter(|seconds| seconds.is_finite())
            .unwrap_or(ESTIMATE_THRESHOLD_SECONDS);
        Progress {
            bar,
            command,
            budget: false,
            started: std::time::Instant::now(),
            total: samples,
            done: AtomicU64::new(0),
            estimated: AtomicBool::new(false),
            settled: threads.max(1) as u64 * rvtol_engine::chunk::CHUNK_SIZE as u64,
            threshold_seconds,
        }
    }

    /// The progress of a command that stops when its estimate is precise enough, within a
    /// budget of `evaluations` model evaluations: a count on a terminal, and, after 30 s of
    /// work, the one-line estimate of how long the whole budget would take when that
    /// exceeds a minute.
    pub fn counter(
        command: &'static str,
        evaluations: u64,
        quiet: bool,
        threads: usize,
    ) -> Progress {
        let mut progress = Progress::new(command, evaluations, true, threads);
        progress.budget = true;
        if !quiet && std::io::stderr().is_terminal() {
            progress.bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            progress.bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {human_pos} model evaluations",
                )
                .expect("valid template"),
            );
        }
        progress
    }

    /// `samples` more are done.
    pub fn inc(&self, samples: u64) {
        self.bar.inc(samples);
        let done = self.done.fetch_add(samples, Ordering::Relaxed) + samples;
        if self.estimated.load(Ordering::Relaxed) {
            return;
        }
        let elapsed = self.started.elapsed().as_secs_f64();
        if done < self.settled && elapsed < ESTIMATE_SETTLE_SECONDS {
            return;
        }
        // A budget is an upper bound that most estimates stop far short of: said only when
        // the command has been at it for a while.
        if self.budget && elapsed < BUDGET_NOTE_SECONDS.min(self.threshold_seconds) {
            return;
        }
        if self.estimated.swap(true, Ordering::Relaxed) || done >= self.total {
            return;
        }
        let total_seconds = elapsed * self.total as f64 / done as f64;
        if total_seconds > self.threshold_seconds && self.budget {
            let line = format!(
                "{}: the budget of {} model evaluations would take about {} at the pace of the first {}; the estimate stops sooner when precise enough (--precision, --max-evaluations)",
                self.command,
                rvtol_engine::format::group_thousands(self.total),
                human_duration(total_seconds),
                rvtol_engine::format::group_thousands(done)
            );
            self.bar.suspend(|| note(&line));
        } else if total_seconds > self.threshold_seconds {
            let line = format!(
                "{}: {} samples will take about {} at the pace of the first {}; fewer --samples take less",
                self.command,
                rvtol_engine::format::group_thousands(self.total),
                human_duration(total_seconds),
                rvtol_engine::format::group_thousands(done)
            );
            self.bar.suspend(|| note(&line));
        }
    }

    pub fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }
}
