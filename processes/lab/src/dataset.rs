//! `hubtrack dataset`: rendered frames with their hub truth, as the learned hub heatmap's input
//! (the detector's own preprocessing, `Detector::network_input`), for `scripts/train-hubnet.py`.

use crate::turbine_family::{self, Family};
use anyhow::Context;
use hubtrack_detect::heat::{NET_HEIGHT, NET_WIDTH};
use hubtrack_detect::ImageView;
use hubtrack_render::dataset::{
    flight, photo_case, photo_case_close, photo_lenses, synth_case, synth_case_between, BEYOND_M,
    CLASSES, CLOSE_IN_M,
};
use hubtrack_render::{Camera, CameraPose, Renderer, Scene};
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_types::PixelFormat;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `hubtrack dataset`.
#[derive(clap::Args)]
pub struct DatasetArgs {
    #[command(flatten)]
    pub config: ConfigArgs,
    /// Output folder (created): one grey PNG per frame and `labels.jsonl`.
    #[arg(long, short = 'o')]
    pub out: PathBuf,
    /// Seed of the scenes (keep the evaluation seeds, 2026, 77 and 500, out of training).
    #[arg(long, default_value_t = 101)]
    pub seed: u64,
    /// Single frames per distance class, plus a quarter as many negatives (no turbine).
    #[arg(long, default_value_t = 1000)]
    pub per_class: u64,
    /// Rendered approach flights (30 → 6 m), of which every `--flight-step`-th frame is kept.
    #[arg(long, default_value_t = 10)]
    pub flights: u64,
    /// Frames per flight.
    #[arg(long, default_value_t = 300)]
    pub flight_frames: u64,
    /// Keep every n-th flight frame.
    #[arg(long, default_value_t = 5)]
    pub flight_step: u64,
    /// Single frames from beyond the far class (45–250 m, as photos show turbines), plus a
    /// quarter as many negatives.
    #[arg(long, default_value_t = 0)]
    pub beyond: u64,
    /// Single frames from inside the close class, where the approach ends (4–8 m), plus a
    /// quarter as many negatives: the hub yaw network's hover views.
    #[arg(long, default_value_t = 0)]
    pub close_in: u64,
    /// Photo-like single frames (12–250 m, from below and above, relative yaw to ±70°, the hub
    /// anywhere in the frame, shrubland and wind farms; two thirds through a 1920x1080 photo
    /// lens), plus a quarter as many negatives: what drone photos show and approaches do not.
    #[arg(long, default_value_t = 0)]
    pub photo_like: u64,
    /// Close photo-like single frames (the same views from 5–12 m: inspection photos next to
    /// the hub), plus a quarter as many negatives.
    #[arg(long, default_value_t = 0)]
    pub photo_close: u64,
    /// Write the whole working pyramid level (grey, e.g. 480x270 for 1920x1080) instead of the
    /// heatmap network's input: the hub crop network's training set (`train-hubnet.py --model
    /// crop` cuts its crops from these).
    #[arg(long)]
    pub working: bool,
    /// Prepare the frames as still photos are detected (`hubtrack detect`: the Gaussian first
    /// pyramid level) instead of as video frames (`detect.default.box_first_level`): the
    /// training sets of the still photos' models.
    #[arg(long)]
    pub stills: bool,
    /// The turbines the frames show: the thesis turbine (the scenes' own), or each scene a
    /// turbine of the learned yaw networks' training family or of the fleet held out of it
    /// (`processes/lab/src/turbine_family.rs`).
    #[arg(long, value_enum, default_value_t = Family::Thesis)]
    pub turbines: Family,
}

/// Seed mix of a scene's turbine draw (independent of the scene's other draws).
const TURBINE_SEED_MIX: u64 = 0x7B1D_FA41_1E50_0047;

/// Writes the set.
pub fn run(a: DatasetArgs) -> anyhow::Result<()> {
    let config = crate::config::load(&a.config)?;
    let mut det = crate::detect_cmd::detector(&config.detect, None)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let labels_path = a.out.join("labels.jsonl");
    let mut labels = std::io::BufWriter::new(
        std::fs::File::create(&labels_path)
            .with_context(|| format!("creating {}", labels_path.display()))?,
    );
    let mut renderers = [
        Renderer::new(Camera::gopro_hero3()),
        Renderer::new(Camera::usb_narrow()),
        Renderer::new(photo_lenses()[1]),
    ];
    let mut buffers: Vec<Vec<u8>> = renderers
        .iter()
        .map(|r| vec![0u8; r.camera().frame_bytes()])
        .collect();
    let mut written = 0u64;
    // Lens: 0 GoPro, 1 USB, 2 the photo lens.
    let mut one =
        |name: String, scene: &Scene, pose: &CameraPose, k: usize| -> anyhow::Result<()> {
            let mut scene = scene.clone();
            if let Some(t) = turbine_family::for_scene(a.turbines, scene.seed ^ TURBINE_SEED_MIX) {
                hubtrack_sim::show_turbine(&mut scene, &t);
            }
            let truth = renderers[k]
                .render(&scene, pose, &mut buffers[k])
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            let cam = renderers[k].camera();
            let (w, h) = (cam.width as f64, cam.height as f64);
            let view = ImageView {
                width: cam.width,
                height: cam.height,
                stride: cam.width as usize * 3,
                format: PixelFormat::Bgr8,
                data: &buffers[k],
            };
            let input = if a.working {
                det.working_level_for(&view, a.stills)?
            } else {
                det.network_input_for(&view, a.stills)?
            };
            let file = format!("{name}.png");
            let path = a.out.join(&file);
            let p = path.to_str().context("non-UTF-8 path")?;
            anyhow::ensure!(
                opencv::imgcodecs::imwrite_def(p, &input)?,
                "cannot write {p}"
            );
            let frac = |q: Option<[f64; 2]>| {
                q.filter(|_| truth.turbine_in_view)
                    .map(|q| [q[0] / w, q[1] / h])
            };
            let line = serde_json::json!({
                "file": file,
                "hub": frac(truth.hub_px),
                "nose": frac(truth.nose_px),
                "distance_m": truth.distance_m,
                "relative_yaw_deg": truth.relative_yaw_deg,
                "focal_per_width": cam.fx / w,
                "image_height": cam.height,
            });
            writeln!(labels, "{line}")?;
            written += 1;
            if written.is_multiple_of(500) {
                eprintln!("[dataset] {written} frames");
            }
            Ok(())
        };
    let lens = |wide: bool| if wide { 0 } else { 1 };
    for (class, def) in CLASSES.iter().enumerate() {
        for i in 0..a.per_class + a.per_class / 4 {
            let negative = i >= a.per_class;
            let case = synth_case(a.seed, class, i, negative);
            one(
                format!("{}_{}_{i:05}", a.seed, def.0),
                &case.scene,
                &case.pose,
                lens(case.wide),
            )?;
        }
    }
    for i in 0..a.beyond + a.beyond / 4 {
        // Class index 3: a scene stream of its own, apart from the three classes'.
        let case = synth_case_between(
            a.seed,
            CLASSES.len(),
            i,
            i >= a.beyond,
            "beyond",
            BEYOND_M.0,
            BEYOND_M.1,
        );
        one(
            format!("{}_beyond_{i:05}", a.seed),
            &case.scene,
            &case.pose,
            lens(case.wide),
        )?;
    }
    for i in 0..a.close_in + a.close_in / 4 {
        // Class index 4: a scene stream of its own.
        let case = synth_case_between(
            a.seed,
            CLASSES.len() + 1,
            i,
            i >= a.close_in,
            "close_in",
            CLOSE_IN_M.0,
            CLOSE_IN_M.1,
        );
        one(
            format!("{}_closein_{i:05}", a.seed),
            &case.scene,
            &case.pose,
            lens(case.wide),
        )?;
    }
    for i in 0..a.photo_like + a.photo_like / 4 {
        let case = photo_case(a.seed, i, i >= a.photo_like);
        one(
            format!("{}_photo_{i:05}", a.seed),
            &case.scene,
            &case.pose,
            if case.wide { 0 } else { 2 },
        )?;
    }
    for i in 0..a.photo_close + a.photo_close / 4 {
        let case = photo_case_close(a.seed, i, i >= a.photo_close);
        one(
            format!("{}_photoclose_{i:05}", a.seed),
            &case.scene,
            &case.pose,
            if case.wide { 0 } else { 2 },
        )?;
    }
    for f in 0..a.flights {
        let seed = a.seed.wrapping_mul(1000).wrapping_add(f);
        for (i, fr) in flight(seed, a.flight_frames)
            .iter()
            .enumerate()
            .step_by(a.flight_step.max(1) as usize)
        {
            one(
                format!("{}_flight{f:02}_{i:04}", a.seed),
                &fr.scene,
                &fr.pose,
                0,
            )?;
        }
    }
    labels.flush()?;
    let size = if a.working {
        "working level".to_string()
    } else {
        format!("{NET_WIDTH}x{NET_HEIGHT}")
    };
    eprintln!(
        "[dataset] {written} frames ({size} grey) and labels.jsonl in {}",
        a.out.display()
    );
    Ok(())
}
