//! Configuration loading: one TOML file plus `--set KEY=VALUE` overrides, read section by section.
//!
//! A process reads only the sections it uses ([`Sections`]): the detect stage `[detect]`, the
//! recorder `[recorder]`, and so on, each with its own types from the crate that uses them, so no
//! process links another stage's code to read its configuration. Parsing inside a section is
//! strict (an unknown key is an error naming its full path, e.g. `capture.synthetic.fsp`) and
//! every value is checked against its declared range. Keys left out take the documented defaults.
//! `hubtrack config` checks a whole file by asking every stage binary to check its sections.

mod files;
mod live;
mod run;

pub use live::LiveConfig;
pub use run::{RestartConfig, RestartPolicy, RunConfig, DEFAULT_NICE, KNOWN_STAGES};

pub use hubtrack_types::params::ParamError;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Largest config file read, bytes: a config is a few kB; this refuses `/dev/zero` and the like
/// before they fill the memory.
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;
/// Longest value quoted back in an error message, characters.
const MAX_QUOTED_CHARS: usize = 120;

/// The top-level sections a config file may have: `[run]`, the `[camera]` and `[turbine]` that
/// detect and track share, and one per stage.
pub const KNOWN_SECTIONS: &[&str] = &[
    "run", "camera", "turbine", "capture", "recorder", "detect", "track", "control", "sim", "live",
];

/// Why a config could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read {what} {path}: {cause}")]
    Io {
        /// What the file is: `config file`, `turbine profile`.
        what: &'static str,
        /// The file.
        path: PathBuf,
        /// The OS error (not a `source`: the message already says it, and error chains would
        /// print it twice).
        cause: std::io::Error,
    },
    /// The file is larger than any config.
    #[error("{what} {path} is larger than {MAX_CONFIG_BYTES} bytes: not one of hubtrack's")]
    TooLarge {
        /// What the file is: `config file`, `turbine profile`.
        what: &'static str,
        /// The file.
        path: PathBuf,
    },
    /// TOML syntax error, unknown key or wrong type.
    #[error("config {origin}: key `{key}`: {message}")]
    Invalid {
        /// File name, "defaults" or "--set".
        origin: String,
        /// Full dotted key path.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A value outside its allowed range.
    #[error("config {origin}: key `{key}` = {value} is out of range: allowed {allowed}")]
    OutOfRange {
        /// File name, "defaults" or "--set".
        origin: String,
        /// Full dotted key path.
        key: String,
        /// The value given.
        value: String,
        /// The allowed range or set.
        allowed: String,
    },
}

impl ConfigError {
    /// A value the checks refused: out of its range, or naming something that cannot be used
    /// (then `Invalid`, saying what is wrong with it, not that it is out of range).
    pub(crate) fn of_param(origin: String, e: ParamError) -> ConfigError {
        match e.problem {
            Some(problem) => ConfigError::Invalid {
                origin,
                key: e.key,
                message: ParamError::unusable(&quoted(&e.value), &problem, &e.allowed),
            },
            None => ConfigError::OutOfRange {
                origin,
                key: e.key,
                value: quoted(&e.value),
                allowed: e.allowed,
            },
        }
    }
}

/// The sections one process reads, composed from the section types of the crates it uses.
///
/// Implementors are plain structs with one field per section, named as the section, with
/// `#[serde(default)]` and *without* `deny_unknown_fields` at the top level (the other stages'
/// sections are none of this process's business); each section type denies unknown keys itself.
pub trait Sections: DeserializeOwned + Serialize + Default {
    /// Checks ranges and constraints across keys; errors name the full key.
    fn validate(&self) -> Result<(), ParamError>;
}

/// A parsed config file with the command line's overrides applied, not yet read into types.
#[derive(Debug, Clone, Default)]
pub struct ConfigDoc {
    table: toml::Table,
    origin: String,
}

impl ConfigDoc {
    /// The empty document: every section at its defaults.
    pub fn defaults() -> ConfigDoc {
        ConfigDoc {
            table: toml::Table::new(),
            origin: "defaults".into(),
        }
    }

    /// Reads a config file (at most [`MAX_CONFIG_BYTES`]).
    pub fn load(path: &Path) -> Result<ConfigDoc, ConfigError> {
        let text = read_bounded(path, "config file")?;
        let mut doc = ConfigDoc::parse(&text, &path.display().to_string())?;
        // Paths in a file are relative to the file.
        if let Some(dir) = path.parent() {
            doc.absolutize_paths(&std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf()));
        }
        Ok(doc)
    }

    /// Parses TOML text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<ConfigDoc, ConfigError> {
        let table = parse_table(text, origin)?;
        Ok(ConfigDoc {
            table,
            origin: origin.to_string(),
        })
    }

    /// Applies `key=value` overrides (TOML values, e.g. `capture.fps=60`; an unquoted word such
    /// as `images` is taken as a string).
    pub fn apply_overrides(&mut self, overrides: &[String]) -> Result<(), ConfigError> {
        for ov in overrides {
            let invalid = |key: &str, message: String| ConfigError::Invalid {
                origin: "--set".into(),
                key: quoted(key),
                message,
            };
            let (key, value) = ov
                .split_once('=')
                .ok_or_else(|| invalid(ov, "expected KEY=VALUE".into()))?;
            let key = key.trim();
            let parts: Vec<&str> = key.split('.').collect();
            if parts.iter().any(|p| p.is_empty()) {
                return Err(invalid(
                    key,
                    "expected a dotted key such as capture.fps".into(),
                ));
            }
            let parsed: toml::Value = format!("v = {}", value.trim())
                .parse::<toml::Table>()
                .ok()
                .and_then(|mut t| t.remove("v"))
                .unwrap_or_else(|| toml::Value::String(value.trim().to_string()));
            let mut table = &mut self.table;
            for part in &parts[..parts.len() - 1] {
                table = table
                    .entry(part.to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                    .as_table_mut()
                    .ok_or_else(|| invalid(key, format!("`{part}` is not a section")))?;
            }
            table.insert(parts[parts.len() - 1].to_string(), parsed);
        }
        if !overrides.is_empty() {
            self.origin = format!("{} with --set", self.origin);
        }
        Ok(())
    }

    /// The top-level sections present, in file order.
    pub fn section_names(&self) -> impl Iterator<Item = &str> {
        self.table.keys().map(String::as_str)
    }

    /// Fails on a top-level section that no part of hubtrack reads.
    pub fn check_section_names(&self) -> Result<(), ConfigError> {
        match self.section_names().find(|s| !KNOWN_SECTIONS.contains(s)) {
            Some(s) => Err(ConfigError::Invalid {
                origin: self.origin.clone(),
                key: quoted(s),
                message: format!("unknown section, expected one of {KNOWN_SECTIONS:?}"),
            }),
            None => Ok(()),
        }
    }

    /// Reads and validates the sections of `C`; other sections are left alone.
    pub fn sections<C: Sections>(&self) -> Result<C, ConfigError> {
        let origin = &self.origin;
        let value = toml::Value::Table(self.table.clone());
        let sections: C = serde_path_to_error::deserialize(value).map_err(|e| {
            let key = e.path().to_string();
            ConfigError::Invalid {
                origin: origin.clone(),
                key: quoted(&key),
                message: quoted(e.into_inner().to_string().trim()),
            }
        })?;
        sections
            .validate()
            .map_err(|e| ConfigError::of_param(origin.clone(), e))?;
        Ok(sections)
    }

    /// Where the document came from, for messages.
    pub fn origin(&self) -> &str {
        &self.origin
    }
}

/// Reads a TOML file of at most [`MAX_CONFIG_BYTES`]; `what` it is (a `config file`, a
/// `turbine profile`) names it in errors.
fn read_bounded(path: &Path, what: &'static str) -> Result<String, ConfigError> {
    let io = |cause| ConfigError::Io {
        what,
        path: path.to_path_buf(),
        cause,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let mut text = String::new();
    file.take(MAX_CONFIG_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(io)?;
    if text.len() as u64 > MAX_CONFIG_BYTES {
        return Err(ConfigError::TooLarge {
            what,
            path: path.to_path_buf(),
        });
    }
    Ok(text)
}

/// Parses a TOML document; a syntax error names `origin` and keeps its reason: each line of
/// the parser's message is cut by [`quoted`] on its own, so that a long line quoted from the
/// file does not cut off the reason printed under it.
fn parse_table(text: &str, origin: &str) -> Result<toml::Table, ConfigError> {
    text.parse::<toml::Table>()
        .map_err(|e| ConfigError::Invalid {
            origin: origin.to_string(),
            key: "(syntax)".into(),
            message: e
                .to_string()
                .trim()
                .lines()
                .map(quoted)
                .collect::<Vec<_>>()
                .join("\n"),
        })
}

/// Cuts a user-given text to [`MAX_QUOTED_CHARS`] for an error message.
fn quoted(text: &str) -> String {
    match text.char_indices().nth(MAX_QUOTED_CHARS) {
        Some((cut, _)) => format!("{}… ({} bytes)", &text[..cut], text.len()),
        None => text.to_string(),
    }
}

/// A config file's path; an empty one (most often `HUBTRACK_CONFIG=` left set) is refused
/// saying what to do, where clap would only say that a value is missing.
fn config_path(text: &str) -> Result<PathBuf, String> {
    if text.is_empty() {
        Err("empty: name a config file, or unset HUBTRACK_CONFIG for the built-in defaults".into())
    } else {
        Ok(PathBuf::from(text))
    }
}

/// Command-line options of every process that reads the config: `--config FILE`, `--set K=V`,
/// and the camera calibration and turbine profile files.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct ConfigArgs {
    /// Config file (TOML); default: built-in defaults, as documented in config/hubtrack.toml.
    #[arg(long, short = 'c', value_name = "FILE", env = "HUBTRACK_CONFIG", value_parser = config_path)]
    pub config: Option<PathBuf>,
    /// Override one key, e.g. `--set capture.fps=60` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,
    /// Camera calibration, ROS camera_info YAML (e.g. config/cameras/*.yaml); the same as
    /// `--set camera.calibration=FILE`.
    #[arg(long = "camera", value_name = "CAL.yaml")]
    pub camera: Option<PathBuf>,
    /// Turbine profile, TOML (e.g. config/turbines/*.toml); the same as
    /// `--set turbine.profile=FILE`.
    #[arg(long = "turbine", value_name = "T.toml")]
    pub turbine: Option<PathBuf>,
}

impl ConfigArgs {
    /// The file (or the defaults) with the overrides applied, file paths made absolute and the
    /// turbine profile read in.
    pub fn document(&self) -> Result<ConfigDoc, ConfigError> {
        let mut doc = match &self.config {
            Some(path) => ConfigDoc::load(path)?,
            None => ConfigDoc::defaults(),
        };
        let mut overrides = self.overrides.clone();
        let as_toml = |p: &Path| toml::Value::String(p.display().to_string()).to_string();
        if let Some(c) = &self.camera {
            overrides.push(format!("camera.calibration={}", as_toml(c)));
        }
        if let Some(t) = &self.turbine {
            overrides.push(format!("turbine.profile={}", as_toml(t)));
        }
        doc.apply_overrides(&overrides)?;
        if let Ok(cwd) = std::env::current_dir() {
            doc.absolutize_paths(&cwd);
        }
        let explicit: Vec<String> = overrides
            .iter()
            .filter_map(|o| o.split_once('=')?.0.trim().strip_prefix("turbine."))
            .map(str::to_string)
            .collect();
        doc.apply_turbine_profile(&explicit)?;
        Ok(doc)
    }

    /// Reads and validates the sections of `C`.
    pub fn load<C: Sections>(&self) -> Result<C, ConfigError> {
        self.document()?.sections()
    }

    /// The same options as arguments for a child process (paths absolute, so that a child in
    /// another working directory reads the same files).
    pub fn to_args(&self) -> Vec<String> {
        let absolute = |p: &Path| {
            std::path::absolute(p)
                .unwrap_or_else(|_| p.to_path_buf())
                .display()
                .to_string()
        };
        let mut args = Vec::new();
        if let Some(c) = &self.config {
            args.push("--config".to_string());
            args.push(c.display().to_string());
        }
        for o in &self.overrides {
            args.push("--set".to_string());
            args.push(o.clone());
        }
        if let Some(c) = &self.camera {
            args.push("--camera".to_string());
            args.push(absolute(c));
        }
        if let Some(t) = &self.turbine {
            args.push("--turbine".to_string());
            args.push(absolute(t));
        }
        args
    }
}

crate::sections! {
    /// The `[run]` section alone, for processes that read nothing else.
    pub struct RunSections { run: RunConfig }
}

crate::sections! {
    /// The `[live]` section: the live-view stage and the supervisor (which starts it) read it.
    pub struct LiveSections { live: LiveConfig }
}

#[cfg(test)]
mod tests;

/// Declares the sections one process reads: a struct with one field per section, named as the
/// section, whose [`Sections::validate`] calls each section's own `validate`.
///
/// ```ignore
/// hubtrack_runtime::sections! {
///     /// What the detect stage reads.
///     pub struct DetectSections { detect: hubtrack_detect::params::DetectConfig }
/// }
/// ```
#[macro_export]
macro_rules! sections {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident { $( $(#[$fmeta:meta])* $field:ident : $ty:ty ),* $(,)? }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(default)]
        $vis struct $name {
            $( $(#[$fmeta])* #[doc = concat!("`[", stringify!($field), "]`.")] pub $field: $ty, )*
        }

        impl $crate::config::Sections for $name {
            fn validate(&self) -> Result<(), $crate::config::ParamError> {
                $( self.$field.validate()?; )*
                Ok(())
            }
        }
    };
}
