//! The readers of the three formats agree on the tree, and their fast paths on the whole read.

use super::Lazy;
use super::json_tree::{json_check, parse_json, parse_json_resume, parse_json_tree};
use super::toml_tree::{parse_toml, parse_toml_chunked, parse_toml_serial};
use super::yaml_tree::{parse_yaml, resolve_plain};
use crate::format::tree::{Node, Value};
use std::borrow::Cow;

fn strip(n: &Node) -> String {
    match &n.value {
        Value::Map(es) => format!(
            "{{{}}}",
            es.iter()
                .map(|e| format!("{}:{}", e.key, strip(&e.value)))
                .collect::<Vec<_>>()
                .join(",")
        ),
        Value::Seq(xs) => format!("[{}]", xs.iter().map(strip).collect::<Vec<_>>().join(",")),
        v => format!("{v:?}"),
    }
}

/// The chunked TOML parse gives exactly the serial tree, or declines.
fn chunked_agrees(text: &str, pieces: usize) -> bool {
    let chunked = parse_toml_chunked(text, pieces);
    let serial = parse_toml_serial(text).ok();
    match chunked {
        Some(c) => {
            assert_eq!(Some(c), serial, "chunked tree differs for {text:?}");
            true
        }
        None => false,
    }
}

#[test]
fn chunked_toml_equals_the_serial_tree() {
    let m = crate::generate::random(60, false, 3).unwrap().0;
    let mut text = crate::generate::to_toml(&m);
    for pieces in [2, 3, 7, 50, 1000] {
        assert!(chunked_agrees(&text, pieces), "a generated file is cut");
    }
    // Geometry subtables, comments after headers, a table after the joints.
    text.push_str("\n[[joint]] # last\ntype = \"R\"\nbodies = [1, 2]\n[joint.geometry]\norigin = [0, 0, 1]\naxis = [0, 0, 1]\n\n[expect]\nmobility = 0\n");
    for pieces in [2, 5, 40] {
        assert!(chunked_agrees(&text, pieces));
    }
}

#[test]
fn chunked_toml_declines_what_it_cannot_join() {
    let joint = "[[joint]]\ntype = \"R\"\nbodies = [1, 2]\n";
    let cases = [
        // A header inside a multi-line string and inside a multi-line array.
        format!(
            "name = \"\"\"\n{}\"\"\"\nframe = 1\n{joint}{joint}",
            joint.repeat(20)
        ),
        format!("frame = 1\nx = [\n1,\n{joint}]\n{joint}"),
        // An inline joint array, and a table given twice in two pieces.
        format!("frame = 1\njoint = []\n{joint}{joint}"),
        format!("frame = 1\njoint = [{{type = \"R\", bodies = [1, 2]}}]\n{joint}{joint}"),
        format!("frame = 1\njoint = [[[1]], [[2]]]\n{joint}{joint}"),
        format!("frame = 1\n{joint}[expect]\nmobility = 1\n{joint}[expect]\ngroups = 1\n"),
        // `[[body]]` arrays in two pieces (valid TOML: the serial parse joins them).
        format!("frame = 1\n{joint}[[body]]\nid = 1\n{joint}[[body]]\nid = 2\n"),
        // A joint table redefined as a plain table.
        format!("frame = 1\n{joint}{joint}[joint]\nx = 1\n"),
    ];
    for text in &cases {
        for pieces in [2, 3, 8] {
            chunked_agrees(text, pieces);
        }
        assert!(parse_toml_chunked(text, 2).is_none(), "{text}");
    }
}

#[test]
fn three_formats_give_the_same_tree() {
    let t = parse_toml("a = 1\nb = [\"x\", 2.5, true]\n[c]\nd = -3\n").unwrap();
    let y = parse_yaml("a: 1\nb: [x, 2.5, true]\nc: {d: -3}\n")
        .unwrap()
        .unwrap();
    let j = parse_json(r#"{"a": 1, "b": ["x", 2.5, true], "c": {"d": -3}}"#)
        .unwrap()
        .0;
    assert_eq!(strip(&t), strip(&y));
    assert_eq!(strip(&t), strip(&j));
}

#[test]
fn spans_point_at_values() {
    let text = "x: 1\nname: \"é\"\nvalue: abc\n";
    let y = parse_yaml(text).unwrap().unwrap();
    let Value::Map(es) = &y.value else { panic!() };
    assert_eq!(&text[es[2].key_span.clone()], "value");
    assert_eq!(&text[es[2].value.span.clone()], "abc");
    let j = r#"{"a": [1, "b"]}"#;
    let n = parse_json(j).unwrap().0;
    let Value::Map(es) = &n.value else { panic!() };
    assert_eq!(&j[es[0].key_span.clone()], "\"a\"");
    assert_eq!(&j[es[0].value.span.clone()], "[1, \"b\"]");
}

#[test]
fn yaml_core_schema() {
    assert_eq!(resolve_plain(Cow::Borrowed("~")), Value::Null);
    assert_eq!(resolve_plain(Cow::Borrowed("0x1F")), Value::Int(31));
    assert_eq!(resolve_plain(Cow::Borrowed("-12")), Value::Int(-12));
    assert_eq!(resolve_plain(Cow::Borrowed("1e3")), Value::Float(1000.0));
    assert_eq!(resolve_plain(Cow::Borrowed(".5")), Value::Float(0.5));
    assert_eq!(
        resolve_plain(Cow::Borrowed("-.inf")),
        Value::Float(f64::NEG_INFINITY)
    );
    assert!(matches!(resolve_plain(Cow::Borrowed(".nan")), Value::Float(f) if f.is_nan()));
    assert_eq!(
        resolve_plain(Cow::Borrowed("1-2")),
        Value::Str(Cow::Borrowed("1-2"))
    );
    assert_eq!(
        resolve_plain(Cow::Borrowed("e3")),
        Value::Str(Cow::Borrowed("e3"))
    );
    assert!(matches!(
        resolve_plain(Cow::Borrowed("100000000000000000000000")),
        Value::BigInt(_)
    ));
}

/// Mutated JSON: whatever serde_json refuses, the tree parser refuses too (the reader runs
/// serde_json's check only after an error).
#[test]
fn json_tree_parser_is_as_strict_as_serde_json() {
    let base = r#"{"name": "a\u00e9", "frame": 1, "joints": [{"type": "R", "bodies": [1, 2], "axis": [0.5, -1e3, 2E+2]}, {"type": "P", "bodies": [2, 3], "driven": 1}], "expect": {"mobility": 0, "determined": true, "x": null}}"#;
    let alphabet = b" \t\n{}[]:,.\"\\-+0123456789eEtrufalsn\x01";
    let mut refused = 0;
    for text in crate::format::mutated_texts(base, alphabet, 0x2545_F491_4F6C_DD1D, 6000, 2) {
        if json_check(&text).is_ok() {
            continue;
        }
        refused += 1;
        let ours = parse_json_tree(&text).and_then(|(root, lazy)| {
            let list = match root.value {
                Value::Map(es) => es
                    .into_iter()
                    .find(|e| matches!(e.value.value, Value::Deferred))
                    .map_or(Value::Null, |e| e.value.value),
                _ => Value::Null,
            };
            lazy.for_each(list, &mut |_| Ok(()))
        });
        assert!(ours.is_err(), "accepted what serde_json refuses: {text:?}");
    }
    assert!(refused > 1000, "{refused}");
}

/// The tree with its deferred joint list read in (as `strip` shows it), by `parse`.
fn with_items<'a>(parsed: Option<(Node<'a>, Lazy<'a>)>) -> Option<String> {
    let (root, lazy) = parsed?;
    let Value::Map(mut es) = root.value else {
        return Some(strip(&root));
    };
    let mut items = Vec::new();
    if let Some(e) = es
        .iter_mut()
        .find(|e| matches!(e.value.value, Value::Deferred))
    {
        let list = std::mem::replace(&mut e.value.value, Value::Null);
        lazy.for_each(list, &mut |n| {
            items.push(n.clone());
            Ok(())
        })
        .ok()?;
        e.value.value = Value::Seq(items);
    }
    Some(strip(&Node {
        span: root.span,
        value: Value::Map(es),
    }))
}

#[test]
fn json_resumed_read_equals_the_whole_read() {
    let base = r#"{"name": "a\u00e9", "frame": 1, "expect": {"mobility": 0, "x": null}, "joints": [{"type": "R", "bodies": [1, 2], "axis": [0.5, -1e3, 2E+2]}, {"type": "P", "bodies": [2, 3], "driven": -12345678901234567}, {"id": 123456789012345678901, "bodies": [-0, 7]}]}"#;
    let alphabet = b" \t\n{}[]:,.\"\\-+0123456789eEtrufalsn\x01";
    let mut resumed = 0;
    let texts = crate::format::mutated_texts(base, alphabet, 0x9E37_79B9_7F4A_7C15, 6000, 2);
    for text in std::iter::once(base.to_string()).chain(texts) {
        let Some(r) = with_items(parse_json_resume(&text)) else {
            continue;
        };
        resumed += 1;
        assert!(
            json_check(&text).is_ok(),
            "accepted what serde_json refuses: {text:?}"
        );
        assert_eq!(Some(r), with_items(parse_json_tree(&text).ok()), "{text:?}");
    }
    assert!(resumed > 1000, "{resumed}");
}

#[test]
fn json_escapes() {
    let n = parse_json(r#"["a\u00e9\ud83d\ude00\n"]"#).unwrap().0;
    assert_eq!(
        n.value,
        Value::Seq(vec![Node {
            span: 1..24,
            value: Value::Str(Cow::Owned("aé😀\n".into()))
        }])
    );
}
