//! A proptest smoke fuzz that runs in `cargo test`: the committed fuzz corpus with random byte
//! edits goes through the reader (each format) and, when it parses, the cheap analyses. No
//! input may panic. The real fuzzing is cargo-fuzz (fuzz/, docs/reliability.md).

use mbsa::format::{Format, load_bytes};
use proptest::prelude::*;

/// The seed files of the `load` fuzz target.
fn seeds() -> Vec<Vec<u8>> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/fuzz/corpus/load");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .expect("the fuzz corpus is committed")
        .map(|e| e.expect("readable").path())
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| std::fs::read(p).expect("readable"))
        .collect()
}

/// One edit of the bytes.
#[derive(Clone, Debug)]
enum Edit {
    Set(usize, u8),
    Insert(usize, &'static str),
    Remove(usize, usize),
    Truncate(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    let tokens = prop::sample::select(vec![
        "[",
        "]",
        "{",
        "}",
        "\"",
        ",",
        ":",
        "=",
        "\n",
        "-",
        "#",
        "&a",
        "*a",
        "1e999",
        "-1",
        "99999999999999999999",
        "[[joint]]",
        "type",
        "bodies",
        "driven",
        "frame",
        "\t",
        "\u{feff}",
    ]);
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        (any::<usize>(), tokens).prop_map(|(i, t)| Edit::Insert(i, t)),
        (any::<usize>(), 0usize..64).prop_map(|(i, n)| Edit::Remove(i, n)),
        any::<usize>().prop_map(Edit::Truncate),
    ]
}

fn apply(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let len = bytes.len().max(1);
        match *e {
            Edit::Set(i, b) if !bytes.is_empty() => bytes[i % len] = b,
            Edit::Set(..) => bytes.push(0),
            Edit::Insert(i, t) => {
                let at = i % (bytes.len() + 1);
                bytes.splice(at..at, t.bytes());
            }
            Edit::Remove(i, n) => {
                let at = i % len;
                let end = (at + n).min(bytes.len());
                bytes.drain(at.min(end)..end);
            }
            Edit::Truncate(i) => bytes.truncate(i % len),
        }
    }
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2048, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn edited_seeds_never_panic(pick in any::<prop::sample::Index>(), edits in prop::collection::vec(edit(), 1..6)) {
        let seeds = seeds();
        let bytes = apply(pick.get(&seeds).clone(), &edits);
        for format in [Format::Toml, Format::Yaml, Format::Json] {
            match load_bytes("smoke", &bytes, format) {
                Ok(m) => {
                    let _ = mbsa::mobility::mobility(&m);
                    if m.bodies.len() <= 40 {
                        let opts = mbsa::structure::Options { count_only: true, ..Default::default() };
                        let _ = mbsa::structure::analyze(&m, &opts, &mbsa::structure::Library::builtin()).unwrap();
                        let _ = mbsa::rigidity::pebble::analyze(&m, &Default::default());
                    }
                }
                Err(e) => {
                    let _ = mbsa::diagnostic::render(&e, false);
                }
            }
        }
    }
}
