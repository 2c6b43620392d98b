//! Every kernel under Oclgrind, an OpenCL device simulator that checks each memory access
//! (and, with `--data-races`, each race): the brute-force and BVH programs of every layout,
//! the primary-ray kernel and each progressive shade mode, and the ray-buffer kernel, on a
//! tiny image, and the probe kernels (through this test binary's own layout tests). Any
//! diagnostic fails the test. Skipped with a notice where `oclgrind` is
//! not installed, except in CI (`CI` set), which installs it.

use crate::common::command::{cltrace, run, text, wrapped};
use std::path::{Path, PathBuf};

/// The `oclgrind` executable, if installed; in CI its absence fails the test.
fn oclgrind() -> Option<PathBuf> {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|p| p.join("oclgrind"))
            .find(|p| p.is_file())
    });
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must run the kernels under Oclgrind: install it (apt-get install oclgrind)"
        );
        eprintln!("notice: oclgrind is not installed: the kernels are not checked under it");
    }
    found
}

/// Runs `cltrace args` under Oclgrind's checks; returns its diagnostics ("" for none) after
/// checking the run succeeded.
fn checked(oclgrind: &Path, dir: &Path, args: &[&str]) -> String {
    let log = dir.join("oclgrind.log");
    let _ = std::fs::remove_file(&log);
    let mut inner = cltrace();
    inner
        .args(args)
        .current_dir(dir)
        .env_remove("CLTRACE_DEVICE");
    let log_arg = log.to_str().expect("a UTF-8 temporary path");
    let cmd = wrapped(
        &inner,
        oclgrind.to_str().expect("a UTF-8 path"),
        &["--check-api", "--data-races", "--log", log_arg],
    );
    let out = run(cmd);
    assert!(
        out.status.success(),
        "{args:?} under oclgrind: {}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    std::fs::read_to_string(&log).unwrap_or_default()
}

#[test]
fn every_kernel_runs_clean_under_oclgrind() {
    let Some(oclgrind) = oclgrind() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/room.toml");
    let scene = scene.to_str().unwrap();
    let png = dir.path().join("out.png");
    let png = png.to_str().unwrap();
    let mut programs: Vec<Vec<&str>> = vec![vec!["--method", "cl-brute"]];
    for layout in ["bin32", "bin64", "wide4", "wide8", "cwbvh"] {
        programs.push(vec!["--method", "cl-bvh", "--layout", layout]);
    }
    let mut found = Vec::new();
    // Runs cltrace with `args` under Oclgrind, keeping any diagnostics.
    let mut check = |args: &[&str]| {
        let log = checked(&oclgrind, dir.path(), args);
        if !log.trim().is_empty() {
            found.push(format!("{args:?}:\n{log}"));
        }
    };
    for program in &programs {
        for shade in ["lambert", "ao", "shadow", "path"] {
            let mut args = vec!["render", scene, "-q", "-o", png];
            args.extend(["--width", "8", "--height", "6", "--spp", "2"]);
            args.extend(["--shade", shade]);
            args.extend(program.iter().copied());
            check(&args);
        }
    }
    // trace_primary_general: an orthographic camera, with barycentric hit records.
    let hits = dir.path().join("hits.bin");
    let mut args = vec![
        "render", scene, "-q", "-o", png, "--width", "8", "--height", "6",
    ];
    args.extend([
        "--projection",
        "orthographic",
        "--hits-format",
        "v2",
        "--hits",
    ]);
    args.push(hits.to_str().unwrap());
    for program in &programs[..2] {
        let args = [&args[..], program].concat();
        check(&args);
    }
    // Every scattering model in the path tracer, under the sky.
    let materials = dir.path().join("materials.toml");
    let mut text = String::new();
    for (x, material) in [
        (-2.5, "bsdf = \"dielectric\", roughness = 0.3"),
        (-1.25, "bsdf = \"dielectric\""),
        (
            0.0,
            "bsdf = \"conductor\", metal = \"gold\", roughness = 0.4",
        ),
        (1.25, "bsdf = \"plastic\", metallic = 0.5, roughness = 0.2"),
        (2.5, "bsdf = \"thin-dielectric\""),
    ] {
        text += &format!(
            "[[mesh]]\ngenerator = {{ kind = \"sphere\", subdivisions = 1 }}\n\
             translate = [{x}, 0.0, 0.0]\nscale = 0.5\nmaterial = {{ {material} }}\n"
        );
    }
    text += "[ground]\n[camera]\neye = [0.0, 1.0, 4.0]\nlook_at = [0.0, 0.0, 0.0]\n";
    std::fs::write(&materials, &text).unwrap();
    let args = [
        "render",
        materials.to_str().unwrap(),
        "-q",
        "-o",
        png,
        "--width",
        "8",
        "--height",
        "6",
        "--spp",
        "2",
        "--shade",
        "path",
    ];
    check(&args);
    // The same lit by an emitter alone, whose shadow rays the path loop traces in the turn
    // after their vertex (DEFERRED_SHADOW, cl/integrator.cl).
    let emitter_lit = dir.path().join("emitter_lit.toml");
    std::fs::write(
        &emitter_lit,
        text.clone()
            + "[[mesh]]\ngenerator = { kind = \"sphere\", subdivisions = 1 }\n\
               translate = [0.0, 2.5, 0.0]\nscale = 0.3\nmaterial = { emission = [4.0, 4.0, 4.0] }\n",
    )
    .unwrap();
    let mut emitter_args = args;
    emitter_args[1] = emitter_lit.to_str().unwrap();
    check(&emitter_args);
    // The same under every other light: an environment map (a 4 x 2 Radiance HDR), a
    // point, a spot and a directional light.
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n".to_vec();
    for k in 0..8u8 {
        hdr.extend([100 + 10 * k, 120, 140, 129]);
    }
    std::fs::write(dir.path().join("env.hdr"), hdr).unwrap();
    text += "[environment]\nfile = \"env.hdr\"\nrotate = 30\n\
             [[light]]\ntype = \"point\"\nposition = [0.0, 2.0, 1.0]\nintensity = 3\n\
             [[light]]\ntype = \"spot\"\nposition = [1.0, 2.0, 1.0]\ndirection = [0.0, -1.0, 0.0]\n\
             [[light]]\ntype = \"directional\"\ndirection = [0.3, -1.0, -0.2]\n";
    let lit = dir.path().join("lit.toml");
    std::fs::write(&lit, text).unwrap();
    let mut args = args;
    args[1] = lit.to_str().unwrap();
    check(&args);
    // The ray-buffer kernel: the bench's diffuse rays.
    let args = [
        "bench",
        scene,
        "-q",
        "--methods",
        "cl-bvh",
        "--layouts",
        "bin32,cwbvh",
        "--rays",
        "diffuse",
        "--resolutions",
        "8x6",
        "--warmup",
        "0",
        "--repetitions",
        "1",
    ];
    check(&args);
    assert!(
        found.is_empty(),
        "Oclgrind's diagnostics:\n{}",
        found.join("\n")
    );
}

/// The probe kernels of cl/probe.cl, which report the shared structs' layout and the
/// shared constants: this test binary runs its own layout tests under Oclgrind, where the
/// simulator is the only OpenCL device.
#[test]
fn the_probe_kernels_run_clean_under_oclgrind() {
    let Some(oclgrind) = oclgrind() else { return };
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("oclgrind.log");
    let tests = [
        "layout::device_structs_match_the_rust_structs",
        "layout::device_constants_match_the_rust_constants",
    ];
    let out = std::process::Command::new(&oclgrind)
        .args(["--check-api", "--data-races", "--log"])
        .arg(&log)
        .arg(std::env::current_exe().unwrap())
        .args(tests)
        .args(["--exact", "--test-threads", "1"])
        // Only the simulator's device is named so: the child cannot run elsewhere.
        .env("CLTRACE_DEVICE", "Oclgrind")
        // The child checks the probe on the one device it sees; which implementations CI
        // must have is this run's concern, not the child's.
        .env_remove("CI")
        .output()
        .unwrap();
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("2 passed"), "{stdout}");
    let log = std::fs::read_to_string(&log).unwrap_or_default();
    assert!(log.trim().is_empty(), "Oclgrind's diagnostics:\n{log}");
}
