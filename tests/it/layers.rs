//! The crate's layers (ARCHITECTURE.md): each top-level module of `src/` uses only modules of
//! its own layer or of the layers below, and the modules of one layer import each other
//! without cycles. Read from the source text, so that an upward `use` fails here before it
//! is built on.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The layers, lowest first, and the top-level modules of each.
const LAYERS: &[(&str, &[&str])] = &[
    (
        "foundations",
        &[
            "budget",
            "rng",
            "par",
            "numbers",
            "words",
            "elimination",
            "cholesky",
            "exact",
            "graph",
        ],
    ),
    ("model", &["joint", "mechanism", "mobility"]),
    (
        "input/output",
        &[
            "format",
            "write",
            "import",
            "generate",
            "examples",
            "diagnostic",
        ],
    ),
    ("kinematics", &["motion", "position", "geometry"]),
    (
        "analyses",
        &[
            "structure",
            "rigidity",
            "transform",
            "expect",
            "repair",
            "cut",
        ],
    ),
    ("rendering", &["report", "export"]),
    ("cli", &["cli", "main"]),
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|(_, ms)| ms.contains(&module))
}

/// The source without comments (doc links name modules without using them) and without the
/// contents of string and character literals.
fn code_only(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                let end = text[i + 2..].find("*/").map_or(b.len(), |e| i + 2 + e + 2);
                i = end;
            }
            b'"' => {
                // Raw strings (r"..", r#".."#) hold no escapes; both end at the first
                // closing quote for the texts this crate has.
                let raw = i > 0 && (b[i - 1] == b'r' || b[i - 1] == b'#');
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    if b[i] == b'\\' && !raw {
                        i += 1;
                    }
                    i += 1;
                }
                i += 1;
                out.push_str("\"\"");
            }
            b'\'' if b.get(i + 2) == Some(&b'\'') || (b.get(i + 1) == Some(&b'\\')) => {
                // A character literal ('x' or '\n'); a lifetime has no closing quote.
                let end = text[i + 1..].find('\'').map_or(b.len(), |e| i + 1 + e + 1);
                i = end;
            }
            c => {
                out.push(c as char);
                i += 1;
            }
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The top-level modules named by `crate::x` / `mbsa::x` paths, and by the first segment of
/// each item of `crate::{x, y::z}` groups.
fn modules_named(code: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for root in ["crate::", "mbsa::"] {
        let mut from = 0;
        while let Some(at) = code[from..].find(root) {
            let start = from + at;
            from = start + root.len();
            if code[..start].chars().next_back().is_some_and(is_ident) {
                continue;
            }
            let rest = &code[from..];
            if let Some(group) = rest.strip_prefix('{') {
                let mut depth = 0;
                let mut item_start = true;
                for (k, c) in group.char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => break,
                        '}' => depth -= 1,
                        ',' if depth == 0 => item_start = true,
                        c if item_start && is_ident(c) => {
                            let name: String =
                                group[k..].chars().take_while(|&c| is_ident(c)).collect();
                            out.insert(name);
                            item_start = false;
                        }
                        _ => {}
                    }
                }
            } else {
                let name: String = rest.chars().take_while(|&c| is_ident(c)).collect();
                out.insert(name);
            }
        }
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .expect("src/ is readable")
        .map(|e| e.expect("a directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// Each top-level module and the other top-level modules its code names, with one file
/// that names each.
fn module_graph() -> BTreeMap<String, BTreeMap<String, String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut graph: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(&src).expect("under src/");
        let first = rel.components().next().expect("a path").as_os_str();
        let module = first.to_string_lossy().trim_end_matches(".rs").to_string();
        if module == "lib" {
            continue;
        }
        let text = std::fs::read_to_string(&f).expect("source is UTF-8");
        let uses = graph.entry(module.clone()).or_default();
        for used in modules_named(&code_only(&text)) {
            if used != module && layer_of(&used).is_some() {
                uses.entry(used)
                    .or_insert_with(|| rel.display().to_string());
            }
        }
    }
    graph
}

#[test]
fn every_module_has_a_layer() {
    let unknown: Vec<_> = module_graph()
        .into_keys()
        .filter(|m| layer_of(m).is_none())
        .collect();
    assert!(
        unknown.is_empty(),
        "modules with no layer in tests/it/layers.rs (and ARCHITECTURE.md): {unknown:?}"
    );
}

#[test]
fn no_module_uses_a_layer_above_its_own() {
    let mut wrong = Vec::new();
    for (module, uses) in module_graph() {
        let Some(own) = layer_of(&module) else {
            continue;
        };
        for (used, file) in uses {
            let theirs = layer_of(&used).expect("filtered to known modules");
            if theirs > own {
                wrong.push(format!(
                    "src/{file}: `{module}` ({}) uses `{used}` ({})",
                    LAYERS[own].0, LAYERS[theirs].0
                ));
            }
        }
    }
    assert!(wrong.is_empty(), "upward imports:\n{}", wrong.join("\n"));
}

#[test]
fn modules_of_one_layer_import_each_other_without_cycles() {
    let graph = module_graph();
    // Depth-first search for a back edge among same-layer edges.
    fn visit(
        m: &str,
        graph: &BTreeMap<String, BTreeMap<String, String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(m.to_string(), 1);
        path.push(m.to_string());
        for next in graph.get(m).into_iter().flat_map(|u| u.keys()) {
            if layer_of(next) != layer_of(m) {
                continue;
            }
            match state.get(next.as_str()) {
                Some(1) => {
                    let from = path.iter().position(|p| p == next).expect("on the path");
                    let mut cycle = path[from..].to_vec();
                    cycle.push(next.clone());
                    return Some(cycle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(next, graph, state, path) {
                        return Some(c);
                    }
                }
            }
        }
        path.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for m in graph.keys() {
        if !state.contains_key(m.as_str()) {
            let cycle = visit(m, &graph, &mut state, &mut Vec::new());
            assert!(
                cycle.is_none(),
                "import cycle: {}",
                cycle.unwrap().join(" -> ")
            );
        }
    }
}

#[test]
fn the_scanner_sees_imports_and_skips_comments() {
    let code = code_only(
        "use crate::{joint::JointType, motion};\n/// [`crate::report`]\nlet s = \"crate::cli\";\nfn f() { crate::rng::x(); }",
    );
    let named = modules_named(&code);
    let want: BTreeSet<String> = ["joint", "motion", "rng"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(named, want);
}
