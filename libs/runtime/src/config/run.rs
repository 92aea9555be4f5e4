//! `[run]`: which stages `hubtrack run` starts, how it watches, restarts and stops them.

use hubtrack_types::params;
use hubtrack_types::params::{Check, ParamError};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The stage names `[run].stages` may contain.
pub const KNOWN_STAGES: &[&str] = &[
    "capture", "sim", "recorder", "detect", "track", "control", "live",
];

/// Default niceness of the stages that do not run at 0 (see [`RunConfig::nice`]).
pub const DEFAULT_NICE: &[(&str, i32)] = &[("recorder", 10), ("live", 10)];

params! {
    /// `[run]`: which stages `hubtrack run` starts and how it stops them.
    pub struct RunConfig {
        /// Stage processes to start. They start in pipeline order (recorder first, so it misses
        /// nothing) and stop in reverse (control first, recorder last), whatever the order here.
        pub stages: Vec<String> = vec!["capture".into(), "recorder".into()];
        /// Folder for recordings when `--record` is not given (relative to the working directory).
        pub record_dir: PathBuf = PathBuf::from("out");
        /// How long a stage may take to exit after SIGTERM before it is killed, ms.
        pub stop_timeout_ms: u64 = 3000, closed(100, 60_000);
        /// How long a stage may take from start to its first heartbeat, ms.
        pub startup_timeout_ms: u64 = 5000, closed(100, 60_000);
        /// Interval of each stage's status heartbeat, ms.
        pub status_interval_ms: u64 = 250, closed(20, 10_000);
        /// The stages get SIGTERM when the supervisor process dies (`kill -9`, a crash), so none
        /// is left running unsupervised. Off for `hubtrack run` by default: in flight a
        /// supervisor crash then leaves the pipeline flying rather than turning into the
        /// autopilot's guided timeout. `hubtrack fly` always sets it (simulated flights must not
        /// leave stages behind).
        pub stop_with_supervisor: bool = false;
        /// What the supervisor does when a stage dies or hangs.
        pub restart: RestartConfig = RestartConfig::default();
        /// Scheduling niceness per stage, added to the niceness `hubtrack run` itself runs at (a
        /// systemd `Nice=` sets the base), -20 … 19. A stage not listed keeps its default: +10
        /// for the recorder and the live view, 0 for the others (see [`RunConfig::nice_of`]).
        /// The recorder is throughput-bound (its queue absorbs delays) while detect → track →
        /// control is latency-bound, so on a 2-core computer the recorder yields the CPU to
        /// them. Going below the base needs CAP_SYS_NICE.
        pub nice: BTreeMap<String, i32> =
            DEFAULT_NICE.iter().map(|(n, v)| (n.to_string(), *v)).collect();
    }
}

/// When a stage is restarted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RestartPolicy {
    /// Never: a stage that ends stays down.
    Never,
    /// When it exits with an error, is killed by a signal, or stops heart-beating.
    OnFailure,
    /// Whenever it ends, also after a clean exit.
    Always,
}

params! {
    /// `[run.restart]`: restart policy, back-off, crash-loop limit and liveness.
    pub struct RestartConfig {
        /// Policy of every stage not listed in `policy`.
        pub default_policy: RestartPolicy = RestartPolicy::OnFailure;
        /// Per-stage policy, e.g. `capture = "never"`.
        pub policy: BTreeMap<String, RestartPolicy> = BTreeMap::new();
        /// Delay before the first restart, ms; doubled after each restart inside the window.
        pub backoff_initial_ms: u64 = 100, closed(0, 60_000);
        /// Longest delay between restarts, ms (at least `backoff_initial_ms`).
        pub backoff_max_ms: u64 = 5000, closed(0, 600_000);
        /// A stage restarted this many times within `window_s` is given up on (the others go on).
        pub max_restarts: u32 = 5, closed(0, 1000);
        /// The crash-loop window, seconds.
        pub window_s: f64 = 60.0, closed(1.0, 86_400.0);
        /// A stage given up on is tried again this long after, seconds (0: never): a cause
        /// that goes away (a disk freed, a device plugged back) does not keep it down for the
        /// rest of the run.
        pub retry_after_s: f64 = 60.0, zero_or_closed(1.0, 86_400.0);
        /// A running stage that sends no heartbeat for this long is hung: it is killed and
        /// restarted, ms (at least 4 × `run.status_interval_ms`).
        pub liveness_timeout_ms: u64 = 1500, closed(0, 600_000);
    }
}

impl RestartConfig {
    /// The policy of `stage`.
    pub fn policy_of(&self, stage: &str) -> RestartPolicy {
        self.policy
            .get(stage)
            .copied()
            .unwrap_or(self.default_policy)
    }
}

impl RunConfig {
    /// The niceness stage `name` runs at: `[run.nice]`, else its default.
    pub fn nice_of(&self, name: &str) -> i32 {
        self.nice.get(name).copied().unwrap_or_else(|| {
            DEFAULT_NICE
                .iter()
                .find(|(n, _)| *n == name)
                .map_or(0, |(_, v)| *v)
        })
    }

    /// Checks every value of `[run]`; errors name the key.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges("run")?;
        let stage_name = |key: String, stage: &str| -> Result<(), ParamError> {
            if KNOWN_STAGES.contains(&stage) {
                Ok(())
            } else {
                Err(ParamError {
                    key,
                    value: format!("{stage:?}"),
                    allowed: format!("a stage of {KNOWN_STAGES:?}"),
                    problem: None,
                })
            }
        };
        for s in &self.stages {
            stage_name("run.stages".into(), s)?;
        }
        if self.stages.iter().any(|s| s == "sim") && self.stages.iter().any(|s| s == "capture") {
            return Err(ParamError {
                key: "run.stages".into(),
                value: format!("{:?}", self.stages),
                allowed: "either \"capture\" or \"sim\" (both publish frames)".into(),
                problem: None,
            });
        }
        for (stage, nice) in &self.nice {
            stage_name(format!("run.nice.{stage}"), stage)?;
            Check::new("run.nice").closed(stage, f64::from(*nice), -20.0, 19.0)?;
        }
        let rs = &self.restart;
        rs.check_ranges("run.restart")?;
        for stage in rs.policy.keys() {
            stage_name(format!("run.restart.policy.{stage}"), stage)?;
        }
        let c = Check::new("run.restart");
        c.closed(
            "backoff_max_ms",
            rs.backoff_max_ms as f64,
            rs.backoff_initial_ms as f64,
            600_000.0,
        )?;
        c.closed(
            "liveness_timeout_ms",
            rs.liveness_timeout_ms as f64,
            (4 * self.status_interval_ms) as f64,
            600_000.0,
        )
    }
}
