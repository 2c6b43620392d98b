//! End-to-end runs of `cltrace bench` and `cltrace tune` on a tiny generated scene, and the
//! tuning cache as `cltrace render` reads it: the one `CLTRACE_TUNE_CACHE` names, never the
//! user's.

use std::path::{Path, PathBuf};
use std::process::Output;

use cltrace::bvh::Layout;
use cltrace::device::{DeviceInfo, DeviceSelector, default_layout, list_devices};
use cltrace::tune::{SHAPES, TuneCache, Tuning};

use crate::common::command::{BIN, cltrace, no_tune_cache, run, succeeded, test_home, text};

/// A generated sphere of 80 triangles, as a scene file in `dir`.
fn tiny_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("sphere.toml");
    std::fs::write(&scene, "[generator]\nkind = \"sphere\"\nsubdivisions = 1\n").unwrap();
    scene
}

/// The device the tests run on (`CLTRACE_DEVICE`, else the default), as the binary's
/// `--device` and `--devices` flags name it.
fn test_device() -> DeviceInfo {
    let selector = DeviceSelector::from_flag_or_env(None).expect("valid CLTRACE_DEVICE");
    let devices = list_devices().expect("the OpenCL devices can be listed");
    selector
        .pick(&devices)
        .unwrap_or_else(|e| panic!("the tests need a device: {e}"))
        .clone()
}

/// `cltrace render -v` of the built-in scene at 32x24 through `cl-bvh` on `device`, with
/// `extra` flags and, if given, `CLTRACE_TUNE_CACHE` pointing at `cache`: its verbose line
/// starting with `prefix`.
fn verbose_line(
    dir: &Path,
    device: &DeviceInfo,
    cache: Option<&Path>,
    extra: &[&str],
    prefix: &str,
) -> String {
    let png = dir.join("render.png");
    let mut cmd = cltrace();
    cmd.args(["render", "-v", "--width", "32", "--height", "24"])
        .args(["--method", "cl-bvh", "--device", &device.index()])
        .arg("-o")
        .arg(&png)
        .args(extra);
    if let Some(cache) = cache {
        cmd.env("CLTRACE_TUNE_CACHE", cache);
    }
    let out = run(cmd);
    succeeded(&out);
    assert!(png.is_file(), "no image");
    std::fs::remove_file(&png).unwrap();
    let stderr = text(&out.stderr);
    stderr
        .lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("no `{prefix}` line in the verbose output:\n{stderr}"))
        .to_string()
}

/// The SAH cost the verbose `bvh:` line of [`verbose_line`]'s render reports: it is the
/// cost of the tree as laid out, so it tells the layouts that are not alike apart.
fn render_sah(dir: &Path, device: &DeviceInfo, cache: Option<&Path>, extra: &[&str]) -> String {
    let line = verbose_line(dir, device, cache, extra, "bvh: ");
    line.split("SAH cost ")
        .nth(1)
        .and_then(|rest| rest.split(',').next())
        .unwrap_or_else(|| panic!("no SAH cost in {line:?}"))
        .to_string()
}

/// A tuning cache for `device` naming `layout` and `work_group`, in the file format
/// `cltrace tune` writes (a table per device key).
fn write_cache(path: &Path, device: &DeviceInfo, layout: Layout, work_group: [usize; 2]) {
    let text = format!(
        "# written by the tests\n[{:?}]\nlayout = \"{}\"\nwork_group = [{}, {}]\n\
         primary_mrays = 1.0\ndiffuse_mrays = 1.0\nscene = \"test\"\n",
        device.key(),
        layout.name(),
        work_group[0],
        work_group[1]
    );
    std::fs::write(path, text).unwrap();
    // The file says what the test means: the library reads it back as that tuning.
    let tuning = TuneCache::load(path).get(device).cloned();
    assert_eq!(
        tuning.map(|t| (t.layout, t.work_group)),
        Some((layout, work_group)),
        "{} does not read back as written",
        path.display()
    );
}

/// The runs of the tests see a tuning cache of their own, in the build's scratch folder,
/// that does not exist, and a home and cache folder there too.
#[test]
fn runs_of_the_binary_never_see_the_users_tuning_cache() {
    let cmd = cltrace();
    let env: Vec<(String, Option<PathBuf>)> = cmd
        .get_envs()
        .map(|(k, v)| (k.to_string_lossy().into_owned(), v.map(PathBuf::from)))
        .collect();
    let get = |name: &str| {
        env.iter()
            .find(|(k, _)| k == name)
            .and_then(|(_, v)| v.clone())
            .unwrap_or_else(|| panic!("{name} is not set for the runs"))
    };
    let home = test_home();
    assert!(home.starts_with(env!("CARGO_TARGET_TMPDIR")));
    assert_eq!(get("HOME"), home);
    assert!(get("XDG_CACHE_HOME").starts_with(&home));
    assert_eq!(get("CLTRACE_TUNE_CACHE"), no_tune_cache());
    assert!(
        !no_tune_cache().exists(),
        "something wrote the tests' tuning cache"
    );
    assert_eq!(cmd.get_program(), BIN);
}

/// `cltrace render` takes the layout from the cache `CLTRACE_TUNE_CACHE` names; without
/// one, or with one it cannot read, the device's default. (`-v` shows the layout only
/// through the laid-out tree's SAH cost, and the work-group not at all: a cached one the
/// device cannot run must only not fail the render.)
#[test]
fn render_reads_the_tuning_cache_it_is_pointed_at() {
    let dir = tempfile::tempdir().unwrap();
    let device = test_device();
    let default = default_layout(&device);
    // A layout whose tree costs differently from the default's (bin64's cost is bin32's).
    let cached = if matches!(default, Layout::Bin32 | Layout::Bin64) {
        Layout::Wide8
    } else {
        Layout::Bin64
    };
    let sah_of =
        |layout: Layout| render_sah(dir.path(), &device, None, &["--layout", layout.name()]);
    let (cached_sah, default_sah) = (sah_of(cached), sah_of(default));
    assert_ne!(
        cached_sah,
        default_sah,
        "{} and {} cost the same: the test cannot tell them apart",
        cached.name(),
        default.name()
    );

    let cache = dir.path().join("tune.toml");
    write_cache(&cache, &device, cached, [16, 4]);
    assert_eq!(
        render_sah(dir.path(), &device, Some(&cache), &[]),
        cached_sah,
        "with the cache naming {}",
        cached.name()
    );
    // A flag still wins over the cache.
    assert_eq!(
        render_sah(
            dir.path(),
            &device,
            Some(&cache),
            &["--layout", default.name()]
        ),
        default_sah
    );
    // Not pointed at it: the device's default.
    assert_eq!(render_sah(dir.path(), &device, None, &[]), default_sah);
    // A work-group beyond the device's limit is ignored, the layout still taken.
    let big = device.max_work_group_size + 1;
    write_cache(&cache, &device, cached, [big, 1]);
    assert_eq!(
        render_sah(dir.path(), &device, Some(&cache), &[]),
        cached_sah
    );
    // A cache that does not parse is no cache.
    std::fs::write(&cache, "this is not a tuning cache [").unwrap();
    assert_eq!(
        render_sah(dir.path(), &device, Some(&cache), &[]),
        default_sah
    );
}

/// `render -v` names the builder that built the tree: the one `auto` (the default) picked,
/// binned for the built-in scene's 454,720 triangles and the exact sweep for a quad's two.
#[test]
fn verbose_render_names_the_builder_auto_picked() {
    let dir = tempfile::tempdir().unwrap();
    let device = test_device();
    let bvh_line = |extra: &[&str]| verbose_line(dir.path(), &device, None, extra, "bvh: ");
    let built_in = bvh_line(&[]);
    assert!(built_in.starts_with("bvh: binned builder, "), "{built_in}");
    let quad = dir.path().join("quad.obj");
    std::fs::write(
        &quad,
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let swept = bvh_line(&[quad.to_str().unwrap()]);
    assert!(swept.starts_with("bvh: sweep builder, "), "{swept}");
}

/// `render -v` names the layout and work-group its kernels run with, and where they came
/// from: the tuning cache's (its work-group too), a flag's, or the device's default.
#[test]
fn verbose_render_names_its_kernels_and_the_tuning_cache() {
    let dir = tempfile::tempdir().unwrap();
    let device = test_device();
    let kernels_line = |cache: Option<&Path>, extra: &[&str]| {
        verbose_line(dir.path(), &device, cache, extra, "kernels: ")
    };
    let default = default_layout(&device);
    assert!(
        kernels_line(None, &[]).starts_with(&format!(
            "kernels: {} layout (the device's default), ",
            default.name()
        )),
        "{}",
        kernels_line(None, &[])
    );
    let cache = dir.path().join("tune.toml");
    let shape = if device.max_work_group_size >= 64 {
        [16, 4]
    } else {
        [1, 1]
    };
    write_cache(&cache, &device, Layout::Bin32, shape);
    let line = kernels_line(Some(&cache), &[]);
    assert_eq!(
        line,
        format!(
            "kernels: bin32 layout (tuning cache), {}x{} work-groups, tuned in {}",
            shape[0],
            shape[1],
            cache.display()
        )
    );
    let line = kernels_line(Some(&cache), &["--layout", "cwbvh"]);
    assert!(
        line.starts_with("kernels: cwbvh layout (asked for), "),
        "{line}"
    );
}

/// Splits a Markdown table's body rows into cells.
fn markdown_rows(table: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let cells = |line: &str| -> Vec<String> {
        line.trim()
            .trim_matches('|')
            .split('|')
            .map(|c| c.trim().to_string())
            .collect()
    };
    let mut lines = table.lines().filter(|l| l.starts_with('|'));
    let header = cells(lines.next().expect("a table header"));
    let separator = lines.next().expect("a separator row");
    assert!(separator.starts_with("|---"), "{table}");
    (header, lines.map(cells).collect())
}

/// One repetition of `cpu-bvh` and `cl-bvh` (bin32) at 32x24: a Markdown table with a row
/// per method, and the same rows as CSV and JSON, each with a positive speed.
#[test]
fn bench_writes_a_table_csv_and_json_with_a_row_per_method() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let (csv_path, json_path) = (dir.path().join("bench.csv"), dir.path().join("bench.json"));
    let device = test_device();
    let mut cmd = cltrace();
    cmd.arg("bench")
        .arg(&scene)
        .args(["--methods", "cpu-bvh,cl-bvh", "--layouts", "bin32"])
        .args(["--rays", "primary", "--resolutions", "32x24"])
        .args(["--warmup", "0", "--repetitions", "1"])
        .args(["--devices", &device.index()])
        .arg("--csv")
        .arg(&csv_path)
        .arg("--json")
        .arg(&json_path);
    let out: Output = run(cmd);
    succeeded(&out);
    let methods = ["cpu-bvh", "cl-bvh:bin32"];

    let stdout = text(&out.stdout);
    let (header, rows) = markdown_rows(&stdout);
    let column = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no {name} column in\n{stdout}"))
    };
    let (method, mrays, resolution) = (column("method"), column("Mrays/s"), column("resolution"));
    let table_methods: Vec<&str> = rows.iter().map(|r| r[method].as_str()).collect();
    assert_eq!(table_methods, methods, "{stdout}");
    for row in &rows {
        assert_eq!(row.len(), header.len(), "{stdout}");
        assert_eq!(row[resolution], "32x24", "{stdout}");
        let speed: f64 = row[mrays].parse().unwrap_or_else(|_| panic!("{stdout}"));
        assert!(speed > 0.0, "{stdout}");
    }

    let mut csv = csv::Reader::from_path(&csv_path).unwrap();
    let csv_header: Vec<String> = csv.headers().unwrap().iter().map(String::from).collect();
    for field in [
        "scene",
        "width",
        "height",
        "method",
        "device",
        "mrays_per_s",
    ] {
        assert!(
            csv_header.iter().any(|h| h == field),
            "{field} in {csv_header:?}"
        );
    }
    let at = |name: &str| csv_header.iter().position(|h| h == name).unwrap();
    let csv_rows: Vec<(String, f64)> = csv
        .records()
        .map(|r| {
            let r = r.unwrap();
            (
                r[at("method")].to_string(),
                r[at("mrays_per_s")].parse().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        csv_rows.iter().map(|(m, _)| m.as_str()).collect::<Vec<_>>(),
        methods
    );
    assert!(csv_rows.iter().all(|(_, s)| *s > 0.0), "{csv_rows:?}");

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    let json_rows: Vec<(String, f64)> = json
        .as_array()
        .expect("a JSON array of rows")
        .iter()
        .map(|r| {
            assert_eq!(r["width"], 32, "{r}");
            assert_eq!(r["height"], 24, "{r}");
            (
                r["method"].as_str().unwrap().to_string(),
                r["mrays_per_s"].as_f64().unwrap(),
            )
        })
        .collect();
    // The same rows; the speeds to the last bits serde_json's float parsing keeps.
    let same = json_rows.len() == csv_rows.len()
        && json_rows
            .iter()
            .zip(&csv_rows)
            .all(|((m, s), (n, t))| m == n && (s - t).abs() <= 1e-12 * s.abs().max(t.abs()));
    assert!(same, "the JSON holds {json_rows:?}, the CSV {csv_rows:?}");
}

/// `--rays path` on the sphere: a row per method naming its samples per pixel and path
/// length, with positive speeds. Its rays (the JSON's) are more than its samples (each
/// sample's camera ray, and the bounces of those that hit the sphere) and at most two a
/// segment of each, its Msamples/s are the pixels x spp over its median time, and the
/// table's two speeds keep the ratio of rays to samples.
/// `bench --scaling` up to a size of its own: a row per size and ray kind asked for, the
/// largest size the one named, and the plot drawn.
#[test]
fn bench_scaling_measures_each_size_up_to_the_one_asked_for_and_plots_them() {
    let dir = tempfile::tempdir().unwrap();
    let plot = dir.path().join("scaling.png");
    let device = test_device();
    let mut cmd = cltrace();
    cmd.args(["bench", "--scaling", "--scaling-to", "30k"])
        .args(["--methods", "cl-bvh", "--layouts", "bin32"])
        .args([
            "--rays",
            "primary,path",
            "--path-spp",
            "1",
            "--path-bounces",
            "1",
        ])
        .args(["--warmup", "0", "--repetitions", "1"])
        .args(["--devices", &device.index()])
        .arg("--plot")
        .arg(&plot);
    let out: Output = run(cmd);
    succeeded(&out);
    let stdout = text(&out.stdout);
    let (header, rows) = markdown_rows(&stdout);
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    let sizes: Vec<(u64, &str)> = rows
        .iter()
        .map(|r| {
            (
                r[column("triangles")].parse().unwrap(),
                r[column("rays")].as_str(),
            )
        })
        .collect();
    // Hillsides of 2 r^2 triangles: r = 71 and 122 come closest to 10k and 30k.
    assert_eq!(
        sizes,
        [
            (10_082, "primary"),
            (10_082, "path"),
            (29_768, "primary"),
            (29_768, "path")
        ],
        "{stdout}"
    );
    let image = image::open(&plot).unwrap();
    assert!(image.width() > 100 && image.height() > 100);
}

#[test]
fn bench_path_rows_count_samples_and_every_ray() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let json_path = dir.path().join("bench.json");
    let device = test_device();
    let (spp, bounces, segments) = (2u64, 3u64, 5u64);
    let mut cmd = cltrace();
    cmd.arg("bench")
        .arg(&scene)
        .args(["--methods", "cpu-bvh,cl-bvh", "--layouts", "bin32"])
        .args(["--rays", "path", "--resolutions", "16x12"])
        .args(["--path-spp", &spp.to_string()])
        .args(["--path-bounces", &bounces.to_string()])
        .args(["--warmup", "1", "--repetitions", "3"])
        .args(["--devices", &device.index()])
        .arg("--json")
        .arg(&json_path);
    let out: Output = run(cmd);
    succeeded(&out);
    let samples = 16 * 12 * spp;

    let stdout = text(&out.stdout);
    let (header, rows) = markdown_rows(&stdout);
    let column = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no {name} column in\n{stdout}"))
    };
    let (kind, mrays, msamples) = (column("rays"), column("Mrays/s"), column("Msamples/s"));
    assert_eq!(rows.len(), 2, "{stdout}");
    for row in &rows {
        assert_eq!(row.len(), header.len(), "{stdout}");
        assert_eq!(row[kind], "path (2 spp, 5 segments)", "{stdout}");
        let number = |i: usize| -> f64 { row[i].parse().unwrap_or_else(|_| panic!("{stdout}")) };
        assert!(number(msamples) > 0.0, "{stdout}");
        assert!(
            number(mrays) >= number(msamples),
            "fewer rays than samples:\n{stdout}"
        );
    }

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    let json_rows = json.as_array().expect("a JSON array of rows");
    let methods: Vec<&str> = json_rows
        .iter()
        .map(|r| r["method"].as_str().unwrap())
        .collect();
    assert_eq!(methods, ["cpu-bvh", "cl-bvh:bin32"]);
    for r in json_rows {
        assert_eq!(r["ray_kind"], "path", "{r}");
        assert_eq!(r["spp"], spp, "{r}");
        assert_eq!(r["segments"], segments, "{r}");
        let rays = r["rays"].as_u64().expect("a ray count");
        assert!(rays > samples, "{rays} rays for {samples} samples: {r}");
        assert!(rays <= 2 * segments * samples, "{rays} rays: {r}");
        let ms = r["kernel_ms_median"].as_f64().unwrap();
        let (mrays, msamples) = (
            r["mrays_per_s"].as_f64().unwrap(),
            r["msamples_per_s"].as_f64().unwrap(),
        );
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
        assert!(close(msamples, samples as f64 / ms / 1e3), "{r}");
        assert!(close(mrays / msamples, rays as f64 / samples as f64), "{r}");
    }
}

/// Path settings out of range, or no whole numbers, are refused before anything runs:
/// exit 2 and one error line naming the flag (clap's pointer to `--help` aside).
#[test]
fn bench_refuses_bad_path_settings_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    for (flag, value, needle) in [
        (
            "--path-spp",
            "0",
            "--path-spp 0 is out of range: use 1 to 65536",
        ),
        ("--path-spp", "65537", "--path-spp 65537 is out of range"),
        (
            "--path-bounces",
            "1025",
            "--path-bounces 1025 is out of range: use 0 to 1024",
        ),
        ("--path-spp", "-3", "-3 is negative"),
        ("--path-bounces", "two", "`two` is not a number"),
    ] {
        let mut cmd = cltrace();
        cmd.arg("bench")
            .arg(&scene)
            .args([
                "--methods",
                "cpu-bvh",
                "--rays",
                "path",
                "--resolutions",
                "8x6",
            ])
            // `--flag=-3`: a separate `-3` would be taken for a flag.
            .arg(format!("{flag}={value}"));
        let out = run(cmd);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag} {value}: {stderr}");
        assert_eq!(text(&out.stdout), "", "{flag} {value}: stdout");
        let lines: Vec<&str> = stderr.lines().collect();
        assert!(
            lines[0].starts_with("error: ") && lines[0].contains(needle),
            "{flag} {value}: {stderr:?}"
        );
        let clap_note = |l: &&str| l.is_empty() || *l == "For more information, try '--help'.";
        assert!(
            lines[1..].iter().all(clap_note),
            "{flag} {value}: not one line: {stderr:?}"
        );
    }
}

/// `--rays diffuse-16` traces 16 rays for each ray of the plain diffuse batch, and names
/// its rows so.
#[test]
fn bench_diffuse_16_rows_trace_sixteen_rays_for_each_diffuse_one() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let csv_path = dir.path().join("bench.csv");
    let mut cmd = cltrace();
    cmd.arg("bench")
        .arg(&scene)
        .args(["--methods", "cpu-bvh", "--rays", "diffuse,diffuse-16"])
        .args([
            "--resolutions",
            "32x24",
            "--warmup",
            "0",
            "--repetitions",
            "1",
        ])
        .arg("--csv")
        .arg(&csv_path);
    succeeded(&run(cmd));
    let mut csv = csv::Reader::from_path(&csv_path).unwrap();
    let header = csv.headers().unwrap().clone();
    let at = |name: &str| header.iter().position(|h| h == name).unwrap();
    let rows: Vec<(String, u64, f64)> = csv
        .records()
        .map(|r| {
            let r = r.unwrap();
            (
                r[at("ray_kind")].to_string(),
                r[at("rays")].parse().unwrap(),
                r[at("mrays_per_s")].parse().unwrap(),
            )
        })
        .collect();
    let kinds: Vec<&str> = rows.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(kinds, ["diffuse", "diffuse-16"]);
    assert!(rows[0].1 > 100, "{rows:?}");
    assert_eq!(rows[1].1, 16 * rows[0].1, "{rows:?}");
    assert!(rows.iter().all(|r| r.2 > 0.0), "{rows:?}");
}

/// `--work-group` launches every kernel the bench measures in that shape: an odd one (the
/// global size rounded up to it) traces the same rays as the device's default, and one the
/// device cannot run is refused in one line, not replaced by the default.
#[test]
fn bench_launches_in_the_work_group_asked_for_and_refuses_one_the_device_cannot_run() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let device = test_device();
    let bench = |shape: Option<&str>| {
        let json_path = dir.path().join("bench.json");
        let mut cmd = cltrace();
        cmd.arg("bench")
            .arg(&scene)
            .args(["--methods", "cl-bvh", "--layouts", "bin32"])
            .args(["--rays", "primary,diffuse,path", "--path-spp", "2"])
            .args(["--resolutions", "32x24"])
            .args(["--warmup", "0", "--repetitions", "1"])
            .args(["--devices", &device.index(), "--json"])
            .arg(&json_path);
        if let Some(shape) = shape {
            cmd.args(["--work-group", shape]);
        }
        let out = run(cmd);
        (out, json_path)
    };
    let rays = |json_path: &Path| -> Vec<(String, u64)> {
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(json_path).unwrap()).unwrap();
        json.as_array()
            .unwrap()
            .iter()
            .map(|r| {
                assert!(r["mrays_per_s"].as_f64().unwrap() > 0.0, "{r}");
                (
                    r["ray_kind"].as_str().unwrap().to_string(),
                    r["rays"].as_u64().unwrap(),
                )
            })
            .collect()
    };
    let (out, json_path) = bench(None);
    succeeded(&out);
    let default = rays(&json_path);
    let (out, json_path) = bench(Some("3x5"));
    succeeded(&out);
    assert_eq!(rays(&json_path), default);

    let too_large = format!("{0}x{0}", device.max_work_group_size + 1);
    let (out, _) = bench(Some(&too_large));
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with(&format!("error: work-group {too_large} does not fit")),
        "{stderr}"
    );
}

/// `cltrace tune` (one repetition, the test device) writes a cache naming a layout and a
/// work-group for the device, and a render pointed at that cache takes its layout.
#[test]
fn tune_writes_a_cache_that_render_then_reads() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_scene(dir.path());
    let cache = dir.path().join("cache").join("tune.toml");
    let device = test_device();
    let mut cmd = cltrace();
    cmd.arg("tune")
        .arg(&scene)
        .args(["--repetitions", "1", "--devices", &device.index()])
        .arg("--cache")
        .arg(&cache);
    let out = run(cmd);
    succeeded(&out);
    let stdout = text(&out.stdout);
    let (header, rows) = markdown_rows(&stdout);
    assert_eq!(header[..3], ["device", "layout", "work-group"], "{stdout}");
    assert!(!rows.is_empty(), "{stdout}");

    let tuned: Tuning = TuneCache::load(&cache)
        .get(&device)
        .cloned()
        .unwrap_or_else(|| panic!("{} holds no tuning for {}", cache.display(), device.key()));
    assert!(SHAPES.contains(&tuned.work_group), "{tuned:?}");
    assert!(
        tuned.primary_mrays > 0.0 && tuned.diffuse_mrays > 0.0,
        "{tuned:?}"
    );
    assert!(
        rows.iter().any(|r| r[1] == tuned.layout.name()),
        "the cached layout {} is not among the measured:\n{stdout}",
        tuned.layout.name()
    );
    assert!(
        !no_tune_cache().exists(),
        "tune wrote the tests' shared cache"
    );

    let expected = render_sah(
        dir.path(),
        &device,
        None,
        &["--layout", tuned.layout.name()],
    );
    assert_eq!(render_sah(dir.path(), &device, Some(&cache), &[]), expected);
}

/// The path rows looked at the Cornell box from behind its back wall: the benchmark's
/// straight-on view, where no path enters the box. They take the scene file's camera
/// (and lights): from inside a closed cube every path bounces on (about 5 rays a sample
/// at 3 bounces with a point light), where from the outside one bounce escapes (at most 3).
#[test]
fn bench_path_rows_looked_at_the_box_from_outside_instead_of_through_the_scene_camera() {
    let dir = tempfile::tempdir().unwrap();
    let rays_per_sample = |camera: &str| {
        let scene = dir.path().join("cube.toml");
        std::fs::write(
            &scene,
            format!(
                "[[mesh]]\ngenerator = {{ kind = \"cube\" }}\nscale = 2.0\n{camera}\n\
                 [[light]]\ntype = \"point\"\nposition = [0.5, 0.5, 0.5]\n"
            ),
        )
        .unwrap();
        let json_path = dir.path().join("bench.json");
        let mut cmd = cltrace();
        cmd.arg("bench")
            .arg(&scene)
            .args([
                "--methods",
                "cpu-bvh",
                "--rays",
                "path",
                "--resolutions",
                "16x12",
            ])
            .args(["--path-spp", "2", "--path-bounces", "3", "--warmup", "0"])
            .args(["--repetitions", "1", "--json"])
            .arg(&json_path);
        succeeded(&run(cmd));
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
        json[0]["rays"].as_u64().unwrap() as f64 / (16.0 * 12.0 * 2.0)
    };
    let inside = rays_per_sample("[camera]\neye = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]");
    let outside = rays_per_sample("");
    assert!(inside > 4.5, "from inside the cube: {inside} rays a sample");
    assert!(
        outside < 3.5,
        "the benchmark's view: {outside} rays a sample"
    );
}
