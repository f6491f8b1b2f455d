//! Determinism of the real binary: the same file twice gives byte-identical output, and the
//! same mechanism written with its joints, the keys inside them and the body declarations in
//! another order gives byte-identical JSON where the output promises it.
//!
//! The strict tests compare the whole output: joints are kept in a canonical order by the model
//! (natural order of their ids), so no analysis or view depends on the file's order.

use assert_cmd::Command;
use mbsa::rng::SplitMix64;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

/// Run `mbsa args... file` and return stdout (the run must succeed).
fn run(args: &[&str], file: &Path) -> String {
    let out = Command::cargo_bin("mbsa")
        .expect("the binary is built")
        .args(args)
        .arg(file)
        .env("NO_COLOR", "1")
        .output()
        .expect("the binary runs");
    assert!(
        out.status.success(),
        "{args:?} {}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("output is UTF-8")
}

/// A scratch directory `name` under the target directory.
fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("reliability_determinism")
        .join(name);
    std::fs::create_dir_all(&dir).expect("the target directory is writable");
    dir
}

/// Write `text` as `<dir>/mech.toml`: the same file name everywhere, since the default
/// mechanism name is the file stem.
fn write(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("mech.toml");
    std::fs::write(&path, text).expect("writable");
    path
}

/// Fisher–Yates with the crate's SplitMix64 (reproducible from the seed).
fn shuffle<T>(v: &mut [T], rng: &mut SplitMix64) {
    for i in (1..v.len()).rev() {
        let j = rng.below(i as u64 + 1) as usize;
        v.swap(i, j);
    }
}

/// The TOML of a random mechanism (`mbsa::generate::to_toml`), rewritten with the top-level
/// keys, the `[[joint]]` tables and the keys inside each table shuffled, every joint given its
/// id explicitly (default ids of parallel joints are numbered in file order, by design) and,
/// if `declare`, every body declared in a `[[body]]` table, in shuffled order.
fn reordered(m: &mbsa::Mechanism, seed: u64, declare: bool) -> String {
    let mut rng = SplitMix64::new(seed);
    let text = mbsa::generate::to_toml(m);
    let text: String = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| format!("{l}\n"))
        .collect();
    let mut blocks = text.split("\n[[joint]]\n");
    let head = blocks.next().expect("split yields at least one part");
    let mut joints: Vec<Vec<String>> = blocks
        .zip(&m.joints)
        .map(|(block, joint)| {
            let mut lines: Vec<String> = block
                .lines()
                .filter(|l| !l.trim().is_empty())
                .map(str::to_string)
                .collect();
            if !lines.iter().any(|l| l.starts_with("id = ")) {
                lines.push(format!("id = {:?}", joint.id));
            }
            shuffle(&mut lines, &mut rng);
            lines
        })
        .collect();
    assert_eq!(joints.len(), m.joints.len(), "one table per joint");
    shuffle(&mut joints, &mut rng);
    let mut head: Vec<&str> = head.lines().filter(|l| !l.trim().is_empty()).collect();
    shuffle(&mut head, &mut rng);
    let mut out = head.join("\n") + "\n";
    if declare {
        let mut ids: Vec<String> = m.bodies.iter().map(|b| b.id.to_string()).collect();
        shuffle(&mut ids, &mut rng);
        for id in ids {
            out.push_str(&format!("\n[[body]]\nid = {id}\n"));
        }
    }
    for lines in joints {
        out.push_str("\n[[joint]]\n");
        out.push_str(&lines.join("\n"));
        out.push('\n');
    }
    out
}

/// The same mechanism as the original file, written in another order, in `dir_b`.
fn pair(bodies: u64, planar: bool, seed: u64, order: u64, name: &str) -> (PathBuf, PathBuf) {
    let (m, _) = mbsa::generate::random(bodies, planar, seed).expect("a valid size");
    let a = write(&scratch(&format!("{name}-a")), &mbsa::generate::to_toml(&m));
    let b = write(
        &scratch(&format!("{name}-b")),
        &reordered(&m, order, order.is_multiple_of(2)),
    );
    (a, b)
}

/// Replace each `groups[].from`/`to` string (`2&1PC.3&1SC.`: one token per joint, in file
/// order) by its tokens sorted: the one order-dependent part of a count-only analysis.
fn canonical_groups(json: &str) -> String {
    let mut v: serde_json::Value = serde_json::from_str(json).expect("JSON output");
    if let Some(groups) = v.get_mut("groups").and_then(|g| g.as_array_mut()) {
        for g in groups {
            for key in ["from", "to"] {
                if let Some(s) = g.get(key).and_then(|s| s.as_str()) {
                    let mut tokens: Vec<&str> = s.split_terminator('.').collect();
                    tokens.sort_unstable();
                    g[key] = serde_json::Value::String(tokens.join("."));
                }
            }
        }
    }
    serde_json::to_string_pretty(&v).expect("serializable")
}

/// Every analysis command, for the same-file-twice check.
const COMMANDS: &[&[&str]] = &[
    &["mobility", "--format", "json"],
    &["mobility"],
    &["analyze", "--format", "json"],
    &["analyze", "--format", "json", "--count-only"],
    &["analyze"],
    &["rigid", "--format", "json"],
    &["rigid"],
    &["dot"],
    &["dot", "--view", "structure"],
    &["dot", "--view", "topology"],
];

#[test]
fn the_same_file_twice_gives_the_same_bytes() {
    for (bodies, planar, seed) in [(12, false, 3), (15, true, 8), (40, false, 1)] {
        let (a, _) = pair(bodies, planar, seed, 1, &format!("twice-{bodies}"));
        for args in COMMANDS {
            assert_eq!(run(args, &a), run(args, &a), "{args:?} on {}", a.display());
        }
    }
    // Bundled examples, transform included (its search runs in parallel; @stewart's takes
    // minutes in a debug build, so it is left out).
    for name in ["@four-bar", "@rotor", "@stewart", "@rig-bennett"] {
        let p = Path::new(name);
        for args in COMMANDS {
            assert_eq!(run(args, p), run(args, p), "{args:?} on {name}");
        }
        if name != "@stewart" {
            let args = ["transform", "--format", "json"];
            assert_eq!(run(&args, p), run(&args, p), "transform on {name}");
        }
    }
}

#[test]
fn the_reader_ignores_the_order_of_tables_and_keys() {
    for seed in 0..20 {
        let (m, _) = mbsa::generate::random(12, seed % 2 == 0, seed).expect("a valid size");
        let text = reordered(&m, seed, seed % 3 == 0);
        let r = mbsa::format::load("mech.toml", &text, mbsa::format::Format::Toml)
            .unwrap_or_else(|e| panic!("{text}\n{}", mbsa::diagnostic::render(&e, false)));
        assert_eq!(
            r.bodies, m.bodies,
            "bodies are sorted by id whatever the order"
        );
        assert_eq!(r.frame, m.frame);
        let mut a = m.joints.clone();
        let mut b = r.joints.clone();
        a.sort_by(|x, y| x.id.cmp(&y.id));
        b.sort_by(|x, y| x.id.cmp(&y.id));
        assert_eq!(a, b, "the same joints");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, failure_persistence: None, ..ProptestConfig::default() })]

    /// Mobility, pebble-game counting and count-only structural groups (joint lists sorted)
    /// do not depend on the order of the file.
    #[test]
    fn reordering_keeps_the_order_free_outputs(
        bodies in 3u64..40,
        planar in any::<bool>(),
        seed in any::<u64>(),
        order in any::<u64>(),
    ) {
        let (a, b) = pair(bodies, planar, seed, order, "prop");
        for args in [&["mobility", "--format", "json"][..], &["rigid", "--format", "json", "--method", "counting"]] {
            prop_assert_eq!(run(args, &a), run(args, &b), "{:?}", args);
        }
        let args = ["analyze", "--format", "json", "--count-only"];
        prop_assert_eq!(canonical_groups(&run(&args, &a)), canonical_groups(&run(&args, &b)));
    }
}

/// Strict reordering check of one command over a few mechanisms; panics on the first
/// difference with both outputs' differing lines.
fn strict(args: &[&str]) {
    strict_on(args, 0..6);
}

/// [`strict`] on the mechanisms `seeds` (even: spatial, odd: planar, of generator seed
/// `seed / 2`).
fn strict_on(args: &[&str], seeds: impl IntoIterator<Item = u64>) {
    for seed in seeds {
        let (a, b) = pair(
            10,
            seed % 2 == 1,
            seed / 2,
            seed + 1,
            // One directory per command: the strict tests run in parallel and must not
            // rewrite each other's files while one reads them.
            &format!("strict-{}-{seed}", args.join("-")),
        );
        let (x, y) = (run(args, &a), run(args, &b));
        if x != y {
            let first = x
                .lines()
                .zip(y.lines())
                .position(|(p, q)| p != q)
                .unwrap_or(0);
            panic!(
                "{args:?} differs for `mbsa generate random --bodies 10 --seed {}{}` reordered \
                 (line {first}):\n{}\n{}",
                seed / 2,
                if seed % 2 == 1 { " --planar" } else { "" },
                x.lines().nth(first).unwrap_or(""),
                y.lines().nth(first).unwrap_or("")
            );
        }
    }
}

#[test]
fn strict_analyze() {
    strict(&["analyze", "--format", "json"]);
}

#[test]
fn strict_analyze_count_only() {
    strict(&["analyze", "--format", "json", "--count-only"]);
}

#[test]
fn strict_rigid() {
    strict(&["rigid", "--format", "json"]);
}

#[test]
fn strict_dot() {
    strict(&["dot", "--view", "structure"]);
    strict(&["dot", "--view", "topology"]);
}

/// Without the spatial mechanism of seed 1: its 74,613 candidate placements take 8 s a run,
/// and the five others already enumerate every placement of spatial and planar mechanisms.
#[test]
fn strict_transform() {
    strict_on(
        &["transform", "--format", "json", "--count-only"],
        [0, 1, 3, 4, 5],
    );
}
