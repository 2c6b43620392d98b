//! Every input the fuzzers crashed on, kept in tests/fuzz_regressions/<target>/ and fed to
//! the same code as its fuzz target: the targets' bodies are fuzz/src/lib.rs, included
//! here as a module. Each input must run without a panic (the bodies panic where an
//! invariant breaks); a loader input must give an error or a valid mesh.

use std::path::PathBuf;

#[path = "../fuzz/src/lib.rs"]
mod fuzz_cases;

/// The regression inputs of one target, by name.
fn inputs(target: &str) -> Vec<(String, Vec<u8>)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz_regressions")
        .join(target);
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Vec::new();
    };
    let mut files: Vec<(String, Vec<u8>)> = entries
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    files.sort();
    files
}

/// Runs `body` on each of `target`'s inputs, catching panics, and fails listing every
/// input that panicked. Returns how many inputs there were.
fn run_all(target: &str, body: impl Fn(&str, &[u8])) -> usize {
    let files = inputs(target);
    let failures: Vec<String> = files
        .iter()
        .filter_map(|(name, bytes)| {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| body(name, bytes)))
                .err()
                .map(|e| {
                    let why = e
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_default();
                    format!("{target}/{name}: {why}")
                })
        })
        .collect();
    assert!(
        failures.is_empty(),
        "regression inputs failed:\n{}",
        failures.join("\n")
    );
    files.len()
}

/// A loader's outcome: an error (already checked to be one clean line naming the file) or
/// a mesh that passes the check.
fn error_or_valid_mesh(name: &str, result: cltrace::Result<cltrace::mesh::Mesh>) {
    if let Ok(mesh) = result {
        assert!(
            mesh.check(std::path::Path::new(name)).is_ok() && mesh.triangle_count() > 0,
            "{name} loaded an invalid mesh"
        );
    }
}

#[test]
fn obj_regression_inputs_load_or_fail_cleanly() {
    run_all("obj", |name, bytes| {
        error_or_valid_mesh(name, fuzz_cases::obj(bytes))
    });
}

#[test]
fn ply_regression_inputs_load_or_fail_cleanly() {
    run_all("ply", |name, bytes| {
        error_or_valid_mesh(name, fuzz_cases::ply(bytes))
    });
}

#[test]
fn scene_regression_inputs_parse_without_a_panic() {
    run_all("scene", |_, bytes| {
        let _ = fuzz_cases::scene(bytes);
    });
}

#[test]
fn bvh_regression_inputs_build_and_trace_like_brute_force() {
    run_all("bvh", |_, bytes| {
        fuzz_cases::bvh(bytes);
    });
}

#[test]
fn bvh_raw_regression_inputs_build_and_trace_without_a_panic() {
    run_all("bvh_raw", |_, bytes| {
        fuzz_cases::bvh_raw(bytes);
    });
}

#[test]
fn mtl_regression_inputs_read_without_a_panic() {
    let n = run_all("mtl", |_, bytes| {
        let _ = fuzz_cases::mtl(bytes);
    });
    assert!(n > 0, "tests/fuzz_regressions/mtl/ holds no inputs");
}

#[test]
fn gltf_regression_inputs_load_or_fail_cleanly() {
    run_all("gltf", |_, bytes| {
        let _ = fuzz_cases::gltf(bytes);
    });
}

#[test]
fn texture_regression_inputs_decode_or_fail_cleanly() {
    run_all("texture", |_, bytes| {
        let _ = fuzz_cases::texture(bytes);
    });
}

/// The glTF and texture seeds are good files: each loads through its fuzz target's body.
#[test]
fn gltf_and_texture_seeds_load() {
    let seeds = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds");
    for (target, body) in [
        (
            "gltf",
            (|b: &[u8]| fuzz_cases::gltf(b).map(drop)) as fn(&[u8]) -> _,
        ),
        ("texture", |b: &[u8]| fuzz_cases::texture(b).map(drop)),
    ] {
        let files = std::fs::read_dir(seeds.join(target)).unwrap();
        let mut n = 0;
        for file in files {
            let path = file.unwrap().path();
            let bytes = std::fs::read(&path).unwrap();
            if let Err(e) = body(&bytes) {
                panic!("seed {} fails: {e}", path.display());
            }
            n += 1;
        }
        assert!(n > 0, "fuzz/seeds/{target} holds no seeds");
    }
}

#[test]
fn there_are_regression_inputs() {
    let total: usize = ["obj", "ply", "scene", "bvh", "bvh_raw", "mtl"]
        .iter()
        .map(|t| inputs(t).len())
        .sum();
    assert!(total > 0, "tests/fuzz_regressions/ holds no inputs");
}

/// Every BVH input crashed after the mesh check, in the build or the traversal: each must
/// still get that far, or it no longer tests anything.
#[test]
fn bvh_regression_inputs_still_pass_the_mesh_check() {
    for (name, bytes) in inputs("bvh") {
        assert!(
            fuzz_cases::bvh(&bytes),
            "{name} no longer passes the mesh check"
        );
    }
}

/// The `obj` fuzzer's overflow (vertical-tab-hides-a-texture-reference.obj): lines that
/// start with a vertical tab, which tobj splits off as whitespace, are read the way tobj
/// reads them, so their texture references are dropped before tobj's arithmetic sees them.
/// (Without debug assertions the overflow only wrapped, to an error; this tells the two
/// apart in release builds too.)
#[test]
fn lines_split_at_unicode_whitespace_as_tobj_splits_them() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\n\x0bvt 0 0\n\x0bf 1/-5/1 2/-5/1\u{a0}3/-5/1\n";
    let mesh = fuzz_cases::obj(text.as_bytes()).expect("a triangle with vt references");
    assert_eq!(mesh.triangles, [[0, 1, 2]]);
}

/// The OpenCL kernels on the BVH regression soups (rays along box planes, subnormal
/// direction components, hits one ulp before `t_max`, slivers): for every OpenCL tracer
/// (the brute-force kernels and each layout's BVH kernels), each ray hits what brute force
/// on the host hits, under the rules of the `bvh` target (the same triangle at the same
/// distance, or a tie within rounding that the kernel's triangle really makes; a miss only
/// where brute force hits at the very end of the ray or outside the triangle's own box).
#[test]
fn bvh_regressions_trace_alike_on_the_opencl_device() {
    use crate::common::tracers::{DeviceTracer, in_file_order};
    use cltrace::brute::BruteForce;
    use cltrace::bvh::BuildOptions;
    use cltrace::intersect::ClosestHit;
    use cltrace::intersect::WatertightRay;
    use fuzz_cases::{TIE, box_entry, decode_soup};

    let device = crate::common::device();
    let mut traced = 0;
    for (name, bytes) in inputs("bvh") {
        let soup = decode_soup(&bytes, true);
        let mesh = &soup.mesh;
        if mesh.check(std::path::Path::new(&name)).is_err() {
            continue;
        }
        let brute = BruteForce {
            triangles: in_file_order(mesh),
        };
        for tracer in DeviceTracer::all() {
            let mut cl = tracer.prepare(&device, mesh, &BuildOptions::default());
            for (k, (ray, t_max)) in soup.rays.iter().enumerate() {
                let hit = cl
                    .trace_rays(std::slice::from_ref(ray), *t_max, false)
                    .unwrap()[0];
                let got = (!hit.is_miss()).then_some((hit.prim, hit.t));
                let expected = brute.closest_hit(ray, *t_max);
                let at_the_end = expected.is_some_and(|(_, s)| s >= *t_max * (1.0 - TIE));
                let impossible = expected.is_some_and(|(i, s)| {
                    let tri = &brute.triangles[i];
                    s < box_entry(ray, [tri.v0, tri.v1, tri.v2]) * (1.0 - TIE)
                });
                let length = ray.dir.length();
                let ok = match (expected, got) {
                    (None, None) => true,
                    (Some(_), None) => at_the_end || impossible,
                    (Some((i, s)), Some((p, t))) => {
                        let s = s * length;
                        let a = brute.triangles[i].prim;
                        let own = WatertightRay::new(ray)
                            .intersect_stored(&brute.triangles[p as usize], *t_max)
                            .map(|u| u * length);
                        let near = |u: f32| (u - s).abs() <= TIE * s.abs().max(u.abs());
                        (a == p && near(t)) || (near(t) && own.is_some_and(near)) || impossible
                    }
                    (None, Some(_)) => false,
                };
                assert!(
                    ok,
                    "{name}, {}, ray {k} {ray:?} (t_max {t_max}): brute force \
                     {expected:?}, the kernel {got:?}",
                    tracer.name()
                );
                traced += 1;
            }
        }
    }
    eprintln!("{traced} regression rays traced on {}", device.info.name);
}
