//! Writing a mechanism as a format-v1 file (the contract [`crate::format`] reads,
//! docs/format.md): TOML, YAML or JSON, the same keys in the same order, with an optional
//! comment per joint (TOML and YAML comments; JSON has none, so there the comments are
//! appended to `description`). Bodies are declared when labelled.

use crate::mechanism::{BodyId, Geometry, Joint, Mechanism, Space};
use serde_json::{Map, Value, json};
use std::fmt::Write;

/// A format to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextFormat {
    /// TOML.
    Toml,
    /// YAML.
    Yaml,
    /// JSON.
    Json,
}

/// `m` as a file of format `format`; `comments[j]`, when given, is written above joint `j`.
pub fn write(m: &Mechanism, format: TextFormat, comments: &[Option<String>]) -> String {
    match format {
        TextFormat::Toml => toml(m, comments),
        TextFormat::Yaml => yaml(m, comments),
        TextFormat::Json => json_text(m, comments),
    }
}

/// A joint's keys after `id`: (key, value) in file order, values as JSON.
fn joint_fields(m: &Mechanism, j: &Joint) -> Vec<(&'static str, Value)> {
    let planar = m.space == Space::Planar;
    let mut out = vec![
        ("type", json!(j.kind.code())),
        (
            "bodies",
            Value::Array(j.bodies.iter().map(|&b| body(m.body_id(b))).collect()),
        ),
    ];
    if j.driven > 0 {
        out.push(("driven", json!(j.driven)));
    }
    let Geometry {
        origin,
        axis,
        axis2,
        origin2,
        normal,
        pitch,
        second,
    } = &*j.geometry;
    for (key, v, two) in [
        ("origin", origin, planar),
        ("origin2", origin2, planar),
        ("axis", axis, false),
        ("axis2", axis2, false),
        ("normal", normal, false),
    ] {
        if let Some(v) = v {
            out.push((key, vector(v, two)));
        }
    }
    if let Some(p) = pitch {
        out.push(("pitch", json!(p)));
    }
    if let Some(s) = second {
        let mut t = Map::new();
        for (key, v) in s.vectors() {
            if let Some(v) = v {
                t.insert(key.into(), vector(&v, planar && key == "origin"));
            }
        }
        out.push(("second", Value::Object(t)));
    }
    out
}

fn body(id: &BodyId) -> Value {
    match id {
        BodyId::Int(i) => json!(i),
        BodyId::Name(s) => json!(s),
    }
}

fn vector(v: &[f64; 3], planar: bool) -> Value {
    let n = if planar { 2 } else { 3 };
    json!(v[..n])
}

/// A value in TOML's (and YAML's flow) syntax: floats as Rust's shortest round trip.
fn inline(v: &Value, toml: bool) -> String {
    match v {
        Value::String(s) if toml => toml::Value::String(s.clone()).to_string(),
        Value::String(s) => Value::String(s.clone()).to_string(),
        Value::Number(n) => match n.as_f64() {
            Some(x) if !n.is_i64() && !n.is_u64() => format!("{x:?}"),
            _ => n.to_string(),
        },
        Value::Array(a) => {
            let parts: Vec<String> = a.iter().map(|x| inline(x, toml)).collect();
            format!("[{}]", parts.join(", "))
        }
        Value::Object(o) => {
            let sep = if toml { " = " } else { ": " };
            let parts: Vec<String> = o
                .iter()
                .map(|(k, x)| format!("{k}{sep}{}", inline(x, toml)))
                .collect();
            if toml {
                format!("{{ {} }}", parts.join(", "))
            } else {
                format!("{{{}}}", parts.join(", "))
            }
        }
        other => other.to_string(),
    }
}

/// The header keys: name, description, space, frame, precision.
fn header(m: &Mechanism, description: Option<String>) -> Vec<(&'static str, Value)> {
    let mut out = vec![("name", json!(m.name))];
    if let Some(d) = description {
        out.push(("description", json!(d)));
    }
    out.push(("space", json!(m.space.name())));
    out.push(("frame", body(m.body_id(m.frame))));
    if let Some(p) = m.precision {
        // Moved numbers are as precise as the file's were (`mbsa assemble` of an import).
        out.push(("precision", json!(p)));
    }
    out
}

fn toml(m: &Mechanism, comments: &[Option<String>]) -> String {
    let mut out = String::new();
    if let Some(d) = &m.description {
        for line in d.lines() {
            let _ = writeln!(out, "# {line}");
        }
    }
    for (k, v) in header(m, m.description.clone()) {
        let _ = writeln!(out, "{k} = {}", inline(&v, true));
    }
    if m.bodies.iter().any(|b| b.label.is_some()) {
        for b in &m.bodies {
            let _ = write!(out, "\n[[body]]\nid = {}\n", inline(&body(&b.id), true));
            if let Some(l) = &b.label {
                let _ = writeln!(out, "label = {}", inline(&json!(l), true));
            }
        }
    }
    for (i, j) in m.joints.iter().enumerate() {
        out.push('\n');
        comment(&mut out, comments.get(i), "");
        out.push_str("[[joint]]\n");
        if j.id != m.joint_bodies_label(j) {
            let _ = writeln!(out, "id = {}", inline(&json!(j.id), true));
        }
        for (k, v) in joint_fields(m, j) {
            let _ = writeln!(out, "{k} = {}", inline(&v, true));
        }
    }
    out
}

fn comment(out: &mut String, c: Option<&Option<String>>, indent: &str) {
    if let Some(Some(c)) = c {
        for line in c.lines() {
            let _ = writeln!(out, "{indent}# {line}");
        }
    }
}

fn yaml(m: &Mechanism, comments: &[Option<String>]) -> String {
    let mut out = String::new();
    if let Some(d) = &m.description {
        for line in d.lines() {
            let _ = writeln!(out, "# {line}");
        }
    }
    for (k, v) in header(m, m.description.clone()) {
        let _ = writeln!(out, "{k}: {}", inline(&v, false));
    }
    if m.bodies.iter().any(|b| b.label.is_some()) {
        out.push_str("body:\n");
        for b in &m.bodies {
            let _ = writeln!(out, "  - id: {}", inline(&body(&b.id), false));
            if let Some(l) = &b.label {
                let _ = writeln!(out, "    label: {}", inline(&json!(l), false));
            }
        }
    }
    out.push_str("joint:\n");
    for (i, j) in m.joints.iter().enumerate() {
        comment(&mut out, comments.get(i), "  ");
        let _ = writeln!(out, "  - id: {}", inline(&json!(j.id), false));
        for (k, v) in joint_fields(m, j) {
            let _ = writeln!(out, "    {k}: {}", inline(&v, false));
        }
    }
    out
}

fn json_text(m: &Mechanism, comments: &[Option<String>]) -> String {
    let notes: Vec<&str> = comments.iter().flatten().map(String::as_str).collect();
    let description = match (&m.description, notes.is_empty()) {
        (d, true) => d.clone(),
        (None, false) => Some(notes.join("\n")),
        (Some(d), false) => Some(format!("{d}\n{}", notes.join("\n"))),
    };
    let mut top = Map::new();
    for (k, v) in header(m, description) {
        top.insert(k.into(), v);
    }
    if m.bodies.iter().any(|b| b.label.is_some()) {
        let bodies = m.bodies.iter().map(|b| {
            let mut t = Map::new();
            t.insert("id".into(), body(&b.id));
            if let Some(l) = &b.label {
                t.insert("label".into(), json!(l));
            }
            Value::Object(t)
        });
        top.insert("body".into(), Value::Array(bodies.collect()));
    }
    let joints = m.joints.iter().map(|j| {
        let mut t = Map::new();
        t.insert("id".into(), json!(j.id));
        for (k, v) in joint_fields(m, j) {
            t.insert(k.into(), v);
        }
        Value::Object(t)
    });
    top.insert("joint".into(), Value::Array(joints.collect()));
    let mut s = serde_json::to_string_pretty(&Value::Object(top)).unwrap_or_default();
    s.push('\n');
    s
}
