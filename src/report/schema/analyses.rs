//! Schemas of the analysis reports: `mobility`, `analyze`, `rigid` (and the finite test that
//! `rigid` and `solve` share).

use super::{
    array, boolean, count, integer, number, obj, one_of, or_null, space, status, string, strings,
    vector,
};
use serde_json::{Value, json};

pub(super) fn mobility() -> Value {
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

pub(super) fn geometry_used() -> Value {
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

pub(super) fn type_count() -> Value {
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
            (
                "pieces",
                array(obj(
                    &[
                        ("missing", count()),
                        ("bodies", strings()),
                        ("input_candidates", strings()),
                    ],
                    &[],
                )),
            ),
        ],
        &["pieces"],
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

/// The `analyze` report; a function over 80 lines because it lists the report's 22 keys.
pub(super) fn analyze() -> Value {
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
            (
                "spins",
                array(obj(
                    &[
                        ("bodies", strings()),
                        ("joints", strings()),
                        ("dimension", count()),
                    ],
                    &[],
                )),
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
            "spins",
            "unchecked",
            "generic",
            "notes",
            "finite",
        ],
    )
}

pub(super) fn pebble() -> Value {
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
pub(super) fn geometric() -> Value {
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

pub(super) fn finite() -> Value {
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

pub(super) fn rigid_both() -> Value {
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
