//! JSON schemas in the subset Foxglove and Lichtblick parse.
//!
//! The viewers turn a channel's JSON schema into message fields themselves and accept only plain
//! trees: every node has one `type` (`object` with `properties`, `array` with `items`, `string`,
//! `number`, `integer`, `boolean`), string enumerations are `{"type": "string", "enum": [...]}`.
//! A `$ref`, a `oneOf`/`anyOf` or a nullable `["T", "null"]` makes them reject the whole channel
//! ("Unsupported type undefined"). schemars writes exactly those for nested structs and unit
//! enums, so its output is rewritten here: references inlined, enumerations flattened, `null`
//! removed from type unions.

use serde_json::{Map, Value};

/// The JSON types a viewer accepts as a node's `type`.
pub const VIEWER_TYPES: [&str; 6] = ["object", "array", "string", "number", "integer", "boolean"];

/// Keywords that make a viewer reject a schema.
const REJECTED_KEYWORDS: [&str; 6] = ["$ref", "$defs", "definitions", "oneOf", "anyOf", "allOf"];

/// Rewrites a schemars schema into the viewers' subset (see the module doc).
pub fn for_viewers(schema: &Value) -> Value {
    let defs = schema
        .get("$defs")
        .or_else(|| schema.get("definitions"))
        .and_then(Value::as_object)
        .cloned()
        .unwrap_or_default();
    let mut out = rewrite(schema, &defs, 0);
    if let Some(o) = out.as_object_mut() {
        o.remove("$schema");
    }
    out
}

/// Nesting beyond this is a recursive type, which a tree cannot express: it becomes an object
/// without fields (none of hubtrack's messages nests deeper than a few levels).
const MAX_DEPTH: usize = 32;

fn rewrite(node: &Value, defs: &Map<String, Value>, depth: usize) -> Value {
    let Some(obj) = node.as_object() else {
        return node.clone();
    };
    if depth > MAX_DEPTH {
        return serde_json::json!({"type": "object", "properties": {}});
    }
    let mut out = Map::new();
    // A reference: the definition's keywords, the referencing node's own (its description) win.
    if let Some(target) = obj
        .get("$ref")
        .and_then(Value::as_str)
        .and_then(|r| r.rsplit('/').next())
        .and_then(|name| defs.get(name))
    {
        if let Value::Object(t) = rewrite(target, defs, depth + 1) {
            out.extend(t);
        }
    }
    for (k, v) in obj {
        match k.as_str() {
            "$ref" | "$defs" | "definitions" | "$schema" => {}
            "properties" => {
                let props = v
                    .as_object()
                    .map(|p| {
                        p.iter()
                            .map(|(name, s)| (name.clone(), rewrite(s, defs, depth + 1)))
                            .collect::<Map<_, _>>()
                    })
                    .unwrap_or_default();
                out.insert(k.clone(), Value::Object(props));
            }
            "items" => {
                out.insert(k.clone(), rewrite(v, defs, depth + 1));
            }
            "oneOf" | "anyOf" => {
                let alternatives: Vec<Value> = v
                    .as_array()
                    .map(|a| a.iter().map(|s| rewrite(s, defs, depth + 1)).collect())
                    .unwrap_or_default();
                merge_union(&alternatives, &mut out);
            }
            "type" => {
                out.insert(k.clone(), single_type(v));
            }
            _ => {
                out.insert(k.clone(), v.clone());
            }
        }
    }
    Value::Object(out)
}

/// `["number", "null"]` → `"number"`.
fn single_type(v: &Value) -> Value {
    match v {
        Value::Array(types) => types
            .iter()
            .find(|t| t.as_str() != Some("null"))
            .cloned()
            .unwrap_or(Value::String("string".into())),
        other => other.clone(),
    }
}

/// A union of string constants becomes one string enumeration; any other union (an option: the
/// value or null) becomes its first non-null alternative.
fn merge_union(alternatives: &[Value], out: &mut Map<String, Value>) {
    let mut names = Vec::new();
    let all_strings = alternatives.iter().all(|a| {
        if let Some(c) = a.get("const").and_then(Value::as_str) {
            names.push(Value::String(c.into()));
            true
        } else if let Some(e) = a.get("enum").and_then(Value::as_array) {
            names.extend(e.iter().filter(|v| v.is_string()).cloned());
            e.iter().all(Value::is_string)
        } else {
            false
        }
    });
    if all_strings && !names.is_empty() {
        out.insert("type".into(), Value::String("string".into()));
        out.insert("enum".into(), Value::Array(names));
    } else if let Some(Value::Object(first)) = alternatives
        .iter()
        .find(|a| a.get("type").and_then(Value::as_str) != Some("null"))
    {
        for (k, v) in first {
            out.entry(k.clone()).or_insert_with(|| v.clone());
        }
    }
}

/// Why `schema` falls outside the viewers' subset, with the path of the first offending node.
pub fn check(schema: &Value) -> Result<(), String> {
    check_node(schema, "$")
}

fn check_node(node: &Value, path: &str) -> Result<(), String> {
    let obj = node
        .as_object()
        .ok_or_else(|| format!("{path}: not an object"))?;
    if let Some(k) = REJECTED_KEYWORDS.iter().find(|k| obj.contains_key(**k)) {
        return Err(format!("{path}: uses {k}"));
    }
    let ty = obj
        .get("type")
        .and_then(Value::as_str)
        .ok_or_else(|| format!("{path}: no single type"))?;
    if !VIEWER_TYPES.contains(&ty) {
        return Err(format!("{path}: type {ty} not supported"));
    }
    if let Some(e) = obj.get("enum") {
        let ok = ty == "string"
            && e.as_array()
                .is_some_and(|a| !a.is_empty() && a.iter().all(Value::is_string));
        if !ok {
            return Err(format!(
                "{path}: enum must be a list of strings on a string"
            ));
        }
    }
    match ty {
        "object" => {
            let props = obj
                .get("properties")
                .and_then(Value::as_object)
                .ok_or_else(|| format!("{path}: object without properties"))?;
            for (name, s) in props {
                check_node(s, &format!("{path}.{name}"))?;
            }
        }
        "array" => {
            let items = obj
                .get("items")
                .ok_or_else(|| format!("{path}: array without items"))?;
            check_node(items, &format!("{path}[]"))?;
        }
        _ => {}
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::writer::ChannelKind;
    use serde_json::json;

    #[test]
    fn every_recorded_schema_is_in_the_subset() {
        for kind in ChannelKind::ALL {
            let s: Value = serde_json::from_slice(&kind.json_schema()).unwrap();
            check(&s).unwrap_or_else(|e| panic!("{}: {e}", kind.schema_name()));
        }
        let overlay: Value = serde_json::from_slice(&crate::annotations::json_schema()).unwrap();
        check(&overlay).unwrap();
    }

    #[test]
    fn enums_and_references_are_flattened() {
        let s: Value = serde_json::from_slice(&ChannelKind::Track.json_schema()).unwrap();
        let mode = &s["properties"]["mode"];
        assert_eq!(mode["type"], "string");
        assert!(mode["enum"].as_array().unwrap().len() >= 2, "{mode}");
        assert_eq!(
            s["properties"]["stamps"]["properties"]["seq"]["type"],
            "integer"
        );
    }

    #[test]
    fn the_checker_rejects_what_viewers_reject() {
        let bad = [
            json!({"type": "object", "properties": {"a": {"$ref": "#/$defs/A"}}}),
            json!({"type": "object", "properties": {"a": {"oneOf": [{"const": "x"}]}}}),
            json!({"type": "object", "properties": {"a": {"type": ["number", "null"]}}}),
            json!({"type": "object", "properties": {"a": {"type": "integer", "enum": [1, 2]}}}),
            json!({"type": "array"}),
        ];
        for b in bad {
            assert!(check(&b).is_err(), "{b}");
        }
        let nullable = json!({"type": "object", "properties": {
            "a": {"anyOf": [{"type": "number"}, {"type": "null"}]},
            "b": {"type": ["string", "null"]}}});
        check(&for_viewers(&nullable)).unwrap();
    }
}
