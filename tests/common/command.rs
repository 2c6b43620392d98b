//! Running the `cltrace` binary. Every run the tests make goes through [`cltrace`], which
//! points the tuning cache (`CLTRACE_TUNE_CACHE`) at a file that is never written, and
//! `HOME` and `XDG_CACHE_HOME` into a folder of the build's own, so that no run reads (or
//! writes) the user's `~/.cache/cltrace/tune.toml`. A run gets the environment the test
//! process started with, not the one OpenCL drivers loaded into it have changed since.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::{Command, Output};
use std::sync::OnceLock;

pub const BIN: &str = env!("CARGO_BIN_EXE_cltrace");

/// The home folder the runs see: `cltrace-home` under the build's test scratch folder.
/// Nothing the tests run writes a tuning cache there (a test that tunes names its own
/// `--cache`); device drivers may keep their kernel caches in it.
pub fn test_home() -> PathBuf {
    let home = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cltrace-home");
    std::fs::create_dir_all(&home).expect("the test home folder can be made");
    home
}

/// Where the runs' `CLTRACE_TUNE_CACHE` points: a file that does not exist.
pub fn no_tune_cache() -> PathBuf {
    test_home().join("no-tune-cache.toml")
}

/// The `cltrace` binary, isolated from the user's caches (see the module's documentation).
/// A test that wants a tuning cache sets `CLTRACE_TUNE_CACHE` again.
pub fn cltrace() -> Command {
    let home = test_home();
    let mut cmd = Command::new(BIN);
    cmd.env_clear()
        .envs(initial_environment().iter().cloned())
        .env("HOME", &home)
        .env("XDG_CACHE_HOME", home.join(".cache"))
        .env("CLTRACE_TUNE_CACHE", no_tune_cache());
    cmd
}

/// `inner` (made by [`cltrace`]) run through another program (`oclgrind`, a shell):
/// `wrapper` with its own `args`, then `inner`'s program and arguments, with `inner`'s
/// environment and folder. [`cltrace`] clears the environment it starts from, so `inner`'s
/// variables are all it has: a variable removed from it is not listed.
pub fn wrapped<S: AsRef<std::ffi::OsStr>>(inner: &Command, wrapper: &str, args: &[S]) -> Command {
    let mut cmd = Command::new(wrapper);
    cmd.env_clear()
        .args(args)
        .arg(inner.get_program())
        .args(inner.get_args());
    if let Some(dir) = inner.get_current_dir() {
        cmd.current_dir(dir);
    }
    for (key, value) in inner.get_envs() {
        match value {
            Some(v) => cmd.env(key, v),
            None => cmd.env_remove(key),
        };
    }
    cmd
}

/// Runs `cmd` to the end.
pub fn run(mut cmd: Command) -> Output {
    cmd.output().expect("the cltrace binary runs")
}

pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Fails the test, showing both streams, unless the run succeeded.
#[track_caller]
pub fn succeeded(out: &Output) {
    assert!(
        out.status.success(),
        "cltrace failed with {:?}\nstdout: {}\nstderr: {}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
}

/// The environment the test process started with (`/proc/self/environ`, which later
/// changes leave alone; the current one where that cannot be read). Regression: on the GPU
/// host a driver loaded into the tests rewrote `OCL_ICD_FILENAMES` without NVIDIA's
/// library, and every run spawned after that found no GPU.
fn initial_environment() -> &'static [(OsString, OsString)] {
    static INITIAL: OnceLock<Vec<(OsString, OsString)>> = OnceLock::new();
    INITIAL.get_or_init(|| {
        use std::os::unix::ffi::OsStrExt;
        let Ok(block) = std::fs::read("/proc/self/environ") else {
            return std::env::vars_os().collect();
        };
        block
            .split(|&b| b == 0)
            .filter_map(|entry| {
                let eq = entry.iter().position(|&b| b == b'=')?;
                let (key, value) = (&entry[..eq], &entry[eq + 1..]);
                (!key.is_empty()).then(|| {
                    let os = |b: &[u8]| std::ffi::OsStr::from_bytes(b).to_os_string();
                    (os(key), os(value))
                })
            })
            .collect()
    })
}
