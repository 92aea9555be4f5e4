//! Checking a whole config file without linking any stage's code: `[run]` here, every other
//! section by the stage binary that reads it (`hubtrack-<stage> --check-config`).

use crate::launch::stage_binary;
use anyhow::{bail, Context};
use hubtrack_runtime::config::{ConfigArgs, ConfigDoc, RunConfig, RunSections};
use std::process::Command;

/// The sections read by stage binaries, each named as its stage.
pub const STAGE_SECTIONS: &[&str] = &["capture", "recorder", "detect", "track", "control", "sim"];

/// What to check beside `[run]`.
pub enum Scope<'a> {
    /// Every stage section (`hubtrack config`); a stage whose binary is not installed is checked
    /// only if the file has its section.
    All,
    /// These stages (they must be installed) and every section the file has.
    Stages(&'a [String]),
}

/// Checks the section names, `[run]` and the stage sections of `scope`; returns `[run]`.
pub fn check(args: &ConfigArgs, scope: Scope) -> anyhow::Result<RunConfig> {
    let (doc, run) = read_run(args)?;
    let mut printed = toml::Table::new();
    for stage in stages_to_read(&doc, &scope)? {
        // Printing also checks; the printed values let shared keys be compared below.
        let text = ask_stage(stage, args, "--print-config")?;
        let table: toml::Table = text
            .parse()
            .with_context(|| format!("hubtrack-{stage} --print-config printed no TOML"))?;
        printed.extend(table.into_iter().filter(|(k, _)| k == stage));
    }
    check_shared_keys(&printed)?;
    Ok(run)
}

/// Keys that detect and track each read and that must agree: the lens and the turbine's sizes
/// (each stage estimates distance and yaw from them).
pub const SHARED_KEYS: &[(&str, &str)] = &[
    ("detect.camera.hfov_deg", "track.camera.hfov_deg"),
    (
        "detect.camera.focal_length_per_width",
        "track.camera.focal_length_per_width",
    ),
    (
        "detect.camera.tower_top_diameter_m",
        "track.distance.tower_diameter_m",
    ),
    (
        "detect.camera.hub_tower_gap_m",
        "track.yaw.hub_tower_offset_m",
    ),
    (
        "detect.camera.spinner_diameter_m",
        "track.distance.spinner_diameter_m",
    ),
];

/// Fails when two keys of [`SHARED_KEYS`] that both stages printed differ.
pub fn check_shared_keys(printed: &toml::Table) -> anyhow::Result<()> {
    let get = |key: &str| -> Option<&toml::Value> {
        let mut parts = key.split('.');
        let mut value = printed.get(parts.next()?)?;
        for part in parts {
            value = value.get(part)?;
        }
        Some(value)
    };
    for (a, b) in SHARED_KEYS {
        if let (Some(va), Some(vb)) = (get(a), get(b)) {
            if va != vb {
                bail!("config key `{a}` = {va} must equal `{b}` = {vb}: detect and track must use the same lens and turbine");
            }
        }
    }
    Ok(())
}

/// Every section (defaults, file and overrides) as one TOML document.
pub fn print(args: &ConfigArgs) -> anyhow::Result<String> {
    let (doc, run) = read_run(args)?;
    let mut all = toml::Table::try_from(RunSections { run })?;
    for stage in stages_to_read(&doc, &Scope::All)? {
        let text = ask_stage(stage, args, "--print-config")?;
        let mut table: toml::Table = text
            .parse()
            .with_context(|| format!("hubtrack-{stage} --print-config printed no TOML"))?;
        table.remove("run");
        all.extend(table);
    }
    Ok(toml::to_string(&all)?)
}

fn read_run(args: &ConfigArgs) -> anyhow::Result<(ConfigDoc, RunConfig)> {
    let doc = args.document()?;
    doc.check_section_names()?;
    let run = doc.sections::<RunSections>()?.run;
    Ok((doc, run))
}

fn stages_to_read(doc: &ConfigDoc, scope: &Scope) -> anyhow::Result<Vec<&'static str>> {
    let present = |s: &str| doc.section_names().any(|n| n == s);
    let runs = |s: &str| matches!(scope, Scope::Stages(run) if run.iter().any(|r| r == s));
    let mut stages = Vec::new();
    for &stage in STAGE_SECTIONS {
        let needed = present(stage) || runs(stage);
        if !needed && !matches!(scope, Scope::All) {
            continue;
        }
        match stage_binary(stage) {
            Ok(_) => stages.push(stage),
            Err(e) if needed => return Err(e),
            Err(_) => log::debug!("[{stage}] not checked: hubtrack-{stage} is not installed"),
        }
    }
    Ok(stages)
}

/// Runs `hubtrack-<stage> <config args> <flag>`; its stdout, or its error message as ours.
fn ask_stage(stage: &str, args: &ConfigArgs, flag: &str) -> anyhow::Result<String> {
    let binary = stage_binary(stage)?;
    let out = Command::new(&binary)
        .args(args.to_args())
        .arg(flag)
        .env("RUST_LOG", "warn")
        .output()
        .with_context(|| format!("cannot run {}", binary.display()))?;
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        let message = stderr
            .lines()
            .rev()
            .find_map(|l| l.split_once("error: ").map(|(_, m)| m.to_string()))
            .unwrap_or_else(|| stderr.trim().to_string());
        bail!("{message}");
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}
