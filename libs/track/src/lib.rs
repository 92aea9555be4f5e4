//! Hub tracking for hubtrack: turns per-frame [`Detection`]s (and, optionally, the vehicle's
//! [`VehicleState`]) into a [`TrackState`]: filtered hub position and velocity in the image, a
//! track mode, and the distance and relative yaw to the hub with their uncertainty.
//!
//! Pure library, no I/O: the track stage process feeds it and publishes the result.
//!
//! # Trackers
//! - [`Tracker`] (the default): the thesis's damped constant-velocity Kalman filter (MSc thesis
//!   section 6.2) in continuous time on the frames' `capture_ns` ([`filter`]), with
//!   Mahalanobis gating of outliers and acceptance of persistent jumps, the modes `acquiring` →
//!   `tracking` → `coasting` → `lost` with time limits and `search_requested`, prediction of the
//!   image motion caused by the vehicle's rotation (and translation) ([`camera`]), and distance
//!   (tower width, spinner) and yaw (hub–tower gap, blade skew) fused by inverse variance and
//!   filtered over time ([`estimate`]).
//! - [`BaselineTracker`]: the thesis filter alone (no gating, no vehicle input, raw per-frame
//!   distance and yaw as in thesis sections 9.2.3–9.2.4), for side-by-side evaluation.
//!
//! # Modes
//! - `acquiring`: no confirmed track yet; the first detection starts a tentative track, each
//!   consistent one (passing the gate) counts, an inconsistent one restarts it;
//!   `modes.confirm_count` consistent detections confirm it → `tracking`.
//! - `tracking`: the frame's detection was accepted (or fewer than `modes.coast_after_missed`
//!   frames in a row were missed or gated out).
//! - `coasting`: no accepted detection for `coast_after_missed` frames: the filter predicts
//!   (damped, with the ego-motion).
//! - `lost`: no accepted detection for `modes.lost_after_s` s. The prediction goes on; the next
//!   detection, wherever it is, starts a new tentative track (`acquiring`). A tentative track that
//!   gets no detection for `lost_after_s` is dropped (`lost` if there had been a confirmed track,
//!   otherwise `acquiring`).
//! - `search_requested`: in `lost` or `acquiring` after `modes.search_after_s` s without an
//!   accepted detection (counted from the first frame if there never was one).
//!
//! A detection whose hub cannot be the profile's hub relative to the tower it found (below the
//! tower top, or farther beside the axis than the overhang allows: [`profile_check`]) is not
//! fed to the track at all.
//!
//! A confirmed track rejects a measurement whose squared Mahalanobis distance exceeds
//! `gating.chi2_threshold` (unless it is within `gating.min_gate_px`); `gating.jump_accept_count`
//! consecutive mutually consistent rejected measurements (the true hub after a jump) restart the
//! track there, already confirmed.
//!
//! # Sign conventions
//! - Image: px, origin top-left, x right, y down, pixel centres at integer coordinates; the
//!   principal point is the image centre.
//! - **Relative yaw** (project contract, as `FrameTruth::relative_yaw_deg`): positive when the
//!   camera stands on the turbine's own left (= the viewer's right when facing the rotor) and
//!   looks at the hub, zero in front of the rotor face.
//! - **Hub–tower gap** (`Detection::hub_tower_gap_px` = hub x − tower-axis x): the hub is in
//!   front of the tower along the rotor axis, so it is the nearer of the two. With the camera on
//!   the viewer's right (ψ > 0) the nearer hub shifts left relative to the tower (parallax), i.e.
//!   the tower appears to the right of the hub and the gap is **negative**. Hence
//!   `ψ = asin(−gap·d_t / (f·L))`: a negative gap means positive yaw. Pinned by the tests
//!   `estimate::tests::gap_sign_from_geometry` and `yaw_from_gap_hand_case_and_sign`.
//! - Vehicle: NED world, FRD body, yaw clockwise from north. Yawing right by Δψ moves the hub
//!   **left** in the image by ≈ f·Δψ px; pitching up by Δθ moves it **down** by ≈ f·Δθ px.
//!
//! # Units
//! `TrackState` carries px, px/s, px², metres and degrees; everything inside is SI (s, m, rad).

#![warn(missing_docs)]

pub mod camera;
pub mod estimate;
pub mod filter;
pub mod parallax;
pub mod params;
pub mod profile_check;
mod tracker;

pub use hubtrack_types::{Detection, TrackMode, TrackState, VehicleState};
pub use params::{ParamError, TrackConfig};
pub use tracker::{BaselineTracker, Tracker};
