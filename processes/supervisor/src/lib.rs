//! The flight side of hubtrack: launching and supervising the stage processes (`run`), replay,
//! and the operator's tools on a running pipeline and on recordings. Links no detector, tracker,
//! renderer or simulator: each stage is its own binary.

#![warn(missing_docs)]

pub mod config_check;
pub mod instance;
pub mod launch;
pub mod replay;
pub mod summary;
pub mod supervise;
pub mod tools;
