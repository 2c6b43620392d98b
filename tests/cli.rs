//! End-to-end runs of the `cltrace` binary: renders, hit records, scene files, and every
//! failure exiting with its documented code, one `error:` line and no output file.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::command::{run, succeeded, text, wrapped};

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

/// A 2x2 square in the z = 0 plane, facing +z (where the auto camera puts the eye), as a
/// quad: triangles 0 and 1.
const QUAD: &str = "\
# a square facing the camera
v -1 -1 0
v 1 -1 0
v 1 1 0
v -1 1 0
f 1 2 3 4
";

/// Distance from the bench view's eye to the square: half the box diagonal over sin(fov / 2).
fn auto_distance() -> f32 {
    (2f32.sqrt()) / (22.5f32.to_radians()).sin()
}

/// A work folder: `in/` holds the inputs, `out/` receives the outputs and must hold
/// nothing else after a run.
struct Work {
    _dir: tempfile::TempDir,
    input: PathBuf,
    out: PathBuf,
}

impl Work {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in");
        let out = dir.path().join("out");
        std::fs::create_dir(&input).unwrap();
        std::fs::create_dir(&out).unwrap();
        Work {
            _dir: dir,
            input,
            out,
        }
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.input.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn quad(&self) -> PathBuf {
        self.write("quad.obj", QUAD)
    }

    fn out(&self, name: &str) -> PathBuf {
        self.out.join(name)
    }

    /// Names in `out/`.
    fn out_entries(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(&self.out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

/// `cltrace` with `args`, run in `cwd`, with no device chosen by the environment and no
/// backtraces asked for (so that a panic would show its "RUST_BACKTRACE" note).
fn cltrace<S: AsRef<OsStr>>(cwd: &Path, args: &[S]) -> Command {
    let mut cmd = crate::common::command::cltrace();
    cmd.args(args)
        .current_dir(cwd)
        .env_remove("CLTRACE_DEVICE")
        .env_remove("RUST_BACKTRACE")
        .env_remove("RUST_LIB_BACKTRACE");
    cmd
}

/// Render arguments for `mesh` into `output`, without a size.
fn unsized_args(mesh: &Path, output: &Path, method: &str) -> Vec<String> {
    vec![
        "render".into(),
        mesh.display().to_string(),
        "-o".into(),
        output.display().to_string(),
        "--method".into(),
        method.into(),
        // The benchmark's straight-on view, whose distances these tests know
        // (auto_distance); the auto view has tests of its own (tests/camera.rs).
        "--camera".into(),
        "bench".into(),
    ]
}

/// Render arguments for `mesh` into `output` at the test size.
fn render_args(mesh: &Path, output: &Path, method: &str) -> Vec<String> {
    let size = [
        "--width",
        &WIDTH.to_string(),
        "--height",
        &HEIGHT.to_string(),
    ]
    .map(String::from);
    let mut args = unsized_args(mesh, output, method);
    args.extend(size);
    args
}

// ---------------------------------------------------------------------------------------
// Renders
// ---------------------------------------------------------------------------------------

/// Checks the image's size and that the square stands out from the background.
#[track_caller]
fn check_image(path: &Path, width: u32, height: u32) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    assert_eq!(img.dimensions(), (width, height), "{}", path.display());
    let centre = img.get_pixel(width / 2, height / 2);
    let corner = img.get_pixel(0, 0);
    let diff: i32 = centre
        .0
        .iter()
        .zip(corner.0)
        .map(|(&a, b)| (a as i32 - b as i32).abs())
        .sum();
    assert!(
        diff > 30,
        "{}: the hit centre {centre:?} looks like the missed corner {corner:?}",
        path.display()
    );
}

#[test]
fn render_png_on_the_cpu() {
    let w = Work::new();
    let png = w.out("out.png");
    let out = run(cltrace(
        &w.input,
        &render_args(&w.quad(), &png, "cpu-brute"),
    ));
    succeeded(&out);
    check_image(&png, WIDTH, HEIGHT);
    assert_eq!(w.out_entries(), ["out.png"]);
}

/// The first three lines of `render --help` from the one naming `flag`, joined.
fn render_help_of(flag: &str) -> String {
    let w = Work::new();
    let out = run(cltrace(&w.input, &["render", "--help"]));
    succeeded(&out);
    text(&out.stdout)
        .lines()
        .skip_while(|l| !l.contains(flag))
        .take(3)
        .collect::<Vec<_>>()
        .join(" ")
}

/// Regression: `--layout`'s help claimed a default of `bin32`; it names the layout an
/// untuned device gets, by kind, as the render picks it.
#[test]
fn layout_help_claimed_a_default_of_bin32() {
    use cltrace::device::DeviceKind;
    let text = render_help_of("--layout");
    let (cpu, other) = (
        DeviceKind::Cpu.default_layout().name(),
        DeviceKind::Gpu.default_layout().name(),
    );
    assert!(
        text.contains(&format!("{cpu} on CPUs and {other} on other devices")),
        "{text}"
    );
    assert!(!text.contains("default: bin32"), "{text}");
}

/// Regression: `render --help` listed the 8-bit formats only; it names every format the
/// extension can choose.
#[test]
fn render_help_names_every_output_format() {
    let line = render_help_of("--output");
    for format in ["png", "bmp", "ppm", "jpg", "exr", "pfm"] {
        assert!(line.contains(format), "{format} missing from {line:?}");
    }
}

#[test]
fn render_writes_the_format_its_extension_names() {
    let w = Work::new();
    let quad = w.quad();
    for name in ["out.bmp", "out.ppm", "out.jpg", "out.jpeg", "OUT.PNG"] {
        let path = w.out(name);
        let out = run(cltrace(&w.input, &render_args(&quad, &path, "cpu-brute")));
        succeeded(&out);
        check_image(&path, WIDTH, HEIGHT);
    }
    // the format follows the extension, not just the name
    let bmp = std::fs::read(w.out("out.bmp")).unwrap();
    assert_eq!(&bmp[..2], b"BM");
    // Regression: `.ppm` was PAM (`P7`), which most PPM readers refuse; it is binary PPM,
    // the same pixels as the PNG.
    let ppm = std::fs::read(w.out("out.ppm")).unwrap();
    let header = format!("P6\n{WIDTH} {HEIGHT}\n255\n");
    assert!(ppm.starts_with(header.as_bytes()), "{:?}", &ppm[..8]);
    let png_pixels = image::open(w.out("OUT.PNG")).unwrap().to_rgb8().into_raw();
    assert_eq!(&ppm[header.len()..], &png_pixels[..]);
    let jpg = std::fs::read(w.out("out.jpg")).unwrap();
    assert_eq!(&jpg[..2], &[0xFF, 0xD8]);
    let png = std::fs::read(w.out("OUT.PNG")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    assert_eq!(w.out_entries().len(), 5, "{:?}", w.out_entries());
}

/// Runs `shell` in bash with `"$0" "$@"` standing for the `cltrace` command line `args`,
/// then prints `status N`, the exit status of the pipeline's first command.
fn pipeline(w: &Work, args: &[String], shell: &str) -> (String, String) {
    let script = format!("{shell}; echo \"status ${{PIPESTATUS[0]}}\"");
    let cmd = wrapped(&cltrace(&w.input, args), "bash", &["-c", &script]);
    let out = run(cmd);
    (text(&out.stdout), text(&out.stderr))
}

/// Regression: a reader that goes away (`| head`, `2>&1 | head -1`) made the binary panic
/// (exit 101). A closed stdout ends it quietly with status 0; a closed stderr loses the
/// messages but not the work.
#[test]
fn closed_pipes_end_quietly() {
    let w = Work::new();
    let devices = ["devices".to_string()];
    // `true` reads nothing: every write to the pipe fails.
    let (stdout, stderr) = pipeline(&w, &devices, "\"$0\" \"$@\" | true");
    assert!(stdout.contains("status 0"), "{stdout} {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let png = w.out("out.png");
    let mut args = render_args(&w.quad(), &png, "cpu-brute");
    args.push("-v".into());
    let (stdout, stderr) = pipeline(&w, &args, "\"$0\" \"$@\" 2>&1 | true");
    assert!(stdout.contains("status 0"), "{stdout} {stderr}");
    check_image(&png, WIDTH, HEIGHT);
}

/// Regression: every output was mode 0600 (the temporary file's) whatever the umask; an
/// image and a hit record file are as readable as the umask lets new files be.
#[cfg(unix)]
#[test]
fn outputs_honour_the_umask() {
    use std::os::unix::fs::PermissionsExt;
    let w = Work::new();
    let png = w.out("out.png");
    let hits = w.out("out.hits");
    for (umask, mode) in [("027", 0o640), ("022", 0o644)] {
        let mut args = render_args(&w.quad(), &png, "cpu-brute");
        args.extend(["--hits".into(), hits.display().to_string()]);
        // The same command, started by a shell that sets the umask first.
        let script = format!("umask {umask} && exec \"$0\" \"$@\"");
        let cmd = wrapped(&cltrace(&w.input, &args), "sh", &["-c", &script]);
        succeeded(&run(cmd));
        for file in [&png, &hits] {
            let got = std::fs::metadata(file).unwrap().permissions().mode() & 0o777;
            assert_eq!(got, mode, "{} under umask {umask}", file.display());
        }
    }
}

/// The hit records: (triangle, distance) per pixel, row-major.
fn read_hits(path: &Path) -> Vec<(u32, f32)> {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(
        bytes.len(),
        (WIDTH * HEIGHT * 8) as usize,
        "{} has the wrong size",
        path.display()
    );
    bytes
        .chunks_exact(8)
        .map(|c| {
            (
                u32::from_le_bytes(c[0..4].try_into().unwrap()),
                f32::from_le_bytes(c[4..8].try_into().unwrap()),
            )
        })
        .collect()
}

#[track_caller]
fn check_hits(hits: &[(u32, f32)]) {
    let at = |x: u32, y: u32| hits[(y * WIDTH + x) as usize];
    // the centre pixel sees the square, straight ahead
    let (prim, t) = at(WIDTH / 2, HEIGHT / 2);
    assert!(prim < 2, "centre: triangle {prim:#x}");
    assert!(t.is_finite() && t > 0.0, "centre: distance {t}");
    assert!(
        (t - auto_distance()).abs() < 1e-3 * auto_distance(),
        "centre: distance {t}, expected {}",
        auto_distance()
    );
    // the corners see nothing
    for (x, y) in [
        (0, 0),
        (WIDTH - 1, 0),
        (0, HEIGHT - 1),
        (WIDTH - 1, HEIGHT - 1),
    ] {
        let (prim, t) = at(x, y);
        assert_eq!(prim, 0xFFFF_FFFF, "corner ({x}, {y})");
        assert_eq!(t, f32::INFINITY, "corner ({x}, {y})");
    }
    // every record is a hit on one of the two triangles at a positive distance, or a miss
    for (i, &(prim, t)) in hits.iter().enumerate() {
        match prim {
            0 | 1 => assert!(t.is_finite() && t > 0.0, "pixel {i}: {prim} at {t}"),
            0xFFFF_FFFF => assert_eq!(t, f32::INFINITY, "pixel {i}"),
            _ => panic!("pixel {i}: triangle {prim} does not exist"),
        }
    }
    // both triangles of the square show, and the square does not fill the image
    assert!(hits.iter().any(|h| h.0 == 0) && hits.iter().any(|h| h.0 == 1));
    let hit = hits.iter().filter(|h| h.0 != 0xFFFF_FFFF).count();
    assert!(
        hit > hits.len() / 8 && hit < hits.len() * 7 / 8,
        "{hit} hits"
    );
}

#[test]
fn hit_records_on_the_cpu() {
    let w = Work::new();
    let hits = w.out("hits.bin");
    let mut args = render_args(&w.quad(), &w.out("out.png"), "cpu-brute");
    args.extend(["--hits".into(), hits.display().to_string()]);
    succeeded(&run(cltrace(&w.input, &args)));
    check_hits(&read_hits(&hits));
    assert_eq!(w.out_entries(), ["hits.bin", "out.png"]);
}

#[test]
fn hit_records_version_2_carry_barycentrics_that_put_the_hit_at_its_distance() {
    let w = Work::new();
    let (quad, eye) = (w.quad(), [0.0, 0.0, auto_distance()]);
    // The square's two triangles as the fan cuts it: (1 2 3) and (1 3 4).
    let corners = [[-1.0f32, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let triangles = [[0, 1, 2], [0, 2, 3]];
    for method in ["cpu-bvh", "cl-bvh"] {
        let hits = w.out(&format!("{method}.bin"));
        let mut args = render_args(&quad, &w.out(&format!("{method}.png")), method);
        args.extend(["--hits", hits.to_str().unwrap(), "--hits-format", "v2"].map(String::from));
        succeeded(&run(cltrace(&w.input, &args)));
        let bytes = std::fs::read(&hits).unwrap();
        assert_eq!(bytes.len(), (WIDTH * HEIGHT * 16) as usize, "{method}");
        let mut seen = 0;
        for r in bytes.chunks_exact(16) {
            let f = |i: usize| f32::from_le_bytes(r[i..i + 4].try_into().unwrap());
            let (prim, t, b1, b2) = (
                u32::from_le_bytes(r[0..4].try_into().unwrap()),
                f(4),
                f(8),
                f(12),
            );
            if prim == u32::MAX {
                assert_eq!((b1, b2), (0.0, 0.0), "{method}: a miss has no barycentrics");
                continue;
            }
            seen += 1;
            let b = [1.0 - b1 - b2, b1, b2];
            assert!(
                b.iter().all(|&x| x >= -1e-6),
                "{method}: {b:?} outside the triangle"
            );
            let v = triangles[prim as usize].map(|k| corners[k]);
            let p = [0, 1].map(|c| b[0] * v[0][c] + b[1] * v[1][c] + b[2] * v[2][c]);
            let d = ((p[0] - eye[0]).powi(2) + (p[1] - eye[1]).powi(2) + eye[2].powi(2)).sqrt();
            assert!(
                (d - t).abs() <= 1e-5 * t,
                "{method}: the point is {d} away, the hit {t}"
            );
        }
        assert!(seen > 0, "{method}: no hits");
    }
    // Version 2 is a layout of --hits's records: without --hits it is a usage error.
    let args = render_args(&quad, &w.out("x.png"), "cpu-bvh");
    let out = run(cltrace(
        &w.input,
        &[args, vec!["--hits-format".into(), "v2".into()]].concat(),
    ));
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
}

#[test]
fn render_with_opencl_matches_the_cpu() {
    let w = Work::new();
    let quad = w.quad();
    let mut records = Vec::new();
    for method in ["cpu-brute", "cl-brute"] {
        let png = w.out(&format!("{method}.png"));
        let hits = w.out(&format!("{method}.bin"));
        let mut args = render_args(&quad, &png, method);
        args.extend(["--hits".into(), hits.display().to_string()]);
        let mut cmd = cltrace(&w.input, &args);
        cmd.env("CLTRACE_DEVICE", "cpu");
        let out = run(cmd);
        succeeded(&out);
        check_image(&png, WIDTH, HEIGHT);
        let h = read_hits(&hits);
        check_hits(&h);
        records.push(h);
    }
    // the same triangles everywhere, at the same distances
    for (i, (cpu, cl)) in records[0].iter().zip(&records[1]).enumerate() {
        assert_eq!(cpu.0, cl.0, "pixel {i}: cpu {cpu:?}, opencl {cl:?}");
        assert!(
            cpu.1 == cl.1 || (cpu.1 - cl.1).abs() <= 1e-5 * cpu.1,
            "pixel {i}: cpu {cpu:?}, opencl {cl:?}"
        );
    }
}

/// Whether the OpenCL platform `platform` is installed. Where it is not, a notice says what
/// goes unchecked, and CI (`CI` set), which installs it, fails instead.
fn platform_installed(platform: &str, unchecked: &str) -> bool {
    let found = cltrace::device::list_devices().unwrap_or_default();
    if found.iter().any(|d| d.platform_name() == platform) {
        return true;
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "CI must have the OpenCL platform \"{platform}\""
    );
    eprintln!("notice: the OpenCL platform \"{platform}\" is not installed: {unchecked}");
    false
}

/// The platform name of Intel's OpenCL CPU runtime.
const INTEL: &str = "Intel(R) OpenCL";

/// `cltrace args` on Intel's runtime with its implicit vectorizer as users have it (on):
/// CI turns it off for every other run.
fn on_intel_as_users_have_it<S: AsRef<OsStr>>(cwd: &Path, args: &[S]) -> Command {
    let mut cmd = cltrace(cwd, args);
    cmd.env("CLTRACE_DEVICE", INTEL)
        .env_remove("CL_CONFIG_USE_VECTORIZER");
    cmd
}

/// CI turns off the implicit vectorizer of Intel's OpenCL CPU runtime
/// (`CL_CONFIG_USE_VECTORIZER=False` in .ci/run: faster compiles); this run keeps it on,
/// so that the traversal kernels as users get them on Intel's runtime are checked too:
/// the same hits as the host, on every pixel.
#[test]
fn intels_kernels_with_its_vectorizer_on_render_as_the_host_does() {
    if !platform_installed(INTEL, "its kernels with the vectorizer on are not tested") {
        return;
    }
    let w = Work::new();
    let quad = w.quad();
    let mut records = Vec::new();
    for method in ["cpu-bvh", "cl-bvh"] {
        let hits = w.out(&format!("{method}.bin"));
        let mut args = render_args(&quad, &w.out(&format!("{method}.png")), method);
        args.extend(["--hits", hits.to_str().unwrap()].map(String::from));
        succeeded(&run(on_intel_as_users_have_it(&w.input, &args)));
        records.push(read_hits(&hits));
    }
    for (i, (cpu, cl)) in records[0].iter().zip(&records[1]).enumerate() {
        assert_eq!(cpu.0, cl.0, "pixel {i}: host {cpu:?}, Intel {cl:?}");
        assert!(
            cpu.1 == cl.1 || (cpu.1 - cl.1).abs() <= 1e-5 * cpu.1,
            "pixel {i}: host {cpu:?}, Intel {cl:?}"
        );
    }
}

/// Regression: Intel's OpenCL CPU runtime packed the kernels into SIMD lanes wherever a
/// work-group filled them (the 8 x 8 groups on an AVX2 CPU), and packed they ran 3-5x
/// slower than scalar. Every kernel now asks it not to (`KERNEL`, cl/common.cl): with its
/// vectorizer on, as users have it, its build log says each kernel was not vectorized.
#[test]
fn intels_vectorizer_packed_the_kernels_into_slower_simd_lanes() {
    if !platform_installed(INTEL, "its vectorizer's verdicts are not checked") {
        return;
    }
    let w = Work::new();
    let quad = w.quad();
    for shade in ["depth", "ao", "path"] {
        let mut args = render_args(&quad, &w.out(&format!("{shade}.png")), "cl-bvh");
        args.extend(["--shade", shade, "--spp", "2"].map(String::from));
        let mut cmd = on_intel_as_users_have_it(&w.input, &args);
        cmd.env("CLTRACE_KERNEL_CACHE", "off")
            .env("CLTRACE_BUILD_LOG", "1");
        let out = run(cmd);
        succeeded(&out);
        let log = text(&out.stderr);
        let verdicts: Vec<&str> = log.lines().filter(|l| l.starts_with("Kernel \"")).collect();
        assert!(
            !verdicts.is_empty(),
            "{shade}: no verdict in the build log:\n{log}"
        );
        for verdict in verdicts {
            assert!(
                verdict.ends_with("was not vectorized"),
                "{shade}: {verdict}"
            );
        }
    }
}

#[test]
fn scene_file_with_a_relative_mesh_and_overriding_flags() {
    let w = Work::new();
    let scenes = w.input.join("scenes");
    std::fs::create_dir(&scenes).unwrap();
    std::fs::write(scenes.join("m.obj"), QUAD).unwrap();
    let scene = scenes.join("s.toml");
    std::fs::write(
        &scene,
        "mesh = \"m.obj\"\n\n[camera]\nwidth = 40\nheight = 30\nfov = 45.0\n\n\
         [render]\nmethod = \"cpu-brute\"\nshade = \"normal\"\n",
    )
    .unwrap();
    // run from elsewhere: the mesh path is relative to the scene file, not the cwd
    let png = w.out("scene.png");
    let out = run(cltrace(
        &w.out,
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ],
    ));
    succeeded(&out);
    check_image(&png, 40, 30);

    // flags override the file
    let png2 = w.out("wide.png");
    let out = run(cltrace(
        &w.out,
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            png2.to_str().unwrap(),
            "--width",
            "64",
        ],
    ));
    succeeded(&out);
    check_image(&png2, 64, 30);

    // a relative scene path and a relative output, from the scene's folder's parent
    let out = run(cltrace(
        &w.input,
        &["render", "scenes/s.toml", "-o", "rel.png", "--height", "20"],
    ));
    succeeded(&out);
    check_image(&w.input.join("rel.png"), 40, 20);
}

// ---------------------------------------------------------------------------------------
// Failures
// ---------------------------------------------------------------------------------------

/// Runs a render that must fail with `code`; checks the one `error:` line (after which only
/// a command-line error has more: clap's tips, possible values and pointer to `--help`)
/// and that `out/` holds nothing new. Returns the error line.
#[track_caller]
fn fails(w: &Work, args: &[String], env: &[(&str, &str)], code: i32) -> String {
    let before = w.out_entries();
    let mut cmd = cltrace(&w.input, args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = run(cmd);
    let stderr = text(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(code),
        "{args:?}\nstdout: {}\nstderr: {stderr}",
        text(&out.stdout)
    );
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    assert!(!stderr.contains("RUST_BACKTRACE"), "{args:?}: {stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    let clap_note = |l: &&str| l.starts_with("  ") || *l == "For more information, try '--help'.";
    assert!(
        !lines.is_empty() && lines[1..].iter().all(clap_note),
        "{args:?}: not one line: {stderr:?}"
    );
    assert!(lines[0].starts_with("error: "), "{args:?}: {stderr:?}");
    assert!(lines[0].len() > "error: ".len() + 5, "{args:?}: {stderr:?}");
    assert_eq!(text(&out.stdout), "", "{args:?}: stdout");
    assert_eq!(w.out_entries(), before, "{args:?} left files behind");
    lines[0].to_string()
}

fn with(mut args: Vec<String>, more: &[&str]) -> Vec<String> {
    args.extend(more.iter().map(|s| s.to_string()));
    args
}

#[test]
fn bad_meshes_exit_2() {
    let w = Work::new();
    let png = w.out("out.png");
    let nan = w.write("nan.obj", "v 0 0 0\nv nan 1 0\nv 0 1 0\nf 1 2 3\n");
    let msg = fails(&w, &render_args(&nan, &png, "cpu-brute"), &[], 2);
    assert!(msg.contains("nan.obj:2:"), "{msg}");
    let missing = w.input.join("missing.obj");
    let msg = fails(&w, &render_args(&missing, &png, "cpu-brute"), &[], 2);
    assert!(msg.contains("missing.obj"), "{msg}");
    // the same through OpenCL: the mesh is refused however it would be traced
    let msg = fails(
        &w,
        &render_args(&missing, &png, "cl-brute"),
        &[("CLTRACE_DEVICE", "cpu")],
        2,
    );
    assert!(msg.contains("missing.obj"), "{msg}");
    let stl = w.write("m.stl", "solid\nendsolid\n");
    fails(&w, &render_args(&stl, &png, "cpu-brute"), &[], 2);
    let bad_ply = w.write("bad.ply", "ply\nformat ascii 1.0\nbogus\nend_header\n");
    let msg = fails(&w, &render_args(&bad_ply, &png, "cpu-brute"), &[], 2);
    assert!(msg.contains("bad.ply:3:"), "{msg}");
    // with --hits too: neither file appears
    let args = with(
        render_args(&nan, &png, "cpu-brute"),
        &["--hits", w.out("h.bin").to_str().unwrap()],
    );
    fails(&w, &args, &[], 2);
}

#[test]
fn bad_options_exit_2() {
    let w = Work::new();
    let quad = w.quad();
    let png = w.out("out.png");
    let base = || render_args(&quad, &png, "cpu-brute");

    let msg = fails(
        &w,
        &render_args(&quad, &w.out("out.tiff"), "cpu-brute"),
        &[],
        2,
    );
    assert!(msg.contains("tiff"), "{msg}");
    fails(
        &w,
        &render_args(&quad, &w.out("noext"), "cpu-brute"),
        &[],
        2,
    );
    let no_size = || unsized_args(&quad, &png, "cpu-brute");
    let msg = fails(
        &w,
        &with(no_size(), &["--width", "0", "--height", "48"]),
        &[],
        2,
    );
    assert!(msg.contains("width") || msg.contains("resolution"), "{msg}");
    let msg = fails(
        &w,
        &with(no_size(), &["--width", "64", "--height", "20000"]),
        &[],
        2,
    );
    assert!(msg.contains("20000"), "{msg}");
    fails(
        &w,
        &with(no_size(), &["--width", "16385", "--height", "1"]),
        &[],
        2,
    );
    fails(&w, &with(base(), &["--fov", "180"]), &[], 2);
    fails(&w, &with(base(), &["--fov", "0"]), &[], 2);
    fails(&w, &with(base(), &["--fov=-10"]), &[], 2);
    let msg = fails(
        &w,
        &with(base(), &["--eye", "0,0,0", "--look-at", "0,0,0"]),
        &[],
        2,
    );
    assert!(msg.contains("eye"), "{msg}");
    let msg = fails(
        &w,
        &with(
            base(),
            &["--eye", "0,0,5", "--look-at", "0,0,0", "--up", "0,0,1"],
        ),
        &[],
        2,
    );
    assert!(msg.contains("up"), "{msg}");
    // up parallel to the bench view's direction (-z)
    fails(&w, &with(base(), &["--up", "0,0,-3"]), &[], 2);
    fails(&w, &with(base(), &["--up", "0,0,0"]), &[], 2);
}

/// Regression: a negative or fractional whole-number flag was refused as "not in
/// 0..=4294967295"; the error says what is wrong with the value, and the range checks that
/// know each flag's limits still speak for values in range.
#[test]
fn whole_number_flags_say_what_is_wrong() {
    let w = Work::new();
    let quad = w.quad();
    let png = w.out("out.png");
    let no_size = || unsized_args(&quad, &png, "cpu-brute");
    for (flags, expected) in [
        (&["--width", "-5", "--height", "8"][..], "negative"),
        (&["--width", "1.5", "--height", "8"], "not a whole number"),
        (&["--width", "8", "--height", "x"], "not a number"),
        (&["--width", "99999999999", "--height", "8"], "too large"),
        (
            &["--width", "8", "--height", "8", "--spp", "-1"],
            "negative",
        ),
        (
            &["--width", "8", "--height", "8", "--bins", "-3"],
            "negative",
        ),
        (&["--width", "0", "--height", "8"], "between 1 and 16384"),
    ] {
        let msg = fails(&w, &with(no_size(), flags), &[], 2);
        assert!(msg.contains(expected), "{flags:?}: {msg}");
        assert!(!msg.contains("4294967295"), "{flags:?}: {msg}");
    }
}

/// A missing output folder exited with 2 (a bad option) while a folder without write
/// permission exited with 1 after the render: every output problem is now exit status 1,
/// found before any work, with the user's path in the message.
#[test]
fn output_folder_that_does_not_exist_exits_1_like_every_output_error() {
    // Refused before any work, and the folder is not created.
    let w = Work::new();
    let quad = w.quad();
    let missing = w.out("missing").join("x.png");
    let msg = fails(&w, &render_args(&quad, &missing, "cpu-brute"), &[], 1);
    assert!(msg.contains(&missing.display().to_string()), "{msg}");
    let args = with(
        render_args(&quad, &w.out("out.png"), "cpu-brute"),
        &["--hits", w.out("missing").join("h.bin").to_str().unwrap()],
    );
    fails(&w, &args, &[], 1);
    let args = with(
        render_args(&quad, &w.out("out.png"), "cpu-brute"),
        &[
            "--json",
            w.out("missing").join("run.json").to_str().unwrap(),
        ],
    );
    fails(&w, &args, &[], 1);
    assert!(!w.out("missing").exists());
}

/// An output folder that takes no new file was found only after the render (9.3 s lost at
/// 64 spp), and the message named the temporary file. `/proc` refuses new files even to
/// root, who may write into any folder whatever its mode.
#[cfg(target_os = "linux")]
#[test]
fn an_unwritable_output_folder_was_found_only_after_the_render() {
    let w = Work::new();
    let quad = w.quad();
    for (image, hits) in [("/proc/x.png", None), ("out.png", Some("/proc/h.bin"))] {
        let image = match image.starts_with('/') {
            true => PathBuf::from(image),
            false => w.out(image),
        };
        let mut args = with(render_args(&quad, &image, "cpu-bvh"), &["-v"]);
        if let Some(hits) = hits {
            args = with(args, &["--hits", hits]);
        }
        let out = run(cltrace(&w.input, &args));
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        let named = hits.map_or(image.display().to_string(), String::from);
        assert!(stderr.starts_with(&format!("error: {named}: ")), "{stderr}");
        assert!(stderr.contains("cannot create a file in /proc"), "{stderr}");
        assert!(
            !stderr.contains(".cltrace-"),
            "the temporary name leaked: {stderr}"
        );
        // Refused before the mesh was even read: `-v` prints no mesh line.
        assert!(!stderr.contains("mesh:"), "the render ran first: {stderr}");
        assert_eq!(w.out_entries(), Vec::<String>::new());
    }
}

/// `-o /dev/null` was refused ("unknown image format"), so a run for the hit records alone
/// was impossible; it must also never be replaced by a regular file (as root, the folder
/// `/dev` takes new files, and the atomic rename would have replaced the device).
#[cfg(unix)]
#[test]
fn an_output_to_dev_null_was_refused() {
    use std::os::unix::fs::FileTypeExt;
    let w = Work::new();
    let quad = w.quad();
    let hits = w.out("h.bin");
    let args = with(
        render_args(&quad, Path::new("/dev/null"), "cpu-bvh"),
        &["--hits", hits.to_str().unwrap()],
    );
    let out = run(cltrace(&w.input, &args));
    succeeded(&out);
    assert_eq!(
        std::fs::metadata(&hits).unwrap().len(),
        8 * WIDTH as u64 * HEIGHT as u64
    );
    assert!(
        std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device()
    );
    assert_eq!(w.out_entries(), ["h.bin"]);
}

/// A named pipe as the output is written into, not renamed over (which would have
/// replaced the pipe with a regular file, and a reader on it would get nothing).
#[cfg(unix)]
#[test]
fn an_output_that_is_a_named_pipe_is_written_into() {
    use std::os::unix::fs::FileTypeExt;
    let w = Work::new();
    let quad = w.quad();
    let fifo = w.out("image.ppm");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("notice: mkfifo is missing: the named-pipe output is not tested");
        return;
    }
    // The reader blocks until a writer opens the pipe: one renamed over it never comes,
    // so the wait has a limit instead of hanging the test.
    let (send, receive) = std::sync::mpsc::channel();
    {
        let fifo = fifo.clone();
        std::thread::spawn(move || send.send(std::fs::read(fifo).unwrap()));
    }
    let out = run(cltrace(&w.input, &render_args(&quad, &fifo, "cpu-bvh")));
    succeeded(&out);
    let bytes = receive
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("nothing was written into the pipe");
    let header = format!("P6\n{WIDTH} {HEIGHT}\n255\n");
    assert!(bytes.starts_with(header.as_bytes()));
    assert_eq!(bytes.len(), header.len() + 3 * (WIDTH * HEIGHT) as usize);
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    assert_eq!(w.out_entries(), ["image.ppm"]);
}

/// Only clap's first error line was kept, losing "a similar argument exists" and the
/// list of possible values.
#[test]
fn command_line_errors_kept_only_their_first_line() {
    let w = Work::new();
    let quad = w.quad();
    let png = w.out("x.png");
    let cases: [(&[&str], &[&str]); 3] = [
        (&["--widht", "5"], &["a similar argument exists: '--width'"]),
        (
            &["--shade", "fast"],
            &["possible values: normal, depth, lambert, ao, shadow, path"],
        ),
        (&["--shade"], &["possible values:", "path"]),
    ];
    for (flags, expected) in cases {
        let args = with(unsized_args(&quad, &png, "cpu-bvh"), flags);
        let msg = fails(&w, &args, &[], 2);
        let out = run(cltrace(&w.input, &args));
        let stderr = text(&out.stderr);
        for e in expected {
            assert!(
                stderr.contains(e),
                "{flags:?}: {e:?} missing from {stderr:?}"
            );
        }
        assert!(!stderr.contains("Usage:"), "{stderr}");
        assert!(msg.starts_with("error: "), "{msg}");
    }
}

#[test]
fn output_that_cannot_be_written_exits_1() {
    // The image path is a folder: refused before the render, and neither the image nor a
    // temporary `.cltrace-*.tmp` file is left behind.
    let w = Work::new();
    let quad = w.quad();
    std::fs::create_dir(w.out("taken.png")).unwrap();
    let msg = fails(
        &w,
        &render_args(&quad, &w.out("taken.png"), "cpu-brute"),
        &[],
        1,
    );
    assert!(msg.contains("taken.png"), "{msg}");
    assert_eq!(w.out_entries(), ["taken.png"]);
    assert!(w.out("taken.png").is_dir());
}

#[test]
fn bad_scene_files_exit_2() {
    let w = Work::new();
    w.quad();
    let png = w.out("out.png");
    let scene = w.write(
        "s.toml",
        "mesh = \"quad.obj\"\n[camera]\nwidth = 32\nzoom = 2\n",
    );
    let msg = fails(
        &w,
        &[
            "render".to_string(),
            scene.display().to_string(),
            "-o".into(),
            png.display().to_string(),
        ],
        &[],
        2,
    );
    assert!(msg.contains("s.toml:4:"), "{msg}");
    assert!(msg.contains("zoom"), "{msg}");
    // a mesh the scene names that does not exist
    let scene = w.write("t.toml", "mesh = \"nothere.obj\"\n");
    let msg = fails(
        &w,
        &[
            "render".to_string(),
            scene.display().to_string(),
            "-o".into(),
            png.display().to_string(),
            "--method".into(),
            "cpu-brute".into(),
        ],
        &[],
        2,
    );
    assert!(msg.contains("nothere.obj"), "{msg}");
    // a scene file that is not there
    fails(
        &w,
        &[
            "render".to_string(),
            w.input.join("gone.toml").display().to_string(),
            "-o".into(),
            png.display().to_string(),
        ],
        &[],
        2,
    );
}

#[test]
fn no_such_device_exits_1() {
    let w = Work::new();
    let quad = w.quad();
    let png = w.out("out.png");
    let msg = fails(
        &w,
        &with(render_args(&quad, &png, "cl-brute"), &["--device", "9:9"]),
        &[("CLTRACE_DEVICE", "cpu")],
        1,
    );
    assert!(msg.contains("9:9"), "{msg}");
    // the same from the environment
    fails(
        &w,
        &render_args(&quad, &png, "cl-brute"),
        &[("CLTRACE_DEVICE", "9:9")],
        1,
    );
}

// ---------------------------------------------------------------------------------------
// Devices and help
// ---------------------------------------------------------------------------------------

#[test]
fn devices_lists_a_table() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(cltrace(dir.path(), &["devices"]));
    succeeded(&out);
    let stdout = text(&out.stdout);
    let mut lines = stdout.lines();
    let header = lines.next().unwrap_or_default();
    assert!(header.starts_with("P:D"), "{stdout}");
    assert!(
        lines.any(|l| l.starts_with("0:0 ")),
        "no device 0:0 in:\n{stdout}"
    );
}

#[test]
fn help_mentions_device_and_examples() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        &["--help"][..],
        &["render", "--help"][..],
        &["help", "render"][..],
    ] {
        let out = run(cltrace(dir.path(), args));
        succeeded(&out);
        let stdout = text(&out.stdout);
        assert!(stdout.contains("--device"), "{args:?}:\n{stdout}");
        assert!(stdout.contains("Examples:"), "{args:?}:\n{stdout}");
        assert!(stdout.contains("cltrace render "), "{args:?}:\n{stdout}");
        assert!(stdout.contains("Exit status"), "{args:?}:\n{stdout}");
    }
    let out = run(cltrace(dir.path(), &["render", "--help"]));
    let stdout = text(&out.stdout);
    for flag in [
        "--width", "--height", "--fov", "--eye", "--method", "--hits",
    ] {
        assert!(stdout.contains(flag), "{flag}:\n{stdout}");
    }
    // help writes nothing into the folder
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn bvh_reports_every_layout() {
    // A 20 x 20 height field: 800 triangles.
    let mut obj = String::new();
    for y in 0..=20 {
        for x in 0..=20 {
            obj += &format!("v {x} {y} {}\n", ((x * 7 + y * 3) % 5) as f32 * 0.3);
        }
    }
    for y in 0..20 {
        for x in 0..20 {
            let i = y * 21 + x + 1;
            obj += &format!(
                "f {} {} {}\nf {} {} {}\n",
                i,
                i + 1,
                i + 22,
                i,
                i + 22,
                i + 21
            );
        }
    }
    let w = Work::new();
    let mesh = w.write("grid.obj", &obj);
    let out = run(cltrace(&w.input, &[OsStr::new("bvh"), mesh.as_os_str()]));
    succeeded(&out);
    let report = text(&out.stdout);
    assert!(report.contains("triangles             800"), "{report}");
    // Each layout's row: name, nodes, SAH cost, bytes per triangle, time.
    let row = |name: &str| -> (u64, f64, f64) {
        let line = report
            .lines()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap_or_else(|| panic!("no {name} row in\n{report}"));
        let f: Vec<&str> = line.split_whitespace().collect();
        (
            f[1].parse().unwrap(),
            f[2].parse().unwrap(),
            f[3].parse().unwrap(),
        )
    };
    let (bin32, bin64, wide8, cwbvh) = (row("bin32"), row("bin64"), row("wide8"), row("cwbvh"));
    for (nodes, sah, bytes) in [bin32, bin64, row("wide4"), wide8, cwbvh] {
        assert!(nodes > 0 && sah > 0.0 && bytes > 48.0, "{report}");
    }
    // Both children's boxes in one node: half the nodes, the same tree.
    assert_eq!(bin64.0 * 2 + 1, bin32.0, "{report}");
    assert_eq!(bin64.1, bin32.1, "{report}");
    // Wide nodes cut the SAH cost; quantized ones the bytes.
    assert!(wide8.1 < bin32.1 && cwbvh.1 < bin32.1, "{report}");
    assert!(cwbvh.2 < wide8.2 && cwbvh.2 < bin32.2, "{report}");
}

/// No value of any render flag makes the binary panic: each flag gets the values that
/// break naive parsers (empty, NaN, infinities, overflow, fractions, hex, other digits,
/// wrong arity, non-finite vectors), one flag at a time on a tiny image, and every run
/// renders or refuses with one `error:` line and a documented status.
#[test]
fn nasty_flag_values_never_panic() {
    let w = Work::new();
    let quad = w.quad();
    let png = w.out("out.png");
    let numbers = [
        "",
        " ",
        "nan",
        "NaN",
        "inf",
        "-inf",
        "1e39",
        "-1e39",
        "-0",
        "0",
        "-1",
        "1.5",
        "0x10",
        "\u{0661}",
        "4294967296",
        "18446744073709551616",
        "9".repeat(400).leak(),
    ];
    let vectors = [
        "",
        "1,2",
        "1,2,3,4",
        "nan,0,1",
        "inf,0,0",
        "0,-inf,0",
        "1e39,0,0",
        "1e-45,0,0",
        ",,",
        "a,b,c",
        "1;2;3",
        "0,0,0",
    ];
    let names = [
        "",
        "?",
        "-",
        "all",
        "0:99",
        "99:0",
        "\u{1F600}",
        "cl-bvh,cpu-bvh",
    ];
    let table: Vec<(&str, Vec<&str>)> = vec![
        ("--width", numbers.to_vec()),
        ("--height", numbers.to_vec()),
        ("--fov", numbers.to_vec()),
        ("--spp", numbers.to_vec()),
        ("--seed", numbers.to_vec()),
        ("--ao-samples", numbers.to_vec()),
        ("--ao-distance", numbers.to_vec()),
        ("--max-bounces", numbers.to_vec()),
        ("--bins", numbers.to_vec()),
        ("--max-leaf-size", numbers.to_vec()),
        ("--optimize", numbers.to_vec()),
        ("--eye", vectors.to_vec()),
        ("--look-at", vectors.to_vec()),
        ("--up", vectors.to_vec()),
        (
            "--light",
            [
                &vectors[..],
                &[
                    "sun:",
                    "point:nan,0,0",
                    "sun:0,0,0",
                    "sun:inf,1,1",
                    "lamp:1,2,3",
                ],
            ]
            .concat(),
        ),
        ("--method", names.to_vec()),
        ("--shade", names.to_vec()),
        ("--layout", names.to_vec()),
        ("--builder", names.to_vec()),
        ("--device", names.to_vec()),
        ("--fallback", names.to_vec()),
    ];
    let mut problems = Vec::new();
    for (flag, values) in &table {
        for value in values {
            // Small sizes unless the size is what is tried; the sampling flags with a
            // progressive mode, cheap enough at any accepted value.
            let mut args = unsized_args(&quad, &png, "cpu-bvh");
            args.retain(|a| a != "--method" && a != "cpu-bvh");
            if *flag != "--method" {
                args.extend(["--method".into(), "cpu-bvh".into()]);
            }
            for (size, small) in [("--width", "8"), ("--height", "6")] {
                if flag != &size {
                    args.extend([size.into(), small.into()]);
                }
            }
            if ["--spp", "--ao-samples", "--ao-distance", "--seed"].contains(flag) {
                args.extend(["--shade", "ao", "--ao-samples", "1"].map(String::from));
            }
            if ["--max-bounces", "--light"].contains(flag) {
                let shade = if *flag == "--light" { "shadow" } else { "path" };
                args.extend(["--shade".into(), shade.into(), "--spp".into(), "1".into()]);
            }
            args.push(format!("{flag}={value}"));
            let out = run(cltrace(&w.input, &args));
            let stderr = text(&out.stderr);
            let code = out.status.code();
            let ok = match code {
                Some(0) => true,
                Some(1 | 2) => stderr.starts_with("error: "),
                _ => false,
            };
            if !ok || stderr.contains("panicked") {
                problems.push(format!("{flag}={value:?}: exit {code:?}: {stderr}"));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

// ---------------------------------------------------------------------------------------
// Warnings and notes about what a mesh file holds
// ---------------------------------------------------------------------------------------

/// A render of `mesh` on the CPU that must succeed: its stderr.
fn render_stderr(w: &Work, mesh: &Path, more: &[&str]) -> String {
    let args = with(render_args(mesh, &w.out("out.png"), "cpu-bvh"), more);
    let out = run(cltrace(&w.input, &args));
    succeeded(&out);
    let stderr = text(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

/// Regression (issue 15): the warning for a missing MTL file named the OBJ only; it names
/// the library it tried to open, where it looked for it.
#[test]
fn a_missing_mtl_file_was_not_named_in_its_warning() {
    let w = Work::new();
    let obj = w.write("x.obj", &format!("mtllib missing.mtl\n{QUAD}"));
    let stderr = render_stderr(&w, &obj, &[]);
    let tried = w.input.join("missing.mtl");
    let want = format!(
        "warning: {}: cannot open its material library {} (no such file); every triangle is grey",
        obj.display(),
        tried.display()
    );
    assert!(
        stderr.lines().any(|l| l == want),
        "no `{want}` in:\n{stderr}"
    );
}

/// Regression (issue 19): PoCL's compiler printed "2 warnings generated." on every compile
/// of a sample program, because cl/sampling.cl redefined the `sin` and `cos` macros of
/// PoCL's headers; a quiet render whose program compiles afresh prints nothing at all.
#[test]
fn compiling_a_sample_program_printed_pocls_warnings() {
    let pocl = "Portable Computing Language";
    if !platform_installed(pocl, "its compiler's messages are not checked") {
        return;
    }
    let w = Work::new();
    let quad = w.quad();
    let args = with(
        render_args(&quad, &w.out("out.png"), "cl-bvh"),
        &["--shade", "path", "--spp", "1", "-q"],
    );
    let mut cmd = cltrace(&w.input, &args);
    cmd.env("CLTRACE_DEVICE", pocl)
        .env("CLTRACE_KERNEL_CACHE", "off");
    let out = run(cmd);
    succeeded(&out);
    assert_eq!(text(&out.stderr), "", "a quiet render printed something");
}

/// Regression (issue 15): a scene file's bad `light` was an error without the file and
/// line (it was checked after the file was read); it is at its line like any bad value.
#[test]
fn a_bad_light_in_a_scene_file_had_no_line() {
    let w = Work::new();
    w.quad();
    for light in ["sun:1,2", "sun:0,0,0", "lamp:1,2,3"] {
        let scene = w.write(
            "s.toml",
            &format!("mesh = \"quad.obj\"\n\n[render]\nshade = \"shadow\"\nlight = \"{light}\"\n"),
        );
        let args = [
            "render".to_string(),
            scene.display().to_string(),
            "-o".into(),
            w.out("out.png").display().to_string(),
        ];
        let msg = fails(&w, &args, &[], 2);
        assert!(
            msg.starts_with(&format!("error: {}:5:", scene.display())),
            "{msg}"
        );
        assert!(msg.contains(light), "{msg}");
    }
}

/// Regression (issue 15): a polygon that crosses itself was fanned without a word; the
/// warning says how many there were. (Ear clipping finds no ear in this pentagon.)
#[test]
fn polygons_that_are_not_simple_were_fanned_without_a_word() {
    let w = Work::new();
    let text = "v 2 0 0\nv 1 2 0\nv 1 3 0\nv 2 2 0\nv 0 1 0\nf 1 2 3 4 5\nf 2 3 4 5 1\nf 1 2 4\n";
    let obj = w.write("crossed.obj", text);
    let stderr = render_stderr(&w, &obj, &[]);
    let want = format!(
        "warning: 2 polygons of {} are not simple: fan-triangulated",
        obj.display()
    );
    assert!(
        stderr.lines().any(|l| l == want),
        "no `{want}` in:\n{stderr}"
    );
    // a simple polygon gives no warning
    let stderr = render_stderr(&w, &w.quad(), &[]);
    assert!(!stderr.contains("warning"), "{stderr}");
}

/// Regression (issue 15): vertex normals, texture coordinates and colours were dropped
/// without a word; `-v` notes which were read (issue 16: they are used), in OBJ and PLY
/// files.
#[test]
fn normals_texture_coordinates_and_colours_were_dropped_without_a_word() {
    let w = Work::new();
    let obj = w.write(
        "smooth.obj",
        &format!(
            "{}vn 0 0 1\nvt 0 0\nvt 1 1\n",
            QUAD.replace("v 1 1 0", "v 1 1 0 1 0 0")
        ),
    );
    let ply = w.write(
        "coloured.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face 1\nproperty list uchar int vertex_indices\nend_header\n\
         -1 -1 0 0 0 1 255 0 0\n1 -1 0 0 0 1 0 255 0\n0 1 0 0 0 1 0 0 255\n3 0 1 2\n",
    );
    let uv = w.write(
        "uv.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nproperty float u\nproperty float v\n\
         element face 1\nproperty list uchar int vertex_indices\nend_header\n\
         -1 -1 0 0 0\n1 -1 0 1 0\n0 1 0 0 1\n3 0 1 2\n",
    );
    for (mesh, what) in [
        (
            &obj,
            "vertex normals, texture coordinates and vertex colours",
        ),
        (&ply, "vertex normals and vertex colours"),
        (&uv, "texture coordinates"),
    ] {
        let want = format!("note: {}: read its {what}", mesh.display());
        let stderr = render_stderr(&w, mesh, &["-v"]);
        assert!(
            stderr.lines().any(|l| l == want),
            "no `{want}` in:\n{stderr}"
        );
        // a detail, not a warning: only with -v
        let stderr = render_stderr(&w, mesh, &[]);
        assert!(!stderr.contains("note:"), "{stderr}");
    }
    let stderr = render_stderr(&w, &w.quad(), &["-v"]);
    assert!(!stderr.contains("note:"), "{stderr}");
}

/// The fuzzers' mesh seeds (concave and self-crossing polygons among them) and the scene
/// seed with a bad light go through the binary without a panic: rendered, or refused with
/// one error line.
#[test]
fn fuzz_seeds_render_or_are_refused_without_a_panic() {
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds");
    let mut inputs: Vec<PathBuf> = ["obj", "ply"]
        .iter()
        .flat_map(|kind| std::fs::read_dir(seeds.join(kind)).unwrap())
        .map(|e| e.unwrap().path())
        .collect();
    inputs.push(seeds.join("scene/bad_light.toml"));
    inputs.sort();
    let w = Work::new();
    for input in &inputs {
        let png = w.out("out.png");
        let out = run(cltrace(&w.input, &render_args(input, &png, "cpu-bvh")));
        let stderr = text(&out.stderr);
        assert!(
            !stderr.contains("panicked"),
            "{}: {stderr}",
            input.display()
        );
        match out.status.code() {
            Some(0) => std::fs::remove_file(&png).unwrap(),
            Some(2) => assert_eq!(stderr.lines().count(), 1, "{}: {stderr}", input.display()),
            code => panic!("{}: exit {code:?}: {stderr}", input.display()),
        }
    }
}
