//! `cltrace render --frames`: each frame of a scene's keyframes or turntable is a render of
//! its own to the output's frame pattern, the very image a single render with that frame's
//! camera on the command line gives; `--skip-existing` resumes; a failing frame ends the run
//! and keeps the frames before it; and every mistake in the scene file or on the command
//! line exits with 2 and one line.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::command::{cltrace, run, succeeded, text};

/// A small landscape (asymmetric, so that each view differs) seen at 32x24, looking at the
/// origin; no animation.
const STILL: &str = "\
[generator]
kind = \"landscape\"
resolution = 16

[camera]
width = 32
height = 24
look_at = [0.0, 0.0, 0.0]
";

/// Eye and fov keyed at frames 0 and 2: frame 1 is halfway, the eye [1, 2, 4] and fov 45,
/// exactly (in binary as in decimal).
const KEYS: &str = "
[[camera.keyframe]]
frame = 0
eye = [0.0, 2.0, 4.0]
fov = 40.0

[[camera.keyframe]]
frame = 2
eye = [2.0, 2.0, 4.0]
fov = 50.0
";

/// A full turn in 4 frames.
const TURNTABLE: &str = "\n[camera.turntable]\nframes = 4\n";

/// A temporary folder the runs work in.
struct Work(tempfile::TempDir);

impl Work {
    fn new() -> Self {
        Work(tempfile::tempdir().unwrap())
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        std::fs::write(self.path(name), text).unwrap();
        self.path(name)
    }

    /// `cltrace render --method cpu-bvh ARGS` in the folder.
    fn render(&self, args: &[&str]) -> Output {
        let mut cmd = cltrace();
        cmd.arg("render")
            .args(["--method", "cpu-bvh"])
            .args(args)
            .current_dir(self.0.path())
            .env_remove("CLTRACE_DEVICE")
            .env_remove("RUST_BACKTRACE");
        run(cmd)
    }

    /// Renders and checks that it succeeded; returns stderr.
    #[track_caller]
    fn rendered(&self, args: &[&str]) -> String {
        let out = self.render(args);
        succeeded(&out);
        text(&out.stderr)
    }

    fn bytes(&self, name: &str) -> Vec<u8> {
        std::fs::read(self.path(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
    }

    /// The names in the folder, sorted.
    fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(self.0.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

/// Fails unless the images are pairwise different.
#[track_caller]
fn all_differ(w: &Work, names: &[&str]) {
    for (i, a) in names.iter().enumerate() {
        for b in &names[i + 1..] {
            assert_ne!(w.bytes(a), w.bytes(b), "{a} and {b} are the same image");
        }
    }
}

#[test]
fn keyframed_frames_are_the_single_renders_of_their_cameras() {
    let w = Work::new();
    w.write("still.toml", STILL);
    w.write("keys.toml", &format!("{STILL}{KEYS}"));
    let stderr = w.rendered(&["keys.toml", "--frames", "0..3", "-o", "out_%04d.png"]);
    for line in [
        "frame 0 (1 of 3)",
        "frame 2 (3 of 3)",
        "3 of 3 frames written",
    ] {
        assert!(stderr.contains(line), "no `{line}` in {stderr}");
    }
    assert_eq!(
        w.names(),
        [
            "keys.toml",
            "out_0000.png",
            "out_0001.png",
            "out_0002.png",
            "still.toml"
        ]
    );
    all_differ(&w, &["out_0000.png", "out_0001.png", "out_0002.png"]);
    // Each frame is the still scene rendered with that frame's camera given as flags.
    for (frame, eye, fov) in [(0, "0,2,4", "40"), (1, "1,2,4", "45"), (2, "2,2,4", "50")] {
        let single = format!("single_{frame}.png");
        w.rendered(&["still.toml", "--eye", eye, "--fov", fov, "-o", &single]);
        assert_eq!(
            w.bytes(&single),
            w.bytes(&format!("out_000{frame}.png")),
            "frame {frame}"
        );
    }
    // After the last key the camera holds; without --frames a render takes frame 0.
    w.rendered(&["keys.toml", "--frames", "7", "-o", "late_%d.png"]);
    assert_eq!(w.bytes("late_7.png"), w.bytes("out_0002.png"));
    w.rendered(&["keys.toml", "-o", "plain.png"]);
    assert_eq!(w.bytes("plain.png"), w.bytes("out_0000.png"));
    // A flag beats a keyed value, in every frame.
    w.rendered(&[
        "keys.toml",
        "--frames",
        "1..=2",
        "--fov",
        "40",
        "-o",
        "f40_%d.png",
    ]);
    w.rendered(&[
        "still.toml",
        "--eye",
        "2,2,4",
        "--fov",
        "40",
        "-o",
        "s40.png",
    ]);
    assert_eq!(w.bytes("f40_2.png"), w.bytes("s40.png"));
}

/// The eye and up of every `camera:` line of a `-v` render, in order.
fn cameras(stderr: &str) -> Vec<([f32; 3], [f32; 3])> {
    let vector = |line: &str, after: &str| -> [f32; 3] {
        let start = line.find(after).unwrap() + after.len();
        let list = &line[start..start + line[start..].find(']').unwrap()];
        let v: Vec<f32> = list.split(',').map(|c| c.trim().parse().unwrap()).collect();
        v.try_into().unwrap()
    };
    stderr
        .lines()
        .filter(|l| l.starts_with("camera: "))
        .map(|l| (vector(l, "eye ["), vector(l, "up [")))
        .collect()
}

#[test]
fn a_turntable_turns_about_up_and_comes_back_after_a_full_turn() {
    let w = Work::new();
    w.write("still.toml", STILL);
    w.write(
        "turn.toml",
        &format!("{STILL}eye = [0.0, 2.0, 4.0]\n{TURNTABLE}"),
    );
    let stderr = w.rendered(&["turn.toml", "--frames", "0..=4", "-o", "t_%d.png", "-v"]);
    let names = ["t_0.png", "t_1.png", "t_2.png", "t_3.png"];
    all_differ(&w, &names);
    assert_eq!(w.bytes("t_4.png"), w.bytes("t_0.png"), "a full turn");
    w.rendered(&["still.toml", "--eye", "0,2,4", "-o", "start.png"]);
    assert_eq!(w.bytes("t_0.png"), w.bytes("start.png"));
    // A quarter turn about +y takes the eye from +z to +x; that camera, given as flags
    // (printed exactly, as -v shows it), renders the same image.
    let cams = cameras(&stderr);
    assert_eq!(cams.len(), 5, "{stderr}");
    let (eye, up) = cams[1];
    let expected = [4.0, 2.0, 0.0];
    assert!(
        (0..3).all(|c| (eye[c] - expected[c]).abs() < 1e-5),
        "frame 1's eye {eye:?}"
    );
    let flag = |v: [f32; 3]| format!("{},{},{}", v[0], v[1], v[2]);
    w.rendered(&[
        "still.toml",
        "--eye",
        &flag(eye),
        "--up",
        &flag(up),
        "-o",
        "quarter.png",
    ]);
    assert_eq!(w.bytes("quarter.png"), w.bytes("t_1.png"));
}

#[test]
fn skip_existing_leaves_the_frames_whose_outputs_exist() {
    let w = Work::new();
    w.write("keys.toml", &format!("{STILL}{KEYS}"));
    let args = ["keys.toml", "--frames", "0..3", "-o", "f_%d.png"];
    w.rendered(&args);
    let originals: Vec<Vec<u8>> = (0..3).map(|k| w.bytes(&format!("f_{k}.png"))).collect();
    std::fs::remove_file(w.path("f_0.png")).unwrap();
    w.write("f_1.png", "not an image");
    let stderr = w.rendered(&[&args[..], &["--skip-existing"]].concat());
    assert!(
        stderr.contains("f_1.png exists, skipped (--skip-existing)"),
        "{stderr}"
    );
    assert!(
        stderr.contains("1 of 3 frames written, 2 skipped"),
        "{stderr}"
    );
    assert_eq!(w.bytes("f_0.png"), originals[0]);
    assert_eq!(w.bytes("f_1.png"), b"not an image");
    // Without it every frame is rendered again.
    w.rendered(&args);
    assert_eq!(w.bytes("f_1.png"), originals[1]);
    // A frame counts as there only when all of its outputs are.
    let stderr = w.rendered(&[&args[..], &["--skip-existing", "--json", "f_%d.json"]].concat());
    assert!(!stderr.contains("skipped"), "{stderr}");
    assert!(w.path("f_2.json").is_file());
}

#[test]
fn a_failing_frame_ends_the_run_and_keeps_the_frames_before_it() {
    // The eye passes through the look-at point at frame 2.
    let keys = "
[[camera.keyframe]]
frame = 0
eye = [0.0, 2.0, 4.0]

[[camera.keyframe]]
frame = 4
eye = [0.0, -2.0, -4.0]
";
    let w = Work::new();
    w.write("through.toml", &format!("{STILL}{keys}"));
    let out = w.render(&["through.toml", "--frames", "0..4", "-o", "f_%d.png"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.contains("error")).collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        stderr
            .lines()
            .last()
            .unwrap()
            .starts_with("error: frame 2: camera eye [0.0, 0.0, 0.0] equals look-at"),
        "{stderr}"
    );
    assert_eq!(w.names(), ["f_0.png", "f_1.png", "through.toml"]);
}

#[test]
fn the_example_scenes_render_frames() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let w = Work::new();
    for (scene, frames) in [("turntable.toml", "0..2"), ("keyframes.toml", "47..=48")] {
        let path = scenes.join(scene).display().to_string();
        let size = ["--width", "32", "--height", "18"];
        w.rendered(&[&[&path, "--frames", frames, "-o", "e_%02d.png"][..], &size].concat());
    }
    all_differ(&w, &["e_00.png", "e_01.png", "e_47.png", "e_48.png"]);
}

/// Runs a render that must fail with 2: one `error:` line (plus, for a mistake clap finds,
/// its indented tips and pointer to `--help`), no panic, nothing on stdout, no new file.
/// Returns stderr.
#[track_caller]
fn fails(w: &Work, args: &[&str]) -> String {
    let before = w.names();
    let out = w.render(args);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    assert_eq!(text(&out.stdout), "", "{args:?}");
    let lines: Vec<&str> = stderr.lines().collect();
    let clap_note = |l: &&str| l.starts_with("  ") || *l == "For more information, try '--help'.";
    assert!(
        !lines.is_empty() && lines[0].starts_with("error: ") && lines[1..].iter().all(clap_note),
        "{args:?}: not one error line: {stderr:?}"
    );
    assert_eq!(w.names(), before, "{args:?} left files behind");
    stderr
}

#[test]
fn mistakes_exit_2_with_one_clear_line() {
    let w = Work::new();
    w.write("still.toml", STILL);
    w.write("keys.toml", &format!("{STILL}{KEYS}"));
    w.write(
        "backwards.toml",
        &format!("{STILL}{}", KEYS.replace("frame = 2", "frame = 0")),
    );
    w.write("both.toml", &format!("{STILL}{KEYS}{TURNTABLE}"));
    let frames = ["--frames", "0..3"];
    let pattern = ["-o", "out_%04d.png"];
    for (args, words) in [
        // The output pattern: needed with --frames, refused without.
        (vec!["keys.toml", "--frames", "0..3"], "has none"),
        (
            vec!["keys.toml", "--frames", "0..3", "-o", "out.png"],
            "out.png has none",
        ),
        (vec!["keys.toml", "-o", "out_%04d.png"], "give --frames"),
        (
            vec!["keys.toml", "-o", "o.png", "--json", "s_%d.json"],
            "--json",
        ),
        (
            [&["keys.toml"][..], &frames, &pattern, &["--hits", "h.bin"]].concat(),
            "--hits",
        ),
        (
            [&["keys.toml"][..], &frames, &["-o", "o_%d_%d.png"]].concat(),
            "2 frame numbers",
        ),
        (
            [&["keys.toml"][..], &frames, &["-o", "o_%5d.png"]].concat(),
            "%0Nd",
        ),
        // The range.
        (
            [&["keys.toml", "--frames", "5..2"][..], &pattern].concat(),
            "holds no frame",
        ),
        (
            [&["keys.toml", "--frames", "3..3"][..], &pattern].concat(),
            "holds no frame",
        ),
        (
            [&["keys.toml", "--frames", "a..b"][..], &pattern].concat(),
            "not a frame range",
        ),
        (
            [&["keys.toml", "--frames=-1..2"][..], &pattern].concat(),
            "not a frame range",
        ),
        (
            vec!["keys.toml", "--skip-existing", "-o", "o.png"],
            "--frames",
        ),
        // The scene.
        (
            [&["still.toml"][..], &frames, &pattern].concat(),
            "no camera animation",
        ),
        (
            [&frames[..], &pattern].concat(),
            "built-in default scene has no camera animation",
        ),
        (
            [&["backwards.toml"][..], &frames, &pattern].concat(),
            "backwards.toml:15: keyframe at frame 0",
        ),
        (
            vec!["backwards.toml", "-o", "o.png"],
            "increasing frame order",
        ),
        (
            [&["both.toml"][..], &frames, &pattern].concat(),
            "both.toml:20: give either",
        ),
    ] {
        let stderr = fails(&w, &args);
        assert!(
            stderr.contains(words),
            "{args:?}: `{words}` not in {stderr}"
        );
    }
}
