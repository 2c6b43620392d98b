//! The lights besides emitting triangles (src/light/): the environment's sampling against
//! its density (a chi-square test of goodness of fit, as for the BSDFs in tests/bsdf.rs),
//! and the scene-file tables and flags that describe lights, with their errors. The
//! kernels against the host on every light are in tests/secondary.rs; the images against
//! Mitsuba 3 in tests/mitsuba.rs.

use std::f64::consts::PI;

use cltrace::light::Environment;
use cltrace::light::sky::Sky;
use glam::Vec3;

use crate::common::command::{cltrace, run, text};
use crate::common::{chi_square_fails, uniform};

const Y_BINS: usize = 16;
const PHI_BINS: usize = 32;

/// The bin of unit direction `w`: equal solid angles, uniform in y and in the world's
/// azimuth atan2(x, -z) (the map's own convention, so that the turn is a shift of u).
fn bin(w: Vec3) -> usize {
    let y = ((w.y.clamp(-1.0, 1.0) + 1.0) * 0.5 * Y_BINS as f32) as usize;
    let mut phi = (w.x as f64).atan2(-w.z as f64);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let p = (phi / (2.0 * PI) * PHI_BINS as f64) as usize;
    y.min(Y_BINS - 1) * PHI_BINS + p.min(PHI_BINS - 1)
}

/// The length of [a0, a1] ∩ [b0, b1].
fn overlap(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.1.min(b.1) - a.0.max(b.0)).max(0.0)
}

/// The probability of each bin, exactly: the density is constant over each texel's
/// rectangle of (u, v), and a bin is a rectangle of (u, v) too (its y range a range of v,
/// its azimuths a range of u shifted by the map's turn, wrapping).
fn bin_probabilities(env: &Environment) -> Vec<f64> {
    let (w, h) = (env.width as usize, env.height as usize);
    let turn = (env.rotation[1] as f64).atan2(env.rotation[0] as f64) / (2.0 * PI);
    let mut out = vec![0.0; Y_BINS * PHI_BINS];
    for yb in 0..Y_BINS {
        let y0 = -1.0 + 2.0 * yb as f64 / Y_BINS as f64;
        let y1 = y0 + 2.0 / Y_BINS as f64;
        let v = ((y1.acos()) / PI, (y0.acos()) / PI);
        for pb in 0..PHI_BINS {
            let u0 = (pb as f64 / PHI_BINS as f64 + turn).rem_euclid(1.0);
            let u1 = u0 + 1.0 / PHI_BINS as f64;
            let mut p = 0.0;
            for j in 0..h {
                let ov = overlap(v, (j as f64 / h as f64, (j + 1) as f64 / h as f64));
                if ov == 0.0 {
                    continue;
                }
                for i in 0..w {
                    let t = (i as f64 / w as f64, (i + 1) as f64 / w as f64);
                    let ou = overlap((u0, u1), t) + overlap((u0 - 1.0, u1 - 1.0), t);
                    p += env.texels[j * w + i][3] as f64 * ou * ov;
                }
            }
            out[yb * PHI_BINS + pb] = p;
        }
    }
    out
}

/// Test maps: a gradient with a bright texel and a black band (which no sample may reach),
/// turned; a baked sun and sky (the sun a few texels); one colour.
fn maps() -> Vec<(&'static str, Environment)> {
    let (w, h) = (24, 12);
    let rgb: Vec<[f32; 3]> = (0..w * h)
        .map(|k| match (k % w, k / w) {
            (_, 9) => [0.0; 3],
            (17, 3) => [80.0, 70.0, 60.0],
            (i, j) => [0.1 + 0.04 * j as f32, 0.3, 0.2 + 0.03 * i as f32],
        })
        .collect();
    let sky = Sky {
        sun: Vec3::new(0.3, 0.5, -0.8).normalize(),
        turbidity: 4.0,
        intensity: 1.0,
    };
    vec![
        (
            "gradient",
            Environment::new(w as u32, h as u32, &rgb, 1.0, 75.0),
        ),
        (
            "sky",
            Environment::new(256, 128, &sky.bake(256, 128), 1.0, -30.0),
        ),
        (
            "colour",
            Environment::constant(Vec3::new(0.2, 0.5, 0.9), 3.0),
        ),
    ]
}

/// The environment samples directions as its density says: histograms of 400,000
/// samples against each bin's probability, computed exactly from the texels' densities;
/// bins expecting fewer than 5 samples are pooled. Each sample's density and radiance are
/// also the ones a lookup of its direction gives (bar the few on a texel's edge).
#[test]
fn environment_maps_sample_directions_as_their_density_says() {
    const N: u64 = 400_000;
    let mut failures = Vec::new();
    for (name, env) in maps() {
        let mut observed = vec![0f64; Y_BINS * PHI_BINS];
        let mut mismatched = 0;
        for i in 0..N {
            let (d, le, pdf) = env.sample(uniform(i, 0), uniform(i, 1));
            if pdf <= 0.0 {
                continue;
            }
            assert!((d.length() - 1.0).abs() < 1e-4, "{name}: {d} not unit");
            let (le2, pdf2) = env.radiance(d);
            if le2 != le || (pdf - pdf2).abs() > 1e-3 * pdf {
                mismatched += 1;
            }
            assert!(
                le.max_element() > 0.0,
                "{name}: a sample where there is no light"
            );
            observed[bin(d)] += 1.0;
        }
        assert!(
            mismatched < N / 1000,
            "{name}: {mismatched} samples look up another texel"
        );
        let probabilities = bin_probabilities(&env);
        let total: f64 = probabilities.iter().sum();
        if (total - 1.0).abs() > 1e-4 {
            failures.push(format!("{name}: the density integrates to {total}"));
        }
        let expected: Vec<f64> = probabilities.iter().map(|p| p * N as f64).collect();
        if let Some(why) = chi_square_fails(&observed, &expected) {
            failures.push(format!("{name}: {why}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Light samples of the map estimate the irradiance of an upward-facing point without bias:
/// the mean of L cos / pdf over many samples equals the exact integral of radiance times
/// cosine, texel by texel (∫ cos θ sin θ dθ dφ over each texel's rectangle above the
/// horizon; a turn about +y changes no texel's share).
#[test]
fn environment_light_samples_estimate_irradiance_without_bias() {
    for (name, env) in maps() {
        let n = 400_000;
        let (mut sum, mut sq) = (0.0f64, 0.0f64);
        for i in 0..n {
            let (d, le, pdf) = env.sample(uniform(i, 2), uniform(i, 3));
            let v = if pdf > 0.0 && d.y > 0.0 {
                (le.y * d.y / pdf) as f64
            } else {
                0.0
            };
            sum += v;
            sq += v * v;
        }
        let mean = sum / n as f64;
        let err = ((sq / n as f64 - mean * mean) / n as f64).sqrt();
        let (w, h) = (env.width as usize, env.height as usize);
        let mut exact = 0.0;
        for j in 0..h {
            let t0 = PI * j as f64 / h as f64;
            let t1 = (PI * (j + 1) as f64 / h as f64).min(PI / 2.0);
            if t0 >= PI / 2.0 {
                break;
            }
            let band = (t1.sin().powi(2) - t0.sin().powi(2)) / 2.0 * (2.0 * PI / w as f64);
            for i in 0..w {
                exact += env.texels[j * w + i][1] as f64 * band;
            }
        }
        assert!(
            (mean - exact).abs() <= 4.0 * err + 1e-4 * exact,
            "{name}: estimate {mean} ± {err}, integral {exact}"
        );
    }
}

fn scene_with(dir: &std::path::Path, lights: &str) -> std::path::PathBuf {
    let path = dir.join("scene.toml");
    std::fs::write(
        &path,
        format!(
            "[[mesh]]\ngenerator = {{ kind = \"sphere\", subdivisions = 1 }}\n[ground]\n\
             [render]\nmethod = \"cpu-bvh\"\nshade = \"path\"\nspp = 2\n{lights}\n"
        ),
    )
    .unwrap();
    path
}

fn render(scene: &std::path::Path, out: &std::path::Path, flags: &[&str]) -> std::process::Output {
    let mut cmd = cltrace();
    cmd.arg("render")
        .arg(scene)
        .args(["--width", "16", "--height", "12", "-q", "-o"])
        .arg(out)
        .args(flags);
    run(cmd)
}

/// Writes a 4 x 2 Radiance HDR map (the format's flat, uncompressed form).
fn write_hdr(path: &std::path::Path, texel: [u8; 4]) {
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n".to_vec();
    for _ in 0..8 {
        bytes.extend(texel);
    }
    std::fs::write(path, bytes).unwrap();
}

/// Every light table and flag renders; each bad value is one line naming the scene file's
/// line (or the flag), exit 2.
#[test]
fn scene_files_and_flags_give_every_light_and_refuse_bad_values() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.png");
    write_hdr(&dir.path().join("sky.hdr"), [128, 128, 160, 129]);
    for good in [
        "[environment]\nfile = \"sky.hdr\"\nintensity = 2.0\nrotate = -45",
        "[environment]\ncolor = [0.2, 0.3, 0.4]",
        "[sky]\nsun_direction = [1.0, 1.0, 0.0]\nturbidity = 5",
        "[sky]\nlatitude = 48.1\nlongitude = 11.6\ntime = \"2026-06-21T09:30:00+02:00\"",
        "[[light]]\ntype = \"point\"\nposition = [0.0, 3.0, 0.0]\nintensity = 5",
        "[[light]]\ntype = \"spot\"\nposition = [0.0, 3.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\n\
         intensity = [5.0, 4.0, 3.0]\ncutoff = 30\nbeam = 10",
        "[[light]]\ntype = \"directional\"\ndirection = [0.3, -1.0, 0.2]\nirradiance = 2\n\
         [[light]]\ntype = \"point\"\nposition = [1.0, 2.0, 0.0]",
    ] {
        let o = render(&scene_with(dir.path(), good), &out, &[]);
        assert!(o.status.success(), "{good}: {}", text(&o.stderr));
    }
    std::fs::remove_file(&out).unwrap();
    for (bad, says) in [
        ("[environment]\nfile = \"none.hdr\"", "none.hdr"),
        ("[environment]\ncolor = [0.2, -0.3, 0.4]", "color"),
        (
            "[environment]\nfile = \"sky.hdr\"\ncolor = [1.0, 1.0, 1.0]",
            "not both",
        ),
        ("[environment]\nintensity = 2.0", "needs a file or a color"),
        (
            "[environment]\ncolor = [1.0, 1.0, 1.0]\nintensity = -1",
            "intensity -1",
        ),
        (
            "[environment]\ncolor = [1.0, 1.0, 1.0]\n[sky]\nsun_direction = [0.0, 1.0, 0.0]",
            "not both",
        ),
        ("[sky]\nsun_direction = [0.0, 0.0, 0.0]", "cannot be zero"),
        (
            "[sky]\nsun_direction = [0.0, 1.0, 0.0]\nturbidity = 20",
            "turbidity 20",
        ),
        (
            "[sky]\nlatitude = 48.1\nlongitude = 11.6\ntime = \"noon\"",
            "noon",
        ),
        ("[sky]\nlatitude = 48.1", "latitude, longitude and time"),
        (
            "[[light]]\ntype = \"area\"\nposition = [0.0, 1.0, 0.0]",
            "area",
        ),
        ("[[light]]\ntype = \"point\"", "needs position"),
        (
            "[[light]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nirradiance = 1",
            "irradiance is for",
        ),
        (
            "[[light]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\ncutoff = 120",
            "cutoff 120",
        ),
        (
            "[[light]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\ncutoff = 20\nbeam = 30",
            "beam 30",
        ),
        (
            "[[light]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [1.0, 1.0]",
            "three numbers",
        ),
        (
            "[[light]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [1.0, 1.0, inf]",
            "intensity",
        ),
        (
            "[[light]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\ncolour = [1.0, 1.0, 1.0]",
            "colour",
        ),
    ] {
        let o = render(&scene_with(dir.path(), bad), &out, &[]);
        let stderr = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{bad}: {stderr}");
        assert!(stderr.contains(says), "{bad}: {stderr}");
        assert!(!out.exists(), "{bad}: an image was written");
    }
    // Flags: a file or a colour, with intensity and rotation over the scene's.
    let plain = scene_with(dir.path(), "");
    let sky = dir.path().join("sky.hdr");
    let sky = sky.to_str().unwrap();
    for good in [
        vec!["--environment", sky, "--environment-rotate", "-90"],
        vec![
            "--environment",
            "0.5,0.5,0.5",
            "--environment-intensity",
            "2",
        ],
    ] {
        let o = render(&plain, &out, &good);
        assert!(o.status.success(), "{good:?}: {}", text(&o.stderr));
    }
    for (bad, says) in [
        (vec!["--environment-intensity", "2"], "need an environment"),
        (vec!["--environment", "0.5,-1,0.5"], "--environment"),
        (
            vec!["--environment", sky, "--environment-intensity", "-2"],
            "--environment-intensity",
        ),
        (vec!["--environment", "missing.exr"], "missing.exr"),
    ] {
        let o = render(&plain, &out, &bad);
        let stderr = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bad:?}: {stderr}");
        assert!(stderr.contains(says), "{bad:?}: {stderr}");
    }
}

/// Rays that leave the scene saw the default sky even with a point light or an
/// environment given (the sky is the fallback of scenes with no light at all): with a
/// point light only, they are black; with a constant environment, its colour.
#[test]
fn the_default_sky_lit_scenes_that_had_lights_of_their_own() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("out.exr");
    let corner = |flags: &[&str], lights: &str| {
        // Looking up, over the sphere, at the sky.
        let mut flags = flags.to_vec();
        flags.extend(["--eye", "0,0,4", "--look-at", "0,3,0"]);
        let o = render(&scene_with(dir.path(), lights), &exr, &flags);
        assert!(o.status.success(), "{}", text(&o.stderr));
        // The top-left pixel looks over the ground at the sky.
        let img = image::open(&exr).unwrap().to_rgb32f();
        let p = img.get_pixel(0, 0).0;
        std::fs::remove_file(&exr).unwrap();
        p
    };
    let sky = corner(&[], "");
    assert!(sky[2] > 0.5, "the default sky: {sky:?}");
    let dark = corner(
        &[],
        "[[light]]\ntype = \"point\"\nposition = [0.0, 3.0, 0.0]",
    );
    assert_eq!(dark, [0.0; 3], "a point light alone");
    let colour = corner(&["--environment", "0.25,0.5,0.75"], "");
    assert_eq!(colour, [0.25, 0.5, 0.75], "a constant environment");
}
