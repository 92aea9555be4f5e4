//! Wind: a steady mean wind plus gusts.
//!
//! The gust is an Ornstein–Uhlenbeck process per horizontal axis (exponentially correlated
//! Gaussian noise, the first-order approximation of a Dryden spectrum) with standard deviation
//! `gust_sigma_m_s` and correlation time `gust_tau_s`, integrated exactly for any step so the
//! statistics do not depend on the physics rate. Vertical wind is zero: at hub height over flat
//! ground it is small, and the altitude controller rejects it well.
//!
//! Wind vectors are air velocities in NED (where the air moves *to*, m/s); the meteorological
//! "from" direction is [`Wind::from_heading_deg`].

use crate::params::WindConfig;
use crate::rng::Rng;

/// Random stream of the wind within a seed.
const STREAM_WIND: u64 = 0x57_1D;

/// A seeded, deterministic wind process.
#[derive(Debug, Clone)]
pub struct Wind {
    rng: Rng,
    mean: [f64; 3],
    gust: [f64; 3],
    sigma: f64,
    tau: f64,
}

impl Wind {
    /// The wind of `seed`: mean speed uniform in `cfg.mean_speed_m_s`, direction uniform, and the
    /// gust started from its stationary distribution (so the statistics are the same from t = 0).
    pub fn new(seed: u64, cfg: &WindConfig) -> Wind {
        let mut rng = Rng::new(seed, STREAM_WIND);
        let speed = rng.within(cfg.mean_speed_m_s);
        let dir = rng.range(0.0, std::f64::consts::TAU);
        let sigma = cfg.gust_sigma_m_s.max(0.0);
        let gust = [sigma * rng.gaussian(), sigma * rng.gaussian(), 0.0];
        Wind {
            rng,
            mean: [speed * dir.cos(), speed * dir.sin(), 0.0],
            gust,
            sigma,
            tau: cfg.gust_tau_s,
        }
    }

    /// Advance the gust by `dt` seconds and return the wind (air velocity, NED, m/s) after it.
    /// `dt <= 0` leaves the state unchanged.
    pub fn step(&mut self, dt: f64) -> [f64; 3] {
        if dt > 0.0 && self.tau > 0.0 {
            // Exact discretisation of dg = -g/τ dt + σ√(2/τ) dW.
            let a = (-dt / self.tau).exp();
            let s = self.sigma * (1.0 - a * a).sqrt();
            for i in 0..2 {
                self.gust[i] = a * self.gust[i] + s * self.rng.gaussian();
            }
        }
        self.current()
    }

    /// The wind now (mean + gust), NED, m/s.
    pub fn current(&self) -> [f64; 3] {
        [
            self.mean[0] + self.gust[0],
            self.mean[1] + self.gust[1],
            0.0,
        ]
    }

    /// The mean wind, NED, m/s.
    pub fn mean_ned(&self) -> [f64; 3] {
        self.mean
    }

    /// The gust part of the wind now, NED, m/s.
    pub fn gust_ned(&self) -> [f64; 3] {
        self.gust
    }

    /// Meteorological direction the mean wind blows *from*, degrees clockwise from north, [0, 360).
    pub fn from_heading_deg(&self) -> f64 {
        (-self.mean[1])
            .atan2(-self.mean[0])
            .to_degrees()
            .rem_euclid(360.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_wind_and_different_seeds_differ() {
        let cfg = WindConfig::default();
        let run = |seed| {
            let mut w = Wind::new(seed, &cfg);
            (0..500).map(|_| w.step(0.005)).collect::<Vec<_>>()
        };
        assert_eq!(run(3), run(3));
        assert_ne!(run(3), run(4));
    }

    #[test]
    fn mean_speed_in_range_and_gust_statistics() {
        let cfg = WindConfig {
            mean_speed_m_s: [1.0, 3.0],
            gust_sigma_m_s: 1.5,
            gust_tau_s: 2.0,
        };
        for seed in 0..50 {
            let w = Wind::new(seed, &cfg);
            let m = w.mean_ned();
            let s = m[0].hypot(m[1]);
            assert!((1.0..=3.0).contains(&s), "{s}");
            assert_eq!(m[2], 0.0);
        }
        // Gust variance and correlation time over a long run.
        let mut w = Wind::new(11, &cfg);
        let dt = 0.05;
        let xs: Vec<f64> = (0..400_000)
            .map(|_| w.step(dt)[0] - w.mean_ned()[0])
            .collect();
        let var = xs.iter().map(|x| x * x).sum::<f64>() / xs.len() as f64;
        assert!((var.sqrt() - 1.5).abs() < 0.1, "sigma {}", var.sqrt());
        // Autocorrelation at one correlation time is e^-1.
        let lag = (2.0 / dt) as usize;
        let cov =
            xs.iter().zip(&xs[lag..]).map(|(a, b)| a * b).sum::<f64>() / (xs.len() - lag) as f64;
        assert!(
            (cov / var - (-1.0f64).exp()).abs() < 0.06,
            "rho {}",
            cov / var
        );
        assert!(xs.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn calm_config_gives_no_wind() {
        let cfg = WindConfig {
            mean_speed_m_s: [0.0, 0.0],
            gust_sigma_m_s: 0.0,
            gust_tau_s: 2.0,
        };
        let mut w = Wind::new(1, &cfg);
        for _ in 0..100 {
            assert_eq!(w.step(0.01), [0.0, 0.0, 0.0]);
        }
    }

    #[test]
    fn from_heading_is_opposite_to_the_air_velocity() {
        let mut w = Wind::new(1, &WindConfig::default());
        w.mean = [-3.0, 0.0, 0.0]; // air moving south = wind from the north
        assert!(
            (w.from_heading_deg() - 0.0).abs() < 1e-9
                || (w.from_heading_deg() - 360.0).abs() < 1e-9
        );
        w.mean = [0.0, -2.0, 0.0]; // air moving west = wind from the east
        assert!((w.from_heading_deg() - 90.0).abs() < 1e-9);
    }
}
