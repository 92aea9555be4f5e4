//! `hubtrack-lab`: the lab's commands — detection and tracking on files, evaluation against
//! truth, simulated flights, benchmarks, training data. Not needed on the flight computer;
//! `hubtrack <command>` hands these commands over to it, so each keeps its documented name.

mod bench;
mod config;
mod dataset;
mod detect_cmd;
mod eval;
mod eval_seq;
mod fly;
mod fly_setup;
mod fuzz;
mod fuzz_detect;
mod score;
mod sitl;
mod track_cmd;
mod train_ranker;
mod turbine_family;

use anyhow::{bail, Context};
use clap::{Parser, Subcommand};
use hubtrack_capture::synthetic::{Filming, SyntheticSource};
use hubtrack_runtime::config::ConfigArgs;
use hubtrack_supervisor::tools::show;
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "hubtrack-lab",
    version,
    about = "hubtrack's lab commands (also reachable as `hubtrack <command>`)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Detect the hub in photos: one JSON object per image on stdout.
    Detect(detect_cmd::DetectArgs),
    /// Detect and track over an image sequence offline: one JSON object per frame on stdout.
    Track(track_cmd::TrackArgs),
    /// Evaluate the detector on photos with truth and on synthetic frames, all modes side by side.
    Eval(eval::EvalArgs),
    /// Fly seeded simulated approaches through the real processes; a table (or JSON lines) of outcomes.
    Fly(fly::FlyArgs),
    /// Benchmarks (commands that print a table; compare columns within one run).
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Write rendered frames with hub truth as the learned heatmap's training set.
    Dataset(dataset::DatasetArgs),
    /// Fit the learned candidate ranker to `eval --candidates` files; prints the weights as TOML.
    TrainRanker(train_ranker::TrainRankerArgs),
    /// Render one synthetic frame exactly as the capture stage would publish it.
    Render(RenderArgs),
    /// Mutate valid inputs millions of times through every parser of outside data (recordings,
    /// MAVLink, config, calibrations) and the detector (images and hints): executions, crashes,
    /// slowest input and peak memory per target.
    Fuzz(fuzz::FuzzArgs),
    /// Compare a simulated flight's detections and track with its truth, per band of distance.
    Diagnose {
        /// A recording with truth (`hubtrack fly --record FILE`, or its replay).
        file: PathBuf,
        /// One JSON object with `bands`, `task_frames` and `last`.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum BenchCommand {
    /// The frames hop over iceoryx2 across real processes vs a Unix-socket copy; renderer cost.
    Frames(bench::FramesBenchArgs),
    /// The whole pipeline pinned to 2 cores with the recorder on: latency, CPU and memory per process.
    Pipeline(bench::PipelineBenchArgs),
    /// Detect alone on the pipeline benchmark's frames, paced at the camera's rate: the solo
    /// figure for detect's time inside the pipeline.
    DetectAlone(bench::DetectAloneArgs),
}

#[derive(clap::Args)]
struct RenderArgs {
    #[command(flatten)]
    config: ConfigArgs,
    /// Frame sequence number to render (the first one with --frames).
    #[arg(long, default_value_t = 0)]
    seq: u64,
    /// Number of frames: with an `.avi` output, a Motion-JPEG clip; with a folder, one PNG each.
    #[arg(long, default_value_t = 1)]
    frames: u64,
    /// Output: `.png`/`.jpg` an image, `.avi` a video, a folder (existing, or named with a
    /// trailing `/`) PNGs, anything else raw BGR8 bytes.
    #[arg(long, short = 'o')]
    out: PathBuf,
}

fn main() {
    hubtrack_runtime::start_tool("hubtrack");
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Detect(a) => detect_cmd::run(a),
        Command::Track(a) => track_cmd::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Fly(a) => fly::run(a),
        Command::Bench(BenchCommand::Frames(a)) => bench::frames(a),
        Command::Bench(BenchCommand::Pipeline(a)) => bench::pipeline(a),
        Command::Bench(BenchCommand::DetectAlone(a)) => bench::detect_alone(a),
        Command::Dataset(a) => dataset::run(a),
        Command::TrainRanker(a) => train_ranker::run(a),
        Command::Render(a) => render(a),
        Command::Diagnose { file, json } => diagnose(&file, json),
        Command::Fuzz(a) => fuzz::run(a),
    };
    hubtrack_runtime::exit_with(result);
}

/// `diagnose`: a simulated flight's detections and track against its truth.
fn diagnose(file: &Path, json: bool) -> anyhow::Result<()> {
    let report = hubtrack_record::flight::analyze(file)?;
    show(
        &report,
        json,
        format!(
            "{} against its truth, per band of true distance",
            file.display()
        ),
        hubtrack_record::flight::print,
    )
}

/// `render`: synthetic frames to images, a video or raw bytes, with their truth as JSON lines.
fn render(args: RenderArgs) -> anyhow::Result<()> {
    use opencv::prelude::*;
    anyhow::ensure!(args.frames > 0, "--frames 0 renders nothing");
    anyhow::ensure!(
        args.seq.checked_add(args.frames).is_some(),
        "--seq {} with --frames {} runs past the last sequence number",
        args.seq,
        args.frames
    );
    if args.out.as_os_str().to_string_lossy().ends_with('/') {
        std::fs::create_dir_all(&args.out)
            .with_context(|| format!("creating {}", args.out.display()))?;
    }
    let config = config::load(&args.config)?;
    let filming = Filming::of(&config.camera, &config.turbine)?;
    let mut source =
        SyntheticSource::new(&config.capture.synthetic, config.capture.fps)?.filming(&filming);
    let (w, h) = source.size();
    let mut pixels = vec![0u8; w as usize * h as usize * 3];
    let ext = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    anyhow::ensure!(
        args.frames == 1 || ext == "avi" || args.out.is_dir(),
        "-o {} holds one frame: give a folder (e.g. {}/) or an .avi for --frames {}",
        args.out.display(),
        args.out.with_extension("").display(),
        args.frames
    );
    let mut video = if ext == "avi" {
        let fourcc = opencv::videoio::VideoWriter::fourcc('M', 'J', 'P', 'G')?;
        let name = args.out.to_str().context("output path is not UTF-8")?;
        let writer = opencv::videoio::VideoWriter::new_def(
            name,
            fourcc,
            config.capture.fps,
            opencv::core::Size::new(w as i32, h as i32),
        )?;
        if !writer.is_opened()? {
            bail!("cannot write video {}", args.out.display());
        }
        Some(writer)
    } else {
        None
    };
    for seq in args.seq..args.seq + args.frames {
        let truth = source.render_index(seq, &mut pixels)?;
        if let Some(writer) = video.as_mut() {
            let flat = Mat::new_rows_cols_with_data(h as i32, (w * 3) as i32, &pixels)?;
            writer.write(&flat.reshape(3, h as i32)?)?;
        } else if args.out.is_dir() {
            let path = args.out.join(format!("frame_{seq:06}.png"));
            hubtrack_capture::convert::write_bgr_image(&path, w, h, &pixels)?;
        } else if ["png", "jpg", "jpeg", "bmp"].contains(&ext.as_str()) {
            hubtrack_capture::convert::write_bgr_image(&args.out, w, h, &pixels)?;
        } else {
            std::fs::write(&args.out, &pixels)
                .with_context(|| format!("writing {}", args.out.display()))?;
        }
        let t = hubtrack_capture::synthetic::frame_truth(&truth);
        println!(
            "{}",
            serde_json::json!({"seq": seq, "width": w, "height": h, "out": args.out, "truth": t})
        );
    }
    if let Some(mut writer) = video {
        writer.release()?;
    }
    Ok(())
}
