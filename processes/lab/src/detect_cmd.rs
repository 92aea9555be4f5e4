//! `hubtrack detect`: batch detection on photos, one JSON object per image on stdout (a contract
//! evaluation tools rely on: keep the keys).

use anyhow::Context;
use hubtrack_capture::images::{has_image_extension, read_image, IMAGE_EXTENSIONS};
use hubtrack_detect::params::{DetectConfig, Mode};
use hubtrack_detect::{Detector, Hints, ImageView, LineKind, Output};
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_track::Tracker;
use hubtrack_types::PixelFormat;
use opencv::core::{Mat, MatTraitConst, MatTraitConstManual, Point, Scalar};
use opencv::imgproc;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Detection mode on the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum ModeArg {
    /// The thesis's pipeline (reference).
    Thesis,
    /// The default, robust pipeline.
    Default,
}

impl From<ModeArg> for Mode {
    fn from(m: ModeArg) -> Mode {
        match m {
            ModeArg::Thesis => Mode::Thesis,
            ModeArg::Default => Mode::Default,
        }
    }
}

/// Arguments of `hubtrack detect`.
#[derive(clap::Args)]
pub struct DetectArgs {
    #[command(flatten)]
    pub config: ConfigArgs,
    /// Detection mode (default: `[detect].mode` of the config).
    #[arg(long, value_enum)]
    pub mode: Option<ModeArg>,
    /// Write an overlay PNG per image into this folder.
    #[arg(long, value_name = "DIR")]
    pub annotate: Option<PathBuf>,
    /// What the detect stage gets from the tracker, for looking at one frame as the pipeline
    /// saw it: the predicted hub, full-resolution px.
    #[arg(long, value_name = "X,Y", value_parser = parse_point, allow_negative_numbers = true)]
    pub hint_hub: Option<[f64; 2]>,
    /// ... and the tracker's distance to the hub, metres (positive).
    #[arg(long, value_name = "M", value_parser = hubtrack_runtime::cli::metres)]
    pub hint_distance: Option<f64>,
    /// ... and the camera roll from the IMU, degrees (clockwise positive, within ±180;
    /// `--hint-roll -1.6` is a negative roll, not a flag).
    #[arg(long, value_name = "DEG", value_parser = hubtrack_runtime::cli::roll_deg, allow_negative_numbers = true)]
    pub hint_roll: Option<f64>,
    /// Detect as the detect stage does on a video frame (its working pyramid level and the
    /// video frames' models), not as on a still photo (two levels, the mirror image, the
    /// photos' models): to look again at a frame `hubtrack eval --misses` scored as a video
    /// frame, as its `misses.jsonl` line's `rerun` says.
    #[arg(long)]
    pub as_frame: bool,
    /// Image files or folders of images (taken in file-name order).
    #[arg(required = true, value_name = "PATH")]
    pub paths: Vec<PathBuf>,
}

/// Parses `X,Y` (two finite numbers).
fn parse_point(s: &str) -> Result<[f64; 2], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))?;
    match v[..] {
        [x, y] if x.is_finite() && y.is_finite() => Ok([x, y]),
        _ => Err(format!("{s:?}: expected X,Y")),
    }
}

impl DetectArgs {
    /// The hints given on the command line (none by default: photos have no tracker).
    fn hints(&self) -> Hints {
        Hints {
            roll_rad: self.hint_roll.map(f64::to_radians),
            predicted_hub_px: self.hint_hub,
            hub_distance_m: self.hint_distance,
        }
    }
}

/// Expands folders into their images (name order); files stay as given (a missing or
/// unreadable one is reported on its own line). A folder that cannot be listed, or holds no
/// image, is an error naming it: nothing would be detected on it, and silence would say so
/// no better than an empty result.
pub fn expand(paths: &[PathBuf]) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut files: Vec<PathBuf> = std::fs::read_dir(p)
                .with_context(|| format!("listing {}", p.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.is_file() && has_image_extension(f))
                .collect();
            anyhow::ensure!(
                !files.is_empty(),
                "{} holds no images (files ending in .{})",
                p.display(),
                IMAGE_EXTENSIONS.join(", .")
            );
            files.sort();
            out.extend(files);
        } else {
            out.push(p.clone());
        }
    }
    Ok(out)
}

/// Reads one input image; a missing file says so rather than that it is no image.
pub fn read_input(path: &Path) -> anyhow::Result<Mat> {
    anyhow::ensure!(path.exists(), "no such file");
    Ok(read_image(path)?)
}

/// A BGR8 OpenCV image as a detector view (no copy).
pub fn view_of(mat: &Mat) -> anyhow::Result<ImageView<'_>> {
    anyhow::ensure!(
        mat.is_continuous() && mat.channels() == 3,
        "image is not continuous BGR8"
    );
    Ok(ImageView {
        width: mat.cols() as u32,
        height: mat.rows() as u32,
        stride: mat.cols() as usize * 3,
        format: PixelFormat::Bgr8,
        data: mat.data_bytes()?,
    })
}

/// The detector configured by `config` with an optional mode override.
pub fn detector(config: &DetectConfig, mode: Option<Mode>) -> anyhow::Result<Detector> {
    let mut c = config.clone();
    if let Some(m) = mode {
        c.mode = m;
    }
    Ok(Detector::new(c)?)
}

/// Runs the command.
pub fn run(args: DetectArgs) -> anyhow::Result<()> {
    let config = crate::config::load(&args.config)?;
    let mut det = detector(&config.detect, args.mode.map(Into::into))?;
    // The hub's distance of each photo, as the tracker takes a frame's tower and spinner.
    let mut tracker = Tracker::new(config.track.clone()).map_err(|e| anyhow::anyhow!("{e}"))?;
    if let Some(dir) = &args.annotate {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let hints = args.hints();
    let (mut done, mut failed) = (0usize, 0usize);
    for path in expand(&args.paths)? {
        let line = match detect_one(
            &mut det,
            &mut tracker,
            &path,
            args.annotate.as_deref(),
            &hints,
            args.as_frame,
        ) {
            Ok(v) => {
                done += 1;
                v
            }
            Err(e) => {
                failed += 1;
                json!({"path": path, "error": format!("{e:#}")})
            }
        };
        println!("{line}");
    }
    // Each failure is on its own line above; a run in which no input gave a result is an error.
    if done == 0 && failed > 0 {
        anyhow::bail!(
            "none of the {failed} input(s) could be read and detected on (each error is above)"
        );
    }
    Ok(())
}

fn detect_one(
    det: &mut Detector,
    tracker: &mut Tracker,
    path: &Path,
    annotate: Option<&Path>,
    hints: &Hints,
    as_frame: bool,
) -> anyhow::Result<serde_json::Value> {
    let mat = read_input(path)?;
    let view = view_of(&mat)?;
    let t = Instant::now();
    let out = if as_frame {
        det.detect(&view, hints)?
    } else {
        det.detect_still(&view, hints)?
    };
    let ms = t.elapsed().as_secs_f64() * 1e3;
    if let Some(dir) = annotate {
        let stem = path
            .file_stem()
            .map_or("image".into(), |s| s.to_string_lossy().into_owned());
        draw_overlay(&mat, &out, None, &dir.join(format!("{stem}.png")))?;
    }
    let distance_m = tracker.still_distance(&out.detection);
    Ok(result_json(
        path,
        view.width,
        view.height,
        &out,
        distance_m,
        ms,
    ))
}

/// The JSON object of one image (keys are a contract: path, width, height, detected, hub,
/// confidence, distance_m, yaw_deg, ms; the rest are extras). `distance_m` is the hub's
/// distance ([`Tracker::still_distance`]).
pub fn result_json(
    path: &Path,
    width: u32,
    height: u32,
    out: &Output,
    distance_m: Option<f64>,
    ms: f64,
) -> serde_json::Value {
    let d = &out.detection;
    json!({
        "path": path, "width": width, "height": height, "detected": d.detected,
        "hub": d.detected.then_some(d.hub_px), "confidence": d.confidence,
        "distance_m": distance_m, "yaw_deg": out.yaw_deg, "ms": ms,
        "tower_top": d.tower_found.then_some(d.tower_top_px),
        "tower_width_px": d.tower_found.then_some(d.tower_width_px),
        "circle": d.circle_found.then_some(d.circle),
        "nacelle_end_dx_px": d.nacelle_found.then_some(d.nacelle_end_dx_px),
        "blade_angles_deg": &d.blade_angles_deg[..(d.blade_count as usize).min(d.blade_angles_deg.len())],
        "lines": d.line_count,
    })
}

/// Draws what the detector saw over the image (and the truth segment, axis point to spinner
/// centre, in red when given) and writes it.
pub fn draw_overlay(
    image: &Mat,
    out: &Output,
    truth: Option<[[f64; 2]; 2]>,
    path: &Path,
) -> anyhow::Result<()> {
    let mut canvas = image.try_clone()?;
    let scale = (image.rows() as f64 / 540.0).max(1.0);
    let thickness = (2.0 * scale).round() as i32;
    let pt = |p: [f64; 2]| Point::new(p[0].round() as i32, p[1].round() as i32);
    for l in &out.overlay.lines {
        let color = match l.kind {
            LineKind::Tower => Scalar::new(40.0, 40.0, 230.0, 0.0),
            LineKind::Blade => Scalar::new(40.0, 220.0, 40.0, 0.0),
            LineKind::Rejected => Scalar::new(0.0, 160.0, 240.0, 0.0),
            LineKind::Other => Scalar::new(200.0, 120.0, 100.0, 0.0),
        };
        imgproc::line(
            &mut canvas,
            pt(l.a),
            pt(l.b),
            color,
            thickness,
            imgproc::LINE_AA,
            0,
        )?;
    }
    if let Some([x, y, r]) = out.overlay.search_circle {
        imgproc::circle(
            &mut canvas,
            pt([x, y]),
            r.round() as i32,
            Scalar::new(60.0, 200.0, 60.0, 0.0),
            1,
            imgproc::LINE_AA,
            0,
        )?;
    }
    let d = &out.detection;
    if d.tower_found {
        imgproc::circle(
            &mut canvas,
            pt(d.tower_top_px),
            (8.0 * scale) as i32,
            Scalar::new(255.0, 80.0, 20.0, 0.0),
            thickness,
            imgproc::LINE_AA,
            0,
        )?;
    }
    if d.circle_found {
        imgproc::circle(
            &mut canvas,
            pt([d.circle[0], d.circle[1]]),
            d.circle[2].round() as i32,
            Scalar::new(255.0, 0.0, 255.0, 0.0),
            thickness,
            imgproc::LINE_AA,
            0,
        )?;
    }
    if d.detected {
        let c = pt(d.hub_px);
        let r = (14.0 * scale) as i32;
        imgproc::circle(
            &mut canvas,
            c,
            r,
            Scalar::new(0.0, 255.0, 255.0, 0.0),
            thickness,
            imgproc::LINE_AA,
            0,
        )?;
        imgproc::line(
            &mut canvas,
            Point::new(c.x - 2 * r, c.y),
            Point::new(c.x + 2 * r, c.y),
            Scalar::new(0.0, 255.0, 255.0, 0.0),
            thickness,
            imgproc::LINE_AA,
            0,
        )?;
        imgproc::line(
            &mut canvas,
            Point::new(c.x, c.y - 2 * r),
            Point::new(c.x, c.y + 2 * r),
            Scalar::new(0.0, 255.0, 255.0, 0.0),
            thickness,
            imgproc::LINE_AA,
            0,
        )?;
    }
    if d.detected && d.nacelle_found {
        // The nacelle's far end: an orange vertical tick beside the hub.
        let (x, y, r) = (
            (d.hub_px[0] + d.nacelle_end_dx_px).round() as i32,
            d.hub_px[1].round() as i32,
            (14.0 * scale) as i32,
        );
        imgproc::line(
            &mut canvas,
            Point::new(x, y - r),
            Point::new(x, y + r),
            Scalar::new(0.0, 128.0, 255.0, 0.0),
            thickness,
            imgproc::LINE_AA,
            0,
        )?;
    }
    if let Some([a, b]) = truth {
        let red = Scalar::new(0.0, 0.0, 255.0, 0.0);
        imgproc::line(
            &mut canvas,
            pt(a),
            pt(b),
            red,
            thickness,
            imgproc::LINE_AA,
            0,
        )?;
        imgproc::circle(
            &mut canvas,
            pt(b),
            (4.0 * scale) as i32,
            red,
            thickness,
            imgproc::LINE_AA,
            0,
        )?;
    }
    let name = path.to_str().context("non-UTF-8 path")?;
    anyhow::ensure!(
        opencv::imgcodecs::imwrite_def(name, &canvas)?,
        "cannot write {name}"
    );
    Ok(())
}
