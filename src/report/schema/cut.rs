//! The schema of `mbsa cut --format json`.

use super::analyses::geometry_used;
use super::{array, boolean, count, obj, one_of, space, string, strings};
use serde_json::Value;

pub(super) fn cut() -> Value {
    let tree_joint = obj(
        &[
            ("joint", string()),
            ("kind", string()),
            ("parent", string()),
            ("child", string()),
            ("dof", count()),
        ],
        &[],
    );
    let closure = obj(
        &[
            ("joint", string()),
            ("kind", string()),
            ("bodies", {
                let mut s = strings();
                s["minItems"] = 2.into();
                s["maxItems"] = 2.into();
                s
            }),
            ("why", one_of(&["spherical", "independent", "order"])),
            ("loop_bodies", strings()),
            ("loop_joints", strings()),
            ("rows", count()),
            ("rank", count()),
            ("redundant", count()),
            ("independent", boolean()),
        ],
        &[],
    );
    obj(
        &[
            ("name", string()),
            ("space", space()),
            ("b", count()),
            ("frame", string()),
            ("bodies", count()),
            ("joints", count()),
            ("pairs", count()),
            ("loops", count()),
            ("coordinates", count()),
            ("rows", count()),
            ("rank", count()),
            ("redundant", count()),
            ("mobility", count()),
            ("independent", count()),
            ("geometry_used", geometry_used()),
            ("tree", array(tree_joint)),
            ("floating", strings()),
            ("cuts", array(closure)),
            ("note", string()),
        ],
        &["note"],
    )
}
