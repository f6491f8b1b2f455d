//! Schemas of the command outputs: `transform` (document and lines), `solve` (one solution
//! or a sweep) and `check` (document and lines).

use super::analyses::{finite, geometry_used, type_count};
use super::{
    array, big_count, boolean, count, integer, number, obj, one_of, or_null, status, string,
    strings, vector,
};
use serde_json::Value;

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

pub(super) fn placement() -> Value {
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

pub(super) fn transform_summary() -> Value {
    obj(
        &[
            ("name", string()),
            ("count", integer()),
            ("isolated", count()),
            ("set_aside", count()),
            ("geometry", geometry_used()),
            ("f", integer()),
            ("drivable", count()),
            ("fixed_base", strings()),
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
        &["geometry", "fixed_base"],
    )
}

/// `object` with more keys (`optional` among them may be absent).
fn with_keys(object: Value, keys: &[(&str, Value)], optional: &[&str]) -> Value {
    let mut object = object;
    for (k, v) in keys {
        if let Some(Value::Object(p)) = object.get_mut("properties") {
            p.insert((*k).into(), v.clone());
        }
        if let (false, Some(Value::Array(r))) = (optional.contains(k), object.get_mut("required")) {
            r.push(Value::String((*k).into()));
        }
    }
    object
}

/// A placement line of a shard: the placement and what the merge needs to rank it.
pub(super) fn shard_placement() -> Value {
    with_keys(
        placement(),
        &[
            ("index", count()),
            ("expansion_index", count()),
            ("expansion_brief", string()),
        ],
        &["expansion_brief"],
    )
}

/// The summary line of a shard: the run's summary and `shard`.
pub(super) fn shard_summary() -> Value {
    let total = string;
    let shard = obj(
        &[
            ("partition", string()),
            ("digest", string()),
            ("placements", count()),
            ("counts", one_of(&["run", "shard"])),
            ("count_valid", total()),
            ("excluded_by_rank", total()),
            ("determined", total()),
            (
                "criteria",
                array(one_of(&["groups", "library", "max-size", "levels"])),
            ),
            ("list_cap", count()),
            ("own", inputs()),
        ],
        &[],
    );
    with_keys(transform_summary(), &[("shard", shard)], &[])
}

pub(super) fn transform() -> Value {
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

pub(super) fn comparison() -> Value {
    let mut keys = vec![("inputs", inputs()), ("status", status())];
    keys.extend(scores());
    keys.push(("types", array(type_count())));
    keys.push(("group_list", array(group_brief())));
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

pub(super) fn solve() -> Value {
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

pub(super) fn sweep() -> Value {
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
pub(super) fn check_record() -> Value {
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

pub(super) fn check() -> Value {
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
