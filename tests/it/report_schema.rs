//! Every JSON report of every bundled mechanism validates against the schema `mbsa schema
//! --output REPORT` prints, with a small validator of the keywords those schemas use (type,
//! const, enum, properties, required, additionalProperties, items, minItems, maxItems,
//! minimum, minProperties, anyOf).

use assert_cmd::Command;
use serde_json::Value;

fn mbsa(args: &[&str]) -> (i32, String) {
    let out = Command::cargo_bin("mbsa")
        .expect("the binary is built")
        .env("NO_COLOR", "1")
        .args(args)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    let code = out.status.code().expect("exited normally");
    (code, String::from_utf8(out.stdout).expect("UTF-8"))
}

fn schema(report: &str) -> Value {
    let (code, text) = mbsa(&["schema", "--output", report]);
    assert_eq!(code, 0, "schema --output {report}");
    serde_json::from_str(&text).expect("the schema is JSON")
}

fn type_matches(t: &str, v: &Value) -> bool {
    match t {
        "object" => v.is_object(),
        "array" => v.is_array(),
        "string" => v.is_string(),
        "boolean" => v.is_boolean(),
        "null" => v.is_null(),
        "number" => v.is_number(),
        "integer" => v.is_i64() || v.is_u64(),
        _ => panic!("keyword type `{t}` not known to the validator"),
    }
}

/// The first way `v` breaks `schema`, as `path: why`.
fn validate(schema: &Value, v: &Value, path: &str) -> Result<(), String> {
    let s = schema.as_object().expect("a schema is an object");
    for key in s.keys() {
        let known = [
            "$schema",
            "title",
            "description",
            "type",
            "const",
            "enum",
            "properties",
            "required",
            "additionalProperties",
            "items",
            "minItems",
            "maxItems",
            "minimum",
            "minProperties",
            "anyOf",
        ];
        assert!(
            known.contains(&key.as_str()),
            "keyword `{key}` not known to the validator"
        );
    }
    let fail = |why: String| Err(format!("{path}: {why}"));
    if let Some(t) = s.get("type").and_then(Value::as_str)
        && !type_matches(t, v)
    {
        return fail(format!("expected {t}, found {v}"));
    }
    if let Some(c) = s.get("const")
        && c != v
    {
        return fail(format!("expected {c}, found {v}"));
    }
    if let Some(Value::Array(e)) = s.get("enum")
        && !e.contains(v)
    {
        return fail(format!("{v} is not one of {e:?}"));
    }
    if let Some(min) = s.get("minimum").and_then(Value::as_f64)
        && v.as_f64().is_some_and(|x| x < min)
    {
        return fail(format!("{v} is below {min}"));
    }
    if let Some(Value::Array(options)) = s.get("anyOf") {
        let errors: Vec<String> = options
            .iter()
            .filter_map(|o| validate(o, v, path).err())
            .collect();
        if errors.len() == options.len() {
            return fail(format!("matches no option: {}", errors.join("; ")));
        }
    }
    if let Value::Object(o) = v {
        let props = s.get("properties").and_then(Value::as_object);
        if let Some(Value::Array(req)) = s.get("required") {
            for r in req.iter().filter_map(Value::as_str) {
                if !o.contains_key(r) {
                    return fail(format!("missing key `{r}`"));
                }
            }
        }
        if let Some(n) = s.get("minProperties").and_then(Value::as_u64)
            && (o.len() as u64) < n
        {
            return fail(format!("fewer than {n} keys"));
        }
        for (k, x) in o {
            match props.and_then(|p| p.get(k)) {
                Some(sub) => validate(sub, x, &format!("{path}.{k}"))?,
                None if s.get("additionalProperties") == Some(&Value::Bool(false)) => {
                    return fail(format!("key `{k}` is not in the schema"));
                }
                None => {}
            }
        }
    }
    if let Value::Array(a) = v {
        if let Some(n) = s.get("minItems").and_then(Value::as_u64)
            && (a.len() as u64) < n
        {
            return fail(format!("fewer than {n} items"));
        }
        if let Some(n) = s.get("maxItems").and_then(Value::as_u64)
            && (a.len() as u64) > n
        {
            return fail(format!("more than {n} items"));
        }
        if let Some(items) = s.get("items") {
            for (i, x) in a.iter().enumerate() {
                validate(items, x, &format!("{path}[{i}]"))?;
            }
        }
    }
    Ok(())
}

/// A JSON document read only to refuse an object that names a key twice (`Value` keeps the
/// last and hides it; readers differ on which one they keep).
struct UniqueKeys;

impl<'de> serde::Deserialize<'de> for UniqueKeys {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(UniqueKeysVisitor)
    }
}

struct UniqueKeysVisitor;

impl<'de> serde::de::Visitor<'de> for UniqueKeysVisitor {
    type Value = UniqueKeys;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_bool<E>(self, _: bool) -> Result<UniqueKeys, E> {
        Ok(UniqueKeys)
    }
    fn visit_i64<E>(self, _: i64) -> Result<UniqueKeys, E> {
        Ok(UniqueKeys)
    }
    fn visit_u64<E>(self, _: u64) -> Result<UniqueKeys, E> {
        Ok(UniqueKeys)
    }
    fn visit_f64<E>(self, _: f64) -> Result<UniqueKeys, E> {
        Ok(UniqueKeys)
    }
    fn visit_str<E>(self, _: &str) -> Result<UniqueKeys, E> {
        Ok(UniqueKeys)
    }
    fn visit_unit<E>(self) -> Result<UniqueKeys, E> {
        Ok(UniqueKeys)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<UniqueKeys, A::Error> {
        while a.next_element::<UniqueKeys>()?.is_some() {}
        Ok(UniqueKeys)
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut a: A) -> Result<UniqueKeys, A::Error> {
        let mut seen = std::collections::HashSet::new();
        while let Some(k) = a.next_key::<String>()? {
            a.next_value::<UniqueKeys>()?;
            if !seen.insert(k.clone()) {
                return Err(serde::de::Error::custom(format!("key `{k}` written twice")));
            }
        }
        Ok(UniqueKeys)
    }
}

/// Run `args`, and validate its output (one document, or each line with `lines`) against
/// the schema of `report`. Runs that fail with no output (`solve` of a file without
/// geometry) are skipped; the number of documents checked is returned.
fn check(report: &Value, args: &[&str], lines: bool) -> usize {
    let (code, out) = mbsa(args);
    if out.is_empty() {
        assert_ne!(code, 0, "{args:?} succeeded with no output");
        return 0;
    }
    let docs: Vec<&str> = if lines {
        out.lines().collect()
    } else {
        vec![&out]
    };
    for d in &docs {
        if let Err(e) = serde_json::from_str::<UniqueKeys>(d) {
            panic!("{args:?}: {e}");
        }
        let v: Value = serde_json::from_str(d).unwrap_or_else(|e| panic!("{args:?}: {e}"));
        assert_eq!(v["format_version"], 1, "{args:?}");
        if let Err(e) = validate(report, &v, "$") {
            panic!("{args:?} does not match its schema: {e}");
        }
    }
    docs.len()
}

#[test]
fn every_bundled_report_matches_its_schema() {
    let names: Vec<String> = mbsa::examples::names().map(|n| format!("@{n}")).collect();
    let s = |r| schema(r);
    let (mobility, analyze, rigid, transform, lines, solve, check_doc, check_line) = (
        s("mobility"),
        s("analyze"),
        s("rigid"),
        s("transform"),
        s("transform-jsonl"),
        s("solve"),
        s("check"),
        s("check-jsonl"),
    );
    let mut checked = 0;
    for f in &names {
        let f = f.as_str();
        checked += check(&mobility, &["mobility", f, "--format", "json"], false);
        checked += check(&analyze, &["analyze", f, "--format", "json"], false);
        checked += check(
            &analyze,
            &["analyze", f, "--count-only", "--format", "json"],
            false,
        );
        for method in ["both", "counting", "geometric"] {
            let args = ["rigid", f, "--method", method, "--format", "json"];
            checked += check(&rigid, &args, false);
        }
        let args = ["transform", f, "--limit", "5", "--format", "json"];
        checked += check(&transform, &args, false);
        let args = ["transform", f, "--limit", "5", "--format", "jsonl"];
        checked += check(&lines, &args, true);
        checked += check(&solve, &["solve", f, "--format", "json"], false);
    }
    let all: Vec<&str> = ["check", "--format", "json"]
        .into_iter()
        .chain(names.iter().map(String::as_str))
        .collect();
    checked += check(&check_doc, &all, false);
    let mut all_lines = all.clone();
    all_lines[2] = "jsonl";
    checked += check(&check_line, &all_lines, true);
    // The other shapes: the comparison of one placement, a sweep, the finite test.
    let rotor = [
        "transform",
        "@rotor",
        "--inputs",
        "1-2,1-13,13-15",
        "--format",
        "json",
    ];
    checked += check(&transform, &rotor, false);
    let shard = [
        "transform",
        "@rotor",
        "--partition",
        "hash:1/2",
        "--format",
        "jsonl",
    ];
    checked += check(&s("transform-shard"), &shard, true);
    let sweep = [
        "solve",
        "@slider-crank-geometry",
        "--sweep",
        "A=0..360:90",
        "--format",
        "json",
    ];
    checked += check(&solve, &sweep, false);
    checked += check(
        &solve,
        &["solve", "@rig-bennett", "--finite", "--format", "json"],
        false,
    );
    checked += check(
        &rigid,
        &["rigid", "@rig-bennett", "--finite", "--format", "json"],
        false,
    );
    assert!(checked > 10 * names.len(), "only {checked} reports checked");
}

#[test]
fn the_validator_rejects_what_the_schema_excludes() {
    let schema = schema("mobility");
    let (_, out) = mbsa(&["mobility", "@four-bar", "--format", "json"]);
    let good: Value = serde_json::from_str(&out).expect("JSON");
    assert_eq!(validate(&schema, &good, "$"), Ok(()));
    assert!(serde_json::from_str::<UniqueKeys>(&out).is_ok());
    let twice = r#"{"a": [{"b": 1, "c": {"d": 2, "d": 3}}], "e": 4}"#;
    let e = serde_json::from_str::<UniqueKeys>(twice)
        .err()
        .expect("a key twice is refused");
    assert!(e.to_string().contains("key `d` written twice"), "{e}");
    let mut extra = good.clone();
    extra["surprise"] = Value::from(1);
    assert!(
        validate(&schema, &extra, "$")
            .unwrap_err()
            .contains("surprise")
    );
    let mut missing = good.clone();
    missing.as_object_mut().expect("object").remove("loops");
    assert!(
        validate(&schema, &missing, "$")
            .unwrap_err()
            .contains("loops")
    );
    let mut wrong = good.clone();
    wrong["mobility"]["verdict"] = Value::from("maybe");
    assert!(validate(&schema, &wrong, "$").is_err());
    let mut version = good;
    version["format_version"] = Value::from(2);
    assert!(validate(&schema, &version, "$").is_err());
}

#[test]
fn every_report_has_a_schema_and_the_input_schema_stays_the_default() {
    for r in mbsa::report::schema::Report::ALL {
        let s = schema(r.name());
        assert_eq!(s["$schema"], "https://json-schema.org/draft/2020-12/schema");
    }
    let (code, default) = mbsa(&["schema"]);
    assert_eq!(code, 0);
    assert_eq!(default, mbsa(&["schema", "--output", "input"]).1);
    assert!(!default.contains("format_version"));
}

#[test]
fn every_cut_report_matches_its_schema() {
    let schema = schema("cut");
    let mut checked = 0;
    for n in mbsa::examples::names() {
        checked += check(
            &schema,
            &["cut", &format!("@{n}"), "--format", "json"],
            false,
        );
    }
    let cassie = "tests/fixtures/import/cassie.xml";
    checked += check(&schema, &["cut", cassie, "--format", "json"], false);
    assert!(checked > mbsa::examples::names().count(), "{checked}");
}
