//! Tests of the default pipeline's steps on synthetic lines.

use super::*;
use crate::geometry::{self, dir_from_up_cw};
use crate::params::Ranking;

use super::blades::{continues_beyond, support_lines, Blade};
use super::context::blind_spinner_max_r;
use super::horizon::{is_horizon, search_roll, usable_lines};
use super::lines::{merge_collinear, merge_collinear_once};
use super::proposals::axis_proposals;
use super::spinner::{kept_support, SPINNER_NEST_TOL_PX};
use super::spinner_search::{edge_points, select_points, spinner_radii, CircleQuery};
use super::tower::axis_along_a_ray;
use bands::pair_edges;

/// No hints at all.
const NO_HINTS: Hints = Hints {
    roll_rad: None,
    predicted_hub_px: None,
    hub_distance_m: None,
};

/// A `w` × `h` working image without hints.
fn frame(p: &DefaultParams, w: f64, h: f64) -> FrameCtx<'_> {
    FrameCtx {
        p,
        w,
        h,
        hints: &NO_HINTS,
        spinner_max_r: p.spinner_max_radius_frac * h,
        camera: None,
    }
}

/// No partner edge is ever found.
fn no_partner(_: &Segment, _: P2) -> Option<Segment> {
    None
}

/// The lines `segs` of a 480 × 270 working image, level, without band axes or hints.
fn scene<'a>(p: &'a DefaultParams, segs: &'a [Segment], usable: &'a [bool]) -> SceneCtx<'a> {
    SceneCtx {
        p,
        w: 480.0,
        h: 270.0,
        hints: &NO_HINTS,
        spinner_max_r: p.spinner_max_radius_frac * 270.0,
        camera: None,
        segs,
        usable,
        axes: &[],
        roll_deg: 0.0,
        partner: &no_partner,
    }
}

/// [`recognise`] on a 480 × 270 working image without a gradient image.
fn recognise_at(
    p: &DefaultParams,
    segs: &[Segment],
    hints: &Hints,
    search: &mut CircleFinder<'_>,
    expected: Expected<'_>,
) -> Result<Found, DetectError> {
    let f = FrameCtx {
        p,
        w: 480.0,
        h: 270.0,
        hints,
        spinner_max_r: p.spinner_max_radius_frac * 270.0,
        camera: None,
    };
    recognise(&f, segs, search, None, expected)
}

/// The default parameters with the rules' ranking: for tests of a rule's effect on the
/// rules' confidence (the learned ranking weighs the same cues differently).
fn rules() -> DefaultParams {
    let mut p = DefaultParams::default();
    p.ranker.ranking = Ranking::Rules;
    p
}

fn no_circles(_: CircleQuery) -> Result<Vec<[f64; 4]>, DetectError> {
    Ok(Vec::new())
}

fn ray(from: P2, angle: f64, start: f64, len: f64) -> Segment {
    let d = dir_from_up_cw(angle);
    Segment::new(
        [from[0] + d[0] * start, from[1] + d[1] * start],
        [
            from[0] + d[0] * (start + len),
            from[1] + d[1] * (start + len),
        ],
    )
}

fn rotor(hub: P2, rot: f64) -> Vec<Segment> {
    let mut v = vec![
        Segment::new([hub[0] - 3.0, 269.0], [hub[0] - 2.0, hub[1] + 8.0]),
        Segment::new([hub[0] + 3.0, 269.0], [hub[0] + 2.0, hub[1] + 8.0]),
    ];
    for a in [rot, rot + 120.0, rot + 240.0] {
        v.push(ray(hub, a - 3.0, 6.0, 70.0));
        v.push(ray(hub, a + 3.0, 6.0, 70.0));
    }
    v
}

#[test]
fn a_circle_keeps_the_blade_support_only_where_the_blades_radiate_from_it() {
    let p = DefaultParams::default();
    let blade = |angle_deg: f64, weight: f64| Blade {
        lines: Vec::new(),
        angle_deg,
        weight,
        axis: None,
    };
    let cand = |blades: Vec<Blade>| Candidate {
        support: blades.iter().map(|b| b.weight).sum(),
        blades,
        ..Candidate::default()
    };
    // The rotor's line candidate (seed-4 frame at 40 m, working px): blades at 309° and 67°.
    let rotor = cand(vec![blade(309.0, 325.0), blade(67.0, 198.0)]);
    // The spinner keeps both; the nacelle's rear beside it sees the same blades pass by,
    // half as long; a circle on the horizon gains a "blade" along it.
    let spinner = cand(vec![blade(309.0, 325.0), blade(67.0, 198.0)]);
    let nacelle = cand(vec![blade(312.0, 145.0), blade(64.0, 112.0)]);
    let horizon = cand(vec![blade(88.0, 424.0), blade(312.0, 145.0)]);
    assert!((kept_support(&p, &rotor, &spinner) - 1.0).abs() < 1e-9);
    let k = kept_support(&p, &rotor, &nacelle);
    assert!((k - 257.0 / 523.0).abs() < 1e-9, "{k}");
    assert!(kept_support(&p, &rotor, &horizon) < 0.3);
    // Longer blades from the circle count no more than the candidate's own.
    assert!(
        (kept_support(
            &p,
            &rotor,
            &cand(vec![blade(309.0, 900.0), blade(67.0, 198.0)])
        ) - 1.0)
            .abs()
            < 1e-9
    );
    // A candidate with one blade (the tracker's prediction at close range) checks nothing.
    assert_eq!(
        kept_support(&p, &cand(vec![blade(0.0, 100.0)]), &horizon),
        1.0
    );
}

#[test]
fn finds_hub_with_horizon_through_it() {
    let p = DefaultParams::default();
    let hub = [200.0, 120.0];
    let mut segs = rotor(hub, 20.0);
    // Horizon split by the tower: two long pieces ending at the tower.
    segs.push(Segment::new([0.0, 125.0], [196.0, 125.0]));
    segs.push(Segment::new([204.0, 125.0], [479.0, 125.0]));
    let f = recognise_at(
        &p,
        &segs,
        &Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        },
        &mut no_circles,
        Expected::default(),
    )
    .unwrap();
    assert!(f.detected, "{f:?}");
    assert!(geometry::dist(f.hub, hub) < 3.0, "{:?}", f.hub);
    assert_eq!(f.blade_angles.len(), 3);
}

#[test]
fn fourth_blade_pointing_down_the_tower_is_the_tower() {
    let p = DefaultParams::default();
    let hub = [200.0, 100.0];
    let mut segs = rotor(hub, 0.0);
    // Edges of the nacelle's shadow on the tower, 7.5° and 8.5° off vertical: they join the
    // tower lines' "blade" pointing down, and the second leans more than a tower line may.
    segs.push(ray(hub, 187.5, 8.0, 60.0));
    segs.push(ray(hub, 188.5, 8.0, 60.0));
    let f = recognise_at(
        &p,
        &segs,
        &Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        },
        &mut no_circles,
        Expected::default(),
    )
    .unwrap();
    assert!(f.detected, "{f:?}");
    assert!(geometry::dist(f.hub, hub) < 3.0, "{:?}", f.hub);
    let mut angles: Vec<f64> = f.blade_angles.iter().map(|a| a.round()).collect();
    angles.sort_by(f64::total_cmp);
    assert_eq!(
        angles.len(),
        3,
        "three blades, the tower is no blade: {angles:?}"
    );
    assert!(
        angles.iter().all(|a| geometry::ang_dist(*a, 180.0) > 30.0),
        "{angles:?}"
    );
}

#[test]
fn a_band_along_a_blade_ray_is_that_blade_not_the_tower() {
    // `fly` seed 279 at 19 m (working px): hub (244, 126.5), a blade at 167.6°; the band
    // the partner search found runs from (254.8, 148) to (269.3, 269), along the blade.
    let hub = [244.0, 126.5];
    let band = Segment::new([254.8, 148.0], [269.3, 269.0]);
    let tol = 0.025 * 270.0;
    assert!(axis_along_a_ray(&band, hub, &[167.6], tol));
    // The tower itself, upright 3.5 px left of the hub, is no blade ...
    let tower = Segment::new([240.5, 139.0], [240.5, 269.0]);
    assert!(!axis_along_a_ray(&tower, hub, &[167.6], tol));
    // ... nor is the band without a ray, or with rays pointing elsewhere.
    assert!(!axis_along_a_ray(&band, hub, &[], tol));
    assert!(!axis_along_a_ray(&band, hub, &[192.4, 48.0], tol));
    // A ray pointing up never reaches a band below the hub.
    assert!(!axis_along_a_ray(&band, hub, &[347.6], tol));
}

#[test]
// 0.4343 is the GoPro's focal length per width, not log10(e).
#[allow(clippy::approx_constant)]
fn a_spinner_implies_the_tower_width_from_its_own_distance() {
    // GoPro at 960 px wide (f = 417 px), the renderer's turbine.
    let o = Optics {
        focal_px: 0.4343 * 960.0,
        spinner_radius_m: 1.6,
        tower_top_diameter_m: 2.2,
        hub_tower_gap_m: 4.2,
        nacelle_width_m: 3.4,
        nacelle_rear_m: 11.2,
        bending_lens: None,
    };
    let r_at = |d: f64| o.focal_px * 1.6 / d;
    // 38 m: the tower top, 42.2 m away, is 1.24 spinner radii wide; 5 m: 0.75.
    let far = o.tower_width_for_spinner(r_at(38.0)).unwrap() / r_at(38.0);
    let close = o.tower_width_for_spinner(r_at(5.0)).unwrap() / r_at(5.0);
    assert!((far - 2.2 / 1.6 * 38.0 / 42.2).abs() < 1e-9, "{far}");
    assert!((close - 2.2 / 1.6 * 5.0 / 9.2).abs() < 1e-9, "{close}");
    // Seed 335 of `hubtrack fly` at 38 m: a band 0.6 r wide (the shading ramp) is outside
    // the default tolerance, the true 1.25 r inside.
    let tol = DefaultParams::default().tower_width_spinner_tol;
    assert!(
        0.6 < far / tol && far / tol < 1.25 && 1.25 < far * tol,
        "{far} {tol}"
    );
    assert!(o.tower_width_for_spinner(0.0).is_none());
}

#[test]
fn roll_search_finds_tilted_tower() {
    let p = DefaultParams::default();
    let d = dir_from_up_cw(-6.0);
    let segs = vec![
        Segment::new([100.0, 260.0], [100.0 + 150.0 * d[0], 260.0 + 150.0 * d[1]]),
        Segment::new([110.0, 260.0], [110.0 + 150.0 * d[0], 260.0 + 150.0 * d[1]]),
        Segment::new([0.0, 50.0], [40.0, 10.0]),
    ];
    assert!((search_roll(&p, &segs) - 6.0).abs() <= 1.0);
}

#[test]
fn collinear_pieces_merge() {
    let p = DefaultParams::default();
    let segs = [
        Segment::new([100.0, 200.0], [100.0, 150.0]),
        Segment::new([100.5, 145.0], [101.0, 90.0]),
        Segment::new([0.0, 0.0], [50.0, 0.0]),
    ];
    let m = merge_collinear(&p, &segs, 270.0);
    assert_eq!(m.len(), 2);
    assert!(m[0].length() > 105.0, "{m:?}");
}

#[test]
fn pieces_bridged_by_a_shorter_one_merge_into_one_line() {
    let p = DefaultParams::default();
    // Longest first: B is placed, A is too far from it, then C bridges A and B but only
    // extends B. A second pass joins A to the grown B.
    let a = Segment::new([0.0, 100.0], [60.0, 100.0]);
    let b = Segment::new([100.0, 100.0], [170.0, 100.0]);
    let c = Segment::new([55.0, 100.0], [105.0, 100.0]);
    assert_eq!(merge_collinear_once(&p, &[a, b, c], 270.0).len(), 2);
    let m = merge_collinear(&p, &[a, b, c], 270.0);
    assert_eq!(m.len(), 1, "{m:?}");
    assert!((m[0].length() - 170.0).abs() < 1e-6, "{m:?}");
}

#[test]
fn two_blades_up_with_the_third_hidden_by_the_tower_count_as_a_rotor() {
    let mut p = DefaultParams::default();
    let hub = [200.0, 100.0];
    // Blades at 60° and 300°: the third would point straight down, over the tower.
    let mut segs = rotor(hub, 60.0);
    segs.retain(|s| {
        geometry::ang_dist(s.angle_away_from(hub), 180.0) > 10.0
            || s.tilt_from_vertical_deg().abs() < 1.0
    });
    assert_eq!(segs.len(), 6, "tower edges and two blades");
    let hints = Hints {
        roll_rad: Some(0.0),
        ..Hints::default()
    };
    let f = recognise_at(&p, &segs, &hints, &mut no_circles, Expected::default()).unwrap();
    assert!(f.detected && geometry::dist(f.hub, hub) < 3.0, "{f:?}");
    let with_rule = f.confidence;
    p.hidden_blade_tol_deg = 0.0;
    let f = recognise_at(&p, &segs, &hints, &mut no_circles, Expected::default()).unwrap();
    assert!(f.confidence < with_rule, "{} vs {with_rule}", f.confidence);
}

#[test]
fn the_learned_ranking_takes_the_rotor_over_longer_single_lines_meeting_elsewhere() {
    let hub = [150.0, 100.0];
    let mut segs = rotor(hub, 10.0);
    // Three field borders, each longer than a blade, ending at one point 120° apart.
    let clutter = [360.0, 160.0];
    for a in [30.0, 150.0, 270.0] {
        segs.push(ray(clutter, a, 6.0, 100.0));
    }
    let hints = Hints {
        roll_rad: Some(0.0),
        ..Hints::default()
    };
    let p = DefaultParams::default();
    assert_eq!(p.ranker.ranking, Ranking::Learned);
    let f = recognise_at(&p, &segs, &hints, &mut no_circles, Expected::default()).unwrap();
    assert!(f.detected && geometry::dist(f.hub, hub) < 3.0, "{f:?}");
    assert!(
        f.candidates
            .iter()
            .any(|c| geometry::dist(c.hub, clutter) < 5.0),
        "the crossing was a candidate: {:?}",
        f.candidates
    );
    // Reported as a probability, above the one the threshold stands for.
    assert!(
        f.confidence > crate::ranker::logistic(p.ranker.min_score) && f.confidence < 1.0,
        "{}",
        f.confidence
    );
}

#[test]
fn two_blades_nearly_opposite_are_one_line_through_the_candidate() {
    let c = [200.0, 120.0];
    // A mast: its top above the candidate, two tower-like edges below, and a field border
    // crossing behind it in two pieces 175° apart (not collinear enough to be caught as a
    // line continuing behind the candidate).
    let mut segs = vec![
        Segment::new([197.0, 269.0], [198.0, 128.0]),
        Segment::new([203.0, 269.0], [202.0, 128.0]),
        ray(c, 0.0, 6.0, 80.0),
    ];
    segs.push(ray(c, 70.0, 6.0, 150.0));
    segs.push(ray(c, 245.0, 6.0, 150.0));
    let hints = Hints {
        roll_rad: Some(0.0),
        ..Hints::default()
    };
    let off = DefaultParams {
        blade_max_separation_deg: 180.0,
        ..rules()
    };
    let f = recognise_at(&off, &segs, &hints, &mut no_circles, Expected::default()).unwrap();
    assert!(
        f.detected,
        "without the rule the three lines pass for a rotor: {f:?}"
    );
    // The learned ranking refuses them without the rule: single edges far from 120° apart.
    let learned = DefaultParams {
        blade_max_separation_deg: 180.0,
        ..DefaultParams::default()
    };
    let f = recognise_at(
        &learned,
        &segs,
        &hints,
        &mut no_circles,
        Expected::default(),
    )
    .unwrap();
    assert!(!f.detected, "{f:?}");
    let on = DefaultParams {
        blade_max_separation_deg: 170.0,
        ..off.clone()
    };
    let f = recognise_at(&on, &segs, &hints, &mut no_circles, Expected::default()).unwrap();
    assert!(!f.detected, "{f:?}");
    // A rotor seen at 60° yaw (blades 0°, 120°, 240° on the rotor plane, horizontal
    // components halved): 139° apart at most, all kept.
    let seen = |a: f64| {
        let d = dir_from_up_cw(a);
        (d[0] * 0.5).atan2(-d[1]).to_degrees().rem_euclid(360.0)
    };
    let mut segs = rotor(c, 0.0);
    segs.truncate(2);
    for a in [0.0, 120.0, 240.0] {
        segs.push(ray(c, seen(a) - 3.0, 6.0, 70.0));
        segs.push(ray(c, seen(a) + 3.0, 6.0, 70.0));
    }
    let f = recognise_at(&on, &segs, &hints, &mut no_circles, Expected::default()).unwrap();
    assert!(
        f.detected && geometry::dist(f.hub, c) < 3.0 && f.blade_angles.len() == 3,
        "{f:?}"
    );
}

#[test]
fn parallel_lines_alone_are_no_turbine() {
    let p = DefaultParams::default();
    // Power-line like: several long near-parallel sagging wires.
    let segs: Vec<Segment> = (0..5)
        .map(|k| {
            Segment::new(
                [0.0, 50.0 + 10.0 * k as f64],
                [479.0, 60.0 + 12.0 * k as f64],
            )
        })
        .collect();
    let f = recognise_at(
        &p,
        &segs,
        &Hints::default(),
        &mut no_circles,
        Expected::default(),
    )
    .unwrap();
    assert!(!f.detected);
}

/// A wide blade as its two edges: root half-width `w0` at `start` from the hub, tip
/// half-width `w1` at `start + len`.
fn blade_edges(hub: P2, angle: f64, start: f64, len: f64, w0: f64, w1: f64) -> [Segment; 2] {
    let d = dir_from_up_cw(angle);
    let n = [-d[1], d[0]];
    let at = |t: f64, off: f64| {
        [
            hub[0] + d[0] * t + n[0] * off,
            hub[1] + d[1] * t + n[1] * off,
        ]
    };
    [
        Segment::new(at(start, w0), at(start + len, w1)),
        Segment::new(at(start, -w0), at(start + len, -w1)),
    ]
}

#[test]
fn a_level_blade_is_no_horizon_but_a_road_is() {
    let p = DefaultParams::default();
    let (w, h) = (480.0, 270.0);
    // Both edges of a blade lying level, 220 px long, narrowing from 20 to 6 px across.
    let blade = blade_edges([400.0, 120.0], 270.0, 10.0, 220.0, 10.0, 3.0);
    // A road of even width and the horizon itself.
    let road = [
        Segment::new([10.0, 200.0], [300.0, 205.0]),
        Segment::new([10.0, 214.0], [300.0, 219.0]),
    ];
    let horizon = Segment::new([0.0, 160.0], [479.0, 162.0]);
    let segs = vec![blade[0], blade[1], road[0], road[1], horizon];
    assert!(
        segs.iter().all(|s| is_horizon(&p, s, w, 0.0)),
        "all are horizon candidates"
    );
    assert_eq!(
        usable_lines(&frame(&p, w, h), &segs, 0.0),
        vec![true, true, false, false, false]
    );
    let off = DefaultParams {
        horizon_band_min_taper: 0.0,
        ..p
    };
    assert_eq!(usable_lines(&frame(&off, w, h), &segs, 0.0), vec![false; 5]);
}

#[test]
fn blade_edges_pair_into_axes_through_the_hub() {
    let p = DefaultParams::default();
    let hub = [240.0, 130.0];
    let mut segs: Vec<Segment> = Vec::new();
    for a in [15.0, 135.0, 255.0] {
        segs.extend(blade_edges(hub, a, 30.0, 100.0, 8.0, 3.0));
    }
    // A lone field border and a power line pair (too far apart to be a blade).
    segs.push(Segment::new([10.0, 250.0], [200.0, 230.0]));
    segs.push(Segment::new([300.0, 20.0], [470.0, 20.0]));
    segs.push(Segment::new([300.0, 90.0], [470.0, 90.0]));
    let usable = vec![true; segs.len()];
    let axes = pair_edges(&frame(&p, 480.0, 270.0), &segs, &usable);
    assert_eq!(axes.len(), 3, "{axes:?}");
    for a in &axes {
        assert_eq!(
            a.edges[0] / 2,
            a.edges[1] / 2,
            "edges of different blades paired: {a:?}"
        );
        assert!(a.axis.line_distance(hub) < 1e-6, "{a:?}");
        assert!(
            (a.width[0] - 16.0).abs() < 0.5 || (a.width[1] - 16.0).abs() < 0.5,
            "{a:?}"
        );
    }
    let props = axis_proposals(&frame(&p, 480.0, 270.0), &axes);
    assert!(
        !props.is_empty() && props.iter().all(|(x, _)| geometry::dist(*x, hub) < 1e-6),
        "{props:?}"
    );
}

#[test]
fn close_range_hub_from_blade_axes_not_edge_crossings() {
    let p = DefaultParams::default();
    let hub = [240.0, 120.0];
    // Close range: blades start 55 px from the hub (beyond support_end_dist_frac * h = 40
    // px), root chord 36 px; their edges cross each other well off the hub.
    let mut segs: Vec<Segment> = Vec::new();
    for a in [40.0, 160.0, 280.0] {
        segs.extend(blade_edges(hub, a, 55.0, 120.0, 18.0, 9.0));
    }
    let f = recognise_at(
        &p,
        &segs,
        &Hints {
            roll_rad: Some(0.0),
            ..Hints::default()
        },
        &mut no_circles,
        Expected::default(),
    )
    .unwrap();
    assert!(f.detected, "{f:?}");
    assert!(geometry::dist(f.hub, hub) < 2.0, "{:?}", f.hub);
}

#[test]
fn tracker_distance_narrows_the_spinner_radii() {
    let p = DefaultParams::default();
    let f = frame(&p, 480.0, 270.0);
    let all = spinner_radii(&f, None);
    assert_eq!(
        all,
        (p.spinner_min_radius_px, p.spinner_max_radius_frac * 270.0)
    );
    // Expected 20 px: 10..40 px, inside the configured limits.
    assert_eq!(spinner_radii(&f, Some(20.0)), (10.0, 40.0));
    // Close in (expected 0.4 h): beyond the blind limit, up to `spinner_hint_max_radius_frac`.
    assert_eq!(
        spinner_radii(&f, Some(108.0)),
        (54.0, p.spinner_hint_max_radius_frac * 270.0)
    );
    // Far away (expected 3 px): clipped to the limits, and empty: nothing to search.
    let (lo, hi) = spinner_radii(&f, Some(1.5));
    assert!(lo >= hi, "{lo} {hi}");
    // Nonsense distances and a disabled window fall back to all radii.
    assert_eq!(spinner_radii(&f, Some(f64::NAN)), all);
    let no_window = DefaultParams {
        spinner_hint_radius_lo: 0.0,
        ..p.clone()
    };
    assert_eq!(
        spinner_radii(&frame(&no_window, 480.0, 270.0), Some(20.0)),
        all
    );
}

#[test]
fn the_lens_sets_how_large_a_spinner_is_searched_blind() {
    let p = DefaultParams::default();
    let optics = |focal_px| Optics {
        focal_px,
        spinner_radius_m: 1.6,
        tower_top_diameter_m: 2.2,
        hub_tower_gap_m: 4.2,
        nacelle_width_m: 3.4,
        nacelle_rear_m: 11.2,
        bending_lens: None,
    };
    // The GoPro at 480 × 270 working px (f = 0.4343 · 480 = 208.5 px): 83 px at 4 m, under the
    // fixed 0.32 · 270 = 86.4 px, which stays.
    let gopro = blind_spinner_max_r(&p, 270.0, Some(&optics(208.5)), &NO_HINTS);
    assert_eq!(gopro, p.spinner_max_radius_frac * 270.0);
    // A 60° lens at 16:9 (f = 0.866 · 480 = 415.7 px): 166 px at 4 m, 0.62 of the height.
    let narrow = blind_spinner_max_r(&p, 270.0, Some(&optics(415.7)), &NO_HINTS);
    assert!((narrow - 415.7 * 1.6 / 4.0).abs() < 1e-9, "{narrow}");
    // Capped where a tracker's distance would be capped; no lens, the fixed limit.
    let tele = blind_spinner_max_r(&p, 270.0, Some(&optics(2000.0)), &NO_HINTS);
    assert_eq!(tele, p.spinner_hint_max_radius_frac * 270.0);
    assert_eq!(
        blind_spinner_max_r(&p, 270.0, None, &NO_HINTS),
        p.spinner_max_radius_frac * 270.0
    );
    // A track without a distance is far away: the fixed limit.
    let tracked = Hints {
        predicted_hub_px: Some([240.0, 135.0]),
        ..NO_HINTS
    };
    assert_eq!(
        blind_spinner_max_r(&p, 270.0, Some(&optics(415.7)), &tracked),
        p.spinner_max_radius_frac * 270.0
    );
}

/// The edge and gradient maps of an image, owned (an [`EdgeImage`] borrows them).
struct EdgeMaps {
    edges: Vec<u8>,
    dx: Vec<i16>,
    dy: Vec<i16>,
    width: usize,
    height: usize,
}

impl EdgeMaps {
    fn image(&self) -> EdgeImage<'_> {
        EdgeImage {
            edges: &self.edges,
            dx: &self.dx,
            dy: &self.dy,
            width: self.width,
            height: self.height,
        }
    }
}

/// The edge maps of a `[w, h]` image holding the arc of the circle `(c, r)` from `from_deg`
/// over `span_deg` (points every `step_deg`, radial gradients), where it lies inside the image.
fn rim_edge_maps(
    [w, h]: [usize; 2],
    c: [f64; 2],
    r: f64,
    (from_deg, span_deg): (f64, f64),
    step_deg: f64,
) -> EdgeMaps {
    let (mut edges, mut dx, mut dy) = (vec![0u8; w * h], vec![0i16; w * h], vec![0i16; w * h]);
    let mut a = from_deg;
    while a < from_deg + span_deg {
        let (s, co) = a.to_radians().sin_cos();
        let (x, y) = (c[0] + r * co, c[1] + r * s);
        if (0.0..w as f64 - 0.5).contains(&x) && (0.0..h as f64 - 0.5).contains(&y) {
            let i = y.round() as usize * w + x.round() as usize;
            edges[i] = 255;
            dx[i] = (200.0 * co).round() as i16;
            dy[i] = (200.0 * s).round() as i16;
        }
        a += step_deg;
    }
    EdgeMaps {
        edges,
        dx,
        dy,
        width: w,
        height: h,
    }
}

#[test]
fn a_spinner_rim_partly_seen_is_enough_at_the_expected_size() {
    // 30 % of a spinner's rim in the edges (the rest grey on grey blades): below
    // `spinner_min_coverage`, above `spinner_hint_min_coverage`.
    let p = DefaultParams::default();
    let (w, h, c, r) = (480usize, 270usize, [240.0, 135.0], 40.0);
    let maps = rim_edge_maps([w, h], c, r, (200.0, 0.3 * 360.0), 0.25);
    let img = maps.image();
    assert!(p.spinner_hint_min_coverage < 0.3 && 0.3 < p.spinner_min_coverage);
    let blind = search_circles(
        &frame(&p, w as f64, h as f64),
        &img,
        c,
        None,
        &mut Vec::new(),
        None,
    );
    assert!(blind.is_empty(), "{blind:?}");
    let hinted = search_circles(
        &frame(&p, w as f64, h as f64),
        &img,
        c,
        Some(r),
        &mut Vec::new(),
        None,
    );
    let k = hinted.first().expect("found with the expected radius");
    assert!(
        geometry::dist([k[0], k[1]], c) < 2.0 && (k[2] - r).abs() < 2.0,
        "{k:?}"
    );
    // The box's points selected from the whole image's are the box's own, in the same
    // order, and find the same circles.
    let mut all = Vec::new();
    edge_points(&img, [0, 0, w as i32, h as i32], &mut all);
    let (mut boxed, mut selected) = (Vec::new(), Vec::new());
    edge_points(&img, [200, 100, 260, 180], &mut boxed);
    select_points(&all, [200, 100, 260, 180], &mut selected);
    assert!(!boxed.is_empty() && boxed.len() < all.len());
    assert_eq!(boxed, selected);
    assert_eq!(
        search_circles(
            &frame(&p, w as f64, h as f64),
            &img,
            c,
            Some(r),
            &mut Vec::new(),
            Some(&all)
        ),
        hinted
    );
}

#[test]
fn a_spinner_larger_than_the_blind_limit_is_found_at_the_expected_size() {
    // Close in through a narrow lens: a spinner of radius 0.45 h, the top and bottom of its rim
    // outside the frame. Beyond `spinner_max_radius_frac` blind; found with the tracker's
    // expected radius (up to `spinner_hint_max_radius_frac`).
    let p = DefaultParams::default();
    let (w, h) = (480usize, 270usize);
    let (c, r) = ([240.0, 135.0], 0.45 * h as f64);
    assert!(r > p.spinner_max_radius_frac * h as f64);
    assert!(r < p.spinner_hint_max_radius_frac * h as f64);
    let maps = rim_edge_maps([w, h], c, r, (0.0, 360.0), 0.1);
    let img = maps.image();
    let f = frame(&p, w as f64, h as f64);
    let blind = search_circles(&f, &img, c, None, &mut Vec::new(), None);
    assert!(blind.iter().all(|k| (k[2] - r).abs() > 5.0), "{blind:?}");
    let hinted = search_circles(&f, &img, c, Some(r * 0.9), &mut Vec::new(), None);
    let k = hinted.first().expect("found with the expected radius");
    assert!(
        geometry::dist([k[0], k[1]], c) < 2.0 && (k[2] - r).abs() < 2.0,
        "{k:?}"
    );
}

#[test]
fn spinner_circle_accepted_only_near_the_candidate_with_blades_at_its_rim() {
    let p = rules();
    let hub = [240.0, 120.0];
    // Single-edge blades that stop at a spinner rim of radius 30 (one edge each, so the
    // edge lines pass 6 px off the centre).
    let mut segs: Vec<Segment> = Vec::new();
    for a in [20.0, 140.0, 260.0] {
        segs.push(blade_edges(hub, a, 30.0, 100.0, 6.0, 2.0)[0]);
    }
    let hints = Hints {
        roll_rad: Some(0.0),
        ..Hints::default()
    };
    let mut at_hub = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
        Ok(vec![[hub[0] + 0.5, hub[1] - 0.5, 30.0, 1.0]])
    };
    let f = recognise_at(&p, &segs, &hints, &mut at_hub, Expected::default()).unwrap();
    assert!(f.detected && f.circle.is_some(), "{f:?}");
    assert!(
        geometry::dist(f.hub, [hub[0] + 0.5, hub[1] - 0.5]) < 1e-9,
        "{:?}",
        f.hub
    );
    // A circle far from every candidate is ignored.
    let mut far_away = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
        Ok(vec![[400.0, 240.0, 30.0, 1.0]])
    };
    let g = recognise_at(&p, &segs, &hints, &mut far_away, Expected::default()).unwrap();
    assert!(g.circle.is_none(), "{g:?}");
    // The circle at the size the tracker's distance expects counts for more; at another
    // size it counts as before.
    let conf = |r_expected: f64| {
        let mut at_hub = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
            Ok(vec![[hub[0] + 0.5, hub[1] - 0.5, 30.0, 1.0]])
        };
        let expected = Expected {
            spinner_radius: Some(r_expected),
            ..Expected::default()
        };
        let f = recognise_at(&p, &segs, &hints, &mut at_hub, expected).unwrap();
        assert!(f.circle.is_some(), "{f:?}");
        f.confidence
    };
    let (base, matched, other) = (f.confidence, conf(32.0), conf(60.0));
    assert!(
        base + p.spinner_size_match_bonus <= 1.0 + 1e-9,
        "room for the bonus: {base}"
    );
    assert!(
        (matched - base - p.spinner_size_match_bonus).abs() < 1e-9,
        "{matched} vs {base}"
    );
    assert!((other - base).abs() < 1e-9, "{other} vs {base}");
}

#[test]
fn an_enclosing_circle_replaces_the_best_covered_one_only_with_a_rim_as_well_covered() {
    let p = DefaultParams::default();
    let hub = [240.0, 120.0];
    let mut segs: Vec<Segment> = Vec::new();
    for a in [20.0, 140.0, 260.0] {
        segs.push(blade_edges(hub, a, 30.0, 100.0, 6.0, 2.0)[0]);
    }
    let hints = Hints {
        roll_rad: Some(0.0),
        ..Hints::default()
    };
    // The spinner (best covered) and a larger circle round it, 6 px off centre, as blade
    // edges crossing near the spinner draw one.
    let inner = [hub[0], hub[1], 30.0];
    let outer = [hub[0] + 4.0, hub[1] + 4.5, 36.5];
    assert!(
        geometry::dist([outer[0], outer[1]], [inner[0], inner[1]]) + inner[2]
            <= outer[2] + SPINNER_NEST_TOL_PX,
        "nested"
    );
    let circle = |outer_cov: f64| {
        let mut circles = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
            Ok(vec![
                [inner[0], inner[1], inner[2], 0.6],
                [outer[0], outer[1], outer[2], outer_cov],
            ])
        };
        recognise_at(&p, &segs, &hints, &mut circles, Expected::default())
            .unwrap()
            .circle
    };
    let ratio = p.spinner_nest_min_coverage_ratio;
    assert!(ratio > 0.0 && ratio < 1.0);
    assert_eq!(
        circle(0.6 * ratio - 0.05),
        Some(inner),
        "a weakly covered outer circle is no silhouette"
    );
    assert_eq!(
        circle(0.6 * ratio + 0.05),
        Some(outer),
        "the silhouette round a ring on the spinner's face"
    );
}

#[test]
fn the_best_covered_spinner_circle_with_blades_wins_whatever_the_tracker_expects() {
    let p = DefaultParams::default();
    let hub = [240.0, 120.0];
    let mut segs: Vec<Segment> = Vec::new();
    for a in [20.0, 140.0, 260.0] {
        segs.extend(blade_edges(hub, a, 30.0, 100.0, 6.0, 2.0));
    }
    // The spinner and a circle beside it (the nacelle's corner between two blade roots),
    // both with blades at their rim.
    let spinner = [hub[0], hub[1], 28.0];
    let beside = [hub[0] + 10.0, hub[1] + 4.0, 20.0];
    let circle = |beside_cov: f64, predicted: Option<P2>, expected_r: Option<f64>| {
        let hints = Hints {
            roll_rad: Some(0.0),
            predicted_hub_px: predicted,
            ..Hints::default()
        };
        let mut circles = |_: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
            let mut v = vec![
                [spinner[0], spinner[1], spinner[2], 0.30],
                [beside[0], beside[1], beside[2], beside_cov],
            ];
            v.sort_by(|a, b| b[3].total_cmp(&a[3]));
            Ok(v)
        };
        let expected = Expected {
            spinner_radius: expected_r,
            ..Expected::default()
        };
        recognise_at(&p, &segs, &hints, &mut circles, expected)
            .unwrap()
            .circle
    };
    let (at_spinner, at_beside) = ([hub[0] + 2.0, hub[1] - 3.0], [beside[0] - 1.0, beside[1]]);
    assert_eq!(circle(0.33, None, None), Some(beside));
    assert_eq!(
        circle(0.33, Some(at_spinner), Some(27.0)),
        Some(beside),
        "neither the prediction nor the expected size outweighs a better rim"
    );
    assert_eq!(circle(0.27, Some(at_beside), Some(21.0)), Some(spinner));
}

#[test]
fn close_spinner_is_searched_anywhere_when_nothing_else_is_found() {
    let p = DefaultParams::default();
    let (hub, r) = ([300.0, 150.0], 40.0);
    // Two blades seen by one edge each, starting at the rim of a close spinner: no
    // candidate from them alone.
    let segs: Vec<Segment> = [30.0, 150.0]
        .iter()
        .map(|&a| blade_edges(hub, a, r, 200.0, 12.0, 6.0)[0])
        .collect();
    let hints = Hints {
        roll_rad: Some(0.0),
        ..Hints::default()
    };
    let f = recognise_at(&p, &segs, &hints, &mut no_circles, Expected::default()).unwrap();
    assert!(!f.detected, "{f:?}");
    let mut close = |q: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
        Ok(if q == CircleQuery::Close {
            vec![[hub[0], hub[1], r, 1.0]]
        } else {
            vec![]
        })
    };
    let g = recognise_at(&p, &segs, &hints, &mut close, Expected::default()).unwrap();
    assert!(
        g.detected && g.circle.is_some() && geometry::dist(g.hub, hub) < 1e-9,
        "{g:?}"
    );
}

#[test]
fn close_spinners_are_candidates_in_every_frame_without_a_tracker_when_always() {
    let (spinner_hub, r) = ([360.0, 150.0], 40.0);
    // A rotor detected from its lines, and a close spinner with two one-edge blades elsewhere.
    let mut segs = rotor([120.0, 100.0], 10.0);
    segs.extend(
        [30.0, 150.0]
            .iter()
            .map(|&a| blade_edges(spinner_hub, a, r, 100.0, 12.0, 6.0)[0]),
    );
    let hints = Hints {
        roll_rad: Some(0.0),
        ..Hints::default()
    };
    let run = |p: &DefaultParams, hints: &Hints| {
        let asked = std::cell::Cell::new(0);
        let mut close = |q: CircleQuery| -> Result<Vec<[f64; 4]>, DetectError> {
            if q == CircleQuery::Close {
                asked.set(asked.get() + 1);
                return Ok(vec![[spinner_hub[0], spinner_hub[1], r, 1.0]]);
            }
            Ok(vec![])
        };
        let f = recognise_at(p, &segs, hints, &mut close, Expected::default()).unwrap();
        (f, asked.get())
    };
    let always = DefaultParams::default();
    assert!(always.close_spinner_always);
    let (f, asked) = run(&always, &hints);
    assert!(f.detected && asked == 1, "{asked} {f:?}");
    assert!(
        f.candidates
            .iter()
            .any(|c| geometry::dist(c.hub, spinner_hub) < 1e-9),
        "{:?}",
        f.candidates
    );
    // Only as a fallback: something was detected, so no whole-image search.
    let fallback = DefaultParams {
        close_spinner_always: false,
        ..always.clone()
    };
    let (f, asked) = run(&fallback, &hints);
    assert!(f.detected && asked == 0, "{asked} {f:?}");
    // With a tracker's prediction never (its neighbourhood is searched instead).
    let tracked = Hints {
        predicted_hub_px: Some([120.0, 100.0]),
        ..hints
    };
    assert_eq!(run(&always, &tracked).1, 0);
}

#[test]
fn line_continuing_behind_the_candidate_is_no_blade() {
    let p = DefaultParams::default();
    let c = [200.0, 120.0];
    // A field border interrupted by the turbine: two collinear pieces either side of c.
    let segs = vec![
        Segment::new([60.0, 100.0], [190.0, 118.6]),
        Segment::new([212.0, 121.7], [400.0, 148.6]),
    ];
    let usable = vec![true; segs.len()];
    assert!(continues_beyond(&scene(&p, &segs, &usable), 0, c));
    assert!(support_lines(&scene(&p, &segs, &usable), c, 0.0).is_empty());
}

#[test]
fn horizon_bent_by_the_lens_still_continues_behind_the_candidate() {
    let p = DefaultParams::default();
    let c = [200.0, 120.0];
    // A horizon seen through a wide lens, interrupted by the tower: the right piece bends
    // 2° away from the left piece's extension (7 px off it at its far end).
    let right_dir = (8.0_f64 - 2.0).to_radians();
    let segs = vec![
        Segment::new(
            [60.0, 120.0 - 140.0 * 8f64.to_radians().tan()],
            [190.0, 120.0 - 10.0 * 8f64.to_radians().tan()],
        ),
        Segment::new(
            [212.0, 120.0 + 12.0 * 8f64.to_radians().tan()],
            [
                212.0 + 190.0 * right_dir.cos(),
                120.0 + 12.0 * 8f64.to_radians().tan() + 190.0 * right_dir.sin(),
            ],
        ),
    ];
    let usable = vec![true; segs.len()];
    assert!(continues_beyond(&scene(&p, &segs, &usable), 0, c));
    // Straight lines only (no bend allowed): the far end is too far off.
    let straight = DefaultParams {
        occluded_bend_deg: 0.0,
        ..p.clone()
    };
    assert!(!continues_beyond(&scene(&straight, &segs, &usable), 0, c));
    // A blade pointing up, nearly in line with a tower edge below: no bend allowance.
    let up = vec![
        Segment::new([200.0, 20.0], [201.0, 110.0]),
        Segment::new([203.0, 135.0], [210.0, 265.0]),
    ];
    assert!(!continues_beyond(&scene(&p, &up, &[true, true]), 0, c));
}

/// Through a fisheye the level horizon is an arc, cut by the Hough transform into pieces each
/// too short (and, beside the centre, too tilted) to be a horizon; judged undistorted, the
/// pieces lie on one level line and together are one. A pinhole judges each piece on its own,
/// as before; a piece of a line that is not level stays usable through either.
#[test]
fn a_horizon_bent_into_pieces_by_a_fisheye_is_still_a_horizon() {
    use hubtrack_types::setup::{CameraModel, Distortion};
    let p = DefaultParams::default();
    // The cross-domain fisheye at a 480 × 270 working size.
    let fisheye = CameraModel::centred(
        480,
        270,
        175.0,
        Distortion::Equidistant {
            k1: -0.03,
            k2: 0.008,
            k3: -0.002,
            k4: 0.0003,
        },
    );
    // A level horizon 0.35 (normalised) above the centre, seen in four pieces of the arc, and
    // a line rising at 30° through the same region (a blade).
    let at = |x: f64, y: f64| fisheye.project([x, y, 1.0]).unwrap();
    let mut segs: Vec<Segment> = [(-1.6, -0.8), (-0.7, -0.05), (0.05, 0.7), (0.8, 1.6)]
        .iter()
        .map(|&(x0, x1)| Segment::new(at(x0, -0.35), at(x1, -0.35)))
        .collect();
    segs.push(Segment::new(at(0.2, -0.1), at(0.6, -0.33)));
    for s in &segs {
        assert!(
            !is_horizon(&p, s, 480.0, 0.0),
            "no piece is a horizon on its own: {s:?}"
        );
    }
    let f = FrameCtx {
        camera: Some(fisheye),
        ..frame(&p, 480.0, 270.0)
    };
    assert_eq!(
        usable_lines(&f, &segs, 0.0),
        vec![false, false, false, false, true]
    );
    // Without the calibration (or with the rule off) every piece stays usable.
    assert!(usable_lines(&frame(&p, 480.0, 270.0), &segs, 0.0)
        .iter()
        .all(|u| *u));
    let off = DefaultParams {
        horizon_piece_tol_frac: 0.0,
        ..p.clone()
    };
    let f = FrameCtx {
        camera: Some(fisheye),
        ..frame(&off, 480.0, 270.0)
    };
    assert!(usable_lines(&f, &segs, 0.0).iter().all(|u| *u));
}

#[test]
fn blades_all_square_to_the_world_are_built_edges_not_a_rotor() {
    let c = [200.0, 120.0];
    // A mast standing on a tower-like mast with a stay or a roof's edge going level from its
    // foot, each seen as a band; the camera rolled 8°.
    let roll_deg: f64 = 8.0;
    let scene = |blades: &[f64]| {
        let mut segs = vec![
            ray(c, 180.0 - roll_deg - 1.0, 8.0, 140.0),
            ray(c, 180.0 - roll_deg + 1.0, 8.0, 140.0),
        ];
        for a in blades {
            segs.push(ray(c, a - roll_deg - 3.0, 6.0, 70.0));
            segs.push(ray(c, a - roll_deg + 3.0, 6.0, 70.0));
        }
        segs
    };
    let hints = Hints {
        roll_rad: Some(roll_deg.to_radians()),
        ..Hints::default()
    };
    let off = DefaultParams {
        square_blades_max_deg: 0.0,
        ..DefaultParams::default()
    };
    let on = DefaultParams::default();
    let square = scene(&[0.0, 90.0]);
    let f = recognise_at(&off, &square, &hints, &mut no_circles, Expected::default()).unwrap();
    assert!(
        f.detected && geometry::dist(f.hub, c) < 3.0,
        "without the rule the mast and the level edge pass for a rotor: {f:?}"
    );
    let f = recognise_at(&on, &square, &hints, &mut no_circles, Expected::default()).unwrap();
    assert!(!f.detected, "{f:?}");
    // Rotors, rolled as the camera is: two blades up with the third hidden down the tower
    // (30° from the level), one blade level (the others 30° from the vertical), one straight
    // up (the others 30° from the level).
    for blades in [
        &[60.0, 300.0][..],
        &[90.0, 210.0, 330.0],
        &[0.0, 120.0, 240.0],
    ] {
        let f = recognise_at(
            &on,
            &scene(blades),
            &hints,
            &mut no_circles,
            Expected::default(),
        )
        .unwrap();
        assert!(
            f.detected && geometry::dist(f.hub, c) < 3.0,
            "{blades:?}: {f:?}"
        );
    }
}
