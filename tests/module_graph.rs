//! The library's module graph: every `crate::` edge between top-level modules goes from a
//! higher layer to a strictly lower one, so the graph has no cycles, and a new edge that
//! breaks the order fails here. Also: only `device` speaks OpenCL, only the binary speaks
//! clap, and the bottom layers do no file I/O.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The library's top-level modules, bottom layer first. A module may use the modules of
/// lower layers only.
const LAYERS: &[&[&str]] = &[
    // Pure values: no I/O, no OpenCL, no command line.
    &["error", "geometry", "hash"],
    &["mesh", "camera", "interrupt", "huge_pages"],
    &["intersect", "animation"],
    &["material", "light"],
    &["brute", "bvh"],
    &["render", "report"],
    // Files in and out.
    &["input", "output"],
    // The OpenCL host side.
    &["device"],
    &["renderer"],
    &["bench"],
    &["tune"],
    &["commands"],
];

/// Layers 0 to this one hold the modules that do no file I/O.
const PURE_LAYERS: usize = 4;

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The library's source files by top-level module (`src/bvh/build.rs` is in `bvh`); the
/// binary's (`main.rs`, `flags/`) under `None`.
fn files_by_module() -> BTreeMap<Option<String>, Vec<(PathBuf, String)>> {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut by = BTreeMap::<Option<String>, Vec<_>>::new();
    for path in files {
        let rel = path
            .strip_prefix(src())
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let first = rel
            .split('/')
            .next()
            .unwrap()
            .trim_end_matches(".rs")
            .to_string();
        let module = match first.as_str() {
            "main" | "flags" => None,
            "lib" => continue,
            _ => Some(first),
        };
        let text = std::fs::read_to_string(&path).unwrap();
        by.entry(module).or_default().push((path, code_of(&text)));
    }
    by
}

/// The code of a file without comments and without its unit tests (a `#[cfg(test)]` module
/// may use what it likes).
fn code_of(text: &str) -> String {
    let mut out = String::new();
    let mut skipping_tests = false;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") && line.starts_with('#') {
            skipping_tests = true;
        }
        if skipping_tests || t.starts_with("//") {
            continue;
        }
        out.push_str(line.split(" // ").next().unwrap());
        out.push('\n');
    }
    out
}

/// The top-level modules `code` names through `crate::`.
fn crate_edges(code: &str) -> BTreeSet<String> {
    let mut edges = BTreeSet::new();
    for (i, _) in code.match_indices("crate::") {
        if code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_') {
            continue; // `cltrace::crate::`-like or an identifier ending in "crate"
        }
        let rest = &code[i + "crate::".len()..];
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if let Some(group) = rest.strip_prefix('{') {
            // `use crate::{a, b::c}`
            let group = &group[..group.find('}').unwrap_or(group.len())];
            for part in group.split(',') {
                let head = part.trim().split("::").next().unwrap().trim();
                if !head.is_empty() {
                    edges.insert(head.to_string());
                }
            }
        } else if !name.is_empty() && name.chars().next().unwrap().is_lowercase() {
            edges.insert(name);
        }
    }
    edges
}

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

#[test]
fn every_library_module_has_a_layer() {
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    let declared: BTreeSet<String> = lib
        .lines()
        .filter_map(|l| {
            let l = l.trim();
            l.strip_prefix("pub mod ")
                .or(l.strip_prefix("pub(crate) mod "))
                .or(l.strip_prefix("mod "))
        })
        .map(|l| l.trim_end_matches(';').to_string())
        .collect();
    let layered: BTreeSet<String> = LAYERS
        .iter()
        .flat_map(|l| l.iter())
        .map(|s| s.to_string())
        .collect();
    assert_eq!(
        declared, layered,
        "src/lib.rs's modules and LAYERS must name the same modules"
    );
}

#[test]
fn modules_use_only_lower_layers() {
    let mut wrong = Vec::new();
    let mut graph = BTreeMap::<String, BTreeSet<String>>::new();
    for (module, files) in files_by_module() {
        let Some(module) = module else { continue };
        let from = layer_of(&module).unwrap_or_else(|| panic!("module `{module}` has no layer"));
        for (path, code) in files {
            for to in crate_edges(&code) {
                if to == module || to == "Error" || to == "Result" {
                    continue;
                }
                graph.entry(module.clone()).or_default().insert(to.clone());
                match layer_of(&to) {
                    Some(l) if l < from => {}
                    _ => wrong.push(format!("{} uses crate::{to}", path.display())),
                }
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "edges against the layer order (tests/module_graph.rs, LAYERS):\n{}\ngraph: {graph:#?}",
        wrong.join("\n")
    );
    // The scan sees the edges that must be there.
    assert!(
        graph["renderer"].contains("device") && graph["bvh"].contains("intersect"),
        "{graph:#?}"
    );
    // The layering makes the graph acyclic; check it directly too.
    let mut order = Vec::new();
    let mut left = graph.clone();
    while !left.is_empty() {
        let free: Vec<String> = left
            .keys()
            .filter(|m| left[*m].iter().all(|d| !left.contains_key(d)))
            .cloned()
            .collect();
        assert!(!free.is_empty(), "a cycle among {:?}", left.keys());
        for m in free {
            left.remove(&m);
            order.push(m);
        }
    }
}

#[test]
fn only_device_uses_opencl_and_only_the_binary_uses_clap() {
    let mut wrong = Vec::new();
    for (module, files) in files_by_module() {
        for (path, code) in files {
            let has = |word: &str| {
                code.match_indices(word).any(|(i, _)| {
                    !code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':')
                })
            };
            if has("ocl::") && module.as_deref() != Some("device") {
                wrong.push(format!("{} uses ocl", path.display()));
            }
            if has("clap::") && module.is_some() {
                wrong.push(format!("{} uses clap", path.display()));
            }
            let pure = module
                .as_deref()
                .and_then(layer_of)
                .is_some_and(|l| l < PURE_LAYERS);
            if pure && (has("std::fs") || has("File::")) {
                wrong.push(format!("{} does file I/O", path.display()));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn edges_are_found_in_every_form() {
    let code = "use crate::bvh::{Bvh, Layout};\nuse crate::{mesh::Mesh, error};\nlet x = crate::camera::Camera::auto();\n";
    let found: Vec<String> = crate_edges(code).into_iter().collect();
    assert_eq!(found, ["bvh", "camera", "error", "mesh"]);
    assert!(
        crate_edges(&code_of(
            "// use crate::device;\n#[cfg(test)]\nmod tests { use crate::device; }\n"
        ))
        .is_empty()
    );
}
