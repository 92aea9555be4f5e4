//! The two keys that name files rather than values: `camera.calibration` (a ROS `camera_info`
//! YAML) and `turbine.profile` (a TOML file with the keys of `[turbine]`).
//!
//! Relative paths in a config file are relative to that file; on the command line (`--camera`,
//! `--turbine`, `--set`) relative to the working directory. Paths are made absolute here, so that
//! the stage processes the supervisor starts read the same files. A profile's keys replace the
//! config file's `[turbine]` keys, except keys given with `--set`, which win.

use super::{parse_table, quoted, read_bounded, ConfigDoc, ConfigError};
use hubtrack_types::setup::TurbineSetup;
use std::path::{Path, PathBuf};

/// `(section, key)` of every key that holds a file path.
const PATH_KEYS: [(&str, &str); 3] = [
    ("camera", "calibration"),
    ("turbine", "profile"),
    ("control", "signing_key_file"),
];

impl ConfigDoc {
    /// Makes the path keys absolute, relative ones taken relative to `base`.
    pub(super) fn absolutize_paths(&mut self, base: &Path) {
        for (section, key) in PATH_KEYS {
            let Some(toml::Value::String(path)) = self
                .table
                .get_mut(section)
                .and_then(|s| s.as_table_mut())
                .and_then(|s| s.get_mut(key))
            else {
                continue;
            };
            if !path.is_empty() && Path::new(path.as_str()).is_relative() {
                *path = base.join(path.as_str()).display().to_string();
            }
        }
    }

    /// Fills `[turbine]` from the profile named by `turbine.profile`, leaving the keys in
    /// `explicit` (given with `--set`) as they are.
    pub(super) fn apply_turbine_profile(&mut self, explicit: &[String]) -> Result<(), ConfigError> {
        let Some(turbine) = self.table.get("turbine").and_then(|t| t.as_table()) else {
            return Ok(());
        };
        let path = match turbine.get("profile") {
            Some(toml::Value::String(p)) if !p.is_empty() => PathBuf::from(p),
            _ => return Ok(()),
        };
        let profile = read_profile(&path)?;
        let section = self
            .table
            .get_mut("turbine")
            .and_then(|t| t.as_table_mut())
            .expect("checked above");
        for (key, value) in profile {
            if !explicit.iter().any(|k| k == &key) {
                section.insert(key, value);
            }
        }
        Ok(())
    }
}

/// Reads and checks a turbine profile: a TOML file of `[turbine]` keys (without `profile`)
/// stating at least [`TurbineSetup::PROFILE_REQUIRED`]. Keys that are not `[turbine]` keys (a
/// datasheet's rated power, a manufacturer) are left out with a warning naming them: a profile
/// describes a turbine, and may say more of it than hubtrack uses.
fn read_profile(path: &Path) -> Result<toml::Table, ConfigError> {
    let origin = format!("turbine profile {}", path.display());
    let text = read_bounded(path, "turbine profile")?;
    let mut table = parse_table(&text, &origin)?;
    if table.contains_key("profile") {
        return Err(ConfigError::Invalid {
            origin,
            key: "profile".into(),
            message: "a profile cannot name another profile".into(),
        });
    }
    let unused: Vec<String> = table
        .keys()
        .filter(|k| !TurbineSetup::KEYS.contains(&k.as_str()))
        .cloned()
        .collect();
    let missing: Vec<&str> = TurbineSetup::PROFILE_REQUIRED
        .into_iter()
        .filter(|k| !table.contains_key(*k))
        .collect();
    if !missing.is_empty() {
        let instead = if unused.is_empty() {
            String::new()
        } else {
            format!(
                "; it has {}, which no [turbine] key is called",
                unused.join(", ")
            )
        };
        return Err(ConfigError::Invalid {
            origin,
            key: missing.join(", "),
            message: format!(
                "missing: a turbine profile states {} (m){instead}",
                TurbineSetup::PROFILE_REQUIRED.join(", ")
            ),
        });
    }
    if !unused.is_empty() {
        log::warn!(
            "{origin}: not used (no such [turbine] key): {}; the keys are {}",
            unused.join(", "),
            TurbineSetup::KEYS
                .iter()
                .filter(|k| **k != "profile")
                .copied()
                .collect::<Vec<_>>()
                .join(", ")
        );
        table.retain(|k, _| TurbineSetup::KEYS.contains(&k));
    }
    let parsed: TurbineSetup = serde_path_to_error::deserialize(toml::Value::Table(table.clone()))
        .map_err(|e| ConfigError::Invalid {
            origin: origin.clone(),
            key: quoted(&e.path().to_string()),
            message: quoted(e.into_inner().to_string().trim()),
        })?;
    parsed
        .validate()
        .map_err(|e| ConfigError::of_param(origin, e))?;
    Ok(table)
}
