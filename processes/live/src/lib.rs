//! The live view for the ground station: the pipeline served through the Foxglove WebSocket
//! protocol by its own stage process, so a slow link, a stalled client or a crash of the server
//! costs the camera and detect nothing.

#![warn(missing_docs)]

pub mod downscale;
pub mod rate;
pub mod server;
pub mod view;
