//! The Slurm job scripts (`scripts/slurm/`) end to end on a real cluster: a frame rendered
//! by `submit.sh` as a job array of tiles, or of sample ranges, and merged by the job that
//! depends on it equals a one-process `cltrace render` of it byte for byte; a failed task
//! fails the merge with a message naming it, and re-running only that task completes it.
//!
//! They need a cluster and `CLTRACE_SLURM=1`: CI starts a one-node cluster on this machine
//! (`scripts/slurm/local-cluster.sh start`, which also offers two stand-in GPUs) and sets
//! it. Without it they print a notice, and fail under CI (`CI` set).

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::command::{BIN, cltrace, run, succeeded, text};

/// How long a job may take to end before the test gives up: far beyond the seconds these
/// need, even on a loaded 2-core machine.
const PATIENCE: Duration = Duration::from_secs(180);

/// The frame: small, path traced, a few samples.
const SIZE: [&str; 4] = ["--width", "64", "--height", "48"];
const SPP: &str = "4";

/// Whether to test: `CLTRACE_SLURM=1`, else a notice (a failure under CI).
fn cluster() -> bool {
    if std::env::var_os("CLTRACE_SLURM").is_some_and(|v| v == "1") {
        return true;
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "CI must test the Slurm job scripts: start a cluster (scripts/slurm/local-cluster.sh \
         start) and set CLTRACE_SLURM=1"
    );
    eprintln!(
        "notice: CLTRACE_SLURM is not 1: the Slurm job scripts are not tested \
         (scripts/slurm/README.md says how to start a cluster on this machine)"
    );
    false
}

/// The device of the jobs and of the reference render: the same for both, so that the
/// images can be equal to the bit.
fn device() -> String {
    std::env::var("CLTRACE_DEVICE").unwrap_or_else(|_| "cpu".into())
}

/// A scene of a few thousand triangles under the sky, written into `dir`.
fn scene(dir: &Path) -> PathBuf {
    let path = dir.join("scene.toml");
    std::fs::write(
        &path,
        "[generator]\nkind = \"sphereflake\"\nlevels = 1\nsubdivisions = 1\nground = 8\n\n\
         [render]\nshade = \"path\"\n",
    )
    .unwrap();
    path
}

/// `cltrace render` of the whole frame in one process, to `output`.
fn reference(scene: &Path, flags: &[&str], output: &Path) {
    let mut cmd = cltrace();
    cmd.arg("render")
        .arg(scene)
        .args(SIZE)
        .args(["--spp", SPP])
        .args(flags)
        .arg("-o")
        .arg(output)
        .env("CLTRACE_DEVICE", device());
    succeeded(&run(cmd));
}

/// The jobs `submit.sh` submitted, as it printed them.
struct Jobs {
    render: String,
    merge: String,
    report: String,
}

/// Runs `submit.sh` with `args` and the environment the tests give `cltrace` (the jobs
/// inherit it), and reads the job ids it printed.
fn submit<S: AsRef<OsStr>>(args: &[S]) -> Jobs {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm/submit.sh");
    let mut cmd = Command::new("bash");
    cmd.arg(script).args(args);
    for (key, value) in cltrace().get_envs() {
        cmd.env(key, value.expect("cltrace() sets, never removes"));
    }
    cmd.env("CLTRACE_DEVICE", device());
    let out = cmd.output().expect("bash runs");
    assert!(
        out.status.success(),
        "submit.sh failed with {:?}\nstdout: {}\nstderr: {}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
    let stdout = text(&out.stdout);
    let id = |kind: &str| {
        stdout
            .lines()
            .find_map(|line| line.strip_prefix(&format!("{kind}: job ")))
            .and_then(|rest| rest.split([',', ' ']).next())
            .unwrap_or_else(|| panic!("submit.sh printed no {kind} job: {stdout}"))
            .to_string()
    };
    Jobs {
        render: id("render"),
        merge: id("merge"),
        report: id("report"),
    }
}

/// `scontrol show job -o ID`: a line per job (per task of an array).
fn show(job: &str) -> Vec<String> {
    let out = Command::new("scontrol")
        .args(["show", "job", "-o", job])
        .output()
        .expect("scontrol runs (is Slurm installed? scripts/slurm/local-cluster.sh)");
    assert!(
        out.status.success(),
        "scontrol show job {job}: {}",
        text(&out.stderr)
    );
    text(&out.stdout).lines().map(str::to_string).collect()
}

/// `KEY=value` of a line of `scontrol show job -o`.
fn field<'a>(line: &'a str, key: &str) -> &'a str {
    line.split_whitespace()
        .find_map(|word| word.strip_prefix(key)?.strip_prefix('='))
        .unwrap_or_else(|| panic!("no {key} in {line}"))
}

/// Waits until the job (every task of an array) has ended; returns its lines.
fn wait(job: &str) -> Vec<String> {
    let deadline = Instant::now() + PATIENCE;
    loop {
        let lines = show(job);
        let ended = |line: &String| {
            !matches!(
                field(line, "JobState"),
                "PENDING" | "RUNNING" | "CONFIGURING" | "COMPLETING" | "SUSPENDED" | "REQUEUED"
            )
        };
        if lines.iter().all(ended) {
            return lines;
        }
        assert!(
            Instant::now() < deadline,
            "job {job} did not end within {PATIENCE:?}:\n{}",
            lines.join("\n")
        );
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// Every log in the parts folder, for failure messages.
fn logs(parts: &Path) -> String {
    let mut names: Vec<PathBuf> = std::fs::read_dir(parts.join("logs"))
        .map(|dir| dir.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    names.sort();
    names
        .iter()
        .map(|p| {
            let body = std::fs::read_to_string(p).unwrap_or_default();
            format!("--- {}\n{body}", p.display())
        })
        .collect()
}

/// The tasks' (array index, state) pairs of the array job `job`, once they have ended.
fn tasks(job: &str) -> Vec<(u32, String)> {
    let mut tasks: Vec<(u32, String)> = wait(job)
        .iter()
        .map(|line| {
            let index = field(line, "ArrayTaskId").parse().expect("one task a line");
            (index, field(line, "JobState").to_string())
        })
        .collect();
    tasks.sort();
    tasks
}

/// Waits for `jobs`: every task and the merge completed, the failure report cancelled as
/// the dependency it can no longer meet.
fn completed(jobs: &Jobs, parts: &Path) {
    let tasks = tasks(&jobs.render);
    let merge = wait(&jobs.merge).remove(0);
    let report = wait(&jobs.report).remove(0);
    assert!(
        tasks.iter().all(|(_, state)| state == "COMPLETED")
            && field(&merge, "JobState") == "COMPLETED",
        "render tasks {tasks:?}, merge {merge}\n{}",
        logs(parts)
    );
    assert_eq!(
        (field(&report, "JobState"), field(&report, "Reason")),
        ("CANCELLED", "DependencyNeverSatisfied"),
        "{report}"
    );
}

/// The files are equal byte for byte.
#[track_caller]
fn same_bytes(merged: &Path, reference: &Path) {
    let (a, b) = (
        std::fs::read(merged).unwrap(),
        std::fs::read(reference).unwrap(),
    );
    let first = a.iter().zip(&b).position(|(x, y)| x != y);
    assert!(
        a == b,
        "{} ({} bytes) differs from the one-process render {} ({} bytes), first at byte {first:?}",
        merged.display(),
        a.len(),
        reference.display(),
        b.len()
    );
}

/// Whether the cluster's nodes offer GPUs as gres (the local cluster's stand-ins do).
fn has_gpus() -> bool {
    let out = Command::new("scontrol")
        .args(["show", "node", "-o"])
        .output()
        .expect("scontrol runs");
    text(&out.stdout).contains("Gres=gpu:")
}

#[test]
fn tiles_merge_to_the_one_process_image() {
    if !cluster() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    reference(&scene, &[], &dir.path().join("reference.exr"));
    let output = dir.path().join("tiles.exr");
    let mut args: Vec<&OsStr> = vec![scene.as_os_str(), "-o".as_ref(), output.as_os_str()];
    args.extend(SIZE.map(OsStr::new));
    args.extend(
        [
            "--spp",
            SPP,
            "--tasks",
            "4",
            "--split",
            "tiles",
            "--cltrace",
            BIN,
        ]
        .map(OsStr::new),
    );
    // A GPU a task where the cluster has them: Slurm gives each task its own.
    let gpus = has_gpus();
    if gpus {
        args.extend(["--gpus-per-task", "1"].map(OsStr::new));
    } else {
        eprintln!("notice: the cluster offers no GPUs: --gpus-per-task is not tested");
    }
    let jobs = submit(&args);
    let parts = dir.path().join("tiles.exr.parts");
    completed(&jobs, &parts);
    same_bytes(&output, &dir.path().join("reference.exr"));
    for task in 0..4 {
        let log =
            std::fs::read_to_string(parts.join(format!("logs/render-{}_{task}.out", jobs.render)))
                .unwrap();
        assert!(log.contains(&format!("task {task} of 4 on ")), "{log}");
        if gpus {
            let visible = log
                .split("CUDA_VISIBLE_DEVICES=")
                .nth(1)
                .and_then(|rest| rest.lines().next())
                .unwrap_or_default();
            assert!(
                !visible.is_empty() && visible.chars().all(|c| c.is_ascii_digit()),
                "task {task} was given no GPU by Slurm: {log}"
            );
        }
    }
}

#[test]
fn sample_ranges_merge_to_the_one_process_image() {
    if !cluster() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    // On the host: the merge's exactness does not depend on an OpenCL device.
    let flags = ["--method", "cpu-bvh"];
    reference(&scene, &flags, &dir.path().join("reference.png"));
    let output = dir.path().join("samples.png");
    let mut args: Vec<&OsStr> = vec![scene.as_os_str(), "-o".as_ref(), output.as_os_str()];
    args.extend(SIZE.map(OsStr::new));
    args.extend(
        [
            "--spp",
            SPP,
            "--tasks",
            "2",
            "--split",
            "samples",
            "--cltrace",
            BIN,
        ]
        .map(OsStr::new),
    );
    args.push("--".as_ref());
    args.extend(flags.map(OsStr::new));
    let jobs = submit(&args);
    completed(&jobs, &dir.path().join("samples.png.parts"));
    same_bytes(&output, &dir.path().join("reference.png"));
}

#[test]
fn a_failed_task_fails_the_merge_and_rerunning_it_completes_the_frame() {
    if !cluster() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    reference(&scene, &[], &dir.path().join("reference.exr"));
    // cltrace, except that task 1 fails the first time, as on a broken node.
    let flaky = dir.path().join("flaky-cltrace");
    std::fs::write(
        &flaky,
        format!(
            "#!/bin/sh\nif [ \"$SLURM_ARRAY_TASK_ID\" = 1 ] && mkdir \"$0.failed\" 2>/dev/null; \
             then echo 'error: task 1 fails on purpose' >&2; exit 1; fi\nexec '{BIN}' \"$@\"\n"
        ),
    )
    .unwrap();
    std::fs::set_permissions(&flaky, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let output = dir.path().join("frame.exr");
    let parts = dir.path().join("frame.exr.parts");
    // Three tasks share four samples: 1, 1 and 2.
    let mut args: Vec<&OsStr> = vec![scene.as_os_str(), "-o".as_ref(), output.as_os_str()];
    args.extend(SIZE.map(OsStr::new));
    args.extend(["--spp", SPP, "--tasks", "3", "--split", "samples"].map(OsStr::new));
    args.extend(["--cltrace".as_ref(), flaky.as_os_str()]);
    let jobs = submit(&args);

    let first = tasks(&jobs.render);
    let merge = wait(&jobs.merge).remove(0);
    let report = wait(&jobs.report).remove(0);
    let states: Vec<&str> = first.iter().map(|(_, s)| s.as_str()).collect();
    assert_eq!(
        states,
        ["COMPLETED", "FAILED", "COMPLETED"],
        "{}",
        logs(&parts)
    );
    assert_eq!(
        (field(&merge, "JobState"), field(&merge, "Reason")),
        ("CANCELLED", "DependencyNeverSatisfied"),
        "{merge}"
    );
    assert_eq!(field(&report, "JobState"), "FAILED", "{report}");
    let message =
        std::fs::read_to_string(parts.join(format!("logs/merge-{}.out", jobs.report))).unwrap();
    for part in [
        "merge: missing the parts of task 1 (1 of 3 tasks",
        "error: task 1 fails on purpose",
        "--rerun-failed",
        "sbatch --array=1 ",
    ] {
        assert!(
            message.contains(part),
            "no {part:?} in the report:\n{message}"
        );
    }
    assert!(!output.exists(), "an image from missing parts");

    let rerun = submit(&["--rerun-failed".as_ref(), parts.as_os_str()]);
    let again = tasks(&rerun.render);
    assert_eq!(
        again.iter().map(|(i, _)| *i).collect::<Vec<_>>(),
        [1],
        "only the failed task"
    );
    completed(&rerun, &parts);
    same_bytes(&output, &dir.path().join("reference.exr"));
}
