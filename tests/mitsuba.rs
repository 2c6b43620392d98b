//! cltrace against a peer: Mitsuba 3 (`scalar_rgb`) rendered small scenes, written by
//! `scripts/mitsuba/compare.py` from one description for both renderers, and the references
//! are committed in `tests/data/mitsuba/<scene>/` (the scene's cltrace inputs, two
//! independent half renders `mitsuba_0.exr` and `mitsuba_1.exr`, `regions.png` and
//! `scene.json`). Each test renders one scene with the binary as two halves of different
//! seeds and holds every region's mean, per channel, to the rule of `scene.json`:
//! `|c - m| <= sigmas * sqrt(sc^2 + sm^2) + bias * m`, each `s^2` the variance of a mean
//! estimated from the two halves pixel by pixel (scripts/mitsuba/README.md says why). One
//! test renders a wrong albedo and checks that the comparison rejects it.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::common::command::{cltrace, run, succeeded};

/// cltrace's samples per pixel in each half: 2 x 512 at 64x64 is 4 M samples a scene, about
/// 2 s on PoCL on CI's two cores.
const SPP_PER_HALF: u32 = 512;

/// The region index of pixels that are not checked.
const UNCHECKED: u8 = 255;

fn references() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba")
}

/// Linear RGB, row by row.
type Image = Vec<[f64; 3]>;

fn read_rgb(path: &Path, width: u32, height: u32) -> Image {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_rgb32f();
    assert_eq!(
        (img.width(), img.height()),
        (width, height),
        "{}: the size of the scene",
        path.display()
    );
    img.pixels()
        .map(|p| [p.0[0] as f64, p.0[1] as f64, p.0[2] as f64])
        .collect()
}

/// One scene's committed reference.
struct Reference {
    name: String,
    dir: PathBuf,
    width: u32,
    height: u32,
    max_bounces: u32,
    sigmas: f64,
    bias: f64,
    /// Region names by index.
    regions: Vec<String>,
    /// Each pixel's region index ([`UNCHECKED`] outside every region).
    map: Vec<u8>,
    halves: [Image; 2],
}

impl Reference {
    fn load(name: &str) -> Self {
        let dir = references().join(name);
        let json = std::fs::read_to_string(dir.join("scene.json"))
            .unwrap_or_else(|e| panic!("{}: {e}", dir.join("scene.json").display()));
        let info: serde_json::Value = serde_json::from_str(&json).expect("scene.json is JSON");
        let number = |v: &serde_json::Value, what: &str| {
            v.as_f64()
                .unwrap_or_else(|| panic!("{name}/scene.json: {what} is a number"))
        };
        let width = number(&info["size"][0], "size[0]") as u32;
        let height = number(&info["size"][1], "size[1]") as u32;
        let regions: Vec<String> = info["regions"]
            .as_array()
            .expect("scene.json lists regions")
            .iter()
            .enumerate()
            .map(|(i, r)| {
                assert_eq!(number(&r["index"], "a region's index") as usize, i);
                r["name"].as_str().expect("a region's name").to_string()
            })
            .collect();
        let map = image::open(dir.join("regions.png"))
            .expect("regions.png")
            .into_luma8();
        assert_eq!((map.width(), map.height()), (width, height), "regions.png");
        let map = map.into_raw();
        assert!(
            map.iter()
                .all(|&r| r == UNCHECKED || (r as usize) < regions.len()),
            "{name}: regions.png names only the regions of scene.json"
        );
        let halves = [0, 1].map(|h| read_rgb(&dir.join(format!("mitsuba_{h}.exr")), width, height));
        Reference {
            name: name.to_string(),
            width,
            height,
            max_bounces: number(&info["max_bounces"], "max_bounces") as u32,
            sigmas: number(&info["tolerance"]["sigmas"], "tolerance.sigmas"),
            bias: number(&info["tolerance"]["bias"], "tolerance.bias"),
            regions,
            map,
            halves,
            dir,
        }
    }

    /// cltrace's two halves of `scene` (this reference's scene.toml, or a changed copy),
    /// seeds 0 and 1, at this reference's size and depth.
    fn render(&self, scene: &Path, spp: u32) -> [Image; 2] {
        let out = tempfile::tempdir().unwrap();
        [0, 1].map(|seed| {
            let path = out.path().join(format!("half_{seed}.exr"));
            let mut cmd = cltrace();
            cmd.arg("render")
                .arg(scene)
                .args(["--shade", "path", "--spp", &spp.to_string()])
                .args(["--seed", &seed.to_string()])
                .args(["--max-bounces", &self.max_bounces.to_string()])
                .args(["--width", &self.width.to_string()])
                .args(["--height", &self.height.to_string()])
                .arg("-o")
                .arg(&path)
                .arg("-q");
            succeeded(&run(cmd));
            read_rgb(&path, self.width, self.height)
        })
    }

    /// Every region and channel: (region, channel, cltrace's mean, Mitsuba's, allowance).
    fn compare(&self, cltrace: &[Image; 2]) -> Vec<Row> {
        let mut rows = Vec::new();
        for (index, region) in self.regions.iter().enumerate() {
            let pixels: Vec<usize> = (0..self.map.len())
                .filter(|&p| self.map[p] as usize == index)
                .collect();
            assert!(
                !pixels.is_empty(),
                "{}: region {region} is empty",
                self.name
            );
            let (c, sc) = mean_and_sigma(cltrace, &pixels);
            let (m, sm) = mean_and_sigma(&self.halves, &pixels);
            for ch in 0..3 {
                rows.push(Row {
                    region: region.clone(),
                    channel: ["R", "G", "B"][ch],
                    cltrace: c[ch],
                    mitsuba: m[ch],
                    allowance: self.sigmas * sc[ch].hypot(sm[ch]) + self.bias * m[ch],
                });
            }
        }
        rows
    }
}

struct Row {
    region: String,
    channel: &'static str,
    cltrace: f64,
    mitsuba: f64,
    allowance: f64,
}

impl Row {
    fn passes(&self) -> bool {
        (self.cltrace - self.mitsuba).abs() <= self.allowance
    }
}

/// The region's mean of both halves, per channel, and the standard deviation of that mean:
/// pixels are independent, and `((a - b) / 2)^2` estimates the variance of a pixel's
/// `(a + b) / 2` without bias when its halves `a` and `b` are independent and alike.
fn mean_and_sigma(halves: &[Image; 2], pixels: &[usize]) -> ([f64; 3], [f64; 3]) {
    let n = pixels.len() as f64;
    let (mut mean, mut var) = ([0.0; 3], [0.0; 3]);
    for &p in pixels {
        for ch in 0..3 {
            let (a, b) = (halves[0][p][ch], halves[1][p][ch]);
            mean[ch] += (a + b) / 2.0 / n;
            var[ch] += ((a - b) / 2.0).powi(2) / (n * n);
        }
    }
    (mean, var.map(f64::sqrt))
}

/// The comparison as compare.py prints it.
fn table(scene: &str, rows: &[Row]) -> String {
    let mut t = String::from(
        "scene     region                       ch   cltrace   mitsuba   diff %  allow %  pass\n",
    );
    for r in rows {
        let pct = |x: f64| {
            if r.mitsuba > 0.0 {
                format!("{:8.2}", 100.0 * x / r.mitsuba)
            } else {
                format!("{:>8}", "-")
            }
        };
        writeln!(
            t,
            "{scene:<9} {:<28} {}  {:9.5} {:9.5} {} {}  {}",
            r.region,
            r.channel,
            r.cltrace,
            r.mitsuba,
            pct(r.cltrace - r.mitsuba),
            pct(r.allowance),
            if r.passes() { "yes" } else { "NO" }
        )
        .unwrap();
    }
    t
}

#[track_caller]
fn regions_match_mitsuba(scene: &str) {
    let reference = Reference::load(scene);
    let rows =
        reference.compare(&reference.render(&reference.dir.join("scene.toml"), SPP_PER_HALF));
    let failures = rows.iter().filter(|r| !r.passes()).count();
    assert!(
        failures == 0,
        "{failures} region channels of {scene} disagree with Mitsuba beyond the tolerance:\n{}",
        table(scene, &rows)
    );
}

#[test]
fn cornell_box_regions_match_mitsuba() {
    regions_match_mitsuba("cornell");
}

#[test]
fn lit_quad_regions_match_mitsuba() {
    regions_match_mitsuba("quad");
}

#[test]
fn faceted_sphere_regions_match_mitsuba() {
    regions_match_mitsuba("sphere");
}

#[test]
fn textured_quad_regions_match_mitsuba() {
    regions_match_mitsuba("textured");
}

// The materials (cltrace's BSDF models with MIS): a closed faceted sphere of each on the
// sphere scene's floor, under its emitter (compare.py's `material_scene`).

#[test]
fn rough_gold_sphere_regions_match_mitsuba() {
    regions_match_mitsuba("gold");
}

#[test]
fn smooth_silver_mirror_sphere_regions_match_mitsuba() {
    regions_match_mitsuba("mirror");
}

#[test]
fn smooth_glass_sphere_regions_match_mitsuba() {
    regions_match_mitsuba("glass");
}

#[test]
fn rough_glass_sphere_regions_match_mitsuba() {
    regions_match_mitsuba("rough-glass");
}

#[test]
fn smooth_plastic_sphere_regions_match_mitsuba() {
    regions_match_mitsuba("plastic");
}

/// cltrace's rough plastic against Mitsuba's rendering of the same model: `roughplastic`'s
/// coating alone plus `plastic`'s base alone (compare.py's "split" correspondence), which
/// holds the rough coating (GGX, dielectric Fresnel) and the base to cltrace's definitions.
#[test]
fn rough_plastic_sphere_regions_match_mitsubas_coating_plus_smooth_base() {
    regions_match_mitsuba("rough-plastic-split");
}

#[test]
fn thin_dielectric_pane_regions_match_mitsuba() {
    regions_match_mitsuba("pane");
}

// The same materials in a closed room: the Cornell box with a closed faceted sphere in
// place of its white box (compare.py's `cornell_sphere_scene`), where most paths bounce
// between the sphere and the walls instead of leaving the scene.

#[test]
fn rough_gold_sphere_in_the_cornell_box_regions_match_mitsuba() {
    regions_match_mitsuba("cornell-gold");
}

#[test]
fn smooth_glass_sphere_in_the_cornell_box_regions_match_mitsuba() {
    regions_match_mitsuba("cornell-glass");
}

// The lights other than emitting surfaces (issue 17): an environment map, a constant
// environment colour, point, spot and directional lights, in scenes without an emitting
// surface (compare.py's `env_scene` to `directional_scene`). Ignored until the renderer reads
// `[environment]` and `[[light]]`.

/// A diffuse and a rough gold sphere under an environment map (nearest texels, rotated 60
/// degrees about +y, intensity 1.25) with a sun of 2 x 2 texels: the floor, the spheres and
/// the map seen directly.
#[test]
fn environment_map_regions_match_mitsuba() {
    regions_match_mitsuba("env");
}

/// The diffuse sphere under a constant environment colour: the background seen directly is
/// its colour times its intensity exactly.
#[test]
fn constant_environment_regions_match_mitsuba() {
    regions_match_mitsuba("background");
}

/// A point light: the floor lit and in the sphere's hard shadow.
#[test]
fn point_light_regions_match_mitsuba() {
    regions_match_mitsuba("point");
}

/// A spot light at an angle: the floor in its full beam, in the falloff band, outside the
/// cone and in the sphere's shadow.
#[test]
fn spot_light_regions_match_mitsuba() {
    regions_match_mitsuba("spot");
}

/// A directional light at an angle: the floor lit and in the sphere's hard shadow.
#[test]
fn directional_light_regions_match_mitsuba() {
    regions_match_mitsuba("directional");
}

/// The comparison can fail: the quad scene with its floor's albedo 10% too dark (a copy of
/// its files, one `Kd` changed) is rejected on the floor, and only there (the emitter's
/// back, black in both, still agrees).
#[test]
fn a_floor_albedo_ten_percent_off_is_rejected_by_the_mitsuba_comparison() {
    let reference = Reference::load("quad");
    let copy = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(&reference.dir).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, copy.path().join(path.file_name().unwrap())).unwrap();
    }
    let mtl_path = copy.path().join("scene.mtl");
    let mtl = std::fs::read_to_string(&mtl_path).unwrap();
    let (head, rest) = mtl
        .split_once("newmtl floor\n")
        .expect("the quad's MTL has a floor");
    let (kd, tail) = rest.split_once('\n').unwrap();
    let albedo: Vec<f64> = kd
        .strip_prefix("Kd ")
        .expect("the floor's first line is its Kd")
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let darker: Vec<String> = albedo.iter().map(|a| (0.9 * a).to_string()).collect();
    std::fs::write(
        &mtl_path,
        format!("{head}newmtl floor\nKd {}\n{tail}", darker.join(" ")),
    )
    .unwrap();

    let rows =
        reference.compare(&reference.render(&copy.path().join("scene.toml"), SPP_PER_HALF / 2));
    let shown = table("quad", &rows);
    assert!(
        rows.iter().any(|r| r.region.starts_with("floor")),
        "the quad has floor regions:\n{shown}"
    );
    for r in &rows {
        assert_eq!(
            r.passes(),
            !r.region.starts_with("floor"),
            "the floor's regions (and only they) must fail with its albedo 10% off:\n{shown}"
        );
    }
}
