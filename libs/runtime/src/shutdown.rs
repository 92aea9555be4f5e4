//! SIGINT / SIGTERM handling: the signal sets a flag; the stage loop checks it and exits cleanly
//! (finishing files, dropping ports) instead of dying mid-write.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A flag set when the process is asked to stop.
#[derive(Clone, Debug)]
pub struct Shutdown(Arc<AtomicBool>);

impl Shutdown {
    /// Registers SIGINT and SIGTERM handlers that set the flag.
    pub fn install() -> std::io::Result<Shutdown> {
        let flag = Arc::new(AtomicBool::new(false));
        signal_hook::flag::register(signal_hook::consts::SIGINT, Arc::clone(&flag))?;
        signal_hook::flag::register(signal_hook::consts::SIGTERM, Arc::clone(&flag))?;
        Ok(Shutdown(flag))
    }

    /// A flag not bound to signals (tests, embedding).
    pub fn manual() -> Shutdown {
        Shutdown(Arc::new(AtomicBool::new(false)))
    }

    /// True once a stop was requested.
    pub fn requested(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// Requests a stop.
    pub fn request(&self) {
        self.0.store(true, Ordering::Relaxed)
    }
}
