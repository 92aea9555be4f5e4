//! `hubtrack train-ranker`: fits the learned candidate ranker (`hubtrack_detect::ranker`) to the
//! candidate files `hubtrack eval --candidates` writes, and prints the fitted weights as a
//! `[detect.default.ranker.weights]` section. `scripts/train-ranker.sh` runs the whole recipe on
//! rendered frames only (never on `../shared/data`).

use anyhow::Context;
use hubtrack_detect::ranker::{
    assess, fit, FitSettings, RankingOutcome, TrainingFrame, FEATURES, FEATURE_NAMES,
};
use std::path::{Path, PathBuf};

/// Arguments of `hubtrack train-ranker`.
#[derive(clap::Args)]
pub struct TrainRankerArgs {
    /// Candidate files to fit (JSON lines from `hubtrack eval --candidates`).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Candidate files to report on without fitting (held-out frames).
    #[arg(long, value_name = "FILE")]
    pub holdout: Vec<PathBuf>,
    /// Weight of the squared-weight penalty.
    #[arg(long, default_value_t = 10.0)]
    pub l2: f64,
    /// Gradient steps.
    #[arg(long, default_value_t = 400)]
    pub iterations: usize,
    /// Step size.
    #[arg(long, default_value_t = 1.0)]
    pub step: f64,
    /// Detection threshold on the score, for the report.
    #[arg(long, default_value_t = -1.0, allow_negative_numbers = true)]
    pub min_score: f64,
    /// Also fit every frame once more with this feature zeroed in all its candidates (repeat
    /// for several), so that the ranker still works where the feature says nothing: for the
    /// learned heatmap's `hub_heat`, trained on renders only and weaker on real photos.
    #[arg(long, value_name = "FEATURE")]
    pub also_without: Vec<String>,
}

/// Frames of one candidate file: (frame, is negative). Frames whose hub is hidden or cut count
/// neither way and are left out.
fn load(path: &Path) -> anyhow::Result<(Vec<TrainingFrame>, Vec<bool>)> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let (mut frames, mut negative) = (Vec::new(), Vec::new());
    for (n, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let at = || format!("{}:{}", path.display(), n + 1);
        let v: serde_json::Value = serde_json::from_str(line).with_context(at)?;
        let truth = v["truth"]
            .as_str()
            .with_context(|| format!("{}: no `truth`", at()))?;
        if truth == "hidden" {
            continue;
        }
        let mut fr = TrainingFrame::default();
        for c in v["candidates"]
            .as_array()
            .with_context(|| format!("{}: no `candidates`", at()))?
        {
            let f: Vec<f64> = c["features"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|x| x.as_f64())
                .collect();
            let f: [f64; FEATURES] = f.try_into().map_err(|f: Vec<f64>| {
                anyhow::anyhow!(
                    "{}: {} features, expected {FEATURES} (file from another version?)",
                    at(),
                    f.len()
                )
            })?;
            fr.features.push(f);
            fr.on_hub.push(c["hit"].as_bool().unwrap_or(false));
        }
        frames.push(fr);
        negative.push(truth == "negative");
    }
    Ok((frames, negative))
}

fn report(label: &str, o: &RankingOutcome) {
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    println!(
        "# {label:<40} hits {:5.1} % of {} frames with a hub (candidates reach {:5.1} %), false positives {:5.1} % of {} negatives",
        pct(o.hits, o.frames_with_hub),
        o.frames_with_hub,
        pct(o.reachable, o.frames_with_hub),
        pct(o.false_positives, o.negatives),
        o.negatives
    );
}

/// Runs the command.
pub fn run(args: TrainRankerArgs) -> anyhow::Result<()> {
    let (mut frames, mut negative) = (Vec::new(), Vec::new());
    for f in &args.files {
        let (a, b) = load(f)?;
        eprintln!("[train-ranker] {}: {} frames", f.display(), a.len());
        frames.extend(a);
        negative.extend(b);
    }
    anyhow::ensure!(
        !frames.is_empty(),
        "no frames with a visible or no turbine in the training files"
    );
    let original = frames.len();
    for name in &args.also_without {
        let k = FEATURE_NAMES
            .iter()
            .position(|n| n == name)
            .with_context(|| {
                format!(
                    "--also-without {name}: no such feature (one of {})",
                    FEATURE_NAMES.join(", ")
                )
            })?;
        let copies: Vec<TrainingFrame> = frames[..original]
            .iter()
            .map(|fr| {
                let mut c = fr.clone();
                c.features.iter_mut().for_each(|f| f[k] = 0.0);
                c
            })
            .collect();
        eprintln!(
            "[train-ranker] {} more frames without `{name}`",
            copies.len()
        );
        negative.extend_from_within(..original);
        frames.extend(copies);
    }
    let settings = FitSettings {
        l2: args.l2,
        iterations: args.iterations,
        step: args.step,
    };
    let w = fit(&frames, &settings);
    report(
        "training frames",
        &assess(&frames, &negative, &w, args.min_score),
    );
    for f in &args.holdout {
        let (a, b) = load(f)?;
        report(
            &format!(
                "held out: {}",
                f.file_name().and_then(|s| s.to_str()).unwrap_or("?")
            ),
            &assess(&a, &b, &w, args.min_score),
        );
    }
    println!(
        "# fitted by `hubtrack train-ranker` (l2 {}, {} steps of {}) on {} frames",
        args.l2,
        args.iterations,
        args.step,
        frames.len()
    );
    println!("[detect.default.ranker.weights]");
    for (name, x) in FEATURE_NAMES.iter().zip(w) {
        println!("{name} = {x:.3}");
    }
    Ok(())
}
