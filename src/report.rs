//! What cltrace tells the user on stderr: stage timings, details, progress. stdout is kept
//! for data (device lists, tables).

use std::io::Write;
use std::time::Instant;

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
        if self >= Verbosity::Verbose {
            print_message(line.as_ref());
        }
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

    pub(crate) fn get(&self, stage: &str) -> Option<f64> {
        self.stages
            .iter()
            .find(|(s, _)| *s == stage)
            .map(|&(_, ms)| ms)
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
