//! The whole configuration, every section at once: the lab runs detector, tracker, approach and
//! simulator in one process, so it reads them all, and is where the documented files are
//! checked against the defaults.

use hubtrack_runtime::config::{ConfigArgs, LiveConfig, ParamError, RunConfig, Sections};
use hubtrack_types::setup::{CameraSetup, Lens, TurbineSetup};
use serde::{Deserialize, Serialize};

/// Every section of a config file.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LabConfig {
    /// `[run]`.
    pub run: RunConfig,
    /// `[camera]`.
    pub camera: CameraSetup,
    /// `[turbine]`.
    pub turbine: TurbineSetup,
    /// `[capture]`.
    pub capture: hubtrack_capture::config::CaptureConfig,
    /// `[recorder]`.
    pub recorder: hubtrack_record::config::RecorderConfig,
    /// `[detect]`.
    pub detect: hubtrack_detect::params::DetectConfig,
    /// `[track]`.
    pub track: hubtrack_track::params::TrackConfig,
    /// `[control]`: read here as TOML only, the control stage owns its type.
    pub control: toml::Table,
    /// `[sim]`.
    pub sim: hubtrack_sim::SimConfig,
    /// `[live]`.
    pub live: LiveConfig,
}

impl Sections for LabConfig {
    fn validate(&self) -> Result<(), ParamError> {
        self.run.validate()?;
        self.camera.validate()?;
        self.turbine.validate()?;
        self.capture.validate()?;
        self.recorder.validate()?;
        self.detect.validate()?;
        self.track.validate()?;
        self.live.validate()?;
        self.sim.validate()
    }
}

/// Reads every section from `args` (file and overrides).
/// Reads every section from `args` (file and overrides); detect and track get the lens and
/// turbine of `[camera]` and `[turbine]`, as their stages do.
pub fn load(args: &ConfigArgs) -> anyhow::Result<LabConfig> {
    let mut config = args.load::<LabConfig>()?;
    let lens = Lens::new(&config.camera)?;
    config.detect = config.detect.with_setup(&lens, &config.turbine);
    config.track = config.track.with_setup(&lens, &config.turbine);
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;
    use hubtrack_runtime::config::ConfigDoc;
    use std::path::Path;

    fn config_dir() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config")
    }

    #[test]
    fn the_documented_file_equals_the_defaults() {
        let doc = ConfigDoc::load(&config_dir().join("hubtrack.toml")).unwrap();
        let from_file: LabConfig = doc.sections().unwrap();
        // `[control]` is kept as TOML here; its defaults are checked by the control stage.
        let defaults = LabConfig {
            control: from_file.control.clone(),
            ..LabConfig::default()
        };
        assert_eq!(from_file, defaults);
    }

    #[test]
    fn every_shipped_config_file_is_valid() {
        let mut n = 0;
        for entry in std::fs::read_dir(config_dir()).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let doc = ConfigDoc::load(&path).unwrap();
                doc.check_section_names().unwrap();
                doc.sections::<LabConfig>()
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                n += 1;
            }
        }
        assert!(
            n >= 3,
            "config/ has hubtrack.toml, demo.toml and flight.toml"
        );
    }
}
