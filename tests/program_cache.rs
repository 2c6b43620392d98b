//! Compiled kernels kept between runs: a second render loads them instead of compiling,
//! gives the same image, and says so under `-v`; a corrupt entry is ignored and rebuilt,
//! a cache that cannot be written only costs the next run its compile, and a changed
//! kernel source is a new entry.

use std::path::{Path, PathBuf};

use crate::common::command::{cltrace, run, succeeded, text};

/// Renders the room with the progressive kernels into `dir/NAME.png` with the cache in
/// `cache` (`off` for none); returns the `program cache:` line, if any.
fn render(dir: &Path, cache: &str, name: &str, env: &[(&str, &Path)]) -> Option<String> {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/room.toml");
    let mut cmd = cltrace();
    // On the tests' device (CLTRACE_DEVICE, PoCL in CI): Intel's runtime, the first device
    // listed on some machines, takes 20 s a compile, and the cache works alike on both.
    cmd.current_dir(dir)
        .env("CLTRACE_KERNEL_CACHE", cache)
        .arg("render")
        .arg(scene)
        .args(["--method", "cl-bvh", "--shade", "ao", "--spp", "2", "-v"])
        .args(["--width", "24", "--height", "16", "-o"])
        .arg(format!("{name}.pfm"))
        .arg("--json")
        .arg(format!("{name}.json"));
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = run(cmd);
    succeeded(&out);
    let stderr = text(&out.stderr);
    let line = stderr
        .lines()
        .find(|l| l.starts_with("program cache: "))
        .map(String::from);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap())
            .unwrap();
    let hit = summary["program_cache_hit"].as_bool();
    assert_eq!(hit, line.as_ref().map(|l| l.contains(": hit,")), "{stderr}");
    line
}

fn entries(folder: &Path) -> Vec<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(folder)
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    found.sort();
    found
}

fn image(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(format!("{name}.pfm"))).unwrap()
}

/// Every run compiled its kernels again (1.4 s of a 3 s dragon render on the H200).
#[test]
fn a_second_run_compiled_its_kernels_again() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("kernels");
    let c = cache.to_str().unwrap();
    let first = render(dir.path(), c, "first", &[]).expect("a program cache line");
    let stored = entries(&cache);
    assert_eq!(stored.len(), 1, "{stored:?}");
    assert_eq!(
        first,
        format!("program cache: compiled, saved to {}", stored[0].display())
    );
    let second = render(dir.path(), c, "second", &[]).unwrap();
    assert_eq!(
        second,
        format!("program cache: hit, {}", stored[0].display())
    );
    assert_eq!(image(dir.path(), "first"), image(dir.path(), "second"));

    // A damaged entry (flipped bytes, a truncation, garbage) is ignored and rebuilt.
    let good = std::fs::read(&stored[0]).unwrap();
    let mut flipped = good.clone();
    let middle = flipped.len() / 2;
    flipped[middle] ^= 0xff;
    for damaged in [
        flipped,
        good[..good.len() / 3].to_vec(),
        b"not a program".to_vec(),
    ] {
        std::fs::write(&stored[0], damaged).unwrap();
        let line = render(dir.path(), c, "rebuilt", &[]).unwrap();
        assert!(
            line.starts_with(&format!("program cache: ignored {}", stored[0].display()))
                && line.ends_with("compiled and saved again"),
            "{line}"
        );
        assert_eq!(image(dir.path(), "first"), image(dir.path(), "rebuilt"));
        let again = render(dir.path(), c, "again", &[]).unwrap();
        assert!(again.contains(": hit,"), "{again}");
    }
    assert_eq!(
        entries(&cache),
        stored,
        "temporary files or extra entries left"
    );

    // A changed kernel source is another program: a new entry beside the old one.
    let kernels = dir.path().join("cl");
    std::fs::create_dir(&kernels).unwrap();
    for e in std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("cl")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), kernels.join(e.file_name())).unwrap();
    }
    let common = kernels.join("common.cl");
    let text = std::fs::read_to_string(&common).unwrap() + "\n// changed\n";
    std::fs::write(&common, text).unwrap();
    let changed = render(
        dir.path(),
        c,
        "changed",
        &[("CLTRACE_KERNEL_DIR", kernels.as_path())],
    )
    .unwrap();
    assert!(
        changed.starts_with("program cache: compiled, saved to"),
        "{changed}"
    );
    assert_eq!(entries(&cache).len(), 2);
}

/// A scene whose tree was deeper or shallower than the last one's compiled its kernels
/// again: programs were compiled for the tree's own stack. They take the layout's largest
/// now, so a new scene of the same layout and surface finds them in the cache.
#[test]
fn a_new_scene_of_the_same_layout_compiled_its_kernels_again() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("kernels");
    let mut depths = Vec::new();
    for (name, subdivisions) in [("coarse", 1), ("fine", 5)] {
        let scene = dir.path().join(format!("{name}.toml"));
        let toml = format!(
            "[[mesh]]\ngenerator = {{ kind = \"sphere\", subdivisions = {subdivisions} }}\n"
        );
        std::fs::write(&scene, toml).unwrap();
        let mut cmd = cltrace();
        cmd.current_dir(dir.path())
            .env("CLTRACE_KERNEL_CACHE", &cache)
            .arg("render")
            .arg(&scene)
            .args(["--method", "cl-bvh", "--shade", "path", "--spp", "1", "-v"])
            .args(["--width", "16", "--height", "12", "-o", "out.png"]);
        let out = run(cmd);
        succeeded(&out);
        let stderr = text(&out.stderr);
        let depth = stderr
            .lines()
            .find_map(|l| {
                l.strip_prefix("bvh: ")?
                    .split(", depth ")
                    .nth(1)?
                    .split(',')
                    .next()
            })
            .unwrap_or_else(|| panic!("no bvh line: {stderr}"))
            .to_string();
        depths.push(depth);
        let cached = stderr.lines().find(|l| l.starts_with("program cache: "));
        let expected = match name {
            "coarse" => "program cache: compiled",
            _ => "program cache: hit",
        };
        assert!(
            cached.is_some_and(|l| l.starts_with(expected)),
            "{name}: {stderr}"
        );
    }
    assert_ne!(depths[0], depths[1], "the trees differ in depth");
    assert_eq!(entries(&cache).len(), 1);
}

/// A cache folder that takes no file costs only the compile; `off` turns the cache off.
#[test]
fn a_cache_that_cannot_be_written_does_not_fail_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let blocked = dir.path().join("a file, not a folder");
    std::fs::write(&blocked, b"").unwrap();
    let line = render(
        dir.path(),
        blocked.join("kernels").to_str().unwrap(),
        "x",
        &[],
    )
    .unwrap();
    assert!(
        line.starts_with("program cache: compiled, not saved ("),
        "{line}"
    );
    assert_eq!(render(dir.path(), "off", "y", &[]), None);
    assert_eq!(image(dir.path(), "x"), image(dir.path(), "y"));
}

/// Regression: PoCL compiled a work-group function for each launch's shape at its first
/// launch, 1.4 s of a first render of the dragon on 2 cores; cltrace has it use the generic
/// one it compiles with the program. Its kernel cache (`POCL_CACHE_DIR`, PoCL 3's layout: a
/// folder per kernel, holding one per work-group function) then holds only the generic
/// function's folder, `0-0-0`, and no shape's, such as `8-8-1-goffs0-smallgrid`.
#[test]
fn pocl_compiles_no_work_group_function_for_a_launch_shape() {
    let dir = tempfile::tempdir().unwrap();
    let pocl_cache = dir.path().join("pocl");
    let mut cmd = cltrace();
    cmd.current_dir(dir.path())
        .env_remove("POCL_WORK_GROUP_SPECIALIZATION")
        .env("POCL_CACHE_DIR", &pocl_cache)
        .env("CLTRACE_KERNEL_CACHE", "off")
        .args([
            "render",
            "--device",
            "Portable Computing Language",
            "--shade",
            "ao",
        ])
        .args(["--width", "24", "--height", "16", "-o", "x.png"]);
    let out = run(cmd);
    if !out.status.success() && text(&out.stderr).contains("no OpenCL device matches") {
        assert!(std::env::var_os("CI").is_none(), "CI must test PoCL");
        eprintln!("notice: PoCL is not installed: its work-group functions are not tested");
        return;
    }
    succeeded(&out);
    // Kernel folders sit two levels below the cache (a hash split in two); their children
    // are the work-group functions.
    let mut functions = Vec::new();
    let children = |p: &Path| -> Vec<PathBuf> {
        std::fs::read_dir(p)
            .map(|d| d.map(|e| e.unwrap().path()).collect())
            .unwrap_or_default()
    };
    for a in children(&pocl_cache) {
        for b in children(&a) {
            for kernel in children(&b) {
                for f in children(&kernel).into_iter().filter(|f| f.is_dir()) {
                    functions.push(f.file_name().unwrap().to_string_lossy().into_owned());
                }
            }
        }
    }
    assert!(
        functions.iter().any(|f| f == "0-0-0"),
        "no generic work-group function in PoCL's cache: {functions:?}"
    );
    assert!(
        functions.iter().all(|f| f == "0-0-0"),
        "PoCL compiled work-group functions for launch shapes: {functions:?}"
    );
}
