//! Distance and relative-yaw measurements from one detection, with their uncertainty.
//!
//! All functions are pure. Distances are metres, angles radians (unless a name says `_deg`),
//! pixel quantities are at the frame's own resolution.
//!
//! ## Distance (thesis section 7.3, eq. 7.2)
//! A pinhole camera sees an object of real size `D` at depth `d` with size `w = f·D/d` px, so
//! `d = f·D/w`. A width error `σ_w` propagates to first order into `σ_d = d·σ_w/w` (the thesis's
//! example: one pixel of tower width moved the estimate from 35 m to 40 m). The tower width gives
//! the depth of the **tower axis**; the spinner (`d = f·D_spinner / (2r)`) gives the depth of the
//! rotor centre. Independent estimates are fused by inverse variance ([`fuse`]).
//!
//! ## Yaw from the hub–tower gap (thesis section 7.4.2, eq. 7.14)
//! Seen from top, the rotor centre lies `L` in front of the tower axis along the rotor axis. With
//! the camera at relative yaw ψ looking at the hub, the tower axis is displaced sideways by
//! `L·sin ψ` and lies at depth `d_t = d_hub + L·cos ψ`, so it appears `f·L·sin ψ / d_t` px from
//! the hub. **Sign:** when the camera stands on the viewer's right (ψ > 0, the turbine's own
//! left), the tower axis appears to the **right** of the hub (near objects shift against the
//! viewer's motion, the hub is nearer), so the gap `hub_x − tower_x` is **negative**:
//! `gap = −f·L·sin ψ / d_t`, i.e. `ψ = asin(−gap·d_t / (f·L))` — eq. 7.14 with the sign of the
//! project contract and `d` the depth of the tower axis (what the tower width measures).
//!
//! ## Yaw from the blade skew
//! The rotor plane seen at relative yaw ψ is foreshortened horizontally by `cos ψ`: a blade at
//! true angle θ from vertical (clockwise) appears at `α = atan2(sin θ·cos ψ, cos θ)`. The blades
//! are equally spaced (`θ_k = θ₀ + k·360°/N`), so the detected angles determine θ₀ and |ψ| (not its
//! sign: the foreshortening is symmetric). [`blade_skew_yaw`] fits both by least squares in the
//! measured angles and returns |ψ| with its Cramér–Rao standard deviation.

use nalgebra::Vector3;

/// A scalar estimate with its standard deviation (same unit as the value).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The value.
    pub value: f64,
    /// Its standard deviation (> 0).
    pub std: f64,
}

impl Estimate {
    /// A value taken as known exactly (std 0).
    pub fn exact(value: f64) -> Estimate {
        Estimate { value, std: 0.0 }
    }

    /// Variance `std²`.
    pub fn var(&self) -> f64 {
        self.std * self.std
    }

    /// The squared difference of two estimates over the sum of their variances (chi-square,
    /// one degree of freedom): how far apart they are for what each is worth; compared with a
    /// gate, whether they contradict each other.
    pub fn chi2_to(&self, other: &Estimate) -> f64 {
        (self.value - other.value).powi(2) / (self.var() + other.var()).max(1e-12)
    }
}

/// Depth of an object of real size `real_size_m` that appears `size_px` large:
/// `d = f·D/w`, `σ_d = d·σ_w/w`. `None` for a non-positive or non-finite size.
pub fn distance_from_size(
    f_px: f64,
    real_size_m: f64,
    size_px: f64,
    size_std_px: f64,
) -> Option<Estimate> {
    if !(size_px.is_finite() && size_px > 0.0 && f_px > 0.0 && real_size_m > 0.0) {
        return None;
    }
    let d = f_px * real_size_m / size_px;
    Some(Estimate {
        value: d,
        std: d * size_std_px / size_px,
    })
}

/// Depth of the tower axis from the tower width: [`distance_from_size`] with the tower diameter.
pub fn distance_from_tower_width(
    f_px: f64,
    tower_diameter_m: f64,
    width_px: f64,
    width_std_px: f64,
) -> Option<Estimate> {
    distance_from_size(f_px, tower_diameter_m, width_px, width_std_px)
}

/// Distance of the rotor centre from the spinner circle radius. The spinner is a dome, not a
/// flat disc: the silhouette of a sphere of radius `R` whose centre is `d` away is the cone of
/// half-angle `asin(R/d)`, so its image radius is `r = f·R / √(d² − R²)` and
/// `d = R·√(1 + (f/r)²)` (the flat-disc `f·R/r` reads 4–5 % short at 5–10 m, which is the whole
/// ±0.5 m tolerance at the 5 m target). `σ_d = |∂d/∂r|·σ_r = R·f² / (r³·√(1 + (f/r)²))·σ_r`.
pub fn distance_from_spinner(
    f_px: f64,
    spinner_diameter_m: f64,
    radius_px: f64,
    radius_std_px: f64,
) -> Option<Estimate> {
    if !(f_px > 0.0
        && spinner_diameter_m > 0.0
        && radius_px > 0.0
        && radius_px.is_finite()
        && radius_std_px >= 0.0)
    {
        return None;
    }
    let rr = spinner_diameter_m / 2.0;
    let k = (1.0 + (f_px / radius_px).powi(2)).sqrt();
    let value = rr * k;
    let std = rr * f_px * f_px / (radius_px.powi(3) * k) * radius_std_px;
    Some(Estimate { value, std })
}

/// Each estimate's share of [`fuse`]'s result: its inverse variance over the sum (0 for one
/// that is absent or unusable); `None` when none is usable.
pub fn fusion_shares<const N: usize>(estimates: [Option<Estimate>; N]) -> Option<[f64; N]> {
    let weight = |e: &Option<Estimate>| {
        e.filter(|e| e.value.is_finite() && e.std.is_finite() && e.std > 0.0)
            .map_or(0.0, |e| 1.0 / e.var())
    };
    let total: f64 = estimates.iter().map(weight).sum();
    (total > 0.0).then(|| estimates.map(|e| weight(&e) / total))
}

/// Inverse-variance fusion of independent estimates: `x = Σ(xᵢ/σᵢ²) / Σ(1/σᵢ²)`,
/// `σ² = 1 / Σ(1/σᵢ²)`. `None` if there is none (non-finite or non-positive std are skipped).
pub fn fuse(estimates: &[Estimate]) -> Option<Estimate> {
    let (mut w_sum, mut wx_sum) = (0.0, 0.0);
    for e in estimates
        .iter()
        .filter(|e| e.value.is_finite() && e.std.is_finite() && e.std > 0.0)
    {
        let w = 1.0 / e.var();
        w_sum += w;
        wx_sum += w * e.value;
    }
    (w_sum > 0.0).then(|| Estimate {
        value: wx_sum / w_sum,
        std: (1.0 / w_sum).sqrt(),
    })
}

/// Where the hub sits relative to the tower point whose depth the tower width measures, seen
/// from the camera (camera frame: x right, y down, z forward).
///
/// The width gives the depth `z_t` (along the optical axis) of the tower axis point on the
/// measured row, not the hub's distance. That point lies `L` behind the hub along the rotor axis
/// (horizontal unit `b`, from the hub toward the tower) and `Δ` below it, so with the hub at
/// distance `s` along its unit ray `u`: `z_t = s·(ẑ·u) + L·(ẑ·b) − Δ·(ẑ·up)`. Looked at level
/// and head-on this is the thesis's `s = z_t − L`; from 5–10 m below the hub, camera pitched up
/// toward it, the `Δ·(ẑ·up)` term and the hub ray's slant make that read 4–8 % short of the
/// distance to the hub at 12–30 m. Without the attitude the camera is taken as level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HubFromTower {
    /// A ray through the hub, any length (e.g. the undistorted `[x, y, 1]`).
    pub hub_ray: Vector3<f64>,
    /// World up in the camera frame (`[0, −1, 0]` for a level camera).
    pub up: Vector3<f64>,
    /// Relative yaw ψ, radians (sign as in the module docs), with its std.
    pub yaw: Estimate,
    /// `L`: horizontal distance from the tower axis to the hub along the rotor axis, m.
    pub overhang_m: f64,
    /// `Δ`: height of the hub above the measured tower point, m.
    pub hub_above_m: f64,
}

/// `sin β`, β the angle between the line of sight to the hub (`hub_ray`, camera frame) and the
/// horizontal rotor axis at relative yaw `psi`, with world up `up` in the camera frame:
/// `cos β = cos(elevation)·cos ψ`.
pub fn off_axis_sin(hub_ray: Vector3<f64>, up: Vector3<f64>, psi: f64) -> Option<f64> {
    let u = hub_ray.try_normalize(1e-12)?;
    let up = up.try_normalize(1e-12)?;
    let cos_elevation = (1.0 - u.dot(&up).powi(2)).max(0.0).sqrt();
    let c = cos_elevation * psi.cos();
    Some((1.0 - c * c).max(0.0).sqrt())
}

impl HubFromTower {
    /// The same view at relative yaw `yaw`.
    pub fn with_yaw(self, yaw: Estimate) -> HubFromTower {
        HubFromTower { yaw, ..self }
    }

    /// `(ẑ·u, ẑ·b, ẑ·∂b/∂ψ, ẑ·up)`; `None` for a hub straight above or below the camera.
    fn depth_terms(&self) -> Option<(f64, f64, f64, f64)> {
        let u = self.hub_ray.try_normalize(1e-12)?;
        let up = self.up.try_normalize(1e-12)?;
        // The rotor axis is horizontal: `b` turns the hub ray's horizontal part by ψ. A
        // positive ψ puts the tower to the right of the hub (`e`, camera right when level).
        let h = (u - up * u.dot(&up)).try_normalize(1e-9)?;
        let e = h.cross(&up);
        let (s, c) = self.yaw.value.sin_cos();
        let b = h * c + e * s;
        let db = e * c - h * s;
        (u.z > 0.0).then_some((u.z, b.z, db.z, up.z))
    }

    /// The hub's distance from the tower point's depth:
    /// `s = (z_t − L·(ẑ·b) + Δ·(ẑ·up)) / (ẑ·u)`. The std carries the depth's and the yaw's
    /// (through `L·∂(ẑ·b)/∂ψ`). `None` for a non-positive result.
    pub fn hub_distance(&self, tower_depth: Estimate) -> Option<Estimate> {
        let (zu, zb, zdb, zup) = self.depth_terms()?;
        let value = (tower_depth.value - self.overhang_m * zb + self.hub_above_m * zup) / zu;
        let std = tower_depth.std.hypot(self.overhang_m * zdb * self.yaw.std) / zu;
        (value.is_finite() && value > 0.0).then_some(Estimate { value, std })
    }

    /// The inverse: the depth the tower point has with the hub at `hub_distance_m`.
    pub fn tower_depth(&self, hub_distance_m: f64) -> Option<f64> {
        let (zu, zb, _, zup) = self.depth_terms()?;
        let depth = hub_distance_m * zu + self.overhang_m * zb - self.hub_above_m * zup;
        (depth.is_finite() && depth > 0.0).then_some(depth)
    }
}

/// Relative yaw from the hub–tower gap (eq. 7.14 with the project sign, see the module docs):
/// `ψ = asin(−gap·d_t / (f·L))`, clipped to ±`max_abs_rad`.
///
/// `gap_px` = hub x − tower-axis x (px), `tower_depth` = depth of the tower axis (m, with std),
/// `offset_m` = L. The std propagates `σ_s² = (d_t·σ_gap / (f·L))² + (gap·σ_d / (f·L))²` through
/// the asin: `σ_ψ = σ_s / cos ψ`.
pub fn yaw_from_gap(
    gap_px: f64,
    gap_std_px: f64,
    tower_depth: Estimate,
    f_px: f64,
    offset_m: f64,
    max_abs_rad: f64,
) -> Option<Estimate> {
    if !(gap_px.is_finite()
        && tower_depth.value.is_finite()
        && tower_depth.value > 0.0
        && f_px > 0.0
        && offset_m > 0.0)
    {
        return None;
    }
    let k = f_px * offset_m;
    let s_max = max_abs_rad.sin();
    let s = (-gap_px * tower_depth.value / k).clamp(-s_max, s_max);
    let sigma_s = ((tower_depth.value * gap_std_px / k).powi(2)
        + (gap_px * tower_depth.std / k).powi(2))
    .sqrt();
    let psi = s.asin();
    Some(Estimate {
        value: psi,
        std: sigma_s / psi.cos(),
    })
}

/// Image offset, in units of the focal length, of the nacelle's far rear corner from the hub at
/// relative yaw `psi` ≥ 0 and hub distance `d`: the corner is `rear_m` behind the hub along the
/// rotor axis and `half_width_m` to its side, so `(Lr·sin ψ + w·cos ψ) / (d + Lr·cos ψ − w·sin ψ)`.
pub fn nacelle_end_offset(psi: f64, d: f64, rear_m: f64, half_width_m: f64) -> f64 {
    (rear_m * psi.sin() + half_width_m * psi.cos())
        / (d + rear_m * psi.cos() - half_width_m * psi.sin())
}

/// Bisection steps inverting [`nacelle_end_offset`] (the bracket halves each step).
const NACELLE_BISECT_ITERS: usize = 50;

/// Relative yaw from the nacelle's far end seen `dx_px` beside the hub (signed, px; positive to
/// the right, where a camera on the turbine's left sees it): the yaw whose
/// [`nacelle_end_offset`] matches `|dx| / f`, with the sign of `dx`, clipped to ±`max_abs_rad`
/// (an offset below the front-view one gives 0). The std propagates the offset's and the
/// distance's through the slope of the offset in ψ.
pub fn yaw_from_nacelle(
    dx_px: f64,
    dx_std_px: f64,
    distance: Estimate,
    f_px: f64,
    rear_m: f64,
    half_width_m: f64,
    max_abs_rad: f64,
) -> Option<Estimate> {
    let d = distance.value;
    if !(dx_px.is_finite()
        && d.is_finite()
        && d > 0.0
        && f_px > 0.0
        && rear_m > 0.0
        && max_abs_rad > 0.0)
    {
        return None;
    }
    let target = dx_px.abs() / f_px;
    let offset = |psi: f64, d: f64| nacelle_end_offset(psi, d, rear_m, half_width_m);
    let (mut lo, mut hi) = (0.0, max_abs_rad);
    if target <= offset(lo, d) {
        hi = 0.0;
    } else if target >= offset(hi, d) {
        lo = hi;
    } else {
        for _ in 0..NACELLE_BISECT_ITERS {
            let mid = 0.5 * (lo + hi);
            if offset(mid, d) < target {
                lo = mid
            } else {
                hi = mid
            }
        }
    }
    let psi = 0.5 * (lo + hi);
    // Slopes of the offset in ψ and in d (central differences).
    let h = 1e-4;
    let slope_psi =
        (offset(psi + h, d) - offset((psi - h).max(0.0), d)) / (psi + h - (psi - h).max(0.0));
    let slope_d = (offset(psi, d + h) - offset(psi, d - h)) / (2.0 * h);
    if slope_psi <= 0.0 {
        return None;
    }
    let var = (dx_std_px / f_px).powi(2) + (slope_d * distance.std).powi(2);
    Some(Estimate {
        value: psi.copysign(dx_px),
        std: var.sqrt() / slope_psi,
    })
}

/// How far, in standard deviations, the nacelle's end seen `dx_px` beside the hub sticks out
/// beyond the nacelle's front corners at zero yaw, `f·w / (d + front_m)`: the least offset the
/// nacelle shows at any yaw (its front face is `front_m` behind the hub, closer than the rear,
/// so head-on its corners peek out beside the spinner farther than the rear-corner model's
/// `f·w / (d + rear)`). `dx_std_px` covers the end and the hub; the distance's std adds through
/// the floor's slope. A reading near the floor says nothing about the yaw, not even its sign.
pub fn nacelle_excess_sigma(
    dx_px: f64,
    dx_std_px: f64,
    distance: Estimate,
    f_px: f64,
    front_m: f64,
    half_width_m: f64,
) -> f64 {
    let depth = distance.value + front_m;
    if !(dx_px.is_finite() && depth > 0.0 && f_px > 0.0) {
        return f64::NEG_INFINITY;
    }
    let floor = f_px * half_width_m / depth;
    let sigma = dx_std_px.hypot(floor / depth * distance.std).max(1e-9);
    (dx_px.abs() - floor) / sigma
}

/// How far beside the hub, px, a nacelle end must lie to be more than the spinner's own rim:
/// the rim (radius `spinner_radius_m` at hub distance `distance_m`, or the detected circle's
/// `circle_radius_px` if that is wider, so a distance read long does not pull it in) plus
/// `clearance_m` at the same scale.
pub fn spinner_rim_reach_px(
    f_px: f64,
    spinner_radius_m: f64,
    distance_m: f64,
    circle_radius_px: Option<f64>,
    clearance_m: f64,
) -> f64 {
    let rim = (f_px * spinner_radius_m / distance_m).max(circle_radius_px.unwrap_or(0.0));
    rim * (1.0 + clearance_m / spinner_radius_m)
}

/// Apparent image angle (clockwise from up) of a blade at true angle `theta` in a rotor plane
/// seen at relative yaw `psi`: `atan2(sin θ·cos ψ, cos θ)`.
pub fn apparent_blade_angle(theta: f64, psi: f64) -> f64 {
    (theta.sin() * psi.cos()).atan2(theta.cos())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fusion_shares_are_the_inverse_variance_weights() {
        let e = |value, std| Some(Estimate { value, std });
        // σ 1 and 2: weights 1 and 1/4 → shares 0.8 and 0.2; an absent or unusable cue has 0.
        let s = fusion_shares([e(20.0, 1.0), None, e(22.0, 2.0), e(21.0, 0.0)]).unwrap();
        assert_eq!(s, [0.8, 0.0, 0.2, 0.0]);
        let fused = fuse(&[e(20.0, 1.0).unwrap(), e(22.0, 2.0).unwrap()]).unwrap();
        assert!((fused.value - (0.8 * 20.0 + 0.2 * 22.0)).abs() < 1e-12);
        assert_eq!(fusion_shares::<2>([None, e(1.0, f64::NAN)]), None);
    }

    /// A camera `d` m from the hub (horizontally), `below` m under it, on the turbine's left
    /// at relative yaw ψ (the rotor faces +x, up is +z, the hub at the origin), looking at the
    /// hub turned by `(pan, tilt)` radians: the hub ray, world up and the tower point (`L` behind
    /// the hub, `Δ` below) in its camera frame (x right, y down, z forward), and the hub's true
    /// distance. Built from the scene, not from [`HubFromTower`]'s formula.
    fn view(
        d: f64,
        below: f64,
        psi: f64,
        pan: f64,
        tilt: f64,
        l: f64,
        delta: f64,
    ) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>, f64) {
        let up_w = Vector3::z();
        let cam = Vector3::new(d * psi.cos(), d * psi.sin(), -below);
        let look = (-cam).normalize();
        let turn = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), pan);
        let fwd = turn * look;
        let right0 = fwd.cross(&up_w).normalize();
        let fwd =
            nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(right0), tilt)
                * fwd;
        let right = fwd.cross(&up_w).normalize();
        let cam_up = right.cross(&fwd);
        let to_cam = |v: Vector3<f64>| Vector3::new(v.dot(&right), -v.dot(&cam_up), v.dot(&fwd));
        let tower = Vector3::new(-l, 0.0, -delta);
        (to_cam(-cam), to_cam(up_w), to_cam(tower - cam), cam.norm())
    }

    #[test]
    fn hub_distance_from_the_tower_point_in_any_view() {
        let (l, delta) = (4.2, 3.4);
        for &(d, below, psi_deg, pan_deg, tilt_deg) in &[
            (25.0, 0.0, 0.0, 0.0, 0.0),
            (25.0, 8.0, 0.0, 0.0, 0.0),
            (25.0, 8.0, 20.0, 12.0, -3.0),
            (12.0, 3.0, -30.0, -15.0, 5.0),
            (40.0, -5.0, 10.0, 5.0, 8.0),
        ] {
            let psi: f64 = f64::to_radians(psi_deg);
            let (hub, up, tower, truth) = view(
                d,
                below,
                psi,
                f64::to_radians(pan_deg),
                f64::to_radians(tilt_deg),
                l,
                delta,
            );
            let g = HubFromTower {
                hub_ray: hub / hub.z,
                up,
                yaw: Estimate {
                    value: psi,
                    std: 0.0,
                },
                overhang_m: l,
                hub_above_m: delta,
            };
            let s = g
                .hub_distance(Estimate {
                    value: tower.z,
                    std: 0.5,
                })
                .unwrap();
            assert!(
                (s.value - truth).abs() < 1e-9,
                "{d} {below} {psi_deg}: {} vs {truth}",
                s.value
            );
            // The depth's std scales by 1/(ẑ·u) ≥ 1; the inverse gives the depth back.
            assert!(s.std >= 0.5 - 1e-12);
            assert!((g.tower_depth(truth).unwrap() - tower.z).abs() < 1e-9);
            // Level and head-on it is the thesis's depth minus the overhang.
            if below == 0.0 && psi_deg == 0.0 && pan_deg == 0.0 && tilt_deg == 0.0 {
                assert!((s.value - (tower.z - l)).abs() < 1e-9);
            }
        }
        // From 8 m below at 25 m, looking up at the hub, depth minus overhang reads about 5 %
        // short.
        let (hub, up, tower, truth) = view(25.0, 8.0, 0.0, 0.0, 0.0, l, delta);
        assert!(hub.x.abs() < 1e-9 && up.z > 0.3);
        assert!((tower.z - l) / truth < 0.96, "{}", (tower.z - l) / truth);
        // A yaw error moves the result by L·∂(ẑ·b)/∂ψ: the std says so when ψ is uncertain.
        let g = HubFromTower {
            hub_ray: Vector3::new(0.0, 0.0, 1.0),
            up: Vector3::new(0.0, -1.0, 0.0),
            yaw: Estimate {
                value: 0.5,
                std: 0.1,
            },
            overhang_m: l,
            hub_above_m: delta,
        };
        let s = g
            .hub_distance(Estimate {
                value: 30.0,
                std: 0.0,
            })
            .unwrap();
        assert!((s.std - l * 0.5f64.sin() * 0.1).abs() < 1e-12);
    }

    #[test]
    fn off_axis_angle_of_the_line_of_sight() {
        let level = Vector3::new(0.0, -1.0, 0.0);
        let ahead = Vector3::new(0.0, 0.0, 1.0);
        assert!(off_axis_sin(ahead, level, 0.0).unwrap() < 1e-12);
        let psi = 0.4f64;
        assert!((off_axis_sin(ahead, level, psi).unwrap() - psi.sin()).abs() < 1e-12);
        // 8 m below the hub at 25 m (camera pitched up at it), head-on: β is the elevation.
        let (_, up, _, _) = view(25.0, 8.0, 0.0, 0.0, 0.0, 4.2, 3.4);
        let elevation = (8.0f64).atan2(25.0);
        assert!((off_axis_sin(ahead, up, 0.0).unwrap() - elevation.sin()).abs() < 1e-9);
        assert_eq!(off_axis_sin(Vector3::zeros(), level, 0.0), None);
    }

    #[test]
    fn distance_pinhole_hand_case_and_std() {
        // f = 1000 px, D = 2.2 m, w = 55 px → 40 m; ±1 px → σ = 40/55 m.
        let e = distance_from_tower_width(1000.0, 2.2, 55.0, 1.0).unwrap();
        assert!((e.value - 40.0).abs() < 1e-12);
        assert!((e.std - 40.0 / 55.0).abs() < 1e-12);
        // The first-order std matches the finite difference of one pixel.
        let e54 = distance_from_tower_width(1000.0, 2.2, 54.0, 1.0).unwrap();
        assert!(((e54.value - e.value) - e.std).abs() < 0.02 * e.std);
        // Spinner: a sphere of R = 1.6 m at d: r = f·R/√(d² − R²). Far away that is the flat
        // f·R/d (r = 40 px → 40.03 m); at 5 m it is 5 % wider than the flat disc, and the
        // formula inverts it exactly.
        let s = distance_from_spinner(1000.0, 3.2, 40.0, 1.0).unwrap();
        assert!(
            (s.value - 1.6 * (1.0f64 + 625.0).sqrt()).abs() < 1e-12
                && (s.value - 40.0).abs() < 0.05
        );
        assert!((s.std - 1.0).abs() < 0.01);
        for d in [4.0, 5.0, 8.0] {
            let r = 1000.0 * 1.6 / (d * d - 1.6f64 * 1.6).sqrt();
            let e = distance_from_spinner(1000.0, 3.2, r, 1.0).unwrap();
            assert!((e.value - d).abs() < 1e-9, "{d}: {}", e.value);
            let e1 = distance_from_spinner(1000.0, 3.2, r - 1.0, 1.0).unwrap();
            assert!(
                ((e1.value - e.value) - e.std).abs() < 0.02 * e.std,
                "first-order std at {d} m"
            );
        }
        assert!(distance_from_spinner(1000.0, 3.2, 0.0, 1.0).is_none());
        assert!(distance_from_tower_width(1000.0, 2.2, 0.0, 1.0).is_none());
        assert!(distance_from_tower_width(1000.0, 2.2, f64::NAN, 1.0).is_none());
    }

    #[test]
    fn fusion_weights_the_lower_variance_more() {
        let a = Estimate {
            value: 40.0,
            std: 1.0,
        };
        let b = Estimate {
            value: 30.0,
            std: 3.0,
        };
        let f = fuse(&[a, b]).unwrap();
        // Weights 1 and 1/9: (40 + 30/9) / (1 + 1/9) = 39.0
        assert!((f.value - 39.0).abs() < 1e-12, "{f:?}");
        assert!((f.std - (1.0f64 / (1.0 + 1.0 / 9.0)).sqrt()).abs() < 1e-12);
        assert!(f.std < a.std);
        assert!(fuse(&[]).is_none());
        assert_eq!(fuse(&[a]).unwrap(), a);
    }

    #[test]
    fn yaw_from_gap_hand_case_and_sign() {
        // f = 1000 px, L = 5 m, tower depth 40 m, gap −62.5 px: sin ψ = 62.5·40/5000 = 0.5 → +30°.
        let d = Estimate {
            value: 40.0,
            std: 0.0,
        };
        let e = yaw_from_gap(-62.5, 1.0, d, 1000.0, 5.0, 85f64.to_radians()).unwrap();
        assert!(
            (e.value.to_degrees() - 30.0).abs() < 1e-9,
            "{}",
            e.value.to_degrees()
        );
        // σ_s = 40·1/5000 = 0.008 → σ_ψ = 0.008 / cos 30°.
        assert!((e.std - 0.008 / 30f64.to_radians().cos()).abs() < 1e-12);
        // Hub right of the tower → camera on the viewer's left → negative yaw.
        let e = yaw_from_gap(62.5, 1.0, d, 1000.0, 5.0, 85f64.to_radians()).unwrap();
        assert!((e.value.to_degrees() + 30.0).abs() < 1e-9);
        // Clipped at the configured maximum.
        let e = yaw_from_gap(-1000.0, 1.0, d, 1000.0, 5.0, 80f64.to_radians()).unwrap();
        assert!((e.value.to_degrees() - 80.0).abs() < 1e-9);
    }

    /// The gap sign from first principles: place hub, tower and camera in a top view and project.
    #[test]
    fn gap_sign_from_geometry() {
        let (f, l, d) = (1000.0, 4.2, 30.0);
        for &psi_deg in &[-40.0f64, -10.0, 10.0, 40.0] {
            let psi = psi_deg.to_radians();
            // World top view: rotor axis +X (towards the viewer), turbine's own left +Y.
            let hub = [0.0, 0.0];
            let tower = [-l, 0.0]; // behind the hub
            let cam = [d * psi.cos(), d * psi.sin()]; // ψ > 0: on the turbine's left
            let fwd = [(hub[0] - cam[0]) / d, (hub[1] - cam[1]) / d];
            let right = [fwd[1], -fwd[0]]; // forward × up, up out of the page
            let proj = |p: [f64; 2]| {
                let rel = [p[0] - cam[0], p[1] - cam[1]];
                f * (rel[0] * right[0] + rel[1] * right[1]) / (rel[0] * fwd[0] + rel[1] * fwd[1])
            };
            // Check the right vector: ψ = 0 → camera on +X looking at −X, its right is +Y
            // (the turbine's left = the viewer's right). The camera sits on the +Y side for ψ > 0.
            let gap = proj(hub) - proj(tower);
            assert_eq!(gap < 0.0, psi > 0.0, "ψ = {psi_deg}: gap {gap}");
            let depth = d + l * psi.cos();
            let e = yaw_from_gap(
                gap,
                1.0,
                Estimate {
                    value: depth,
                    std: 0.0,
                },
                f,
                l,
                1.5,
            )
            .unwrap();
            assert!(
                (e.value - psi).abs() < 1e-9,
                "ψ = {psi_deg}: got {}",
                e.value.to_degrees()
            );
        }
    }

    #[test]
    fn nacelle_excess_over_the_head_on_front_corners() {
        // Hand case: f = 1000 px, half width 1.7 m, front face 1.2 m behind the hub, 30 m:
        // head-on the front corners are 1000·1.7/31.2 = 54.487 px beside the hub.
        let exact = Estimate {
            value: 30.0,
            std: 0.0,
        };
        let floor = 1000.0 * 1.7 / 31.2;
        let e = nacelle_excess_sigma(floor + 10.0, 5.0, exact, 1000.0, 1.2, 1.7);
        assert!((e - 2.0).abs() < 1e-9, "{e}");
        // Either side; a reading inside the floor is negative.
        assert!(
            (nacelle_excess_sigma(-(floor + 10.0), 5.0, exact, 1000.0, 1.2, 1.7) - 2.0).abs()
                < 1e-9
        );
        assert!(nacelle_excess_sigma(floor - 5.0, 5.0, exact, 1000.0, 1.2, 1.7) < 0.0);
        // A distance std of 3.12 m moves the floor by 54.487·3.12/31.2 = 5.449 px: σ = hypot(5, 5.449).
        let loose = Estimate {
            value: 30.0,
            std: 3.12,
        };
        let e = nacelle_excess_sigma(floor + 10.0, 5.0, loose, 1000.0, 1.2, 1.7);
        assert!((e - 10.0 / 5f64.hypot(floor * 0.1)).abs() < 1e-9, "{e}");
        assert_eq!(
            nacelle_excess_sigma(f64::NAN, 5.0, exact, 1000.0, 1.2, 1.7),
            f64::NEG_INFINITY
        );
    }

    #[test]
    fn the_spinner_rim_reach_takes_the_wider_rim_and_scales_the_clearance_with_it() {
        // 2 m spinner at 20 m through f 1000: rim 100 px; 0.5 m more is 25 px more.
        assert!((spinner_rim_reach_px(1000.0, 2.0, 20.0, None, 0.5) - 125.0).abs() < 1e-9);
        // A circle smaller than the rim changes nothing; a wider one (the distance read long)
        // sets the rim, and the clearance scales with it.
        assert!((spinner_rim_reach_px(1000.0, 2.0, 20.0, Some(80.0), 0.5) - 125.0).abs() < 1e-9);
        assert!((spinner_rim_reach_px(1000.0, 2.0, 20.0, Some(120.0), 0.5) - 150.0).abs() < 1e-9);
        assert!((spinner_rim_reach_px(1000.0, 2.0, 20.0, None, 0.0) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn nacelle_yaw_inverts_the_pinhole_offset_of_the_rear_corner() {
        // Hand case: 20 m, ψ = 20°, rear 11.2 m, half width 1.7 m, f = 1000 px:
        // X = 11.2·0.3420 + 1.7·0.9397 = 5.4278 m, Z = 20 + 11.2·0.9397 − 1.7·0.3420 = 29.943 m,
        // dx = 1000·X/Z = 181.27 px.
        let d = Estimate {
            value: 20.0,
            std: 0.0,
        };
        let e = yaw_from_nacelle(181.27, 2.0, d, 1000.0, 11.2, 1.7, 1.4).unwrap();
        assert!((e.value.to_degrees() - 20.0).abs() < 0.01, "{e:?}");
        let m = yaw_from_nacelle(-181.27, 2.0, d, 1000.0, 11.2, 1.7, 1.4).unwrap();
        assert!((m.value + e.value).abs() < 1e-9 && (m.std - e.std).abs() < 1e-12);
        // Slope d(dx)/dψ = f·(X'·Z − X·Z')/Z² = 1000·(9.94·29.943 + 5.4278·5.43)/29.943² ≈ 365 px
        // per radian (6.4 px per degree): 2 px give 0.31°.
        assert!((e.std.to_degrees() - 0.314).abs() < 0.01, "{e:?}");
        // An offset inside the front-view one (1000·1.7/31.2 = 54.5 px) reads as 0; a distance
        // uncertainty widens the std.
        assert_eq!(
            yaw_from_nacelle(40.0, 2.0, d, 1000.0, 11.2, 1.7, 1.4)
                .unwrap()
                .value,
            0.0
        );
        let wide = yaw_from_nacelle(
            181.27,
            2.0,
            Estimate {
                value: 20.0,
                std: 2.0,
            },
            1000.0,
            11.2,
            1.7,
            1.4,
        )
        .unwrap();
        assert!(wide.std > e.std);
    }
}
