//! `hubtrack replay --compare`: the replayed outputs against the recorded ones, per channel.

use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Differing fields named in a table row, at most (the rest are counted).
const FIELDS_SHOWN: usize = 4;

/// Fields that legitimately differ between runs (times measured on this run), removed before
/// comparing. A setpoint's `sent` stays: replay decides it by the live rule, on the recorded
/// vehicle state at the track's time.
fn strip_run_specific(topic: &str, mut v: Value) -> Value {
    if let Some(s) = v.get_mut("stamps").and_then(Value::as_object_mut) {
        s.remove("recv_ns");
        s.remove("publish_ns");
    }
    if topic == "/detections" {
        if let Some(o) = v.as_object_mut() {
            o.remove("timings");
            o.remove("frames_skipped");
        }
    }
    v
}

/// How two messages differ: the largest numeric difference, and every field that differs
/// (numbers, flags, names, missing fields).
#[derive(Debug, Default)]
struct Diff {
    largest: f64,
    fields: BTreeSet<String>,
}

fn diff(path: &str, a: &Value, b: &Value, out: &mut Diff) {
    let field = |k: &str| {
        if path.is_empty() {
            k.to_string()
        } else {
            format!("{path}.{k}")
        }
    };
    match (a, b) {
        (Value::Number(x), Value::Number(y)) if x != y => {
            out.largest = out
                .largest
                .max((x.as_f64().unwrap_or(0.0) - y.as_f64().unwrap_or(0.0)).abs());
            out.fields.insert(path.to_string());
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (p, q) in x.iter().zip(y) {
                diff(path, p, q, out);
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            for k in x.keys().chain(y.keys().filter(|k| !x.contains_key(*k))) {
                match (x.get(k), y.get(k)) {
                    (Some(p), Some(q)) => diff(&field(k), p, q, out),
                    _ => {
                        out.fields.insert(field(k));
                    }
                }
            }
        }
        (p, q) if p == q => {}
        _ => {
            out.fields.insert(path.to_string());
        }
    }
}

/// The messages of `topic` by seq, run-specific fields removed; the first per seq (live control
/// publishes a second, silent setpoint under the last track's seq when its input goes stale).
fn outputs(path: &Path, topic: &str) -> anyhow::Result<BTreeMap<u64, Value>> {
    let mut out = BTreeMap::new();
    for m in hubtrack_record::reader::messages(path)? {
        if m.channel.topic == topic {
            if let Ok(v) = serde_json::from_slice::<Value>(&m.data) {
                let seq = v["stamps"]["seq"].as_u64().unwrap_or(u64::from(m.sequence));
                out.entry(seq)
                    .or_insert_with(|| strip_run_specific(topic, v));
            }
        }
    }
    Ok(out)
}

/// Prints, per output channel of the replayed stages, how many messages were compared,
/// reproduced exactly, found in only one file, the largest numeric difference, and which fields
/// differ.
pub fn compare(old: &Path, new: &Path, stages: &[&str]) -> anyhow::Result<()> {
    println!("\ncomparison with the recorded outputs (run-specific times excluded):");
    println!(
        "{:<14}{:>10}{:>10}{:>12}{:>12}{:>18}  differing fields",
        "channel", "compared", "exact", "only old", "only new", "largest diff"
    );
    for (stage, topic) in [
        ("detect", "/detections"),
        ("track", "/track"),
        ("control", "/setpoints"),
    ] {
        if !stages.contains(&stage) {
            continue;
        }
        let (a, b) = (outputs(old, topic)?, outputs(new, topic)?);
        let (mut compared, mut exact) = (0, 0);
        let mut worst = Diff::default();
        let mut field_counts: BTreeMap<String, u64> = BTreeMap::new();
        for (seq, va) in &a {
            if let Some(vb) = b.get(seq) {
                compared += 1;
                if va == vb {
                    exact += 1;
                } else {
                    let mut d = Diff::default();
                    diff("", va, vb, &mut d);
                    worst.largest = worst.largest.max(d.largest);
                    for f in d.fields {
                        *field_counts.entry(f).or_insert(0) += 1;
                    }
                }
            }
        }
        let only_old = a.keys().filter(|k| !b.contains_key(k)).count();
        let only_new = b.keys().filter(|k| !a.contains_key(k)).count();
        let mut fields: Vec<(String, u64)> = field_counts.into_iter().collect();
        fields.sort_by(|x, y| y.1.cmp(&x.1).then(x.0.cmp(&y.0)));
        let mut named: Vec<String> = fields
            .iter()
            .take(FIELDS_SHOWN)
            .map(|(f, n)| format!("{f} ({n})"))
            .collect();
        if fields.len() > FIELDS_SHOWN {
            named.push(format!("+{} more", fields.len() - FIELDS_SHOWN));
        }
        println!(
            "{topic:<14}{compared:>10}{exact:>10}{only_old:>12}{only_new:>12}{:>18.6}  {}",
            worst.largest,
            named.join(", ")
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn numbers_flags_and_missing_fields_are_named() {
        let a = json!({"stamps": {"seq": 1, "capture_ns": 5}, "sent": true, "vx_m_s": 0.5, "rates": [1.0, 2.0], "task": "approach"});
        let b = json!({"stamps": {"seq": 1, "capture_ns": 5}, "sent": false, "vx_m_s": 0.25, "rates": [1.0, 2.5], "extra": 1, "task": "approach"});
        let mut d = Diff::default();
        diff("", &a, &b, &mut d);
        assert_eq!(d.largest, 0.5);
        assert_eq!(
            d.fields.into_iter().collect::<Vec<_>>(),
            ["extra", "rates", "sent", "vx_m_s"]
        );
    }

    #[test]
    fn run_specific_stamps_are_removed_and_sent_is_kept() {
        let v = json!({"stamps": {"seq": 3, "capture_ns": 9, "recv_ns": 10, "publish_ns": 11}, "sent": true});
        assert_eq!(
            strip_run_specific("/setpoints", v),
            json!({"stamps": {"seq": 3, "capture_ns": 9}, "sent": true})
        );
    }
}
