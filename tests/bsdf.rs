//! The scattering models (src/render/bsdf.rs), as Mitsuba's and pbrt's test suites check
//! theirs: every model's sampling against its density (a chi-square test of goodness of
//! fit), energy kept or lost as designed and never gained (a white furnace), and the
//! kernels' path tracer against the host's on every model.

use cltrace::material::{Bsdf, CONDUCTORS, Material};
use cltrace::render::bsdf::Shading;
use glam::Vec3;

use crate::common::{chi_square_fails, uniform};

/// The models to check, each with a name: every [`Bsdf`], smooth and rough, and glTF's
/// metal blend.
fn models() -> Vec<(String, Shading)> {
    let gold = CONDUCTORS.iter().find(|c| c.0 == "gold").unwrap();
    let base = |bsdf: Bsdf, alpha: f32| Shading {
        bsdf: bsdf.code(),
        albedo: Vec3::new(0.9, 0.6, 0.3),
        specular: Vec3::ONE,
        eta: Vec3::ZERO,
        k: Vec3::ZERO,
        ior: 1.5,
        alpha,
        metallic: 0.0,
    };
    let mut out = Vec::new();
    for alpha in [0.0, 0.05, 0.3, 0.8] {
        for bsdf in Bsdf::ALL {
            out.push((format!("{} alpha {alpha}", bsdf.name()), base(bsdf, alpha)));
        }
        out.push((
            format!("gold alpha {alpha}"),
            Shading {
                eta: Vec3::from(gold.1),
                k: Vec3::from(gold.2),
                ..base(Bsdf::Conductor, alpha)
            },
        ));
        out.push((
            format!("glass from inside alpha {alpha}"),
            Shading {
                ior: 1.0 / 1.5,
                ..base(Bsdf::Dielectric, alpha)
            },
        ));
        out.push((
            format!("plastic half metal alpha {alpha}"),
            Shading {
                metallic: 0.5,
                ..base(Bsdf::Plastic, alpha)
            },
        ));
    }
    out
}

/// Directions of the viewer to check from: near the normal, oblique, grazing.
fn views() -> [Vec3; 3] {
    [
        Vec3::new(0.1, 0.0, 1.0).normalize(),
        Vec3::new(0.6, 0.3, 0.5).normalize(),
        Vec3::new(0.95, -0.1, 0.12).normalize(),
    ]
}

const THETA_BINS: usize = 10;
const PHI_BINS: usize = 20;

/// The bin of unit direction `w`: equal solid angles (uniform in z and in phi).
fn bin(w: Vec3) -> usize {
    let z = ((w.z.clamp(-1.0, 1.0) + 1.0) * 0.5 * THETA_BINS as f32) as usize;
    let phi = w.y.atan2(w.x) + std::f32::consts::PI;
    let p = (phi / (2.0 * std::f32::consts::PI) * PHI_BINS as f32) as usize;
    z.min(THETA_BINS - 1) * PHI_BINS + p.min(PHI_BINS - 1)
}

/// The density of `model` seen from `wo` integrated over polar angles `theta` and
/// azimuths `phi`: the midpoint rule, its points doubled until two estimates agree to
/// 0.1% (narrow lobes, and the density's steep edges where refraction stops, need many).
fn integrate(model: &Shading, wo: Vec3, theta: (f64, f64), phi: (f64, f64)) -> f64 {
    let estimate = |n: usize| {
        let (dt, dp) = ((theta.1 - theta.0) / n as f64, (phi.1 - phi.0) / n as f64);
        let mut sum = 0.0;
        for a in 0..n {
            let t = theta.0 + (a as f64 + 0.5) * dt;
            let (r, z) = (t.sin(), t.cos());
            for b in 0..n {
                let p = phi.0 + (b as f64 + 0.5) * dp;
                let wi = Vec3::new((r * p.cos()) as f32, (r * p.sin()) as f32, z as f32);
                sum += model.eval(wo, wi).1 as f64 * r;
            }
        }
        sum * dt * dp
    };
    let (mut n, mut last) = (8, estimate(8));
    loop {
        n *= 2;
        let next = estimate(n);
        // Zero twice may be a narrow region that no point has found yet.
        let agree = (next - last).abs() <= 1e-3 * next + 1e-8 && (next > 0.0 || n >= 128);
        if agree || n >= 512 {
            return next;
        }
        last = next;
    }
}

/// Sampling draws its directions as its density says: histograms of 200,000 samples per
/// model and view against the density integrated over each bin (8 x 8 points a bin);
/// bins expecting fewer than 5 samples are pooled, as in Mitsuba's test suite. Delta
/// lobes' samples are left out: the densities integrate to the share that is not delta.
#[test]
fn every_bsdf_samples_directions_as_its_density_says() {
    const N: u64 = 200_000;
    let mut failures = Vec::new();
    for (name, model) in models() {
        if model.all_delta() {
            continue;
        }
        for (v, wo) in views().into_iter().enumerate() {
            let mut observed = vec![0f64; THETA_BINS * PHI_BINS];
            for i in 0..N {
                let u = |d| uniform(i + 7919 * v as u64, d);
                if let Some(s) = model.sample(wo, u(0), u(1), u(2), u(3))
                    && !s.delta
                {
                    assert!(
                        (s.wi.length() - 1.0).abs() < 1e-3,
                        "{name}: wi {} not unit",
                        s.wi
                    );
                    let (f, pdf) = model.eval(wo, s.wi);
                    assert!(
                        (pdf - s.pdf).abs() <= 1e-3 * pdf.max(1.0),
                        "{name}: sampled pdf {} against eval's {pdf}",
                        s.pdf
                    );
                    assert!(f.is_finite() && s.weight.is_finite(), "{name}: not finite");
                    observed[bin(s.wi)] += 1.0;
                }
            }
            // The expected count: the density integrated over each bin.
            let mut expected = vec![0f64; THETA_BINS * PHI_BINS];
            let pi = std::f64::consts::PI;
            for zb in 0..THETA_BINS {
                let z0 = -1.0 + 2.0 * zb as f64 / THETA_BINS as f64;
                let z1 = -1.0 + 2.0 * (zb + 1) as f64 / THETA_BINS as f64;
                for pb in 0..PHI_BINS {
                    let p0 = -pi + 2.0 * pi * pb as f64 / PHI_BINS as f64;
                    let p1 = p0 + 2.0 * pi / PHI_BINS as f64;
                    expected[zb * PHI_BINS + pb] =
                        integrate(&model, wo, (z1.acos(), z0.acos()), (p0, p1)) * N as f64;
                }
            }
            if let Some(why) = chi_square_fails(&observed, &expected) {
                failures.push(format!("{name}, view {v}: {why}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The white furnace: with a white base colour and untinted specular parts, the share of
/// light a model reflects or passes on (the mean of its sample weights) is at most 1 from
/// every view, within 4 standard errors; the smooth dielectrics and the thin sheet keep
/// exactly all of it (refracted radiance counted without its 1 / eta² compression), and a
/// smooth mirror of a conductor keeps its Fresnel reflectance.
#[test]
fn no_bsdf_reflects_more_light_than_arrives() {
    const N: u64 = 100_000;
    let mut failures = Vec::new();
    for (name, model) in models() {
        let model = Shading {
            albedo: Vec3::ONE,
            ..model
        };
        for (v, wo) in views().into_iter().enumerate() {
            let (mut sum, mut sum2) = (0f64, 0f64);
            for i in 0..N {
                let u = |d| uniform(i + 104_729 * v as u64, d);
                let Some(s) = model.sample(wo, u(0), u(1), u(2), u(3)) else {
                    continue;
                };
                let mut w = s.weight.max_element() as f64;
                if s.transmitted && model.bsdf == Bsdf::Dielectric.code() {
                    w *= (model.ior * model.ior) as f64;
                }
                sum += w;
                sum2 += w * w;
            }
            let mean = sum / N as f64;
            let se = ((sum2 / N as f64 - mean * mean).max(0.0) / N as f64).sqrt();
            if mean > 1.0 + 4.0 * se + 1e-3 {
                failures.push(format!("{name}, view {v}: keeps {mean:.4} +- {se:.4}"));
            }
            let exact = model.smooth()
                && (model.bsdf == Bsdf::Dielectric.code()
                    || model.bsdf == Bsdf::ThinDielectric.code());
            if exact && (mean - 1.0).abs() > 1e-4 {
                failures.push(format!("{name}, view {v}: keeps {mean:.6}, not all"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Materials in the scene files: each model's keys reach the material, and bad values are
/// one-line errors at their line.
#[test]
fn scene_files_give_every_model_and_refuse_bad_values() {
    use crate::common::command::{cltrace, run, text};
    let dir = tempfile::tempdir().unwrap();
    let scene = |material: &str| {
        let path = dir.path().join("scene.toml");
        std::fs::write(
            &path,
            format!(
                "[[mesh]]\ngenerator = {{ kind = \"sphere\", subdivisions = 1 }}\n\
                 material = {{ {material} }}\n[render]\nmethod = \"cpu-bvh\"\nshade = \"path\"\nspp = 1\n"
            ),
        )
        .unwrap();
        let mut cmd = cltrace();
        cmd.arg("render")
            .arg(&path)
            .args(["--width", "8", "--height", "8", "-q", "-o"])
            .arg(dir.path().join("out.png"));
        run(cmd)
    };
    for good in [
        "bsdf = \"conductor\", metal = \"gold\", roughness = 0.3",
        "bsdf = \"conductor\", eta = [0.2, 0.9, 1.1], k = [3.9, 2.4, 2.1]",
        "bsdf = \"dielectric\", ior = 1.33, specular = [0.9, 1.0, 0.9]",
        "bsdf = \"thin-dielectric\"",
        "bsdf = \"plastic\", albedo = [0.2, 0.3, 0.8], roughness = 0.2",
        "albedo = [0.8, 0.8, 0.8], metallic = 0.5, roughness = 0.5",
    ] {
        let out = scene(good);
        assert!(out.status.success(), "{good}: {}", text(&out.stderr));
    }
    for (bad, says) in [
        ("bsdf = \"velvet\"", "velvet"),
        ("roughness = 1.5", "roughness 1.5"),
        ("metallic = -0.1", "metallic -0.1"),
        ("ior = 0.0", "ior 0"),
        ("metal = \"unobtainium\"", "unobtainium"),
        (
            "metal = \"gold\", eta = [1.0, 1.0, 1.0]",
            "one or the other",
        ),
        ("specular = [2.0, 0.0, 0.0]", "specular"),
        ("k = [1.0, 1.0, 1.0]", "positive eta"),
    ] {
        let out = scene(bad);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{bad}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{bad}: {stderr}");
        assert!(
            stderr.contains(says) && stderr.contains("scene.toml:"),
            "{bad}: {stderr}"
        );
    }
}

/// [`Material`] keeps the model a scene file names, by code.
#[test]
fn bsdf_codes_round_trip() {
    for b in Bsdf::ALL {
        assert_eq!(Bsdf::from_code(b.code()), b);
        let m = Material::with_bsdf(b, [0.5; 3], 0.2);
        assert_eq!(Bsdf::from_code(m.bsdf), b);
    }
}
