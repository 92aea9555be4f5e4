//! Pacing of sources that do not pace themselves.

use std::time::{Duration, Instant};

/// Releases frames at a fixed rate without drift: deadlines advance by exact periods; if a frame
/// ran late the schedule restarts from now instead of bursting to catch up.
pub struct Pacer {
    period: Option<Duration>,
    next: Instant,
}

impl Pacer {
    /// `fps = None` releases immediately (fast mode, self-paced cameras).
    pub fn new(fps: Option<f64>) -> Pacer {
        Pacer {
            period: fps
                .filter(|f| *f > 0.0)
                .map(|f| Duration::from_secs_f64(1.0 / f)),
            next: Instant::now(),
        }
    }

    /// Sleeps until the next frame is due.
    pub fn wait(&mut self) {
        let Some(period) = self.period else { return };
        let now = Instant::now();
        if self.next > now {
            std::thread::sleep(self.next - now);
            self.next += period;
        } else {
            self.next = now + period;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_mode_never_sleeps() {
        let mut p = Pacer::new(None);
        let t = Instant::now();
        for _ in 0..1000 {
            p.wait();
        }
        assert!(t.elapsed() < Duration::from_millis(50));
    }

    #[test]
    fn paced_mode_keeps_at_least_the_period() {
        let mut p = Pacer::new(Some(200.0));
        let t = Instant::now();
        for _ in 0..11 {
            p.wait();
        }
        // 10 periods of 5 ms after the first immediate release: never faster than the rate.
        assert!(t.elapsed() >= Duration::from_millis(50));
    }
}
