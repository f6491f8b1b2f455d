//! The `[expect]` table: the results a file expects, checked by their own type.

use super::values::{as_map, check_keys, err, out_of_range};
use crate::format::error::{ErrorKind, LoadError};
use crate::format::tree::{Node, Value};
use crate::mechanism::Expect;

/// `[expect]`: keys and types from [`Expect`] itself, so the two stay in sync.
pub(super) fn parse_expect(node: &Node) -> Result<Expect, LoadError> {
    let es = as_map(node, "`expect`")?;
    let schema = schemars::schema_for!(Expect);
    let keys: Vec<&str> = schema
        .get("properties")
        .and_then(|p| p.as_object())
        .map(|p| p.keys().map(String::as_str).collect())
        .unwrap_or_default();
    check_keys(es, &keys, "expect")?;
    let mut object = serde_json::Map::new();
    for e in es {
        refuse_absent(&e.key, &e.value)?;
        let v = to_json(&e.value)?;
        let one = serde_json::Value::Object([(e.key.to_string(), v.clone())].into_iter().collect());
        if let Err(x) = serde_json::from_value::<Expect>(one) {
            let msg = x.to_string();
            return Err(err(
                ErrorKind::WrongType,
                format!("`expect.{}`: {msg}", e.key),
                &e.value.span,
                "wrong type",
                Some(match e.key.as_ref() {
                    "determined" => "write true or false".to_string(),
                    "mobility" | "generic_dof" | "true_mobility" => "write an integer".to_string(),
                    _ => "write a non-negative integer".to_string(),
                }),
            ));
        }
        object.insert(e.key.to_string(), v);
    }
    let mut expect: Expect =
        serde_json::from_value(serde_json::Value::Object(object)).map_err(|x| {
            err(
                ErrorKind::WrongType,
                format!("`expect`: {x}"),
                &node.span,
                "here",
                None,
            )
        })?;
    expect.written = true;
    Ok(expect)
}

/// A value that would read as "not expected": NaN or an infinity (JSON `1e999`, YAML `.nan`),
/// or an explicit null. Dropping it would make `mbsa check` pass a file that checks nothing.
fn refuse_absent(key: &str, node: &Node) -> Result<(), LoadError> {
    let (what, label) = match node.value {
        Value::Float(f) if !f.is_finite() => ("is not a finite number", "not finite"),
        Value::Null => ("has no value", "no value"),
        _ => return Ok(()),
    };
    Err(err(
        ErrorKind::WrongType,
        format!("`expect.{key}` {what}"),
        &node.span,
        label,
        Some(match key {
            "determined" => "write true or false, or remove the key".to_string(),
            _ => "write the expected integer, or remove the key".to_string(),
        }),
    ))
}

fn to_json(node: &Node) -> Result<serde_json::Value, LoadError> {
    use serde_json::Value as J;
    Ok(match &node.value {
        Value::Map(es) => {
            let mut m = serde_json::Map::new();
            for e in es {
                m.insert(e.key.to_string(), to_json(&e.value)?);
            }
            J::Object(m)
        }
        Value::Seq(xs) => J::Array(xs.iter().map(to_json).collect::<Result<_, _>>()?),
        Value::Str(s) => J::String(s.to_string()),
        Value::Int(i) => J::from(*i),
        Value::BigInt(_) => return Err(out_of_range(node, "this number")),
        Value::Float(f) => serde_json::Number::from_f64(*f).map_or(J::Null, J::Number),
        Value::Bool(b) => J::Bool(*b),
        Value::Null | Value::DateTime | Value::Deferred => J::Null,
    })
}
