//! The contract between hubtrack processes.
//!
//! Everything that crosses a process boundary is defined here, once:
//! - [`messages`]: the `#[repr(C)]`, fixed-size, pointer-free payloads and user headers sent over
//!   iceoryx2 shared memory ([`FrameHeader`], [`Detection`], [`TrackState`], [`Setpoint`],
//!   [`VehicleState`]);
//! - [`services`]: the service names and their quality-of-service settings;
//! - [`time`]: the time-stamp convention.
//!
//! ## Time-stamp convention
//! Every message carries the `seq` and `capture_ns` of the camera frame it derives from, and each
//! stage stamps when it received its input (`recv_ns`) and when it published (`publish_ns`).
//! All `*_ns` stamps are `CLOCK_MONOTONIC` nanoseconds, which is one clock for every process on the
//! machine, so any recording yields the latency of every stage and every hop. Wall-clock time
//! (`CLOCK_REALTIME`, epoch ns) is used only for MCAP `log_time` and carried in
//! [`FrameHeader::capture_realtime_ns`].

#![warn(missing_docs)]

pub mod messages;
pub mod mutate;
pub mod params;
pub mod services;
pub mod setup;
pub mod time;

pub use messages::*;
