//! Evaluation sets of synthetic frames with exact truth: scenes and poses drawn deterministically
//! from a seed, by distance class, with the conditions the detector must survive (relative yaw,
//! pointing error, roll, horizon near the hub, shadows, propellers, skies, both lenses, negatives).
//! One generator for `hubtrack eval`, the detector benchmark and the sequence evaluation.

use crate::{CameraPose, Distractor, Scene};

/// Distance classes of the synthetic set, metres: far ≥ 25, medium 12–25, close < 12.
pub const CLASSES: [(&str, f64, f64); 3] = [("far", 25.0, 45.0), ("medium", 12.0, 25.0), ("close", 6.0, 12.0)];
/// Largest relative yaw in the synthetic set, degrees.
pub const MAX_REL_YAW_DEG: f64 = 30.0;
/// Largest camera pointing error (hub away from the image centre), degrees.
pub const MAX_POINTING_DEG: f64 = 12.0;
/// Largest camera roll, degrees.
pub const MAX_ROLL_DEG: f64 = 10.0;
/// Camera height relative to the hub, metres.
pub const HEIGHT_RANGE_M: (f64, f64) = (-12.0, 6.0);
/// Camera heights within this of the hub height put the horizon near the hub, metres.
pub const HORIZON_NEAR_M: f64 = 3.0;
/// Relative yaw beyond which a view counts as oblique, degrees.
pub const OBLIQUE_DEG: f64 = 15.0;

/// A small deterministic generator (SplitMix64) for the synthetic set.
pub struct Rng(pub u64);

impl Rng {
    /// Next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One synthetic evaluation case: scene, pose, lens and the roll the vehicle would report.
pub struct SynthCase {
    /// Scene.
    pub scene: Scene,
    /// Camera pose.
    pub pose: CameraPose,
    /// GoPro (3 of 4) or USB camera.
    pub wide: bool,
    /// Categories the case counts in.
    pub categories: Vec<String>,
}

/// The `index`-th case of a distance class (deterministic in `seed`).
pub fn synth_case(seed: u64, class: usize, index: u64, negative: bool) -> SynthCase {
    let mut r = Rng(seed ^ (class as u64) << 40 ^ index.wrapping_mul(0x9E37));
    let (name, lo, hi) = CLASSES[class];
    let mut scene = Scene::random(r.next());
    scene.turbine_present = !negative;
    if negative && scene.distractor == Distractor::None {
        scene.distractor = Distractor::Mast;
    }
    let distance = r.range(lo, hi);
    let rel_yaw = r.range(-MAX_REL_YAW_DEG, MAX_REL_YAW_DEG);
    let nacelle = r.range(-0.5, 0.5) * rel_yaw;
    let lateral = distance * (rel_yaw - nacelle).to_radians().tan();
    scene.nacelle_yaw_deg = nacelle;
    let height = r.range(HEIGHT_RANGE_M.0, HEIGHT_RANGE_M.1);
    let mut pose = CameraPose::looking_at_hub(distance, lateral, height);
    pose.yaw_deg += r.range(-MAX_POINTING_DEG, MAX_POINTING_DEG);
    pose.pitch_deg += r.range(-0.6, 0.6) * MAX_POINTING_DEG;
    pose.roll_deg = r.range(-MAX_ROLL_DEG, MAX_ROLL_DEG);
    let wide = r.next() % 4 != 0;
    let mut categories = vec!["all".to_string(), format!("distance:{name}")];
    categories.push(format!("sky:{:?}", scene.sky).to_lowercase());
    categories.push(if rel_yaw.abs() > OBLIQUE_DEG { "view:oblique".into() } else { "view:front".into() });
    if height.abs() < HORIZON_NEAR_M {
        categories.push("effects:horizon_near_hub".into());
    }
    if scene.propellers_in_view {
        categories.push("effects:propellers".into());
    }
    if scene.nacelle_shadow {
        categories.push("effects:nacelle_shadow".into());
    }
    categories.push(if wide { "camera:gopro".into() } else { "camera:usb".into() });
    if negative {
        categories = vec!["negatives".into()];
    }
    SynthCase { scene, pose, wide, categories }
}

