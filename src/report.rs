//! What cltrace tells the user on stderr: stage timings, details, progress. stdout is kept
//! for data (device lists, tables).

use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Writes data (a table, a device list) to stdout. A reader that has gone (`| head`) ends
/// the process quietly with status 0, as Unix tools do, instead of a panic.
pub fn print_data(text: &str) {
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|()| out.flush())
        && e.kind() == std::io::ErrorKind::BrokenPipe
    {
        std::process::exit(0);
    }
}

/// Writes a line to stderr. Messages are best effort: with stderr closed the work goes on
/// without them, never panics.
pub fn print_message(line: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}

/// Seconds between progress lines when stderr is not a terminal (a render farm's log):
/// `CLTRACE_PROGRESS_SECONDS`, else this.
pub const PROGRESS_SECONDS: f64 = 5.0;

/// Progress of long work on stderr: a bar on a terminal; elsewhere (a log file, a pipe) a
/// line every [`PROGRESS_SECONDS`], the first once that much time has passed, so that short
/// work prints none.
pub(crate) struct Progress {
    bar: Option<ProgressBar>,
    log: Option<Mutex<Log>>,
}

struct Log {
    what: String,
    unit: &'static str,
    len: u64,
    pos: u64,
    message: String,
    start: Instant,
    last: Instant,
    every: Duration,
}

impl Progress {
    /// Progress through `len` `unit`s (`rows`, `samples`) of `what` (`tracing on the CPU`);
    /// nothing at all when `show` is false.
    pub(crate) fn new(show: bool, what: impl Into<String>, len: u64, unit: &'static str) -> Self {
        let what = what.into();
        if !show {
            return Progress {
                bar: None,
                log: None,
            };
        }
        if std::io::stderr().is_terminal() {
            let template =
                format!("{{prefix}} [{{bar:30}}] {{pos}}/{{len}} {unit}{{msg}}, {{eta}} left");
            let bar = ProgressBar::new(len)
                .with_style(ProgressStyle::with_template(&template).expect("valid template"))
                .with_prefix(what);
            return Progress {
                bar: Some(bar),
                log: None,
            };
        }
        let every = std::env::var("CLTRACE_PROGRESS_SECONDS")
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .filter(|s| s.is_finite() && *s >= 0.0)
            .unwrap_or(PROGRESS_SECONDS);
        let now = Instant::now();
        Progress {
            bar: None,
            log: Some(Mutex::new(Log {
                what,
                unit,
                len,
                pos: 0,
                message: String::new(),
                start: now,
                last: now,
                every: Duration::from_secs_f64(every),
            })),
        }
    }

    /// Sets how much is done.
    pub(crate) fn set_position(&self, pos: u64) {
        self.update(|log| log.pos = pos, |bar| bar.set_position(pos));
    }

    /// Adds `n` to what is done.
    pub(crate) fn inc(&self, n: u64) {
        self.update(|log| log.pos += n, |bar| bar.inc(n));
    }

    /// Sets the note after the count (`12.3 Mrays/s`).
    pub(crate) fn set_message(&self, message: String) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!(", {message}"));
        } else if let Some(log) = &self.log {
            // The note goes with the next count; it prints nothing on its own.
            log.lock().unwrap_or_else(|e| e.into_inner()).message = message;
        }
    }

    fn update(&self, log_update: impl FnOnce(&mut Log), bar_update: impl FnOnce(&ProgressBar)) {
        if let Some(bar) = &self.bar {
            bar_update(bar);
        } else if let Some(log) = &self.log {
            let mut log = log.lock().unwrap_or_else(|e| e.into_inner());
            log_update(&mut log);
            let now = Instant::now();
            if now - log.last >= log.every && log.pos < log.len {
                log.last = now;
                print_message(&log.line(now));
            }
        }
    }

    /// Runs `f` (which prints) with the bar out of the way.
    pub(crate) fn suspend<T>(&self, f: impl FnOnce() -> T) -> T {
        match &self.bar {
            Some(bar) => bar.suspend(f),
            None => f(),
        }
    }

    /// Clears the bar (a log keeps its lines).
    pub(crate) fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
    }
}

impl Log {
    /// `sampling: 12/64 samples, 3.1 Mrays/s, 40 s left`
    fn line(&self, now: Instant) -> String {
        let elapsed = (now - self.start).as_secs_f64();
        let mut line = format!("{}: {}/{} {}", self.what, self.pos, self.len, self.unit);
        if !self.message.is_empty() {
            line.push_str(", ");
            line.push_str(&self.message);
        }
        if self.pos > 0 {
            let left = elapsed / self.pos as f64 * (self.len - self.pos) as f64;
            line.push_str(&format!(", {left:.0} s left"));
        }
        line
    }
}

/// How much to say on stderr.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verbosity {
    /// Errors only.
    Quiet,
    /// A summary line and the stage timings.
    #[default]
    Normal,
    /// Also mesh, device and acceleration-structure details.
    Verbose,
}

impl Verbosity {
    /// The level `--quiet` and `--verbose` ask for; `--quiet` wins when both are given.
    pub fn from_flags(quiet: bool, verbose: bool) -> Self {
        if quiet {
            Verbosity::Quiet
        } else if verbose {
            Verbosity::Verbose
        } else {
            Verbosity::Normal
        }
    }

    /// Prints a line at normal verbosity and above.
    pub(crate) fn say(self, line: impl AsRef<str>) {
        if self >= Verbosity::Normal {
            print_message(line.as_ref());
        }
    }

    /// Prints a line with `--verbose` only.
    pub(crate) fn detail(self, line: impl AsRef<str>) {
        if self.shows_details() {
            print_message(line.as_ref());
        }
    }

    /// Whether [`Verbosity::detail`] prints: for details that cost time to compute.
    pub(crate) fn shows_details(self) -> bool {
        self >= Verbosity::Verbose
    }

    pub(crate) fn progress(self) -> bool {
        self >= Verbosity::Normal
    }
}

/// Wall or device times of the stages of one run, in milliseconds, in the order they ran.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timings {
    stages: Vec<(&'static str, f64)>,
}

impl Timings {
    /// Runs `f`, recording its wall time under `stage`.
    pub(crate) fn time<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.add(stage, start.elapsed().as_secs_f64() * 1e3);
        out
    }

    /// Adds `ms` to `stage` (created at the end if new).
    pub(crate) fn add(&mut self, stage: &'static str, ms: f64) {
        match self.stages.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, total)) => *total += ms,
            None => self.stages.push((stage, ms)),
        }
    }

    /// The stages' times together, ms.
    pub(crate) fn total_ms(&self) -> f64 {
        self.stages.iter().map(|&(_, ms)| ms).sum()
    }

    pub(crate) fn get(&self, stage: &str) -> Option<f64> {
        self.stages
            .iter()
            .find(|(s, _)| *s == stage)
            .map(|&(_, ms)| ms)
    }

    /// The stages and their times, in the order they ran.
    pub(crate) fn stages(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        self.stages.iter().copied()
    }

    /// Ends the record of a run that took `wall_ms`: what no stage counted (the gaps
    /// between them) becomes the stage `other`, so that the stages add up to the wall time.
    pub(crate) fn close(&mut self, wall_ms: f64) {
        let counted: f64 = self.stages.iter().map(|(_, ms)| ms).sum();
        self.add("other", (wall_ms - counted).max(0.0));
    }

    /// `load 12.3 ms, build 4.0 ms, ...`
    pub(crate) fn summary(&self) -> String {
        self.stages
            .iter()
            .map(|(s, ms)| format!("{s} {}", format_ms(*ms)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Milliseconds with three significant digits, e.g. `0.0412 ms`, `3.14 ms`, `2718 ms`.
pub(crate) fn format_ms(ms: f64) -> String {
    if ms >= 100.0 {
        format!("{ms:.0} ms")
    } else if ms >= 10.0 {
        format!("{ms:.1} ms")
    } else if ms >= 1.0 {
        format!("{ms:.2} ms")
    } else {
        format!("{ms:.3} ms")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_accumulate_in_order() {
        let mut t = Timings::default();
        t.add("load", 1.0);
        t.add("kernel", 2.0);
        t.add("load", 0.5);
        assert_eq!(t.get("load"), Some(1.5));
        assert_eq!(t.summary(), "load 1.50 ms, kernel 2.00 ms");
    }
}
