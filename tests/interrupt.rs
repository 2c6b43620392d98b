//! Ctrl-C, as `SIGINT` sent to the running binary: it stops at the next band, sample pass
//! or measurement, writes a partial image only when every pixel has a sample (exit status
//! 3), and otherwise writes nothing and replaces nothing (exit status 130). Each test waits
//! for a line the run prints at a known point before it sends the signal, so what the run
//! has done by then is known; the waits have generous limits, which only a hung run reaches.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::Duration;

use crate::common::command::{cltrace, text};

/// How long a run may take to reach a line or to end after the signal before the test
/// gives up on it: far beyond what any of these runs needs.
const PATIENCE: Duration = Duration::from_secs(120);

/// A running `cltrace` whose stderr lines arrive on a channel.
struct Running {
    child: Child,
    lines: Receiver<String>,
    seen: Vec<String>,
}

impl Running {
    fn start(mut cmd: Command) -> Running {
        cmd.stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .env_remove("CLTRACE_DEVICE")
            .env("CLTRACE_PROGRESS_SECONDS", "0");
        let mut child = cmd.spawn().expect("the cltrace binary starts");
        let stderr = child.stderr.take().unwrap();
        let (send, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines() {
                let Ok(line) = line else { break };
                if send.send(line).is_err() {
                    break;
                }
            }
        });
        Running {
            child,
            lines,
            seen: Vec::new(),
        }
    }

    /// Waits for a stderr line with `part` in it.
    fn wait_for(&mut self, part: &str) {
        let deadline = std::time::Instant::now() + PATIENCE;
        while std::time::Instant::now() < deadline {
            match self.lines.recv_timeout(Duration::from_millis(100)) {
                Ok(line) => {
                    let found = line.contains(part);
                    self.seen.push(line);
                    if found {
                        return;
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                Err(_) => break,
            }
        }
        let _ = self.child.kill();
        panic!("no line with {part:?} came; stderr: {:#?}", self.seen);
    }

    /// Sends `SIGINT`, as Ctrl-C does (through the shell's `kill`, which every system has).
    fn interrupt(&self) {
        let status = Command::new("sh")
            .arg("-c")
            .arg(format!("kill -INT {}", self.child.id()))
            .status()
            .expect("sh runs");
        assert!(status.success(), "kill -INT failed");
    }

    /// Waits for the end; returns its status, stdout and all of stderr.
    fn finish(mut self) -> (ExitStatus, String, String) {
        let deadline = std::time::Instant::now() + PATIENCE;
        let status = loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                break status;
            }
            if std::time::Instant::now() > deadline {
                let _ = self.child.kill();
                panic!("the run did not end after the interrupt: {:#?}", self.seen);
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        let mut stdout = Vec::new();
        std::io::Read::read_to_end(self.child.stdout.as_mut().unwrap(), &mut stdout).unwrap();
        self.seen.extend(self.lines.iter());
        (status, text(&stdout), self.seen.join("\n"))
    }
}

fn render(dir: &Path, image: &Path, args: &[&str]) -> Command {
    let mut cmd = cltrace();
    cmd.current_dir(dir)
        .arg("render")
        .arg("-o")
        .arg(image)
        .args(args);
    cmd
}

/// Ctrl-C before the first sample pass still loaded, built, uploaded and wrote an almost
/// empty image over the output, with exit status 0.
#[test]
fn interrupting_before_the_first_sample_pass_replaced_the_image_with_an_empty_one() {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("render.png");
    std::fs::write(&image, b"the good image of an earlier run").unwrap();
    // The mesh line comes after the load; the first pass of 4 million path samples on the
    // host takes seconds, so the signal comes before it ends.
    let mut cmd = render(
        dir.path(),
        &image,
        &["--method", "cpu-bvh", "--shade", "path"],
    );
    cmd.args(["--width", "2048", "--height", "2048", "--spp", "64", "-v"]);
    let mut running = Running::start(cmd);
    running.wait_for("mesh:");
    running.interrupt();
    let (status, _, stderr) = running.finish();
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    assert!(
        stderr.contains("error: interrupted: nothing written"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read(&image).unwrap(),
        b"the good image of an earlier run"
    );
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1, "files left behind: {names:?}");
}

/// Interrupted after whole sample passes, the image holds the samples taken and the exit
/// status (3) says it is partial: on the host and on the OpenCL device.
#[test]
fn interrupting_sampling_writes_the_samples_taken_with_status_3() {
    for method in ["cpu-bvh", "cl-bvh"] {
        let dir = tempfile::tempdir().unwrap();
        let image = dir.path().join("partial.pfm");
        let json = dir.path().join("run.json");
        let mut cmd = render(dir.path(), &image, &["--method", method, "--shade", "path"]);
        cmd.args(["--width", "32", "--height", "24", "--spp", "65536"]);
        cmd.arg("--json").arg(&json);
        let mut running = Running::start(cmd);
        running.wait_for("sampling: ");
        running.interrupt();
        let (status, _, stderr) = running.finish();
        assert_eq!(status.code(), Some(3), "{method}: {stderr}");
        assert!(
            stderr.contains("interrupted:") && stderr.contains("of 65536 samples per pixel"),
            "{method}: {stderr}"
        );
        let bytes = std::fs::read(&image).unwrap();
        let header = b"PF\n32 24\n-1.0\n";
        assert_eq!(&bytes[..header.len()], header);
        let floats: Vec<f32> = bytes[header.len()..]
            .chunks(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(floats.len(), 32 * 24 * 3);
        assert!(
            floats.iter().all(|v| v.is_finite()) && floats.iter().any(|&v| v > 0.0),
            "{method}: the image holds no light"
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(summary["complete"], false);
        let taken = summary["samples_per_pixel"].as_f64().unwrap();
        assert!((1.0..65536.0).contains(&taken), "{method}: {taken}");
    }
}

/// The first Ctrl-C was ignored by `bench`: it ran the whole matrix. Interrupted, it prints
/// the rows measured and exits with 3.
#[test]
fn the_first_ctrl_c_was_ignored_by_bench() {
    let dir = tempfile::tempdir().unwrap();
    let mut cmd = cltrace();
    cmd.current_dir(dir.path()).args([
        "bench",
        "--methods",
        "cpu-bvh",
        "--rays",
        "primary",
        "--resolutions",
        "16x12,1920x1080",
        "--warmup",
        "0",
        "--repetitions",
        "1000",
    ]);
    let mut running = Running::start(cmd);
    // The line of the first run, the small one; the second runs a thousand frames.
    running.wait_for("bench: 1/2 runs");
    running.interrupt();
    let (status, stdout, stderr) = running.finish();
    assert_eq!(status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    let rows = stdout.lines().filter(|l| l.contains("16x12")).count();
    assert_eq!(rows, 1, "the measured row is not in the table: {stdout}");
    assert!(!stdout.contains("1920x1080"), "{stdout}");
}

/// The first Ctrl-C was ignored by `tune`. Interrupted, it saves nothing: a half-tuned
/// device's best is not known.
#[test]
fn the_first_ctrl_c_was_ignored_by_tune() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("tune.toml");
    let mut cmd = cltrace();
    cmd.current_dir(dir.path())
        .args(["tune", "--repetitions", "50", "--cache"])
        .arg(&cache);
    let mut running = Running::start(cmd);
    running.wait_for("tuning ");
    running.interrupt();
    let (status, _, stderr) = running.finish();
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("error: interrupted"), "{stderr}");
    assert!(!cache.exists(), "an interrupted tune wrote its cache");
}
