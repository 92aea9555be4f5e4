//! The control stage's library part: the rules of live control that need no process to test.
//!
//! [`gate`]: when live control sends its HEARTBEAT and its setpoints to the autopilot, and
//! when it goes silent, as a state machine fed with events and times.
//! [`envelope`]: whether the camera sees the turbine's spinner whole at the approach's target.

#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod envelope;
pub mod gate;

pub use gate::{may_command, Action, Actions, AutopilotView, CommandGate, GateTiming};
