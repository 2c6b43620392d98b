//! Four `cltrace render` processes at once on the same OpenCL device (`cl-bvh`), each
//! writing its own image and hit records: all must succeed, and all must produce the same
//! pixels and hits as each other.

use std::path::Path;
use std::process::Stdio;

use crate::common::command::cltrace;
const RUNS: usize = 4;
const WIDTH: u32 = 96;
const HEIGHT: u32 = 72;

#[test]
fn four_renders_at_once_on_one_device_agree() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(
        &scene,
        "[generator]\nkind = \"sphereflake\"\nlevels = 1\nsubdivisions = 2\nground = 16\n\n\
         [camera]\neye = [2.2, 1.2, 2.8]\nlook_at = [0.0, -0.15, 0.0]\n",
    )
    .unwrap();
    let output = |i: usize, ext: &str| dir.path().join(format!("out{i}.{ext}"));

    // Spawn all four before waiting for any.
    let children: Vec<_> = (0..RUNS)
        .map(|i| {
            cltrace()
                .arg("render")
                .arg(&scene)
                .arg("-o")
                .arg(output(i, "png"))
                .arg("--hits")
                .arg(output(i, "hits"))
                .args([
                    "--width",
                    &WIDTH.to_string(),
                    "--height",
                    &HEIGHT.to_string(),
                ])
                .args(["--method", "cl-bvh", "--shade", "lambert", "-q"])
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("the cltrace binary starts")
        })
        .collect();
    for (i, child) in children.into_iter().enumerate() {
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "render {i} failed with {:?}: {stderr}",
            out.status.code()
        );
        assert!(!stderr.contains("panicked"), "render {i}: {stderr}");
    }

    let pixels = |i: usize| -> Vec<u8> {
        let img = image::open(output(i, "png")).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (WIDTH, HEIGHT), "render {i}");
        img.into_raw()
    };
    let hits = |i: usize| std::fs::read(output(i, "hits")).unwrap();
    let (first, first_hits) = (pixels(0), hits(0));
    // Something to compare: the scene fills part of the image, not all of it.
    let lit = first
        .chunks(3)
        .filter(|p| p.iter().any(|&c| c != 0))
        .count();
    let total = (WIDTH * HEIGHT) as usize;
    assert!(
        lit > total / 10 && lit < total,
        "{lit} of {total} pixels are lit"
    );
    assert_eq!(first_hits.len(), 8 * total);
    for i in 1..RUNS {
        let other = pixels(i);
        let differing = first
            .chunks(3)
            .zip(other.chunks(3))
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(
            differing, 0,
            "render {i} differs from render 0 in {differing} pixels"
        );
        assert!(
            hits(i) == first_hits,
            "render {i}'s hit records differ from render 0's"
        );
    }
    assert_no_temporaries(dir.path());
}

/// No `.cltrace-*.tmp` is left behind by any of the renders.
fn assert_no_temporaries(dir: &Path) {
    let left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}
