//! Synthetic test-frame generator shared by the examples, the bench and the tests.
//!
//! Poses follow the evaluation brief: distance classes far ≥ 25 m, medium 12–25 m, close < 12 m
//! (camera-to-hub), relative yaw up to ±30°, camera from 10° below to 25° above the hub (so the
//! horizon often passes near the hub), pointing error, roll ±10°, and `Scene::random` skies,
//! grounds, shadows, propellers, noise, blur and JPEG.
#![allow(dead_code)]

use hubtrack_render::{CameraPose, Distractor, Scene};

/// Distance class of a synthetic frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    Far,
    Medium,
    Close,
    Negative,
}

impl Class {
    pub const ALL: [Class; 4] = [Class::Far, Class::Medium, Class::Close, Class::Negative];
    pub fn name(self) -> &'static str {
        match self {
            Class::Far => "far",
            Class::Medium => "medium",
            Class::Close => "close",
            Class::Negative => "negative",
        }
    }
    /// Camera-to-hub distance range, metres.
    pub fn range_m(self) -> (f64, f64) {
        match self {
            Class::Far => (25.0, 80.0),
            Class::Medium => (12.0, 25.0),
            Class::Close => (7.0, 12.0),
            Class::Negative => (25.0, 120.0),
        }
    }
}

/// splitmix64-based uniform numbers.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// One synthetic frame's scene and pose for `class` and `seed`.
pub fn sample(class: Class, seed: u64) -> (Scene, CameraPose) {
    let mut r = Rng::new(seed.wrapping_mul(31).wrapping_add(class as u64));
    let mut scene = Scene::random(seed);
    scene.turbine_present = class != Class::Negative;
    if class == Class::Negative && scene.distractor == Distractor::None {
        scene.distractor = if r.range(0.0, 1.0) < 0.5 { Distractor::Mast } else { Distractor::PowerLines };
    }
    let (lo, hi) = class.range_m();
    let d = r.range(lo, hi);
    let yaw = r.range(-30.0, 30.0).to_radians();
    let el = r.range(-10.0, 25.0).to_radians();
    let horiz = d * el.cos();
    let mut pose = CameraPose::looking_at_hub(horiz * yaw.cos(), horiz * yaw.sin(), d * el.sin());
    // Pointing error: the hub stays inside the image (the flight controller keeps it centred,
    // but not perfectly).
    pose.yaw_deg += r.range(-15.0, 15.0);
    pose.pitch_deg += r.range(-8.0, 8.0);
    pose.roll_deg = r.range(-10.0, 10.0);
    (scene, pose)
}

/// Score: distance (px) from `p` to the segment `a`–`b`.
pub fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 < 1e-12 { 0.0 } else { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0) };
    ((a[0] + t * dx - p[0]).powi(2) + (a[1] + t * dy - p[1]).powi(2)).sqrt()
}
