//! The JSON Schema of format v1, derived from plain "document" structs that mirror the format
//! (their doc comments become the descriptions editors show). The reader does not use these
//! structs: it reads a spanned tree so that errors are located. Keep both in step.

#![allow(dead_code)] // The document structs exist only for their schema.

use crate::joint::CATALOGUE;
use crate::mechanism::Expect;
use schemars::{JsonSchema, Schema, SchemaGenerator, json_schema};

/// A mechanism file (mbsa format v1): bodies joined by kinematic pairs, or a bar-joint
/// framework (points and bars).
#[derive(JsonSchema)]
#[schemars(title = "mbsa mechanism file (format v1)")]
#[serde(deny_unknown_fields)]
struct Document {
    /// The URL or path of this schema (JSON files only; ignored by mbsa).
    #[serde(rename = "$schema")]
    schema: Option<String>,
    /// Display name (default: the file stem).
    name: Option<String>,
    /// Free text.
    description: Option<String>,
    /// Motion space: spatial (B = 6, default), planar or spherical (B = 3).
    space: Option<SpaceDoc>,
    /// The fixed body (ground): a body id, or a bar id in a framework.
    frame: IdDoc,
    /// Optional body declarations; when present, every body a joint names must be declared.
    body: Option<Vec<BodyDoc>>,
    /// Alias of `body`.
    bodies: Option<Vec<BodyDoc>>,
    /// The kinematic pairs (at least one).
    joint: Option<Vec<JointDoc>>,
    /// Alias of `joint`.
    joints: Option<Vec<JointDoc>>,
    /// Framework points (bar-joint frameworks; not with `joint`/`body`).
    point: Option<Vec<PointDoc>>,
    /// Alias of `point`.
    points: Option<Vec<PointDoc>>,
    /// Framework bars: each is a body; the bars meeting at a point share one multiple joint
    /// (S in space, R in the plane).
    bar: Option<Vec<BarDoc>>,
    /// Alias of `bar`.
    bars: Option<Vec<BarDoc>>,
    /// Expectations compared by `mbsa check`.
    expect: Option<Expect>,
    /// How precisely every geometry number is known (±, in file units; default: judged from
    /// the digits written). `mbsa import` writes it from the source file; `--tolerance`
    /// overrides it.
    #[schemars(range(min = 0.0, max = 1e100))]
    precision: Option<f64>,
}

/// The motion space.
#[derive(JsonSchema)]
#[serde(rename_all = "lowercase")]
enum SpaceDoc {
    /// B = 6.
    Spatial,
    /// B = 3, motion in the xy plane.
    Planar,
    /// B = 3, rotation about a fixed point.
    Spherical,
}

/// A body, point or bar id: an integer or a non-empty string.
#[derive(JsonSchema)]
#[serde(untagged)]
enum IdDoc {
    /// Integer id.
    Int(i64),
    /// Name.
    Name(#[schemars(length(min = 1))] String),
}

/// A body declaration.
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
struct BodyDoc {
    /// Its id.
    id: IdDoc,
    /// Display label.
    label: Option<String>,
}

/// A joint (kinematic pair).
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
struct JointDoc {
    /// Unique name (default `<a>-<b>` of its bodies, suffixed `#2`, `#3`... if repeated).
    id: Option<String>,
    /// Joint type: a code or a long name (matched case-insensitively).
    #[schemars(schema_with = "joint_type_schema")]
    r#type: String,
    /// The bodies it joins (two, or more for a multiple joint).
    #[schemars(length(min = 2))]
    bodies: Vec<IdDoc>,
    /// Driven DOF of this joint: 0 ..= grade x (number of bodies - 1). Order: translations
    /// before rotations (C: slide, turn; PL: two slides, turn; U: axis, axis2; S: x, y, z).
    #[schemars(range(min = 0))]
    driven: Option<u32>,
    /// A point of the joint: [x, y, z] ([x, y] in a planar mechanism).
    #[serde(default)]
    #[schemars(schema_with = "point_schema")]
    origin: Option<Vec<f64>>,
    /// Second point ([x, y, z]): the centre on the second body of a sphere-sphere contact (SPSP).
    #[serde(default)]
    #[schemars(schema_with = "point_schema")]
    origin2: Option<Vec<f64>>,
    /// Joint axis (R, P, H, C, ER, first axis of U; cylinder axis of SC, PC, CR); non-zero.
    #[serde(default)]
    #[schemars(schema_with = "vector_schema")]
    axis: Option<Vec<f64>>,
    /// Second axis of a universal joint; non-zero.
    #[serde(default)]
    #[schemars(schema_with = "vector_schema")]
    axis2: Option<Vec<f64>>,
    /// Plane normal of a planar joint (PL), of the plane of a sphere-plane (SP) or plane-cylinder
    /// (PC) contact, of the slot plane of a slotted cylindrical joint (CR); non-zero.
    #[serde(default)]
    #[schemars(schema_with = "vector_schema")]
    normal: Option<Vec<f64>>,
    /// Helical lead per radian.
    pitch: Option<f64>,
    /// The joint as carried by the second body, when the configuration written is not closed
    /// (absent: the same as the first body's). Only the features the second body carries: R,
    /// P, H, C, ER, PC, CR `origin`, `axis`; U `origin`, `axis2`; S, SC, SP `origin`; PL `origin`,
    /// `normal`; planar R `origin`, planar P `origin`, `axis`; spherical R `axis`.
    second: Option<SecondDoc>,
}

/// A joint's geometry on its second body (`mbsa assemble` closes the configuration and drops it).
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
struct SecondDoc {
    /// The joint point on the second body.
    #[serde(default)]
    #[schemars(schema_with = "point_schema")]
    origin: Option<Vec<f64>>,
    /// The joint axis on the second body; non-zero.
    #[serde(default)]
    #[schemars(schema_with = "vector_schema")]
    axis: Option<Vec<f64>>,
    /// The second axis of a universal joint, on the second body; non-zero.
    #[serde(default)]
    #[schemars(schema_with = "vector_schema")]
    axis2: Option<Vec<f64>>,
    /// The plane normal on the second body (PL); non-zero.
    #[serde(default)]
    #[schemars(schema_with = "vector_schema")]
    normal: Option<Vec<f64>>,
}

/// A framework point.
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
struct PointDoc {
    /// Its id (names the joint at this point in reports).
    id: IdDoc,
    /// Position: [x, y, z] ([x, y] in a planar mechanism).
    #[serde(default)]
    #[schemars(schema_with = "point_schema")]
    at: Option<Vec<f64>>,
}

/// A framework bar (a body joining two points).
#[derive(JsonSchema)]
#[serde(deny_unknown_fields)]
struct BarDoc {
    /// Its body id (default `"p-q"`).
    id: Option<IdDoc>,
    /// Its two end points.
    #[schemars(length(min = 2, max = 2))]
    points: Vec<IdDoc>,
}

fn joint_type_schema(_: &mut SchemaGenerator) -> Schema {
    let mut names: Vec<&str> = Vec::new();
    for i in CATALOGUE.iter() {
        names.push(i.code);
        names.extend(i.names.iter().copied());
    }
    json_schema!({
        "type": "string",
        "description": "Joint type: a code (R, P, H, C, U, S, ...) or a long name (revolute, prismatic, ...).",
        "enum": names,
    })
}

fn point_schema(_: &mut SchemaGenerator) -> Schema {
    json_schema!({
        "type": "array",
        "items": {"type": "number"},
        "minItems": 2,
        "maxItems": 3,
    })
}

fn vector_schema(_: &mut SchemaGenerator) -> Schema {
    json_schema!({
        "type": "array",
        "items": {"type": "number"},
        "minItems": 2,
        "maxItems": 3,
        "description": "[x, y, z], non-zero ([x, y] allowed in a planar mechanism)",
    })
}

/// The JSON Schema (draft 2020-12) of the mechanism file format, for editor completion and
/// validation of TOML (taplo) and YAML (yaml-language-server) files.
pub fn schema() -> serde_json::Value {
    let mut v = schemars::schema_for!(Document).to_value();
    // Optional keys are absent, never null (TOML has no null; the reader rejects it).
    strip_null(&mut v);
    v
}

/// Remove `null` from `type` arrays and `{"type": "null"}` from `anyOf` lists, recursively.
fn strip_null(v: &mut serde_json::Value) {
    use serde_json::Value;
    match v {
        Value::Object(o) => {
            if o.get("default").is_some_and(Value::is_null) {
                o.remove("default");
            }
            if let Some(Value::Array(types)) = o.get_mut("type") {
                types.retain(|t| t != "null");
                if types.len() == 1 {
                    let only = types.remove(0);
                    o.insert("type".into(), only);
                }
            }
            if let Some(Value::Array(any)) = o.get_mut("anyOf") {
                any.retain(|s| {
                    s.get("type").is_none_or(|t| t != "null")
                        || s.as_object().is_some_and(|m| m.len() > 1)
                });
                if any.len() == 1 {
                    let only = any.remove(0);
                    o.remove("anyOf");
                    if let Value::Object(inner) = only {
                        for (k, x) in inner {
                            o.entry(k).or_insert(x);
                        }
                    }
                }
            }
            for x in o.values_mut() {
                strip_null(x);
            }
        }
        Value::Array(xs) => xs.iter_mut().for_each(strip_null),
        _ => {}
    }
}
