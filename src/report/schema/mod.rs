//! JSON Schemas (draft 2020-12) of the JSON reports, for `mbsa schema --output REPORT`.
//!
//! Written from the report types' serialized form (docs/json.md describes each key): every
//! object lists its keys, the optional ones (skipped when empty or absent) left out of
//! `required`, and admits no other key, so a key added to a report without its schema fails
//! the test that validates every bundled mechanism's reports (tests/it/report_schema.rs).

mod analyses;
mod commands;
mod cut;

use analyses::{analyze, geometric, mobility, pebble, rigid_both};
use commands::{
    check, check_record, comparison, placement, shard_placement, shard_summary, solve, sweep,
    transform, transform_summary,
};
use serde_json::{Map, Value, json};

/// The reports that have a schema.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Report {
    /// `mbsa mobility --format json`.
    Mobility,
    /// `mbsa analyze --format json`.
    Analyze,
    /// `mbsa rigid --format json` (both methods, one, or with `--finite`).
    Rigid,
    /// `mbsa transform --format json` (the ranking, or the comparison of `--inputs`).
    Transform,
    /// One line of `mbsa transform --format jsonl` (a placement, or the closing summary).
    TransformJsonl,
    /// One line of a `mbsa transform --partition` shard (a placement, or the closing summary).
    TransformShard,
    /// `mbsa solve --format json` (one solution, or a `--sweep`).
    Solve,
    /// `mbsa check --format json`.
    Check,
    /// One line of `mbsa check --format jsonl` (one file's record).
    CheckJsonl,
    /// `mbsa cut --format json`.
    Cut,
}

impl Report {
    /// Every report, in the order of `mbsa schema --help`.
    pub const ALL: [Report; 10] = [
        Report::Mobility,
        Report::Analyze,
        Report::Rigid,
        Report::Transform,
        Report::TransformJsonl,
        Report::TransformShard,
        Report::Solve,
        Report::Check,
        Report::CheckJsonl,
        Report::Cut,
    ];

    /// The report's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Report::Mobility => "mobility",
            Report::Analyze => "analyze",
            Report::Rigid => "rigid",
            Report::Transform => "transform",
            Report::TransformJsonl => "transform-jsonl",
            Report::TransformShard => "transform-shard",
            Report::Solve => "solve",
            Report::Check => "check",
            Report::CheckJsonl => "check-jsonl",
            Report::Cut => "cut",
        }
    }
}

/// The JSON Schema of `report`.
pub fn schema(report: Report) -> Value {
    let (title, variants) = match report {
        Report::Mobility => ("mbsa mobility --format json", vec![mobility()]),
        Report::Analyze => ("mbsa analyze --format json", vec![analyze()]),
        Report::Rigid => (
            "mbsa rigid --format json",
            vec![rigid_both(), pebble(), geometric()],
        ),
        Report::Transform => (
            "mbsa transform --format json",
            vec![transform(), comparison()],
        ),
        Report::TransformJsonl => (
            "one line of mbsa transform --format jsonl",
            vec![placement(), transform_summary()],
        ),
        Report::TransformShard => (
            "one line of mbsa transform --partition ... --format jsonl",
            vec![shard_placement(), shard_summary()],
        ),
        Report::Solve => ("mbsa solve --format json", vec![solve(), sweep()]),
        Report::Check => ("mbsa check --format json", vec![check()]),
        Report::CheckJsonl => (
            "one line of mbsa check --format jsonl",
            vec![check_record()],
        ),
        Report::Cut => ("mbsa cut --format json", vec![cut::cut()]),
    };
    let mut root = Map::new();
    root.insert(
        "$schema".into(),
        json!("https://json-schema.org/draft/2020-12/schema"),
    );
    root.insert("title".into(), json!(title));
    root.insert(
        "description".into(),
        json!(format!(
            "Keys and their meaning: docs/json.md. format_version {}.",
            super::FORMAT_VERSION
        )),
    );
    let mut variants: Vec<Value> = variants.into_iter().map(versioned).collect();
    if variants.len() == 1 {
        if let Some(Value::Object(only)) = variants.pop() {
            root.extend(only);
        }
    } else {
        root.insert("anyOf".into(), Value::Array(variants));
    }
    Value::Object(root)
}

/// `object` with `format_version` as its first, required key.
fn versioned(object: Value) -> Value {
    let Value::Object(mut o) = object else {
        return object;
    };
    let mut props = Map::new();
    props.insert(
        "format_version".into(),
        json!({"const": super::FORMAT_VERSION}),
    );
    if let Some(Value::Object(p)) = o.remove("properties") {
        props.extend(p);
    }
    o.insert("properties".into(), Value::Object(props));
    if let Some(Value::Array(req)) = o.get_mut("required") {
        req.insert(0, json!("format_version"));
    }
    Value::Object(o)
}

/// An object with these keys, all required but those in `optional`, and no other key.
fn obj(props: &[(&str, Value)], optional: &[&str]) -> Value {
    let mut p = Map::new();
    let mut required = Vec::new();
    for (k, v) in props {
        p.insert((*k).into(), v.clone());
        if !optional.contains(k) {
            required.push(json!(k));
        }
    }
    json!({"type": "object", "properties": p, "required": required, "additionalProperties": false})
}

fn string() -> Value {
    json!({"type": "string"})
}
fn integer() -> Value {
    json!({"type": "integer"})
}
fn count() -> Value {
    json!({"type": "integer", "minimum": 0})
}
fn number() -> Value {
    json!({"type": "number"})
}
fn boolean() -> Value {
    json!({"type": "boolean"})
}
fn one_of(words: &[&str]) -> Value {
    json!({"type": "string", "enum": words})
}
fn array(items: Value) -> Value {
    json!({"type": "array", "items": items})
}
fn strings() -> Value {
    array(string())
}
fn vector(n: usize) -> Value {
    json!({"type": "array", "items": number(), "minItems": n, "maxItems": n})
}
fn or_null(v: Value) -> Value {
    json!({"anyOf": [v, {"type": "null"}]})
}
/// A count that may exceed 2^128 − 1: then written in words.
fn big_count() -> Value {
    json!({"anyOf": [count(), string()]})
}
fn space() -> Value {
    one_of(&["spatial", "planar", "spherical"])
}
fn status() -> Value {
    one_of(&["determined", "overdetermined", "underdetermined", "mixed"])
}
