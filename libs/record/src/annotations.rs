//! The detector's overlay as `foxglove.ImageAnnotations` (JSON encoding with a JSON schema), so
//! Foxglove and Lichtblick draw lines, tower top, hub, spinner circle and nacelle end over `/frames`.

use hubtrack_types::{DetectOverlay, OverlayKind};
use serde_json::{json, Value};

/// Schema name Foxglove recognises.
pub const SCHEMA_NAME: &str = "foxglove.ImageAnnotations";

/// `PointsAnnotation.type` LINE_LIST: pairs of points are segments (foxglove/PointsAnnotation.proto:
/// UNKNOWN 0, POINTS 1, LINE_LOOP 2, LINE_STRIP 3, LINE_LIST 4).
pub const LINE_LIST: u32 = 4;
/// Line thickness on the full-resolution image, px.
const THICKNESS_PX: f64 = 3.0;
/// Marker diameters, px.
const HUB_MARKER_PX: f64 = 24.0;
const TOWER_TOP_MARKER_PX: f64 = 16.0;

fn color(kind: OverlayKind) -> Value {
    let (r, g, b) = match kind {
        OverlayKind::Tower => (0.9, 0.1, 0.1),
        OverlayKind::Blade => (0.1, 0.9, 0.1),
        OverlayKind::Rejected => (0.9, 0.6, 0.0),
        OverlayKind::Other => (0.4, 0.4, 0.9),
    };
    json!({"r": r, "g": g, "b": b, "a": 1.0})
}

fn time(ns: u64) -> Value {
    json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
}

/// The annotations of one overlay; `timestamp_ns` must equal the image's timestamp.
pub fn to_json(overlay: &DetectOverlay, timestamp_ns: u64) -> Value {
    let ts = time(timestamp_ns);
    let mut points = Vec::new();
    for kind in [
        OverlayKind::Other,
        OverlayKind::Rejected,
        OverlayKind::Tower,
        OverlayKind::Blade,
    ] {
        let pts: Vec<Value> = overlay
            .segments()
            .iter()
            .filter(|s| s.kind == kind)
            .flat_map(|s| {
                [
                    json!({"x": s.a[0], "y": s.a[1]}),
                    json!({"x": s.b[0], "y": s.b[1]}),
                ]
            })
            .collect();
        if !pts.is_empty() {
            points.push(json!({
                "timestamp": ts, "type": LINE_LIST, "points": pts, "outline_color": color(kind),
                "outline_colors": [], "fill_color": {"r": 0, "g": 0, "b": 0, "a": 0}, "thickness": THICKNESS_PX
            }));
        }
    }
    let d = &overlay.detection;
    if d.detected && d.nacelle_found {
        // The nacelle's far end: a vertical tick beside the hub, as long as the hub marker.
        let x = d.hub_px[0] + d.nacelle_end_dx_px;
        let pts = [
            json!({"x": x, "y": d.hub_px[1] - HUB_MARKER_PX}),
            json!({"x": x, "y": d.hub_px[1] + HUB_MARKER_PX}),
        ];
        points.push(json!({
            "timestamp": ts, "type": LINE_LIST, "points": pts, "outline_color": {"r": 1.0, "g": 0.5, "b": 0.0, "a": 1.0},
            "outline_colors": [], "fill_color": {"r": 0, "g": 0, "b": 0, "a": 0}, "thickness": THICKNESS_PX
        }));
    }
    let mut circles = Vec::new();
    let circle = |x: f64, y: f64, diameter: f64, c: Value| {
        json!({"timestamp": ts, "position": {"x": x, "y": y}, "diameter": diameter, "thickness": THICKNESS_PX,
               "fill_color": {"r": 0, "g": 0, "b": 0, "a": 0}, "outline_color": c})
    };
    if overlay.search_circle[2] > 0.0 {
        let [x, y, r] = overlay.search_circle;
        circles.push(circle(
            x as f64,
            y as f64,
            2.0 * r as f64,
            json!({"r": 0.2, "g": 0.8, "b": 0.2, "a": 0.5}),
        ));
    }
    if d.tower_found {
        circles.push(circle(
            d.tower_top_px[0],
            d.tower_top_px[1],
            TOWER_TOP_MARKER_PX,
            json!({"r": 0.1, "g": 0.3, "b": 1.0, "a": 1.0}),
        ));
    }
    if d.circle_found {
        circles.push(circle(
            d.circle[0],
            d.circle[1],
            2.0 * d.circle[2],
            json!({"r": 1.0, "g": 0.0, "b": 1.0, "a": 1.0}),
        ));
    }
    let mut texts = Vec::new();
    if d.detected {
        circles.push(circle(
            d.hub_px[0],
            d.hub_px[1],
            HUB_MARKER_PX,
            json!({"r": 1.0, "g": 1.0, "b": 0.0, "a": 1.0}),
        ));
        texts.push(json!({
            "timestamp": ts, "position": {"x": d.hub_px[0] + HUB_MARKER_PX, "y": d.hub_px[1]},
            "text": format!("hub {:.2}", d.confidence), "font_size": 24.0,
            "text_color": {"r": 1.0, "g": 1.0, "b": 0.0, "a": 1.0}, "background_color": {"r": 0, "g": 0, "b": 0, "a": 0.5}
        }));
    }
    json!({"circles": circles, "points": points, "texts": texts})
}

/// Scales the image coordinates of annotations made by [`to_json`] by `factor` (positions,
/// points and circle diameters; line widths and font sizes stay as they are), for an image
/// shrunk by that factor (the live view's video).
pub fn rescale(annotations: &mut Value, factor: f64) {
    let scale_point = |p: &mut Value| {
        for axis in ["x", "y"] {
            if let Some(v) = p.get(axis).and_then(Value::as_f64) {
                p[axis] = json!(v * factor);
            }
        }
    };
    for circle in annotations["circles"].as_array_mut().into_iter().flatten() {
        scale_point(&mut circle["position"]);
        if let Some(d) = circle.get("diameter").and_then(Value::as_f64) {
            circle["diameter"] = json!(d * factor);
        }
    }
    for points in annotations["points"].as_array_mut().into_iter().flatten() {
        for p in points["points"].as_array_mut().into_iter().flatten() {
            scale_point(p);
        }
    }
    for text in annotations["texts"].as_array_mut().into_iter().flatten() {
        scale_point(&mut text["position"]);
    }
}

/// A JSON schema for the subset of `foxglove.ImageAnnotations` written here.
pub fn json_schema() -> Vec<u8> {
    let color = json!({"type": "object", "properties": {"r": {"type": "number"}, "g": {"type": "number"}, "b": {"type": "number"}, "a": {"type": "number"}}});
    let point =
        json!({"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}}});
    let time = json!({"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}});
    let schema = json!({
        "title": SCHEMA_NAME,
        "type": "object",
        "properties": {
            "circles": {"type": "array", "items": {"type": "object", "properties": {
                "timestamp": time, "position": point, "diameter": {"type": "number"}, "thickness": {"type": "number"},
                "fill_color": color, "outline_color": color}}},
            "points": {"type": "array", "items": {"type": "object", "properties": {
                "timestamp": time, "type": {"type": "integer"}, "points": {"type": "array", "items": point},
                "outline_color": color, "outline_colors": {"type": "array", "items": color}, "fill_color": color,
                "thickness": {"type": "number"}}}},
            "texts": {"type": "array", "items": {"type": "object", "properties": {
                "timestamp": time, "position": point, "text": {"type": "string"}, "font_size": {"type": "number"},
                "text_color": color, "background_color": color}}}
        }
    });
    serde_json::to_vec(&schema).expect("schema serialises")
}

#[cfg(test)]
mod tests {
    use super::*;
    use hubtrack_types::OverlaySegment;

    #[test]
    #[allow(clippy::field_reassign_with_default)] // a fixed-size message, filled field by field
    fn overlay_becomes_line_lists_and_markers() {
        let mut o = DetectOverlay::default();
        o.segment_count = 3;
        o.segments[0] = OverlaySegment {
            a: [1.0, 2.0],
            b: [3.0, 4.0],
            kind: OverlayKind::Tower,
        };
        o.segments[1] = OverlaySegment {
            a: [5.0, 6.0],
            b: [7.0, 8.0],
            kind: OverlayKind::Blade,
        };
        o.segments[2] = OverlaySegment {
            a: [0.0, 0.0],
            b: [9.0, 9.0],
            kind: OverlayKind::Blade,
        };
        o.detection.detected = true;
        o.detection.hub_px = [100.0, 50.0];
        let v = to_json(&o, 1_500_000_000);
        let points = v["points"].as_array().unwrap();
        assert_eq!(points.len(), 2, "one LINE_LIST per kind present");
        assert_eq!(
            points[1]["points"].as_array().unwrap().len(),
            4,
            "two blade segments, two points each"
        );
        assert_eq!(v["circles"][0]["position"]["x"], 100.0);
        assert_eq!(v["circles"][0]["timestamp"]["sec"], 1);
    }

    #[test]
    #[allow(clippy::field_reassign_with_default)] // a fixed-size message, filled field by field
    fn rescale_moves_every_coordinate() {
        let mut o = DetectOverlay::default();
        o.segment_count = 1;
        o.segments[0] = OverlaySegment {
            a: [30.0, 60.0],
            b: [90.0, 120.0],
            kind: OverlayKind::Tower,
        };
        o.detection.detected = true;
        o.detection.hub_px = [300.0, 150.0];
        let mut v = to_json(&o, 0);
        rescale(&mut v, 0.5);
        let p = &v["points"][0]["points"];
        assert_eq!(
            (p[0]["x"].as_f64(), p[1]["y"].as_f64()),
            (Some(15.0), Some(60.0))
        );
        assert_eq!(v["circles"][0]["position"]["x"].as_f64(), Some(150.0));
        assert_eq!(
            v["circles"][0]["diameter"].as_f64(),
            Some(HUB_MARKER_PX / 2.0)
        );
        assert_eq!(v["texts"][0]["position"]["y"].as_f64(), Some(75.0));
        assert_eq!(v["points"][0]["thickness"].as_f64(), Some(THICKNESS_PX));
    }
}
