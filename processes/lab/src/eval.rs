//! `hubtrack eval`: the detector over real photos with truth (`truth.jsonl` as in
//! `../shared/data`) and over synthetic frames with exact truth, every mode side by side.

use crate::detect_cmd::{detector, draw_overlay, result_json, view_of};
use crate::score::{print_table, score, Outcome, Table, Tally, Truth};
use anyhow::Context;
use hubtrack_capture::images::read_image;
use hubtrack_detect::params::Mode;
use hubtrack_detect::{Hints, ImageView, Output};
use hubtrack_render::dataset::{
    held_out_cameras, held_out_scene, held_out_turbine, photo_case, photo_case_close, photo_lenses,
    synth_case, SynthCase, CLASSES, HELD_OUT_BLADE_M, HELD_OUT_CHIMNEY_SHARE,
    HELD_OUT_MOTION_BLUR_FRAC, HELD_OUT_TOWER_TOP_M,
};
use hubtrack_render::{Camera, Renderer};
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_types::setup::Lens;
use hubtrack_types::PixelFormat;
use opencv::core::{Mat, MatTraitConst};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The modes compared, in column order.
const MODES: [(Mode, &str); 2] = [(Mode::Thesis, "thesis"), (Mode::Default, "default")];
/// Arguments of `hubtrack eval`.
#[derive(clap::Args)]
pub struct EvalArgs {
    #[command(flatten)]
    pub config: ConfigArgs,
    /// Truth file(s) in the format of ../shared/data/*/truth.jsonl (default: ../shared/data/real-dev/truth.jsonl if present).
    #[arg(long, value_name = "FILE")]
    pub truth: Vec<PathBuf>,
    /// Rendered frames only: no photos, neither the default set nor --truth files.
    #[arg(long, conflicts_with = "truth")]
    pub no_photos: bool,
    /// Synthetic frames per distance class (0: none), plus as many negatives (no turbine) / 4,
    /// filmed through the `--camera` calibration if one is given, else the GoPro and USB lenses.
    #[arg(long, default_value_t = 200)]
    pub synthetic: u64,
    /// Negatives (frames without a turbine) per synthetic set instead of a quarter of
    /// `--synthetic`: enough of them to state a false-positive rate of a few per cent (each
    /// cross-domain set gets as many).
    #[arg(long, value_name = "N")]
    pub negatives: Option<u64>,
    /// Photo-like rendered views (0: none; 12–250 m, from below and above, relative yaw to ±70°,
    /// shrubland and wind farms), plus a twelfth as many negatives, detected as still photos:
    /// the renderer's stand-in for the photos' domain, in the table `photo-like` (categories
    /// `photo-like:approach` within 45 m, `photo-like:beyond`).
    #[arg(long, default_value_t = 0)]
    pub photo_like: u64,
    /// Close photo-like rendered views (0: none; the same views from 5–12 m, inspection photos
    /// next to the hub), plus a twelfth as many negatives, detected as still photos: in the table
    /// `photo-like close` (category `photo-like:close`).
    #[arg(long, default_value_t = 0)]
    pub photo_close: u64,
    /// Detect the `--synthetic` frames as still photos are (`hubtrack detect`: no attitude,
    /// both pyramid levels) instead of as video frames with the roll known (the detect stage).
    #[arg(long)]
    pub as_stills: bool,
    /// Cross-domain: also render the `--synthetic` set through cameras no model was trained on
    /// (other sizes, fields of view, plumb_bob and fisheye lenses; detect gets each one's
    /// calibration) and with turbine proportions outside the training family, one table each,
    /// printed after the in-domain table.
    #[arg(long)]
    pub cross_domain: bool,
    /// Seed of the synthetic set and flights.
    #[arg(long, default_value_t = 2026)]
    pub seed: u64,
    /// Evaluate tracking on rendered flights instead: detect -> track per frame, with truth.
    #[arg(long)]
    pub sequence: bool,
    /// Flights for --sequence.
    #[arg(long, default_value_t = 10)]
    pub flights: u64,
    /// Frames per flight for --sequence.
    #[arg(long, default_value_t = 300)]
    pub frames: u64,
    /// With --sequence: film the flights in the held-out scenes of --cross-domain (a chimney
    /// beside or behind the turbine in half the flights, motion blur in all), to count the
    /// locks a chimney's top takes.
    #[arg(long, requires = "sequence")]
    pub held_out_scenes: bool,
    /// Write an overlay PNG (truth in red) of every `default`-mode miss and false positive to
    /// this folder, with `misses.jsonl` listing them (each --cross-domain set in a subfolder
    /// `cross-domain-<set>`); with --sequence, of every frame whose detection lies off the truth
    /// (named `f<flight>_<frame>`).
    #[arg(long, value_name = "DIR")]
    pub misses: Option<PathBuf>,
    /// With --sequence: write one JSON line per frame (flight, frame, truth, detection, both
    /// trackers' outputs) to this file, to see where a flight's errors come from.
    #[arg(long, value_name = "FILE", requires = "sequence")]
    pub trace: Option<PathBuf>,
    /// Write every hub candidate the `default` mode evaluated, with its features and whether it
    /// lies on the truth, one JSON line per image, to this file (the data `train-ranker` fits).
    #[arg(long, value_name = "FILE")]
    pub candidates: Option<PathBuf>,
}

/// Runs the command.
pub fn run(args: EvalArgs) -> anyhow::Result<()> {
    let config = crate::config::load(&args.config)?;
    if let Some(dir) = &args.misses {
        start_misses_dir(dir)?;
    }
    if args.sequence {
        let out = crate::eval_seq::Outputs {
            trace: args.trace.as_deref(),
            misses: args.misses.as_deref(),
            candidates: args.candidates.as_deref(),
        };
        let flights = crate::eval_seq::Flights {
            count: args.flights,
            frames: args.frames,
            seed: args.seed,
            held_out_scenes: args.held_out_scenes,
        };
        return crate::eval_seq::run(&config, &flights, out);
    }
    let misses = args.misses.as_deref();
    let mut cand_out = match &args.candidates {
        Some(p) => Some(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?,
        )),
        None => None,
    };
    let mut detectors = MODES
        .iter()
        .map(|(m, _)| detector(&config.detect, Some(*m)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let names: Vec<&str> = MODES.iter().map(|(_, n)| *n).collect();
    let mut truths = args.truth.clone();
    if truths.is_empty() && !args.no_photos {
        let default =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real-dev/truth.jsonl");
        if default.is_file() {
            truths.push(default);
        } else {
            eprintln!(
                "[eval] skipping real photos: {} not found (../shared absent)",
                default.display()
            );
        }
    }
    for truth in &truths {
        let table = eval_truth_file(truth, &mut detectors, misses, cand_out.as_mut())?;
        print_table(&format!("real photos: {}", truth.display()), &names, &table);
    }
    if args.synthetic > 0 {
        // With a calibration (`--camera`) the set is filmed through that camera alone.
        let calibrated = config.camera.calibrated()?;
        let table = eval_synthetic(
            &Synthetic {
                camera_label: calibrated.is_some().then_some("calibrated"),
                ..Synthetic::of_args(&args, calibrated.map_or_else(in_domain_lenses, |c| [c, c]))
            },
            &mut detectors,
            misses,
            cand_out.as_mut(),
        )?;
        let how = if args.as_stills {
            ", as still photos"
        } else {
            ""
        };
        print_table(
            &format!(
                "synthetic frames: {} per distance class, seed {}{how}",
                args.synthetic, args.seed
            ),
            &names,
            &table,
        );
    }
    if args.cross_domain && args.synthetic > 0 {
        eval_cross_domain(&args, &config, &names, &mut detectors)?;
    }
    if args.photo_like > 0 {
        let table = eval_photo_like(
            args.photo_like,
            args.seed,
            false,
            &mut detectors,
            misses,
            cand_out.as_mut(),
        )?;
        print_table(
            &format!(
                "photo-like rendered views: {}, seed {}, as still photos",
                args.photo_like, args.seed
            ),
            &names,
            &table,
        );
    }
    if args.photo_close > 0 {
        let table = eval_photo_like(
            args.photo_close,
            args.seed,
            true,
            &mut detectors,
            misses,
            cand_out.as_mut(),
        )?;
        print_table(
            &format!(
                "photo-like close views (5-12 m): {}, seed {}, as still photos",
                args.photo_close, args.seed
            ),
            &names,
            &table,
        );
    }
    if let Some(w) = cand_out.as_mut() {
        w.flush().context("writing the candidates file")?;
    }
    Ok(())
}

fn add(table: &mut Table, categories: &[String], truth: &Truth, outcomes: &[Outcome]) {
    for cat in categories {
        let row = table
            .entry(cat.clone())
            .or_insert_with(|| vec![Tally::default(); outcomes.len()]);
        for (t, o) in row.iter_mut().zip(outcomes) {
            t.add(truth, o);
        }
    }
}

/// Every mode's output: as on a still photo (`hubtrack detect`) or as on a video frame (the
/// detect stage).
fn detect_all(
    detectors: &mut [hubtrack_detect::Detector],
    view: &ImageView<'_>,
    hints: &Hints,
    still: bool,
) -> anyhow::Result<Vec<Output>> {
    detectors
        .iter_mut()
        .map(|d| {
            Ok(if still {
                d.detect_still(view, hints)?
            } else {
                d.detect(view, hints)?
            })
        })
        .collect()
}

/// Scores every mode's output against the truth.
fn score_all(outputs: &[Output], truth: &Truth, height: u32) -> Vec<Outcome> {
    outputs
        .iter()
        .map(|o| {
            score(
                truth,
                o.detection.detected.then_some(o.detection.hub_px),
                height as f64,
            )
        })
        .collect()
}

/// Writes the overlay of the last (`default`) mode's output when it missed or fired on a
/// negative; true when it did.
pub(crate) fn write_miss(
    dir: Option<&Path>,
    name: &str,
    image: &Mat,
    truth: &Truth,
    outputs: &[Output],
    outcomes: &[Outcome],
    rerun: Option<&str>,
) -> anyhow::Result<bool> {
    let (Some(dir), Some(out), Some(o)) = (dir, outputs.last(), outcomes.last()) else {
        return Ok(false);
    };
    let missed = match truth {
        Truth::Visible { .. } => !o.hit,
        Truth::Negative => o.detected,
        Truth::Hidden => false,
    };
    if !missed {
        return Ok(false);
    }
    let png = dir.join(format!("{name}.png"));
    let truth_segment = match truth {
        Truth::Visible { axis, hub } => Some([*axis, *hub]),
        _ => None,
    };
    draw_overlay(image, out, truth_segment, &png)?;
    let line = serde_json::json!({"name": name, "truth": truth_segment, "error_pct": o.error_pct,
        // The hub's distance is left to the rerun (`hubtrack detect`), which has the tracker's.
        "result": result_json(&png, image.cols() as u32, image.rows() as u32, out, None, 0.0),
        "rerun": rerun});
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(dir.join("misses.jsonl"))?;
    writeln!(f, "{line}")?;
    Ok(true)
}

/// The `hubtrack detect` command line that detects a rendered frame written to `input` as it
/// was scored: as a video frame (`--as-frame`, the roll known) unless `still`, through the
/// held-out camera whose calibration the set's misses folder holds (`camera`), if any.
fn rerun_command(camera: Option<&Path>, input: &str, still: bool, roll_deg: f64) -> String {
    let mut cmd = String::from("hubtrack detect");
    if !still {
        cmd += &format!(" --as-frame --hint-roll {roll_deg:.3}");
    }
    if let Some(camera) = camera {
        cmd += &format!(" --camera {}", shell_quoted(&camera.display().to_string()));
    }
    cmd + " " + &shell_quoted(input)
}

/// `s` as one POSIX shell word: in single quotes, each `'` in it closed, escaped and reopened.
fn shell_quoted(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The calibration of a held-out camera set, in its misses folder (see [`rerun_command`]).
const MISSES_CAMERA_FILE: &str = "camera.yaml";

/// Creates `dir` with an empty `misses.jsonl` (see `--misses`).
fn start_misses_dir(dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    std::fs::write(dir.join("misses.jsonl"), "")
        .with_context(|| format!("writing {}", dir.display()))
}

/// Where `--candidates` lines go.
pub(crate) type CandidateSink = std::io::BufWriter<std::fs::File>;

/// Writes the `default` mode's candidates of one image as a JSON line (see `--candidates`).
pub(crate) fn write_candidates(
    out: Option<&mut CandidateSink>,
    name: &str,
    truth: &Truth,
    output: &Output,
    height: u32,
) -> anyhow::Result<()> {
    let Some(out) = out else { return Ok(()) };
    let kind = match truth {
        Truth::Visible { .. } => "visible",
        Truth::Hidden => "hidden",
        Truth::Negative => "negative",
    };
    let cands: Vec<serde_json::Value> = output
        .candidates
        .iter()
        .map(|c| {
            let hit = score(truth, Some(c.hub), height as f64).hit;
            serde_json::json!({"hub": c.hub, "confidence": c.confidence, "hit": hit, "features": c.features.to_vec()})
        })
        .collect();
    let line = serde_json::json!({"name": name, "truth": kind, "height": height, "detected": output.detection.detected, "candidates": cands});
    writeln!(out, "{line}")?;
    Ok(())
}

fn eval_truth_file(
    path: &Path,
    detectors: &mut [hubtrack_detect::Detector],
    misses: Option<&Path>,
    mut cand_out: Option<&mut CandidateSink>,
) -> anyhow::Result<Table> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut table = Table::new();
    for (n, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let v: serde_json::Value =
            serde_json::from_str(line).with_context(|| format!("{}:{}", path.display(), n + 1))?;
        let file = dir.join(v["file"].as_str().context("truth line without `file`")?);
        let xy = |k: &str| {
            v[k].as_array()
                .and_then(|a| Some([a.first()?.as_f64()?, a.get(1)?.as_f64()?]))
        };
        let truth = match (v["set"].as_str(), v["hub_visible"].as_bool()) {
            (Some("negative"), _) => Truth::Negative,
            (_, Some(false)) => Truth::Hidden,
            _ => {
                let hub = xy("hub").context("positive without hub")?;
                Truth::Visible {
                    axis: xy("axis_point").unwrap_or(hub),
                    hub,
                }
            }
        };
        let mat = match read_image(&file) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("[eval] {e}");
                continue;
            }
        };
        let view = view_of(&mat)?;
        let outputs = detect_all(detectors, &view, &Hints::default(), true)?;
        let outcomes = score_all(&outputs, &truth, view.height);
        let id = v["id"]
            .as_str()
            .map_or_else(|| format!("line{}", n + 1), |s| s.replace('/', "_"));
        write_miss(misses, &id, &mat, &truth, &outputs, &outcomes, None)?;
        if let Some(out) = outputs.last() {
            write_candidates(cand_out.as_deref_mut(), &id, &truth, out, view.height)?;
        }
        let mut cats = vec!["all".to_string()];
        for key in ["distance_class", "view", "env"] {
            if let Some(c) = v[key].as_str() {
                cats.push(format!("{}:{c}", key.trim_end_matches("_class")));
            }
        }
        add(&mut table, &cats, &truth, &outcomes);
    }
    Ok(table)
}

/// `per_class` synthetic frames per distance class (plus negatives), as video frames or, with
/// `still`, as still photos.
/// One synthetic set: cases per distance class, through which lenses (`[0]` for the wide
/// cases, `[1]` for the narrow ones), and whether the turbines are of the held-out family.
struct Synthetic {
    per_class: u64,
    /// Negatives per distance class's scenes (a third of the set's).
    negatives_per_class: u64,
    seed: u64,
    still: bool,
    lenses: [Camera; 2],
    held_out_turbines: bool,
    /// Chimneys and motion blur (`dataset::held_out_scene`).
    held_out_scenes: bool,
    /// The category label of a single held-out camera.
    camera_label: Option<&'static str>,
}

/// The lenses the learned parts were trained through: wide cases through the GoPro, the others
/// through the narrow USB camera.
fn in_domain_lenses() -> [Camera; 2] {
    [Camera::gopro_hero3(), Camera::usb_narrow()]
}

impl Synthetic {
    /// The set `args` asks for through `lenses`: in-domain scenes and turbines, each case
    /// labelled with the lens it drew.
    fn of_args(args: &EvalArgs, lenses: [Camera; 2]) -> Synthetic {
        Synthetic {
            per_class: args.synthetic,
            negatives_per_class: negatives_per_class(args),
            seed: args.seed,
            still: args.as_stills,
            lenses,
            held_out_turbines: false,
            held_out_scenes: false,
            camera_label: None,
        }
    }
}

/// Negatives per distance class: `--negatives` spread over the classes, else a twelfth of
/// `--synthetic` (a quarter over the three classes).
fn negatives_per_class(args: &EvalArgs) -> u64 {
    args.negatives
        .map_or(args.synthetic / 12, |n| n.div_ceil(CLASSES.len() as u64))
}

fn eval_synthetic(
    set: &Synthetic,
    detectors: &mut [hubtrack_detect::Detector],
    misses: Option<&Path>,
    mut cand_out: Option<&mut CandidateSink>,
) -> anyhow::Result<Table> {
    let mut table = Table::new();
    let per_class = set.per_class;
    for (class, class_def) in CLASSES.iter().enumerate() {
        let cases = (0..per_class + set.negatives_per_class).map(|i| {
            let mut case = synth_case(set.seed, class, i, i >= per_class);
            if set.held_out_turbines {
                let seed = case.scene.seed;
                held_out_turbine(&mut case.scene, seed);
            }
            if set.held_out_scenes {
                let seed = case.scene.seed;
                held_out_scene(&mut case.scene, seed);
            }
            if let Some(label) = set.camera_label {
                // One camera for every case: its name, not the in-domain lens the case drew.
                for c in case
                    .categories
                    .iter_mut()
                    .filter(|c| c.starts_with("camera:"))
                {
                    *c = format!("camera:{label}");
                }
            }
            (format!("{}_{i:04}", class_def.0), case)
        });
        eval_rendered(
            cases,
            set.lenses,
            set.still,
            detectors,
            misses,
            cand_out.as_deref_mut(),
            &mut table,
        )?;
        eprintln!("[eval] synthetic class {} done", class_def.0);
    }
    Ok(table)
}

/// The synthetic set through each held-out camera (detect configured with its calibration),
/// then through the in-domain cameras with held-out turbine proportions and with held-out
/// scenes, one table each.
fn eval_cross_domain(
    args: &EvalArgs,
    config: &crate::config::LabConfig,
    names: &[&str],
    in_domain_detectors: &mut [hubtrack_detect::Detector],
) -> anyhow::Result<()> {
    // Each held-out set's misses in a folder of its own (the sets reuse the frame names).
    let misses_of = |set: &str| -> anyhow::Result<Option<PathBuf>> {
        let Some(dir) = &args.misses else {
            return Ok(None);
        };
        let dir = dir.join(format!("cross-domain-{set}"));
        start_misses_dir(&dir)?;
        Ok(Some(dir))
    };
    for (name, camera) in held_out_cameras() {
        let misses = misses_of(name)?;
        if let Some(dir) = &misses {
            // What `hubtrack detect --camera` needs to look at a miss as it was scored.
            let file = dir.join(MISSES_CAMERA_FILE);
            std::fs::write(&file, camera.to_ros_yaml(name))
                .with_context(|| format!("writing {}", file.display()))?;
        }
        let lens = Lens::from_model(camera);
        let detect = config.detect.clone().with_setup(&lens, &config.turbine);
        let mut detectors = MODES
            .iter()
            .map(|(m, _)| detector(&detect, Some(*m)))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let table = eval_synthetic(
            &Synthetic {
                camera_label: Some(name),
                ..Synthetic::of_args(args, [camera, camera])
            },
            &mut detectors,
            misses.as_deref(),
            None,
        )?;
        print_table(
            &format!(
                "cross-domain camera {name}: {} per distance class, seed {}",
                args.synthetic, args.seed
            ),
            names,
            &table,
        );
    }
    // The in-domain lenses on what their training never varied: turbine proportions, scenes.
    let in_domain_lens_sets = [
        (
            "turbines",
            true,
            false,
            format!(
                "cross-domain turbines (tower top {}-{} m, blades {}-{} m)",
                HELD_OUT_TOWER_TOP_M.0,
                HELD_OUT_TOWER_TOP_M.1,
                HELD_OUT_BLADE_M.0,
                HELD_OUT_BLADE_M.1,
            ),
        ),
        (
            "scenes",
            false,
            true,
            format!(
                "cross-domain scenes (chimneys in {:.0} % of the scenes with a turbine and in all \
                 without, motion blur {:.1}-{:.1} % of the width)",
                100.0 * HELD_OUT_CHIMNEY_SHARE,
                100.0 * HELD_OUT_MOTION_BLUR_FRAC.0,
                100.0 * HELD_OUT_MOTION_BLUR_FRAC.1,
            ),
        ),
    ];
    for (set, held_out_turbines, held_out_scenes, title) in in_domain_lens_sets {
        let misses = misses_of(set)?;
        let table = eval_synthetic(
            &Synthetic {
                held_out_turbines,
                held_out_scenes,
                ..Synthetic::of_args(args, in_domain_lenses())
            },
            in_domain_detectors,
            misses.as_deref(),
            None,
        )?;
        print_table(
            &format!(
                "{title}: {} per distance class, seed {}",
                args.synthetic, args.seed
            ),
            names,
            &table,
        );
    }
    Ok(())
}

/// `count` photo-like rendered views (plus a twelfth as many negatives), the `close` ones or
/// the others, detected as still photos are: no attitude, both pyramid levels.
fn eval_photo_like(
    count: u64,
    seed: u64,
    close: bool,
    detectors: &mut [hubtrack_detect::Detector],
    misses: Option<&Path>,
    cand_out: Option<&mut CandidateSink>,
) -> anyhow::Result<Table> {
    let mut table = Table::new();
    let (case, prefix): (fn(u64, u64, bool) -> SynthCase, _) = if close {
        (photo_case_close, "photoclose")
    } else {
        (photo_case, "photo")
    };
    let cases =
        (0..count + count / 12).map(|i| (format!("{prefix}_{i:04}"), case(seed, i, i >= count)));
    eval_rendered(
        cases,
        photo_lenses(),
        true,
        detectors,
        misses,
        cand_out,
        &mut table,
    )?;
    Ok(table)
}

/// Renders and scores `cases` (name, case) through `lenses` (`[0]` for wide cases): as video
/// frames with the roll known, or as still photos.
fn eval_rendered(
    cases: impl Iterator<Item = (String, SynthCase)>,
    lenses: [Camera; 2],
    still: bool,
    detectors: &mut [hubtrack_detect::Detector],
    misses: Option<&Path>,
    mut cand_out: Option<&mut CandidateSink>,
    table: &mut Table,
) -> anyhow::Result<()> {
    let mut renderers = lenses.map(Renderer::new);
    let mut buffers: Vec<Vec<u8>> = renderers
        .iter()
        .map(|r| vec![0u8; r.camera().frame_bytes()])
        .collect();
    // A held-out camera's calibration beside its misses, for their reruns.
    let camera_file = misses
        .map(|dir| dir.join(MISSES_CAMERA_FILE))
        .filter(|f| f.is_file());
    for (name, case) in cases {
        let negative = case.categories.iter().any(|c| c == "negatives");
        let k = if case.wide { 0 } else { 1 };
        let truth = renderers[k]
            .render(&case.scene, &case.pose, &mut buffers[k])
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let cam = renderers[k].camera();
        let view = ImageView {
            width: cam.width,
            height: cam.height,
            stride: cam.width as usize * 3,
            format: PixelFormat::Bgr8,
            data: &buffers[k],
        };
        let t = if negative {
            Truth::Negative
        } else {
            Truth::of_rendered(&truth)
        };
        let hints = if still {
            Hints::default()
        } else {
            Hints {
                roll_rad: Some(case.pose.roll_deg.to_radians()),
                ..Hints::default()
            }
        };
        let outputs = detect_all(detectors, &view, &hints, still)?;
        let outcomes = score_all(&outputs, &t, view.height);
        if let Some(out) = outputs.last() {
            write_candidates(cand_out.as_deref_mut(), &name, &t, out, view.height)?;
        }
        if let Some(dir) = misses {
            let mat = Mat::from_slice(&buffers[k])?
                .reshape(3, cam.height as i32)?
                .try_clone()?;
            // The rendered input too, to re-run `hubtrack detect` on (with RUST_LOG=trace) as
            // this frame was scored.
            let input = dir.join(format!("{name}_input.png"));
            let path = input.to_str().context("non-UTF-8 path")?;
            let rerun = rerun_command(camera_file.as_deref(), path, still, case.pose.roll_deg);
            if write_miss(misses, &name, &mat, &t, &outputs, &outcomes, Some(&rerun))? {
                anyhow::ensure!(
                    opencv::imgcodecs::imwrite_def(path, &mat)?,
                    "cannot write {path}"
                );
            }
        }
        add(table, &case.categories, &t, &outcomes);
    }
    Ok(())
}
