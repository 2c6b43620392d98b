//! The bad-input corpus: every file in tests/bad_inputs/, plus a few made at run time (a
//! directory in place of a mesh, an unreadable file, a face line with millions of
//! vertices), rendered by the real binary. Each must exit with 2 and one `error:` line on
//! stderr that names the file, and leave nothing in the output folder: no image, no
//! temporary `.cltrace-*.tmp`.

use crate::common::command::cltrace;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Files whose error names another file than themselves: scene files whose mesh is at
/// fault.
const NAMES_ANOTHER_FILE: &[(&str, &str)] = &[
    ("missing_mesh.toml", "does_not_exist.obj"),
    ("mesh_refers_to_bad_mesh.toml", "coordinate_nan.obj"),
];

fn corpus() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/bad_inputs")
}

/// Renders `input` into an empty folder and returns a description of everything wrong
/// with the outcome (empty when it failed the right way).
fn check(input: &Path, expected_name: &str) -> Vec<String> {
    let out = tempfile::tempdir().unwrap();
    let png = out.path().join("out.png");
    let result = cltrace()
        .arg("render")
        .arg(input)
        .arg("-o")
        .arg(&png)
        .args(["--width", "32", "--height", "24", "--method", "cpu-bvh"])
        .env_remove("CLTRACE_DEVICE")
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("the cltrace binary runs");
    let stderr = String::from_utf8_lossy(&result.stderr).into_owned();
    let mut problems = Vec::new();
    if result.status.code() != Some(2) {
        problems.push(format!("exit status {:?}, not 2", result.status.code()));
    }
    let lines: Vec<&str> = stderr.lines().collect();
    if lines.len() != 1 || !stderr.ends_with('\n') || stderr.contains('\r') {
        problems.push(format!("stderr is not exactly one line: {stderr:?}"));
    }
    match lines.first() {
        Some(line) if line.starts_with("error:") && line.contains(expected_name) => {}
        _ => problems.push(format!(
            "stderr does not start with `error:` naming {expected_name}: {stderr:?}"
        )),
    }
    if stderr.contains("panicked") {
        problems.push(format!("it panicked: {stderr:?}"));
    }
    let left: Vec<String> = std::fs::read_dir(out.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    if !left.is_empty() {
        problems.push(format!("the output folder holds {left:?}"));
    }
    problems
}

/// Checks every case and reports all failures at once.
fn check_all(cases: &[(PathBuf, String)]) {
    let mut failures = Vec::new();
    for (input, name) in cases {
        let problems = check(input, name);
        if !problems.is_empty() {
            failures.push(format!("{}: {}", input.display(), problems.join("; ")));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} bad inputs were not refused properly:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

#[test]
fn every_file_in_the_corpus_is_refused_with_one_line_naming_it() {
    let mut cases: Vec<(PathBuf, String)> = std::fs::read_dir(corpus())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            let own = p.file_name().unwrap().to_string_lossy().into_owned();
            let name = NAMES_ANOTHER_FILE
                .iter()
                .find(|(file, _)| *file == own)
                .map_or(own, |(_, other)| other.to_string());
            (p, name)
        })
        .collect();
    cases.sort();
    assert!(
        cases.len() >= 30,
        "the corpus holds only {} files",
        cases.len()
    );
    for (file, _) in NAMES_ANOTHER_FILE {
        assert!(corpus().join(file).is_file(), "{file} is missing");
    }
    check_all(&cases);
}

#[test]
fn files_made_at_run_time_are_refused_too() {
    let dir = tempfile::tempdir().unwrap();
    let mut cases = Vec::new();

    // A directory where a mesh should be.
    let folder = dir.path().join("folder.obj");
    std::fs::create_dir(&folder).unwrap();
    cases.push((folder, "folder.obj".to_string()));
    // Regression: one without a mesh extension was "unknown mesh format"; it is a folder.
    let plain = dir.path().join("scans");
    std::fs::create_dir(&plain).unwrap();
    cases.push((plain, "scans".to_string()));

    // One face line with three million vertices, the last of them past the vertex list.
    let huge = dir.path().join("huge_face.obj");
    let mut file = std::io::BufWriter::new(std::fs::File::create(&huge).unwrap());
    file.write_all(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf").unwrap();
    for _ in 0..1_000_000 {
        file.write_all(b" 1 2 3").unwrap();
    }
    file.write_all(b" 4\n").unwrap();
    file.into_inner().unwrap().sync_all().unwrap();
    cases.push((huge, "huge_face.obj".to_string()));

    // A file nobody may read; root reads it anyway, so then the case is skipped.
    let locked = dir.path().join("locked.obj");
    std::fs::write(&locked, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    set_mode(&locked, 0o000);
    if std::fs::read(&locked).is_ok() {
        eprintln!(
            "notice: running as root (or without permission checks): an unreadable file \
             cannot be made, so that case is skipped"
        );
    } else {
        cases.push((locked.clone(), "locked.obj".to_string()));
    }
    check_all(&cases);
    set_mode(&locked, 0o644);
}

#[cfg(unix)]
fn set_mode(path: &Path, mode: u32) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
}

#[cfg(not(unix))]
fn set_mode(path: &Path, mode: u32) {
    let mut p = std::fs::metadata(path).unwrap().permissions();
    p.set_readonly(mode == 0);
    std::fs::set_permissions(path, p).unwrap();
}
