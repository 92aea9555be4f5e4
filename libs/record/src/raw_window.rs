//! Raw windows: every frame recorded raw as well for a while, on request.
//!
//! A compressed recording is what a flight can afford; a raw frame is what bit-exact replay and
//! debugging need. When something interesting happens, the operator asks (`hubtrack
//! raw-window`) and the recorder adds a raw copy of every frame to `/frames/raw` for the
//! window's length of capture time, starting at the next frame. Sans-IO: the recorder feeds
//! requests and frame capture times, and asks per frame.

use std::fmt;

/// Why a request opened no window.
#[derive(Debug, Clone, PartialEq)]
pub enum Refused {
    /// `recorder.raw_window_max_s` is 0.
    Disabled,
    /// Not a finite, non-negative length.
    BadLength(f64),
}

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refused::Disabled => write!(f, "raw windows are off (recorder.raw_window_max_s = 0)"),
            Refused::BadLength(s) => write!(f, "a raw window of {s} s is no length"),
        }
    }
}

/// The window state.
#[derive(Debug, Clone, PartialEq)]
pub struct RawWindow {
    default_s: f64,
    max_s: f64,
    /// A request waiting for the next frame, seconds.
    pending_s: Option<f64>,
    /// Capture time up to which frames go raw.
    until_ns: Option<u64>,
}

impl RawWindow {
    /// Windows of `default_s` when a request names no length, at most `max_s`.
    pub fn new(default_s: f64, max_s: f64) -> RawWindow {
        RawWindow {
            default_s,
            max_s,
            pending_s: None,
            until_ns: None,
        }
    }

    /// A request for `seconds` (0: the default); returns the length granted (capped at the
    /// maximum). It starts at the next frame, or extends the open window.
    pub fn request(&mut self, seconds: f64) -> Result<f64, Refused> {
        if self.max_s <= 0.0 {
            return Err(Refused::Disabled);
        }
        if !seconds.is_finite() || seconds < 0.0 {
            return Err(Refused::BadLength(seconds));
        }
        let s = if seconds == 0.0 {
            self.default_s
        } else {
            seconds
        }
        .min(self.max_s);
        self.pending_s = Some(self.pending_s.map_or(s, |p| p.max(s)));
        Ok(s)
    }

    /// Whether the frame captured at `capture_ns` goes raw as well.
    pub fn take(&mut self, capture_ns: u64) -> bool {
        if let Some(s) = self.pending_s.take() {
            let until = capture_ns.saturating_add((s * 1e9) as u64);
            self.until_ns = Some(self.until_ns.map_or(until, |u| u.max(until)));
        }
        match self.until_ns {
            Some(u) if capture_ns <= u => true,
            Some(_) => {
                self.until_ns = None;
                false
            }
            None => false,
        }
    }

    /// A window is open or about to open.
    pub fn is_open(&self) -> bool {
        self.pending_s.is_some() || self.until_ns.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: u64 = 1_000_000_000;

    /// Frames at 10 Hz from `t0`; which of `n` went raw.
    fn raw_frames(w: &mut RawWindow, t0: u64, n: u64) -> Vec<u64> {
        (0..n).filter(|i| w.take(t0 + i * S / 10)).collect()
    }

    #[test]
    fn a_window_starts_at_the_next_frame_and_lasts_its_length_of_capture_time() {
        let mut w = RawWindow::new(10.0, 60.0);
        assert_eq!(raw_frames(&mut w, 0, 5), Vec::<u64>::new());
        assert_eq!(w.request(1.0), Ok(1.0));
        assert!(w.is_open());
        // From the next frame, 1 s of capture time: 11 frames at 10 Hz (both ends).
        assert_eq!(raw_frames(&mut w, 5 * S, 20), (0..=10).collect::<Vec<_>>());
        assert!(!w.is_open());
    }

    #[test]
    fn lengths_default_cap_extend_and_refuse() {
        let mut w = RawWindow::new(0.5, 2.0);
        assert_eq!(w.request(0.0), Ok(0.5));
        assert_eq!(w.request(100.0), Ok(2.0));
        assert_eq!(raw_frames(&mut w, 0, 40).len(), 21);
        // A request inside an open window extends it from the frame after the request.
        let mut w = RawWindow::new(1.0, 60.0);
        w.request(1.0).unwrap();
        assert_eq!(raw_frames(&mut w, 0, 5).len(), 5);
        w.request(1.0).unwrap();
        assert_eq!(raw_frames(&mut w, S / 2, 30).len(), 11);
        assert!(matches!(w.request(f64::NAN), Err(Refused::BadLength(_))));
        assert!(matches!(w.request(-1.0), Err(Refused::BadLength(_))));
        let mut off = RawWindow::new(1.0, 0.0);
        assert_eq!(off.request(1.0), Err(Refused::Disabled));
        assert!(!off.take(0));
    }
}
