//! The bandwidth cap: a frame-rate gate per channel and a bitrate budget, plain state driven by
//! the caller's clock (nanoseconds), so they are tested without sleeping.

/// Lets through at most one event per `period`: on average exactly `1 / period` events per
/// second when the input is faster (the next slot is counted from the previous slot, not from
/// the late event that used it), never a burst after a pause.
#[derive(Debug, Clone)]
pub struct RateGate {
    period_ns: u64,
    next_ns: Option<u64>,
}

impl RateGate {
    /// A gate for `hz` events per second (`hz` > 0).
    pub fn new(hz: f64) -> RateGate {
        RateGate {
            period_ns: (1e9 / hz.max(1e-3)) as u64,
            next_ns: None,
        }
    }

    /// Whether an event at `now_ns` may pass (without taking the slot).
    pub fn due(&self, now_ns: u64) -> bool {
        self.next_ns.is_none_or(|next| now_ns >= next)
    }

    /// Takes the slot for an event that passed at `now_ns`.
    pub fn take(&mut self, now_ns: u64) {
        let next = match self.next_ns {
            // On schedule: the next slot follows this one, so the average rate is exact.
            Some(next) if now_ns < next + self.period_ns => next + self.period_ns,
            // After a pause (no input, no client): start again from now, no catch-up burst.
            _ => now_ns + self.period_ns,
        };
        self.next_ns = Some(next);
    }

    /// Passes and takes the slot in one go.
    pub fn pass(&mut self, now_ns: u64) -> bool {
        let due = self.due(now_ns);
        if due {
            self.take(now_ns);
        }
        due
    }
}

/// A token bucket of bytes refilled at `kbps`, holding at most one second's worth: what was sent
/// in any second stays within the cap plus one frame.
#[derive(Debug, Clone)]
pub struct ByteBudget {
    bytes_per_s: f64,
    tokens: f64,
    at_ns: Option<u64>,
}

impl ByteBudget {
    /// A budget of `kbps` kbit/s.
    pub fn new(kbps: f64) -> ByteBudget {
        let bytes_per_s = kbps * 1000.0 / 8.0;
        ByteBudget {
            bytes_per_s,
            tokens: bytes_per_s,
            at_ns: None,
        }
    }

    fn refill(&mut self, now_ns: u64) {
        if let Some(at) = self.at_ns {
            let dt = now_ns.saturating_sub(at) as f64 * 1e-9;
            self.tokens = (self.tokens + dt * self.bytes_per_s).min(self.bytes_per_s);
        }
        self.at_ns = Some(now_ns);
    }

    /// Whether a frame may be sent at `now_ns`: the budget is not overdrawn.
    pub fn available(&mut self, now_ns: u64) -> bool {
        self.refill(now_ns);
        self.tokens > 0.0
    }

    /// Spends `bytes` sent at `now_ns` (the budget may go negative by the last frame: the frames
    /// after it wait until it is paid back).
    pub fn spend(&mut self, bytes: usize, now_ns: u64) {
        self.refill(now_ns);
        self.tokens -= bytes as f64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    #[test]
    fn gate_keeps_the_average_rate_of_a_faster_input() {
        // 30 fps camera, 5 fps gate, 10 s: 50 frames pass.
        let mut gate = RateGate::new(5.0);
        let passed = (0..300u64)
            .filter(|i| gate.pass(i * 1000 * MS / 30))
            .count();
        assert_eq!(passed, 50);
    }

    #[test]
    fn gate_does_not_burst_after_a_pause() {
        let mut gate = RateGate::new(10.0);
        assert!(gate.pass(0));
        assert!(!gate.pass(50 * MS));
        // Five seconds without input: one event passes, the next waits a full period.
        assert!(gate.pass(5000 * MS));
        assert!(!gate.pass(5001 * MS));
        assert!(gate.pass(5100 * MS));
    }

    #[test]
    fn budget_caps_the_bitrate() {
        // 800 kbit/s = 100 kB/s; 30 frames/s of 10 kB offered for 10 s: about 100 pass.
        let mut budget = ByteBudget::new(800.0);
        let mut sent = 0u64;
        for i in 0..300u64 {
            let now = i * 1000 * MS / 30;
            if budget.available(now) {
                budget.spend(10_000, now);
                sent += 10_000;
            }
        }
        let kbps = sent as f64 * 8.0 / 1000.0 / 10.0;
        assert!((800.0..=800.0 * 1.15).contains(&kbps), "{kbps} kbit/s");
    }

    #[test]
    fn budget_refills_only_up_to_one_second() {
        let mut budget = ByteBudget::new(80.0); // 10 kB/s
        budget.spend(15_000, 0);
        assert!(!budget.available(MS), "overdrawn: waits until paid back");
        assert!(budget.available(600 * MS));
        // A minute idle does not save up more than one second's worth: 15 kB overdraw it again.
        assert!(budget.available(60_000 * MS));
        budget.spend(15_000, 60_000 * MS);
        assert!(!budget.available(60_001 * MS));
    }
}
