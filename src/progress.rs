//! Progress of long commands (`reference`, `bench`, `stress`, large imports): a bar with an ETA on a terminal,
//! plain periodic lines (every 10% or 30 s, once the work has run 5 s) when stderr is a log, so CI output stays
//! readable and a quick command prints nothing extra.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Work done out of a known total, safe to advance from many threads.
pub struct Progress {
    label: String,
    total: u64,
    done: AtomicU64,
    bar: Option<ProgressBar>,
    /// Plain mode: when and at which tenth the last line was printed.
    last_line: Mutex<(Instant, u64)>,
    start: Instant,
    quiet: bool,
}

impl Progress {
    /// A bar on a terminal, lines otherwise.
    pub fn new(label: &str, total: u64) -> Self {
        let terminal = std::io::stderr().is_terminal();
        Self::with_mode(label, total, terminal, false)
    }

    /// Progress nobody sees (tests, nested work).
    pub fn hidden(total: u64) -> Self {
        Self::with_mode("", total, false, true)
    }

    fn with_mode(label: &str, total: u64, terminal: bool, quiet: bool) -> Self {
        let bar = (terminal && !quiet).then(|| {
            let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
            let style = ProgressStyle::with_template("{prefix} [{bar:40}] {percent:>3}% {elapsed_precise} ETA {eta}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ");
            bar.set_style(style);
            bar.set_prefix(label.to_string());
            bar.enable_steady_tick(Duration::from_millis(250));
            bar
        });
        Progress {
            label: label.to_string(),
            total: total.max(1),
            done: AtomicU64::new(0),
            bar,
            last_line: Mutex::new((Instant::now(), 0)),
            start: Instant::now(),
            quiet,
        }
    }

    /// Marks `n` more units done.
    pub fn advance(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        if let Some(bar) = &self.bar {
            bar.set_position(done);
            return;
        }
        if self.quiet {
            return;
        }
        if self.start.elapsed() < Duration::from_secs(5) {
            return;
        }
        let tenth = done * 10 / self.total;
        let Ok(mut last) = self.last_line.try_lock() else { return };
        if tenth > last.1 || last.0.elapsed() >= Duration::from_secs(30) {
            *last = (Instant::now(), tenth.max(last.1));
            eprintln!("{}: {}%", self.label, (done * 100 / self.total).min(100));
        }
    }

    /// Prints a line above the bar (or just a line).
    pub fn println(&self, line: &str) {
        match &self.bar {
            Some(bar) => bar.println(line),
            None if !self.quiet => eprintln!("{line}"),
            None => {}
        }
    }

    /// Units done so far.
    pub fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }

    /// Removes the bar (its line is replaced by whatever the command prints next).
    pub fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_from_many_threads() {
        let progress = Progress::hidden(1000);
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| (0..250).for_each(|_| progress.advance(1)));
            }
        });
        assert_eq!(progress.done(), 1000);
    }
}
