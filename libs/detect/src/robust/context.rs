//! What every step of the default pipeline reads: the working image's size, the parameters and
//! the caller's hints ([`FrameCtx`]), and once the lines are classified, the lines with their
//! roll, usable flags and band axes ([`SceneCtx`]). Steps take one of these instead of the
//! same half-dozen loose arguments each.

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
        }
    }
}
