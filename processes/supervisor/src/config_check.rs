//! Checking a whole config file without linking any stage's code: `[run]` here, every other
//! section by the stage binary that reads it (`hubtrack-<stage> --check-config`).

use crate::launch::stage_binary;
use anyhow::{bail, Context};
use hubtrack_runtime::config::{ConfigArgs, ConfigDoc, RunConfig, RunSections};
use std::process::Command;

/// The stage binaries that read sections, each its own (named as the stage).
pub const STAGE_SECTIONS: &[&str] = &[
    "capture", "recorder", "detect", "track", "control", "sim", "live",
];
/// Sections several stages read, and the stages that read them.
const SHARED_SECTIONS: &[(&str, &[&str])] = &[
    ("camera", &["detect", "track", "control"]),
    ("turbine", &["detect", "track", "control"]),
];

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
    for stage in stages_to_read(&doc, &scope)? {
        ask_stage(stage, args, "--check-config")?;
    }
    Ok(run)
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
    let present = |stage: &str| {
        doc.section_names().any(|n| {
            n == stage
                || SHARED_SECTIONS
                    .iter()
                    .any(|(section, readers)| n == *section && readers.contains(&stage))
        })
    };
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
