//! Progress bars (indicatif) for anything that runs over a second; silent when stderr is not a
//! terminal, so CI logs stay short.

use indicatif::{ProgressBar, ProgressStyle};
use std::cell::RefCell;
use std::time::{Duration, Instant};

/// One stage's wall time, as `run.json` records it (`meta.stages`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StageTime {
    /// The stage's message.
    pub stage: String,
    /// Seconds from its start to its end, repeats included.
    pub wall_s: f64,
}

thread_local! {
    /// The run in progress on this thread: its start and the stages timed so far.
    static RUN: RefCell<Option<(Instant, Vec<StageTime>)>> = const { RefCell::new(None) };
}

/// Starts timing a run on this thread: [`run_times`] reports the wall time since this call and
/// every stage timed on this thread since.
pub fn begin_run() {
    RUN.with(|r| *r.borrow_mut() = Some((Instant::now(), Vec::new())));
}

/// The wall time of the run begun on this thread ([`begin_run`]) and its stages so far; `None`
/// when none was begun.
pub fn run_times() -> Option<(f64, Vec<StageTime>)> {
    RUN.with(|r| {
        r.borrow()
            .as_ref()
            .map(|(t, stages)| (t.elapsed().as_secs_f64(), stages.clone()))
    })
}

fn record(msg: &str, started: Instant) {
    let wall_s = started.elapsed().as_secs_f64();
    RUN.with(|r| {
        if let Some((_, stages)) = r.borrow_mut().as_mut() {
            stages.push(StageTime {
                stage: msg.to_string(),
                wall_s,
            });
        }
    });
}

/// A bar of `len` steps with a message.
pub fn bar(len: u64, msg: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template(
            "{spinner} {msg:<28} [{bar:30}] {pos}/{len} {per_sec} eta {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    pb.set_message(msg.to_string());
    pb
}

/// Runs `f` under a spinner named `msg`, printing the elapsed time when done; returns its value
/// and the wall time in seconds.
pub fn stage<T>(msg: &str, f: impl FnOnce() -> T) -> (T, f64) {
    let pb = ProgressBar::new_spinner();
    pb.set_message(msg.to_string());
    pb.enable_steady_tick(Duration::from_millis(120));
    let t = Instant::now();
    let v = f();
    let s = t.elapsed().as_secs_f64();
    record(msg, t);
    pb.finish_and_clear();
    eprintln!("  {msg:<40} {:>9.3} s", s);
    (v, s)
}

/// Like [`stage`], but runs `f` `repeats` times (at least once) and reports the fastest run:
/// the first run warms caches and thread pools, and the minimum is the least noisy estimate of
/// the cost on a shared machine. Returns the last value.
pub fn stage_best_of<T>(msg: &str, repeats: usize, mut f: impl FnMut() -> T) -> (T, f64) {
    let pb = ProgressBar::new_spinner();
    pb.set_message(msg.to_string());
    pb.enable_steady_tick(Duration::from_millis(120));
    let mut best = f64::INFINITY;
    let mut value = None;
    let started = Instant::now();
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        value = Some(f());
        best = best.min(t.elapsed().as_secs_f64());
    }
    record(msg, started);
    pb.finish_and_clear();
    eprintln!("  {msg:<40} {best:>9.3} s (best of {})", repeats.max(1));
    (value.expect("ran at least once"), best)
}

/// Times `f` as [`stage_best_of`] does when it is short: the first run decides; if it took less
/// than `short_s` seconds, `f` runs `repeats − 1` more times and the fastest run is reported
/// (noise on a shared machine matters most for short stages); a long first run is reported as
/// is. Returns the last value, the time, and the number of runs.
pub fn stage_adaptive<T, E>(
    msg: &str,
    short_s: f64,
    repeats: usize,
    mut f: impl FnMut() -> Result<T, E>,
) -> Result<(T, f64, usize), E> {
    let pb = ProgressBar::new_spinner();
    pb.set_message(msg.to_string());
    pb.enable_steady_tick(Duration::from_millis(120));
    let t = Instant::now();
    let mut value = f()?;
    let mut best = t.elapsed().as_secs_f64();
    let mut runs = 1;
    if best < short_s {
        for _ in 1..repeats.max(1) {
            let t = Instant::now();
            value = f()?;
            best = best.min(t.elapsed().as_secs_f64());
            runs += 1;
        }
    }
    record(msg, t);
    pb.finish_and_clear();
    eprintln!("  {msg:<40} {best:>9.3} s (best of {runs})");
    Ok((value, best, runs))
}
