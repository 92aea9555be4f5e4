//! Does a detection's geometry fit the turbine profile? A hub the detector put on something else
//! (a lattice mast beside the turbine, a crossing on the tower shaft, a blade root) usually sits
//! where the turbine's hub cannot be relative to the tower it found: below the tower top, or
//! farther beside the tower axis than the hub overhang allows. Such detections are not fed to the
//! track, so a wrong object cannot hold a lock (see `[track.profile_check]`).
//!
//! Metres come from the tower's own width (the profile's tower-top diameter over the measured
//! band width): no distance or focal length needed, so the check holds before the track has a
//! distance and with any lens.

use crate::params::ProfileCheckConfig;
use hubtrack_types::Detection;

/// Why a detection contradicts the profile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Contradiction {
    /// The hub is this far (m) below the tower top.
    HubBelowTowerTop(f64),
    /// The hub is this far (m) beside the tower axis.
    HubBesideTower(f64),
}

impl std::fmt::Display for Contradiction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Contradiction::HubBelowTowerTop(m) => write!(f, "hub {m:.1} m below the tower top"),
            Contradiction::HubBesideTower(m) => write!(f, "hub {m:.1} m beside the tower axis"),
        }
    }
}

/// The turbine's dimensions the check compares with, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Profile {
    /// Tower diameter where the detector measures the band.
    pub tower_top_diameter_m: f64,
    /// Tower axis to hub centre, horizontally.
    pub hub_overhang_m: f64,
    /// Spinner diameter.
    pub spinner_diameter_m: f64,
}

/// The first way `det` contradicts `profile`, or `None` when it fits or cannot be checked (no
/// hub, no tower band, a camera rolled more than `cfg.max_roll_deg`).
pub fn contradiction(
    det: &Detection,
    profile: &Profile,
    cfg: &ProfileCheckConfig,
) -> Option<Contradiction> {
    if !cfg.enabled
        || !det.detected
        || !det.tower_found
        || det.roll_used_deg.abs() > cfg.max_roll_deg
        || det.tower_width_px.is_nan()
        || det.tower_width_px <= 0.0
    {
        return None;
    }
    let m_per_px = profile.tower_top_diameter_m / det.tower_width_px;
    let above_m = (det.tower_top_px[1] - det.hub_px[1]) * m_per_px;
    let beside_m = det.hub_tower_gap_px.abs() * m_per_px;
    if !(above_m.is_finite() && beside_m.is_finite()) {
        return None;
    }
    // The hub sits on the nacelle, about half a spinner above the tower top; the slack covers
    // a band measured lower on a tapered tower and a tower top the nacelle hides. No limit
    // above: a blade pointing down hides the tower's upper part (the visible band then starts
    // at the blade tip, tens of metres below the hub), a common parking position.
    let spinner = profile.spinner_diameter_m;
    if above_m < -cfg.below_top_spinners * spinner {
        return Some(Contradiction::HubBelowTowerTop(-above_m));
    }
    // Seen from the side the hub is at most the overhang beside the axis (plus the spinner's
    // radius where the detector puts the hub on its rim).
    let beside_max = cfg.beside_slack * (profile.hub_overhang_m + 0.5 * spinner);
    (beside_m > beside_max).then_some(Contradiction::HubBesideTower(beside_m))
}

#[cfg(test)]
mod tests {
    use super::*;

    const PROFILE: Profile = Profile {
        tower_top_diameter_m: 2.2,
        hub_overhang_m: 4.2,
        spinner_diameter_m: 3.2,
    };

    /// A hub `above_m` above the tower top and `beside_m` beside its axis, the tower 22 px wide
    /// (0.1 m per px).
    fn det(above_m: f64, beside_m: f64) -> Detection {
        Detection {
            detected: true,
            tower_found: true,
            hub_px: [500.0 + beside_m * 10.0, 300.0],
            tower_top_px: [500.0, 300.0 + above_m * 10.0],
            tower_width_px: 22.0,
            hub_tower_gap_px: beside_m * 10.0,
            ..Detection::default()
        }
    }

    #[test]
    fn a_hub_on_the_nacelle_fits() {
        let cfg = ProfileCheckConfig::default();
        for (above, beside) in [(1.6, 0.0), (2.5, 4.0), (0.0, -3.0), (-1.0, 2.0), (6.0, 1.0)] {
            assert_eq!(
                contradiction(&det(above, beside), &PROFILE, &cfg),
                None,
                "{above} {beside}"
            );
        }
    }

    #[test]
    fn a_hub_on_the_shaft_or_beside_the_tower_does_not() {
        let cfg = ProfileCheckConfig::default();
        assert!(matches!(
            contradiction(&det(-12.0, 0.0), &PROFILE, &cfg),
            Some(Contradiction::HubBelowTowerTop(m)) if (m - 12.0).abs() < 1e-9
        ));
        assert!(matches!(
            contradiction(&det(2.0, 25.0), &PROFILE, &cfg),
            Some(Contradiction::HubBesideTower(m)) if (m - 25.0).abs() < 1e-9
        ));
        // A blade down the tower hides its top: the band starts at the tip, far below the hub.
        assert_eq!(contradiction(&det(30.0, 0.0), &PROFILE, &cfg), None);
    }

    #[test]
    fn the_profile_sets_the_limits() {
        let cfg = ProfileCheckConfig::default();
        let wide = Profile {
            hub_overhang_m: 12.0,
            ..PROFILE
        };
        let d = det(2.0, 12.0);
        assert!(contradiction(&d, &PROFILE, &cfg).is_some());
        assert_eq!(contradiction(&d, &wide, &cfg), None);
    }

    #[test]
    fn what_cannot_be_checked_passes() {
        let cfg = ProfileCheckConfig::default();
        let mut d = det(-12.0, 0.0);
        d.tower_found = false;
        assert_eq!(contradiction(&d, &PROFILE, &cfg), None);
        let mut d = det(-12.0, 0.0);
        d.tower_width_px = 0.0;
        assert_eq!(contradiction(&d, &PROFILE, &cfg), None);
        let mut d = det(-12.0, 0.0);
        d.roll_used_deg = 40.0;
        assert_eq!(contradiction(&d, &PROFILE, &cfg), None);
        let mut d = det(-12.0, 0.0);
        d.hub_px[1] = f64::NAN;
        assert_eq!(contradiction(&d, &PROFILE, &cfg), None);
        let off = ProfileCheckConfig {
            enabled: false,
            ..ProfileCheckConfig::default()
        };
        assert_eq!(contradiction(&det(-12.0, 0.0), &PROFILE, &off), None);
    }
}
