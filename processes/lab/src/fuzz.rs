//! `hubtrack fuzz`: millions of mutations of valid inputs through every parser of outside data
//! (recordings, MAVLink bytes and link state, configuration, camera calibrations) and through
//! the detector (images and hints, [`crate::fuzz_detect`]); each must end in a result or an
//! error, never a panic. Prints executions, crashes, the slowest input and the peak memory.
//!
//! Seeds are the corpus in `tests/fuzz-corpus/` and the documented config files; mutations are
//! [`hubtrack_types::mutate`] from `--seed`, so a crash is reproduced from its seed and index
//! (and its input is saved under `--out`).

use anyhow::{bail, Context};
use hubtrack_types::mutate::{mutate, Rng};
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Largest mutant, bytes (larger than every seed: mutations may grow it).
const MAX_INPUT: usize = 1 << 17;

/// `hubtrack fuzz`'s options.
#[derive(clap::Args)]
pub struct FuzzArgs {
    /// Targets, comma separated: mcap, mavlink, config, calibration, detect (default: all).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "mcap,mavlink,config,calibration,detect"
    )]
    pub targets: Vec<String>,
    /// Mutations per target.
    #[arg(long, default_value_t = 1_000_000)]
    pub executions: u64,
    /// Stop each target after this many seconds even if not all executions ran.
    #[arg(long, value_parser = hubtrack_runtime::cli::seconds)]
    pub seconds: Option<f64>,
    /// Seed of the mutations.
    #[arg(long, default_value_t = 45)]
    pub seed: u64,
    /// The seed corpus (one folder per target).
    #[arg(long, default_value = "tests/fuzz-corpus")]
    pub corpus: PathBuf,
    /// Where crashing inputs are saved.
    #[arg(long, default_value = "fuzz-crashes")]
    pub out: PathBuf,
}

/// Every target.
const TARGETS: [&str; 5] = ["mcap", "mavlink", "config", "calibration", "detect"];

thread_local! {
    /// The detect target's detector, made once (its networks take a while to set up).
    static DETECTOR: std::cell::RefCell<Option<hubtrack_detect::Detector>> =
        const { std::cell::RefCell::new(None) };
}

/// One target: what it reads.
fn run_target(name: &str, input: &[u8]) {
    match name {
        "detect" => DETECTOR.with(|d| {
            let mut d = d.borrow_mut();
            let det = d.get_or_insert_with(crate::fuzz_detect::detector);
            crate::fuzz_detect::run(det, input);
        }),
        "mcap" => {
            let mut m = hubtrack_record::reader::messages_from(
                Box::new(std::io::Cursor::new(input.to_vec())),
                Path::new("mutant.mcap"),
            );
            for msg in m.by_ref() {
                std::hint::black_box(msg.data.len());
            }
            let _ = mcap::Summary::read(input);
        }
        "mavlink" => {
            use hubtrack_mavlink::{AutopilotId, FrameParser, PeerLock, VehicleMonitor};
            let mut parser = FrameParser::new();
            let mut monitor =
                VehicleMonitor::new(3_000_000_000, 500_000_000).expect_autopilot(AutopilotId {
                    system_id: 1,
                    component_id: 1,
                });
            let mut lock = PeerLock::<u8>::default();
            // In two pieces, as datagrams or serial reads cut a stream.
            let cut = input.len() / 3;
            let mut now = 0;
            for (i, part) in [&input[..cut], &input[cut..]].into_iter().enumerate() {
                let frames = parser.push(part);
                lock.observe(
                    i as u8,
                    frames.iter().map(|(h, _)| h),
                    Some(AutopilotId {
                        system_id: 1,
                        component_id: 1,
                    }),
                );
                for (h, m) in &frames {
                    now += 20_000_000;
                    std::hint::black_box(monitor.handle(now, h, m));
                }
                std::hint::black_box(monitor.state(now));
            }
        }
        "config" => {
            let text = String::from_utf8_lossy(input);
            if let Ok(doc) = hubtrack_runtime::config::ConfigDoc::parse(&text, "mutant") {
                let _ = doc.check_section_names();
                let _ = doc.sections::<crate::config::LabConfig>();
            }
        }
        "calibration" => {
            // A camera that loads is then used: every pixel ↔ ray path, scaled, on the corners.
            let text = String::from_utf8_lossy(input);
            if let Ok(cam) = hubtrack_types::setup::CameraModel::from_ros_yaml(&text) {
                let (w, h) = (f64::from(cam.width), f64::from(cam.height));
                for px in [
                    [0.0, 0.0],
                    [w - 1.0, h - 1.0],
                    [cam.cx, cam.cy],
                    [w / 3.0, h],
                ] {
                    let ray = cam.ray(px);
                    std::hint::black_box(cam.project(ray));
                    std::hint::black_box(cam.local_focal_px(px));
                }
                std::hint::black_box(cam.scaled_to(cam.width / 2, cam.height / 2).ok());
                std::hint::black_box(cam.hfov_deg());
            }
        }
        other => unreachable!("unknown target {other}"),
    }
}

fn seeds(args: &FuzzArgs, target: &str) -> anyhow::Result<Vec<Vec<u8>>> {
    let dir = args.corpus.join(target);
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .with_context(|| {
            format!(
                "the seed corpus {} (run from the repository)",
                dir.display()
            )
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    if target == "config" {
        // The documented files are seeds too.
        for f in [
            "config/hubtrack.toml",
            "config/flight.toml",
            "config/demo.toml",
        ] {
            paths.push(PathBuf::from(f));
        }
    }
    paths.sort();
    let seeds: Vec<Vec<u8>> = paths
        .iter()
        .filter_map(|p| std::fs::read(p).ok())
        .filter(|d| !d.is_empty() && d.len() <= MAX_INPUT)
        .collect();
    if seeds.is_empty() {
        bail!("no seed in {}", dir.display());
    }
    Ok(seeds)
}

/// Peak resident memory of this process (VmHWM), MiB.
fn peak_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

/// Runs the command.
pub fn run(args: FuzzArgs) -> anyhow::Result<()> {
    for t in &args.targets {
        if !TARGETS.contains(&t.as_str()) {
            bail!("--targets {t}: one of {}", TARGETS.join(", "));
        }
    }
    // Panics are what we count: keep their messages off the terminal.
    std::panic::set_hook(Box::new(|_| {}));
    println!(
        "{:<9}{:>7}{:>13}{:>10}{:>9}{:>13}{:>12}",
        "target", "seeds", "executions", "exec/s", "crashes", "slowest ms", "peak MiB"
    );
    let mut total = 0u64;
    let mut crashes_total = 0u64;
    for target in &args.targets {
        let seeds = seeds(&args, target)?;
        let mut rng = Rng::new(args.seed);
        let (mut crashes, mut slowest, mut slowest_at) = (0u64, Duration::ZERO, 0u64);
        let t0 = Instant::now();
        let mut n = 0u64;
        let limit = args.seconds.map(Duration::from_secs_f64);
        let mut data = Vec::with_capacity(MAX_INPUT);
        while n < args.executions && limit.is_none_or(|l| t0.elapsed() < l) {
            data.clear();
            data.extend_from_slice(&seeds[rng.below(seeds.len())]);
            mutate(&mut rng, &mut data, MAX_INPUT);
            let t = Instant::now();
            let ok = std::panic::catch_unwind(AssertUnwindSafe(|| run_target(target, &data)));
            let dt = t.elapsed();
            if dt > slowest {
                (slowest, slowest_at) = (dt, n);
            }
            if ok.is_err() {
                crashes += 1;
                std::fs::create_dir_all(&args.out)?;
                let path = args.out.join(format!("{target}-{}-{n}.bin", args.seed));
                std::fs::write(&path, &data)?;
                eprintln!("crash: {target} input {n} saved to {}", path.display());
            }
            n += 1;
        }
        let secs = t0.elapsed().as_secs_f64();
        println!(
            "{:<9}{:>7}{:>13}{:>10.0}{:>9}{:>13.2}{:>12.1}",
            target,
            seeds.len(),
            n,
            n as f64 / secs,
            crashes,
            slowest.as_secs_f64() * 1e3,
            peak_mib()
        );
        println!(
            "{:<9}slowest input: mutant {slowest_at} of seed {}",
            "", args.seed
        );
        total += n;
        crashes_total += crashes;
    }
    println!(
        "total    {total} executions, {crashes_total} crashes, peak memory {:.1} MiB",
        peak_mib()
    );
    if crashes_total > 0 {
        bail!(
            "{crashes_total} inputs crashed a parser (saved under {})",
            args.out.display()
        );
    }
    Ok(())
}
