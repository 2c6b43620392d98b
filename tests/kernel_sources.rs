//! The kernel sources (`cl/`) as every OpenCL compiler takes them: checked on the text,
//! because the compilers the tests run on (PoCL, Intel's CPU runtime, Oclgrind) let
//! through what NVIDIA's rejects.

use std::path::Path;

/// NVIDIA's OpenCL C compiler rejects variadic macros ("variadic macros not supported in
/// OpenCL"), which the CPU compilers accept even with `-cl-std=CL1.2`: a `trace(scene,
/// ...)` macro of 2026-12-06 built on them and failed every program on an H100.
#[test]
fn kernels_define_no_variadic_macros_which_nvidia_rejects() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cl");
    let mut files = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "cl") {
            continue;
        }
        files += 1;
        let text = std::fs::read_to_string(&path).unwrap();
        for (n, line) in text.lines().enumerate() {
            let variadic = line.trim_start().starts_with("#define") && line.contains("...");
            assert!(
                !variadic && !line.contains("__VA_ARGS__"),
                "{}:{}: a variadic macro: {line}",
                path.display(),
                n + 1
            );
        }
    }
    assert!(files > 10, "only {files} kernel files in {}", dir.display());
}
