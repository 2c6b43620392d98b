//! Parts of a render (`render --region/--samples`), `cltrace merge`, and one frame split
//! over several devices: the merged or split image equals the one-shot render bit for bit,
//! and parts that do not fit together are refused with one clear line.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::command::{cltrace, run, succeeded, text};

/// The built-in scene, small, path traced: every run of these tests renders it.
const SCENE: [&str; 8] = [
    "--shade", "path", "--spp", "6", "--width", "48", "--height", "32",
];

/// The scene's flags without `--spp` (parts name their samples).
fn scene_without_spp() -> Vec<&'static str> {
    vec!["--shade", "path", "--width", "48", "--height", "32"]
}

fn render(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let path = dir.join(name);
    let mut cmd = cltrace();
    cmd.arg("render").args(extra).arg("-o").arg(&path).arg("-q");
    succeeded(&run(cmd));
    path
}

fn part(dir: &Path, name: &str, method: &str, extra: &[&str]) -> PathBuf {
    let mut args = scene_without_spp();
    args.extend(["--method", method]);
    args.extend(extra);
    render(dir, name, &args)
}

fn merge(parts: &[&PathBuf], output: &Path) -> Output {
    let mut cmd = cltrace();
    cmd.arg("merge").args(parts).arg("-o").arg(output);
    run(cmd)
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A refusal: exit 2 and one line on stderr that contains `needle`.
#[track_caller]
fn refused(out: &Output, needle: &str) {
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    assert!(err.contains(needle), "`{needle}` not in: {err}");
}

#[test]
fn merged_tiles_and_sample_ranges_equal_the_one_shot_render_bit_for_bit() {
    for method in ["cl-bvh", "cpu-bvh"] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let mut whole = SCENE.to_vec();
        whole.extend(["--method", method]);
        let png = render(d, "whole.png", &whole);
        let exr = render(d, "whole.exr", &whole);

        // Tiles: four quarters, one of them split into two sample ranges (both at once).
        let tiles = [
            part(
                d,
                "a.exr",
                method,
                &["--region", "0,0,20,13", "--samples", "0..6"],
            ),
            part(
                d,
                "b.exr",
                method,
                &["--region", "20,0,48,13", "--samples", "0..2"],
            ),
            part(
                d,
                "c.exr",
                method,
                &["--region", "20,0,48,13", "--samples", "2..6"],
            ),
            part(
                d,
                "d.exr",
                method,
                &["--region", "0,13,48,32", "--samples", "0..6"],
            ),
        ];
        let refs: Vec<&PathBuf> = tiles.iter().collect();
        for (name, whole) in [("merged.png", &png), ("merged.exr", &exr)] {
            let merged = d.join(name);
            succeeded(&merge(&refs, &merged));
            assert!(
                bytes(&merged) == bytes(whole),
                "{method}: merged tiles differ from the one-shot {name}"
            );
        }
        // Sample ranges alone, in reverse order.
        let ranges = [
            part(d, "s1.exr", method, &["--samples", "3..6"]),
            part(d, "s0.exr", method, &["--samples", "0..3"]),
        ];
        let merged = d.join("ranges.png");
        succeeded(&merge(&ranges.iter().collect::<Vec<_>>(), &merged));
        assert!(
            bytes(&merged) == bytes(&png),
            "{method}: merged sample ranges differ from the one-shot render"
        );
    }
}

#[test]
fn parts_that_do_not_fit_together_are_refused_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let top = part(
        d,
        "top.exr",
        "cl-bvh",
        &["--region", "0,0,48,16", "--samples", "0..2"],
    );
    let bottom = part(
        d,
        "bottom.exr",
        "cl-bvh",
        &["--region", "0,16,48,32", "--samples", "0..2"],
    );
    let moved = part(
        d,
        "moved.exr",
        "cl-bvh",
        &["--region", "0,16,48,32", "--samples", "0..2", "--fov", "50"],
    );
    let seeded = part(
        d,
        "seeded.exr",
        "cl-bvh",
        &["--region", "0,16,48,32", "--samples", "0..2", "--seed", "7"],
    );
    let out = d.join("out.png");
    refused(&merge(&[&top, &moved], &out), "camera=");
    refused(&merge(&[&top, &seeded], &out), "seed=");
    refused(
        &merge(&[&top, &bottom, &top], &out),
        "both hold samples 0..2",
    );
    refused(&merge(&[&top], &out), "have no samples");
    // Not a part: a plain EXR image, a damaged part, a file that is not there.
    let image = render(d, "image.exr", &SCENE);
    refused(&merge(&[&image], &out), "not a part of a cltrace render");
    let damaged = d.join("damaged.exr");
    let b = bytes(&top);
    std::fs::write(&damaged, &b[..b.len() / 2]).unwrap();
    refused(&merge(&[&damaged, &bottom], &out), "damaged.exr");
    refused(&merge(&[&d.join("gone.exr")], &out), "gone.exr");
    assert!(!out.exists(), "nothing is written after a refusal");
}

#[test]
fn part_flags_that_cannot_make_a_part_exit_2_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(&[&str], &str); 9] = [
        (&["--region", "0,0,8,8", "-o", "p.png"], "*.exr"),
        (
            &["--region", "0,0,8,8", "--shade", "lambert"],
            "--shade lambert",
        ),
        (&["--region", "0,0,49,8"], "outside the 48x32 image"),
        (&["--region", "0,0,8"], "not a region"),
        (&["--region", "8,0,8,8"], "empty"),
        (&["--samples", "5..2"], "empty"),
        (&["--samples", "0..70000"], "go up to"),
        (&["--samples", "0..4", "--spp", "4"], "--spp"),
        (&["--region", "0,0,8,8", "--hits", "h.bin"], "--hits"),
    ];
    for (args, needle) in cases {
        let mut cmd = cltrace();
        cmd.current_dir(d)
            .args(["render", "--width", "48", "--height", "32"])
            .args(args);
        if !args.contains(&"--shade") {
            cmd.args(["--shade", "path"]);
        }
        if !args.contains(&"-o") {
            cmd.args(["-o", "p.exr"]);
        }
        let out = run(cmd);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
        assert!(!d.join("p.exr").exists() && !d.join("p.png").exists());
    }
}

/// The `P:D` indices of the devices on `platform`, as `cltrace devices` lists them with
/// `env` set.
fn indices(platform: &str, env: &[(&str, &str)]) -> Vec<String> {
    let mut cmd = cltrace();
    cmd.arg("devices").envs(env.iter().copied());
    let out = run(cmd);
    text(&out.stdout)
        .lines()
        .filter(|l| l.trim_end().ends_with(platform))
        .filter_map(|l| l.split_whitespace().next().map(String::from))
        .collect()
}

/// One frame on two PoCL devices (PoCL shows two with `POCL_DEVICES="pthread pthread"`):
/// the same image as one device, every pixel's samples split between them.
#[test]
fn two_pocl_devices_render_the_image_of_one_bit_for_bit() {
    let env = [("POCL_DEVICES", "pthread pthread")];
    let pocl = indices("Portable Computing Language", &env);
    if pocl.len() < 2 {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must test two PoCL devices"
        );
        eprintln!("notice: PoCL is not installed: the two-device render is not tested");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (width, height, spp) = (64u64, 40u64, 12u64);
    let render_on = |devices: &str, name: &str| {
        let path = d.join(name);
        let json = d.join(format!("{name}.json"));
        let mut cmd = cltrace();
        cmd.envs(env)
            .args(["render", "--shade", "path", "--spp", "12", "--width", "64"])
            .args(["--height", "40", "--device", devices, "-o"])
            .arg(&path)
            .arg("--json")
            .arg(&json);
        succeeded(&run(cmd));
        let summary: serde_json::Value = serde_json::from_slice(&bytes(&json)).unwrap();
        (bytes(&path), summary)
    };
    let (one, _) = render_on(&pocl[0], "one.png");
    let (two, summary) = render_on(&format!("{},{}", pocl[0], pocl[1]), "two.png");
    assert!(one == two, "two PoCL devices differ from one");
    let shares = summary["devices"].as_array().expect("a share per device");
    assert_eq!(shares.len(), 2, "{summary}");
    let taken: u64 = shares
        .iter()
        .map(|s| s["pixel_samples"].as_u64().unwrap())
        .sum();
    assert_eq!(
        taken,
        width * height * spp,
        "every pixel sample once: {summary}"
    );
}

/// PoCL beside Intel's runtime: the split frame agrees with PoCL's alone within what
/// separates the two implementations (their `sin`, `cos` and `sqrt` may differ in the last
/// bits, which can send a path elsewhere).
#[test]
fn pocl_beside_intel_agrees_with_pocl_alone() {
    let pocl = indices("Portable Computing Language", &[]);
    let intel = indices("Intel(R) OpenCL", &[]);
    if pocl.is_empty() || intel.is_empty() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must test PoCL beside Intel's runtime"
        );
        eprintln!("notice: PoCL or Intel's runtime is missing: PoCL + Intel is not tested");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut flags = SCENE.to_vec();
    flags.extend(["--device", &pocl[0]]);
    let alone = render(d, "alone.exr", &flags);
    let both = format!("{},{}", pocl[0], intel[0]);
    let mut flags = SCENE.to_vec();
    flags.extend(["--device", &both]);
    let split = render(d, "split.exr", &flags);
    let read = |p: &Path| image::open(p).unwrap().into_rgb32f().into_raw();
    let (a, b) = (read(&alone), read(&split));
    assert_eq!(a.len(), b.len());
    let mean = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
    let (ma, mb) = (mean(&a), mean(&b));
    assert!(ma > 0.05, "the image is dark: {ma}");
    assert!((ma - mb).abs() <= 0.01 * ma, "means {ma} and {mb}");
    let close = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| (*x - *y).abs() <= 1e-4 * x.abs().max(1.0))
        .count();
    assert!(
        close as f64 >= 0.95 * a.len() as f64,
        "only {close} of {} values agree",
        a.len()
    );
}
