//! JSON Schemas (draft 2020-12) of the JSON reports, for `mbsa schema --output REPORT`.
//!
//! Written from the report types' serialized form (docs/json.md describes each key): every
//! object lists its keys, the optional ones (skipped when empty or absent) left out of
//! `required`, and admits no other key, so a key added to a report without its schema fails
//! the test that validates every bundled mechanism's reports (tests/it/report_schema.rs).

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
    /// `mbsa solve --format json` (one solution, or a `--sweep`).
    Solve,
    /// `mbsa check --format json`.
    Check,
    /// One line of `mbsa check --format jsonl` (one file's record).
    CheckJsonl,
}

impl Report {
    /// Every report, in the order of `mbsa schema --help`.
    pub const ALL: [Report; 8] = [
        Report::Mobility,
        Report::Analyze,
        Report::Rigid,
        Report::Transform,
        Report::TransformJsonl,
        Report::Solve,
        Report::Check,
        Report::CheckJsonl,
    ];

    /// The report's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Report::Mobility => "mobility",
            Report::Analyze => "analyze",
            Report::Rigid => "rigid",
            Report::Transform => "transform",
            Report::TransformJsonl => "transform-jsonl",
            Report::Solve => "solve",
            Report::Check => "check",
            Report::CheckJsonl => "check-jsonl",
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
        Report::Solve => ("mbsa solve --format json", vec![solve(), sweep()]),
        Report::Check => ("mbsa check --format json", vec![check()]),
        Report::CheckJsonl => (
            "one line of mbsa check --format jsonl",
            vec![check_record()],
        ),
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

fn mobility() -> Value {
    obj(
        &[
            ("name", string()),
            ("space", space()),
            ("b", count()),
            ("bodies", count()),
            ("movable", count()),
            ("joints", count()),
            ("pairs", count()),
            ("constraints", count()),
            ("loops", count()),
            (
                "mobility",
                obj(
                    &[
                        ("count", integer()),
                        ("inputs", count()),
                        ("verdict", one_of(&["equal", "fewer", "more"])),
                    ],
                    &[],
                ),
            ),
            ("disconnected", strings()),
        ],
        &[],
    )
}

fn closure() -> Value {
    obj(
        &[
            ("model_size", number()),
            ("tolerance", number()),
            ("gross_limit", number()),
            ("max_residual", number()),
            ("status", one_of(&["closed", "open", "broken"])),
            (
                "joints",
                array(obj(&[("joint", string()), ("residual", number())], &[])),
            ),
        ],
        &[],
    )
}

fn geometry_used() -> Value {
    obj(
        &[
            ("mode", one_of(&["file", "random"])),
            ("seed", count()),
            ("configuration", string()),
            ("note", string()),
            ("precision", number()),
            ("closure", closure()),
        ],
        &["seed", "note", "precision", "closure"],
    )
}

fn type_count() -> Value {
    obj(
        &[
            ("type", string()),
            ("count", count()),
            ("in_library", boolean()),
        ],
        &[],
    )
}

fn analyze_group() -> Value {
    obj(
        &[
            ("name", string()),
            ("bodies", strings()),
            ("nm", count()),
            ("level", count()),
            ("inputs", count()),
            ("type", string()),
            ("in_library", boolean()),
            ("depends_on", array(count())),
            ("from", string()),
            ("internal", string()),
            ("to", string()),
        ],
        &[],
    )
}

fn diagnosis() -> Value {
    let over = obj(
        &[
            ("excess", count()),
            (
                "unsaturated",
                array(obj(
                    &[("joint", string()), ("pair", string()), ("excess", count())],
                    &[],
                )),
            ),
            ("joints", strings()),
            ("bodies", strings()),
        ],
        &[],
    );
    let under = obj(
        &[
            ("missing", count()),
            (
                "short",
                array(obj(&[("body", string()), ("missing", count())], &[])),
            ),
            ("bodies", strings()),
            ("input_candidates", strings()),
        ],
        &[],
    );
    obj(
        &[
            ("overdetermined", or_null(over)),
            ("underdetermined", or_null(under)),
            ("unsolved", strings()),
            ("notes", strings()),
        ],
        &["unsolved"],
    )
}

/// The `analyze` report; a function over 80 lines because it lists the report's 21 keys.
fn analyze() -> Value {
    let redundancy = obj(
        &[
            ("bodies", strings()),
            ("joints", strings()),
            ("count", count()),
            ("lowered", string()),
            ("freedom", string()),
            ("configuration", boolean()),
        ],
        &[],
    );
    let unchecked = obj(
        &[
            ("bodies", count()),
            ("unknowns", count()),
            ("equations", count()),
        ],
        &[],
    );
    let generic = obj(
        &[
            ("status", status()),
            ("groups", count()),
            ("uncontrolled", count()),
            ("why", string()),
        ],
        &[],
    );
    let finite = obj(
        &[
            ("first_order", count()),
            ("finite", count()),
            ("instantaneous_only", count()),
            ("singular_joints", strings()),
            ("note", string()),
        ],
        &[],
    );
    obj(
        &[
            ("name", string()),
            ("space", space()),
            ("b", count()),
            ("method", one_of(&["flow", "exhaustive"])),
            ("count_only", boolean()),
            (
                "mobility",
                obj(&[("count", integer()), ("inputs", count())], &[]),
            ),
            ("status", status()),
            ("geometry", geometry_used()),
            ("uncontrolled", count()),
            ("disconnected", strings()),
            ("levels", count()),
            ("groups", array(analyze_group())),
            ("types", array(type_count())),
            ("library", string()),
            (
                "isolated",
                array(obj(&[("body", string()), ("dimension", count())], &[])),
            ),
            ("redundant", array(redundancy)),
            ("unchecked", array(unchecked)),
            ("diagnosis", or_null(diagnosis())),
            ("generic", generic),
            ("notes", strings()),
            ("finite", finite),
        ],
        &[
            "geometry",
            "disconnected",
            "unchecked",
            "generic",
            "notes",
            "finite",
        ],
    )
}

fn pebble() -> Value {
    obj(
        &[
            ("name", string()),
            ("space", space()),
            ("b", count()),
            ("bodies", count()),
            ("bars", count()),
            ("with_inputs", boolean()),
            ("count", integer()),
            ("dof", integer()),
            ("dof_free", integer()),
            ("redundant", count()),
            ("rigid", array(strings())),
            ("immobile", strings()),
            (
                "overconstrained",
                array(obj(
                    &[
                        ("bodies", strings()),
                        ("joints", strings()),
                        ("redundant", count()),
                    ],
                    &[],
                )),
            ),
            ("degenerate", boolean()),
            ("limits", string()),
        ],
        &[],
    )
}

fn isolated_motion() -> Value {
    let axis = obj(
        &[
            ("kind", string()),
            ("point", vector(3)),
            ("direction", vector(3)),
            ("pitch", number()),
        ],
        &["point", "pitch"],
    );
    obj(
        &[
            ("kind", string()),
            ("bodies", strings()),
            ("joints", strings()),
            ("dof", count()),
            ("axis", axis),
        ],
        &["axis"],
    )
}

/// The geometric `rigid` report; a function over 80 lines because it lists the report's 30
/// keys.
fn geometric() -> Value {
    let numeric = obj(
        &[
            ("tolerance", number()),
            ("sigma_max", number()),
            ("smallest_kept", number()),
            ("largest_dropped", number()),
            ("warning", string()),
            ("exact", string()),
        ],
        &["smallest_kept", "largest_dropped", "warning", "exact"],
    );
    let loop_info = obj(
        &[
            ("joints", strings()),
            ("bodies", strings()),
            ("spatiality", count()),
            ("overconstraint", count()),
        ],
        &[],
    );
    obj(
        &[
            ("name", string()),
            ("space", space()),
            ("b", count()),
            ("frame", string()),
            ("geometry", string()),
            ("geometry_note", string()),
            ("geometry_used", geometry_used()),
            ("bodies", count()),
            ("rows", count()),
            ("columns", count()),
            ("rank", count()),
            ("count", integer()),
            ("mobility", count()),
            ("redundant", count()),
            (
                "redundant_joints",
                array(obj(&[("joint", string()), ("weight", number())], &[])),
            ),
            ("redundant_joints_unweighted", strings()),
            ("locked", count()),
            (
                "locked_joints",
                array(obj(&[("joint", string()), ("dof", count())], &[])),
            ),
            ("isolated", count()),
            ("fully_isolated", count()),
            ("structurally_isolated", count()),
            ("isolated_motions", array(isolated_motion())),
            ("proper_mobility", integer()),
            (
                "rigid",
                array(obj(&[("bodies", strings()), ("frame", boolean())], &[])),
            ),
            ("loops", array(loop_info)),
            ("loops_note", string()),
            ("weights_note", string()),
            ("finite_note", string()),
            ("numeric", numeric),
        ],
        &[
            "geometry_note",
            "redundant_joints_unweighted",
            "loops_note",
            "weights_note",
            "finite_note",
        ],
    )
}

fn finite() -> Value {
    obj(
        &[
            ("count", integer()),
            ("first_order", count()),
            ("finite", count()),
            ("samples", array(count())),
            (
                "verdict",
                one_of(&[
                    "regular",
                    "singular",
                    "overconstrained_moving",
                    "singular_overconstrained",
                    "undecided",
                ]),
            ),
            ("instantaneous_only", count()),
            ("singular_joints", strings()),
            ("locked_at_toggle", strings()),
            ("notes", strings()),
            ("assembled", boolean()),
            ("rounded", number()),
        ],
        &["assembled", "rounded"],
    )
}

fn rigid_both() -> Value {
    let mut both = obj(
        &[
            ("counting", pebble()),
            ("geometric", geometric()),
            ("finite", finite()),
        ],
        &["counting", "geometric", "finite"],
    );
    // Two members at least: a lone report is written at the top level instead.
    both["minProperties"] = json!(2);
    both
}

fn criteria() -> Value {
    array(one_of(&["groups", "library", "max-size", "levels"]))
}

fn inputs() -> Value {
    array(obj(
        &[("joint", string()), ("pair", string()), ("driven", count())],
        &[],
    ))
}

/// The scores of a placement, written among its own keys.
fn scores() -> [(&'static str, Value); 5] {
    [
        ("groups", count()),
        ("largest", count()),
        ("levels", count()),
        ("covered", count()),
        ("all_covered", boolean()),
    ]
}

fn placement() -> Value {
    let mut keys = vec![
        ("rank", count()),
        ("family", count()),
        ("inputs", inputs()),
        ("expansion", string()),
    ];
    keys.extend(scores());
    keys.push(("types", array(type_count())));
    keys.push(("partition", array(strings())));
    obj(&keys, &["rank", "family", "expansion"])
}

fn transform_summary() -> Value {
    obj(
        &[
            ("name", string()),
            ("count", integer()),
            ("isolated", count()),
            ("set_aside", count()),
            ("geometry", geometry_used()),
            ("f", integer()),
            ("drivable", count()),
            ("parts", count()),
            ("expansions", count()),
            ("expansions_total", count()),
            ("count_valid", big_count()),
            ("excluded_by_rank", big_count()),
            ("determined", big_count()),
            ("listed", count()),
            ("limit", or_null(count())),
            ("truncated", boolean()),
            ("notes", strings()),
        ],
        &["geometry"],
    )
}

fn transform() -> Value {
    let family = obj(
        &[
            ("id", count()),
            ("partition", array(strings())),
            ("placements", array(count())),
        ],
        &[],
    );
    obj(
        &[
            ("summary", transform_summary()),
            ("criteria", criteria()),
            ("original_rank", or_null(count())),
            ("placements", array(placement())),
            ("families", array(family)),
        ],
        &[],
    )
}

fn group_brief() -> Value {
    obj(
        &[
            ("bodies", strings()),
            ("level", count()),
            ("type", string()),
            ("in_library", boolean()),
        ],
        &[],
    )
}

fn comparison() -> Value {
    // The scores' `groups` (a count) is written before the list of groups under the same
    // key; a JSON reader keeps the later one, the list.
    let mut keys = vec![("inputs", inputs()), ("status", status())];
    keys.extend(scores());
    keys.push(("types", array(type_count())));
    keys.push(("groups", array(group_brief())));
    let evaluation = obj(&keys, &[]);
    let changes = obj(
        &[
            ("groups", integer()),
            ("largest", integer()),
            ("levels", integer()),
            ("covered", integer()),
            ("same_partition", boolean()),
            ("common", count()),
            ("only_file", array(group_brief())),
            ("only_given", array(group_brief())),
            ("verdict", string()),
        ],
        &[],
    );
    obj(
        &[
            ("name", string()),
            ("criteria", criteria()),
            ("file", evaluation.clone()),
            ("given", evaluation),
            ("changes", changes),
        ],
        &[],
    )
}

fn pose() -> Value {
    obj(
        &[
            ("body", string()),
            ("translation", vector(3)),
            ("quaternion", vector(4)),
            ("angle_deg", number()),
            ("axis", vector(3)),
        ],
        &[],
    )
}

fn joint_values() -> Value {
    obj(
        &[
            ("joint", string()),
            ("values", array(number())),
            ("units", strings()),
        ],
        &[],
    )
}

fn solve() -> Value {
    let step = obj(
        &[
            ("name", string()),
            ("level", count()),
            ("bodies", strings()),
            ("iterations", count()),
            ("residual", number()),
            ("nullity", count()),
            ("conditioning", number()),
        ],
        &[],
    );
    obj(
        &[
            ("name", string()),
            ("method", string()),
            ("steps", array(step)),
            ("max_residual", number()),
            ("poses", array(pose())),
            ("joint_values", array(joint_values())),
            ("finite", finite()),
        ],
        &["finite"],
    )
}

fn sweep() -> Value {
    let step = obj(
        &[
            ("value", number()),
            ("poses", array(pose())),
            ("joint_values", array(joint_values())),
        ],
        &[],
    );
    obj(
        &[
            ("name", string()),
            ("joint", string()),
            ("steps", array(step)),
            ("stopped", or_null(string())),
        ],
        &[],
    )
}

/// One file's record of `mbsa check`.
fn check_record() -> Value {
    let check = obj(
        &[
            ("key", string()),
            ("expected", string()),
            ("found", string()),
            ("ok", boolean()),
            ("note", string()),
        ],
        &["note"],
    );
    let error = obj(
        &[
            ("file", string()),
            ("line", or_null(count())),
            ("col", or_null(count())),
            ("message", string()),
            ("help", string()),
        ],
        &["help"],
    );
    obj(
        &[
            ("file", string()),
            ("ok", boolean()),
            ("expect_table", boolean()),
            ("checks", array(check.clone())),
            ("mismatches", array(check)),
            ("error", or_null(error)),
        ],
        &[],
    )
}

fn check() -> Value {
    obj(
        &[
            ("ok", boolean()),
            ("files", array(check_record())),
            ("checked", count()),
            ("failed", count()),
            ("unreadable", count()),
        ],
        &[],
    )
}
