//! What a render reports about itself: the stage times that add up to the total, the JSON
//! summary of `--json`, progress lines where stderr is not a terminal, and the warning
//! when the image shows nothing.

use std::path::{Path, PathBuf};

use crate::common::command::{cltrace, run, succeeded, text};

/// A closed box, 2 units on a side around the origin, its faces wound to face inwards (a
/// room), with a small lamp inside: from outside, the camera sees only the backs of faces,
/// and no light gets out (a scene with an emitter has no sky).
const CLOSED_ROOM: &str = "\
mtllib room.mtl
v -0.1 0.9 -0.1
v 0.1 0.9 -0.1
v 0 0.9 0.1
usemtl lamp
f 1 2 3
usemtl wall
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
f 4 5 6
f 4 6 7
f 8 11 10
f 8 10 9
f 4 7 11
f 4 11 8
f 5 9 10
f 5 10 6
f 4 8 9
f 4 9 5
f 7 6 10
f 7 10 11
";

/// The room's materials: a grey wall and a bright lamp.
const ROOM_MTL: &str = "newmtl wall\nKd 0.8 0.8 0.8\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n";

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs `cltrace render MESH -o out.png ARGS` in `dir`; returns stderr.
fn render(dir: &Path, mesh: &Path, args: &[&str]) -> String {
    let mut cmd = cltrace();
    cmd.current_dir(dir)
        .env_remove("CLTRACE_DEVICE")
        .arg("render")
        .arg(mesh)
        .args(["-o", "out.png", "--width", "32", "--height", "24"])
        .args(args);
    let out = run(cmd);
    succeeded(&out);
    text(&out.stderr)
}

/// The stage times did not add up to the wall time on a first run (a kernel compiled
/// lazily at its first launch was in no stage): every stage is counted, the rest is
/// `other`, and `--json` holds them with the wall time, the device, the layout, the
/// work-group, the samples and the rays.
#[test]
fn stage_times_add_up_to_the_total_and_json_summarises_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write(dir.path(), "room.obj", CLOSED_ROOM);
    for method in ["cpu-bvh", "cl-bvh"] {
        let stderr = render(
            dir.path(),
            &mesh,
            &[
                "--method", method, "--shade", "ao", "--spp", "3", "--json", "run.json",
            ],
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("run.json")).unwrap())
                .unwrap();
        assert_eq!(summary["version"], env!("CARGO_PKG_VERSION"));
        assert_eq!(summary["method"], method);
        assert_eq!(summary["shade"], "ao");
        assert_eq!(summary["width"], 32);
        assert_eq!(summary["spp"], 3);
        assert_eq!(summary["samples_per_pixel"], 3.0);
        assert_eq!(summary["complete"], true);
        assert_eq!(summary["triangles"], 13);
        let rays = summary["rays"].as_u64().unwrap();
        // Per sample one camera ray a pixel, and 16 occlusion rays at most for each pixel
        // whose camera ray hit: a progressive frame traces no primary rays of its own.
        assert!(rays > 32 * 24 * 3 && rays <= 32 * 24 * 3 * 17, "{rays}");
        let outputs = summary["outputs"].as_array().unwrap();
        assert_eq!(outputs.len(), 1);
        assert!(outputs[0].as_str().unwrap().ends_with("out.png"));
        let stages = summary["stages"].as_array().unwrap();
        let names: Vec<&str> = stages.iter().map(|s| s["name"].as_str().unwrap()).collect();
        for stage in ["load", "build", "write", "other"] {
            assert!(names.contains(&stage), "{method}: no {stage} in {names:?}");
        }
        let total: f64 = stages.iter().map(|s| s["ms"].as_f64().unwrap()).sum();
        let wall = summary["wall_ms"].as_f64().unwrap();
        // The sampling's wall time holds at least its stage (for one OpenCL device, its
        // kernels' time) and fits in the run's.
        let stage = |name: &str| {
            stages.iter().find(|s| s["name"] == name).unwrap()["ms"]
                .as_f64()
                .unwrap()
        };
        let sampling = summary["sampling_ms"].as_f64().unwrap();
        assert!(
            sampling >= stage("samples") && sampling <= wall,
            "{method}: sampling {sampling} ms, samples stage {}, wall {wall}",
            stage("samples")
        );
        assert!(
            (total - wall).abs() <= 1e-6 * wall,
            "{method}: stages {total} ms, wall {wall} ms"
        );
        if method == "cl-bvh" {
            for stage in ["open", "compile", "upload", "launch", "samples"] {
                assert!(names.contains(&stage), "{method}: no {stage} in {names:?}");
            }
            assert!(!names.contains(&"kernel"), "no primary frame: {names:?}");
            assert!(summary["device"].is_string());
            assert!(summary["layout"].is_string());
            assert_eq!(summary["work_group"].as_array().unwrap().len(), 2);
        } else {
            assert!(summary["device"].is_null());
        }
        // The line on stderr ends with the same total.
        let line = stderr.lines().last().unwrap();
        assert!(
            line.starts_with("load ") && line.contains(", total "),
            "{stderr}"
        );
    }
}

/// Progress on a non-terminal (a render farm's log) printed nothing: there a line comes
/// every `CLTRACE_PROGRESS_SECONDS` (every update at 0).
#[test]
fn progress_on_a_non_terminal_printed_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write(dir.path(), "room.obj", CLOSED_ROOM);
    let mut cmd = cltrace();
    cmd.current_dir(dir.path())
        .env("CLTRACE_PROGRESS_SECONDS", "0")
        .arg("render")
        .arg(&mesh)
        .args(["-o", "out.png", "--width", "16", "--height", "12"])
        .args(["--method", "cpu-bvh", "--shade", "ao", "--spp", "5"]);
    let out = run(cmd);
    succeeded(&out);
    let stderr = text(&out.stderr);
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("sampling: "))
        .collect();
    // After each of the first four samples (the fifth ends the work and prints none).
    assert_eq!(lines.len(), 4, "{stderr}");
    assert!(lines[0].starts_with("sampling: 1/5 samples, "), "{stderr}");
    assert!(
        lines[0].contains("Mrays/s") && lines[0].ends_with(" s left"),
        "{stderr}"
    );
    // With the default interval, a render this short prints none.
    let quiet = render(
        dir.path(),
        &mesh,
        &["--method", "cpu-bvh", "--shade", "ao", "--spp", "5"],
    );
    assert!(!quiet.contains("sampling: "), "{quiet}");
}

/// An image with no lit pixel (the auto camera outside a closed room) exited 0 without a
/// hint; so did one where every camera ray missed.
#[test]
fn an_image_with_no_lit_pixel_gave_no_hint() {
    let dir = tempfile::tempdir().unwrap();
    let room = write(dir.path(), "room.obj", CLOSED_ROOM);
    write(dir.path(), "room.mtl", ROOM_MTL);
    let stderr = render(
        dir.path(),
        &room,
        &["--method", "cpu-bvh", "--shade", "path", "--spp", "2"],
    );
    assert!(
        stderr.contains("warning: no pixel is lit (path)"),
        "{stderr}"
    );
    assert!(
        stderr.contains("100% of those on the back of a face"),
        "{stderr}"
    );
    let away = render(
        dir.path(),
        &room,
        &[
            "--method",
            "cpu-bvh",
            "--eye",
            "0,0,10",
            "--look-at",
            "0,0,20",
        ],
    );
    assert!(
        away.contains("warning: the image is empty: every camera ray missed the scene"),
        "{away}"
    );
    // Inside the room a lambert image, lit from the eye, has nothing to warn of.
    let inside = [
        "--method",
        "cpu-bvh",
        "--eye",
        "0,0,0.5",
        "--look-at",
        "0,0,-1",
    ];
    let lambert = render(dir.path(), &room, &inside);
    assert!(!lambert.contains("warning"), "{lambert}");
}
