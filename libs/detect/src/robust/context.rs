//! What every step of the default pipeline reads: the working image's size, the parameters and
//! the caller's hints ([`FrameCtx`]), and once the lines are classified, the lines with their
//! roll, usable flags and band axes ([`SceneCtx`]). Steps take one of these instead of the
//! same half-dozen loose arguments each.

use hubtrack_types::setup::CameraModel;

use crate::geometry::{Segment, P2};
use crate::params::DefaultParams;
use crate::Hints;

use super::bands::BandAxis;

/// Sizes a tracker's distance lets the detector expect, working px.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Expected<'a> {
    /// Tower width just under the nacelle.
    pub tower_width: Option<f64>,
    /// Spinner radius.
    pub spinner_radius: Option<f64>,
    /// Image scale at the hub's depth, px per metre.
    pub px_per_m: Option<f64>,
    /// The camera and turbine sizes that turn a spinner's radius into a tower width.
    pub optics: Option<Optics>,
    /// The learned hub heatmap of the frame (`hub_heat`).
    pub heat: Option<&'a crate::heat::Heatmap>,
}

/// Focal length (working px) and the turbine's known sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Optics {
    /// Focal length, working px.
    pub focal_px: f64,
    /// Spinner radius, m.
    pub spinner_radius_m: f64,
    /// Tower diameter just under the nacelle, m.
    pub tower_top_diameter_m: f64,
    /// Horizontal distance from the hub back to the tower axis, m.
    pub hub_tower_gap_m: f64,
    /// Nacelle width, m.
    pub nacelle_width_m: f64,
    /// Distance from the hub back to the nacelle's rear face, m.
    pub nacelle_rear_m: f64,
    /// The calibrated camera at the working size, when its lens bends straight lines (see
    /// [`FrameCtx::camera`]).
    pub bending_lens: Option<CameraModel>,
}

impl Optics {
    /// The tower width (working px) a spinner of radius `r` px implies: the spinner gives the
    /// hub's distance `f·R/r`, the tower stands `hub_tower_gap_m` farther. `None` for r ≤ 0.
    pub fn tower_width_for_spinner(&self, r: f64) -> Option<f64> {
        (r > 0.0).then(|| {
            self.focal_px * self.tower_top_diameter_m
                / (self.focal_px * self.spinner_radius_m / r + self.hub_tower_gap_m)
        })
    }
}

/// The working image and what every step reads about it: the parameters, the image's size
/// (working px) and the caller's hints (in working px).
#[derive(Clone, Copy)]
pub(super) struct FrameCtx<'a> {
    /// The default pipeline's parameters.
    pub p: &'a DefaultParams,
    /// Width of the working image, px.
    pub w: f64,
    /// Height of the working image, px: the unit of every `_frac` parameter.
    pub h: f64,
    /// Roll, predicted hub (working px) and distance from the IMU and the tracker.
    pub hints: &'a Hints,
    /// The largest spinner radius searched without a tracker's distance, working px (see
    /// [`blind_spinner_max_r`]).
    pub spinner_max_r: f64,
    /// The calibrated camera at the working size when its lens bends straight lines (fisheye,
    /// plumb_bob): a horizon is judged straight and level where a pinhole would have imaged it
    /// (see `horizon::usable_lines`).
    pub camera: Option<CameraModel>,
}

/// The largest spinner radius the spinner step searches without a tracker's distance, working px.
/// Without a predicted hub either (a still photo, a lost track), the radius the spinner has
/// `spinner_closest_m` away through the frame's lens (`optics`), at least
/// `spinner_max_radius_frac` and at most `spinner_hint_max_radius_frac` of the height `h`: a
/// wide lens (the GoPro: 0.31 of the height at 4 m) keeps the fixed limit; a narrow one sees the
/// spinner at the end of the approach half the height or more across. A track without a
/// distance yet is far away: `spinner_max_radius_frac` (larger radii searched around its hub
/// let a larger circle of clutter outscore the spinner's own rim there).
pub(crate) fn blind_spinner_max_r(
    p: &DefaultParams,
    h: f64,
    optics: Option<&Optics>,
    hints: &Hints,
) -> f64 {
    let floor = p.spinner_max_radius_frac * h;
    if hints.predicted_hub_px.is_some() {
        return floor;
    }
    let at_closest = optics.map_or(0.0, |o| {
        o.focal_px * o.spinner_radius_m / p.spinner_closest_m
    });
    floor.max(at_closest.min(p.spinner_hint_max_radius_frac * h))
}

/// A blade seen by one edge: its axis from the partner edge in the gradient image, when found
/// (`crate::blade`); the arguments are the edge and the hub candidate.
pub(super) type PartnerAxis<'a> = dyn Fn(&Segment, P2) -> Option<Segment> + 'a;

/// The frame once its lines are classified (steps 2–4 and 8): what the steps around each hub
/// candidate read.
#[derive(Clone, Copy)]
pub(super) struct SceneCtx<'a> {
    /// The default pipeline's parameters.
    pub p: &'a DefaultParams,
    /// Width of the working image, px.
    pub w: f64,
    /// Height of the working image, px.
    pub h: f64,
    /// Roll, predicted hub (working px) and distance from the IMU and the tracker.
    pub hints: &'a Hints,
    /// The largest spinner radius searched without a tracker's distance, working px.
    pub spinner_max_r: f64,
    /// The calibrated camera at the working size when its lens bends straight lines.
    pub camera: Option<CameraModel>,
    /// The merged Hough lines, longest first.
    pub segs: &'a [Segment],
    /// Per line: may it be a blade or tower edge (not a horizon, step 4).
    pub usable: &'a [bool],
    /// The band axes of paired edges (step 8).
    pub axes: &'a [BandAxis],
    /// The roll used, degrees (the hint's, or searched).
    pub roll_deg: f64,
    /// The partner-edge search of blades seen by one edge.
    pub partner: &'a PartnerAxis<'a>,
}

impl<'a> SceneCtx<'a> {
    /// The frame this scene was found in.
    pub fn frame(&self) -> FrameCtx<'a> {
        FrameCtx {
            p: self.p,
            w: self.w,
            h: self.h,
            hints: self.hints,
            spinner_max_r: self.spinner_max_r,
            camera: self.camera,
        }
    }
}
