//! `hubtrack bench frames`: the frames hop measured across real processes, against a copying
//! baseline. A command that prints a table, not a timed test: compare the columns of one run.

use crate::config::LabConfig;
use anyhow::Context;
use hubtrack_capture::config::{SyntheticCamera, SyntheticConfig};
use hubtrack_capture::synthetic::SyntheticSource;
use hubtrack_supervisor::launch::{stage_binary, Stage};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Arguments of `hubtrack bench frames`.
#[derive(clap::Args)]
pub struct FramesBenchArgs {
    /// Seconds per measurement.
    #[arg(long, default_value_t = 20.0, value_parser = hubtrack_runtime::cli::seconds)]
    pub seconds: f64,
    /// Frame rate.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Lens / frame size: gopro (1920x1080) or usb (640x480).
    #[arg(long, default_value = "gopro")]
    pub camera: String,
    /// Also run the recorder (as in flight).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub record: bool,
}

/// p50, p99 and max of a sample, in the sample's unit.
fn percentiles(v: &mut [f64]) -> (f64, f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    v.sort_by(|a, b| a.total_cmp(b));
    (quantile(v, 0.5), quantile(v, 0.99), v[v.len() - 1])
}

/// The `q` quantile of a sorted, non-empty sample (nearest rank).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

struct HopResult {
    published: u64,
    received: u64,
    recorded: Option<u64>,
    dropped: u64,
    latency_us: Vec<f64>,
}

/// Runs the benchmark and prints the table.
pub fn frames(args: FramesBenchArgs) -> anyhow::Result<()> {
    let camera = match args.camera.as_str() {
        "gopro" => SyntheticCamera::Gopro,
        "usb" => SyntheticCamera::Usb,
        other => anyhow::bail!("--camera {other}: expected gopro or usb"),
    };
    let mut config = LabConfig::default();
    config.capture.synthetic.camera = camera;
    config.capture.fps = args.fps;

    // Renderer cost, in this process (the capture process pays the same per frame).
    let mut source = SyntheticSource::new(&config.capture.synthetic, args.fps)?;
    let (w, h) = source.size();
    let frame_len = w as usize * h as usize * 3;
    let mut pixels = vec![0u8; frame_len];
    let mut render_ms = Vec::new();
    for i in 0..60 {
        let t = Instant::now();
        source.render_index(i, &mut pixels)?;
        render_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let (r50, r99, _) = percentiles(&mut render_ms);

    // Both hops run at the same time, so both see the same load (renderer, recorder, copies).
    eprintln!(
        "[bench] {} s: iceoryx2 hop capture -> reader{} and, concurrently, a Unix-socket hop of the same frames",
        args.seconds,
        if args.record { " (+ recorder)" } else { "" }
    );
    let frame = pixels.clone();
    let (fps, seconds) = (args.fps, args.seconds);
    let socket = std::thread::spawn(move || {
        // Start once the capture process is up (it takes ~0.5 s to start and render).
        std::thread::sleep(Duration::from_millis(900));
        socket_hop(&frame, fps, seconds - 1.0)
    });
    let shm = iceoryx2_hop(&args, camera)?;
    let uds = socket
        .join()
        .map_err(|_| anyhow::anyhow!("socket hop panicked"))??;

    let mut shm_lat = shm.latency_us.clone();
    let mut uds_lat = uds.latency_us.clone();
    let (s50, s99, smax) = percentiles(&mut shm_lat);
    let (u50, u99, umax) = percentiles(&mut uds_lat);
    println!(
        "\nframes hop: {w}x{h} BGR8 ({:.1} MB) at {} fps for {} s, {} cores, both hops concurrently",
        frame_len as f64 / 1e6,
        args.fps,
        args.seconds,
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!(
        "{:<34}{:>22}{:>22}",
        "", "iceoryx2 (zero-copy)", "Unix socket (copy)"
    );
    println!(
        "{:<34}{:>22}{:>22}",
        "frames published", shm.published, uds.published
    );
    println!(
        "{:<34}{:>22}{:>22}",
        "frames received by a reader", shm.received, uds.received
    );
    println!(
        "{:<34}{:>22}{:>22}",
        "frames recorded (MCAP)",
        shm.recorded.map_or("-".into(), |n| n.to_string()),
        "-"
    );
    println!(
        "{:<34}{:>22}{:>22}",
        "frames dropped / lost", shm.dropped, uds.dropped
    );
    println!(
        "{:<34}{:>22.0}{:>22.0}",
        "publish -> receive p50 [us]", s50, u50
    );
    println!(
        "{:<34}{:>22.0}{:>22.0}",
        "publish -> receive p99 [us]", s99, u99
    );
    println!(
        "{:<34}{:>22.0}{:>22.0}",
        "publish -> receive max [us]", smax, umax
    );
    println!(
        "{:<34}{:>22.1}{:>22}",
        "p50 ratio (socket / iceoryx2)",
        u50 / s50,
        ""
    );
    println!("renderer per {w}x{h} frame: median {r50:.2} ms, p99 {r99:.2} ms (budget at {} fps: {:.1} ms)", args.fps, 1e3 / args.fps);
    Ok(())
}

fn iceoryx2_hop(args: &FramesBenchArgs, camera: SyntheticCamera) -> anyhow::Result<HopResult> {
    // A private IPC domain so a running pipeline is not disturbed.
    let domain = format!("bench-{}", std::process::id());
    std::env::set_var(hubtrack_runtime::ipc::DOMAIN_ENV, &domain);
    let cam = match camera {
        SyntheticCamera::Gopro => "gopro",
        SyntheticCamera::Usb => "usb",
    };
    let common = vec![
        "--set".to_string(),
        format!("capture.synthetic.camera={cam}"),
        "--set".into(),
        format!("capture.fps={}", args.fps),
    ];
    let dir = std::env::temp_dir().join(&domain);
    std::fs::create_dir_all(&dir)?;
    let rec_path = dir.join("bench.mcap");
    let mut recorder = None;
    if args.record {
        let mut a = common.clone();
        a.extend(["--output".to_string(), rec_path.display().to_string()]);
        recorder = Some(Stage::spawn(
            "recorder",
            &stage_binary("recorder")?,
            &a,
            false,
            0,
            true,
        )?);
        std::thread::sleep(Duration::from_millis(300));
    }
    let exe = flight_binary()?;
    let mut tap = Command::new(&exe)
        .args(["tap", "--duration", &format!("{}", args.seconds + 1.0)])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .context("starting the tap reader")?;
    // Read the reader's lines while it runs: a full pipe would block it and lose frames.
    let tap_out = tap.stdout.take().expect("piped");
    let lines = std::thread::spawn(move || {
        BufReader::new(tap_out)
            .lines()
            .map_while(Result::ok)
            .collect::<Vec<_>>()
    });
    std::thread::sleep(Duration::from_millis(300));
    let mut capture = Stage::spawn(
        "capture",
        &stage_binary("capture")?,
        &common,
        false,
        0,
        true,
    )?;
    std::thread::sleep(Duration::from_secs_f64(args.seconds));
    capture.stop(Duration::from_secs(3));
    let mut latency_us = Vec::new();
    let mut received = 0;
    let mut last = None;
    let mut lost = 0;
    let _ = tap.wait();
    for line in lines
        .join()
        .map_err(|_| anyhow::anyhow!("tap reader thread panicked"))?
    {
        let v: serde_json::Value = serde_json::from_str(&line)?;
        received += 1;
        latency_us.push(v["latency_us"].as_f64().unwrap_or(f64::NAN));
        last = v["seq"].as_u64();
        lost = v["lost"].as_u64().unwrap_or(0);
    }
    let published = last.map_or(0, |s| s + 1);
    let mut recorded = None;
    if let Some(mut r) = recorder {
        r.stop(Duration::from_secs(30));
        let info = hubtrack_record::inspect(&rec_path)?;
        recorded = info.topic_counts.get("/frames").copied();
        let _ = std::fs::remove_file(&rec_path);
    }
    let _ = std::fs::remove_dir(&dir);
    Ok(HopResult {
        published,
        received,
        recorded,
        dropped: lost,
        latency_us,
    })
}

/// The same frames, written whole into a Unix stream socket by one thread and read whole by
/// another: every byte is copied into and out of the kernel.
fn socket_hop(frame: &[u8], fps: f64, seconds: f64) -> anyhow::Result<HopResult> {
    let (mut tx, mut rx) = UnixStream::pair()?;
    let len = frame.len();
    let period = Duration::from_secs_f64(1.0 / fps);
    let n = (seconds * fps) as u64;
    let epoch = Instant::now();
    let reader = std::thread::spawn(move || -> std::io::Result<(u64, Vec<f64>)> {
        let mut buf = vec![0u8; len];
        let mut stamp = [0u8; 8];
        let mut lat = Vec::new();
        let mut got = 0;
        loop {
            if rx.read_exact(&mut stamp).is_err() {
                break;
            }
            rx.read_exact(&mut buf)?;
            let sent = u64::from_le_bytes(stamp);
            lat.push((epoch.elapsed().as_nanos() as u64 - sent) as f64 / 1e3);
            got += 1;
        }
        Ok((got, lat))
    });
    let mut next = Instant::now();
    for _ in 0..n {
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        }
        next += period;
        tx.write_all(&(epoch.elapsed().as_nanos() as u64).to_le_bytes())?;
        tx.write_all(frame)?;
    }
    drop(tx);
    let (received, latency_us) = reader
        .join()
        .map_err(|_| anyhow::anyhow!("reader panicked"))??;
    Ok(HopResult {
        published: n,
        received,
        recorded: None,
        dropped: n - received,
        latency_us,
    })
}

/// The stages `hubtrack bench pipeline` runs, in pipeline order.
const PIPELINE_STAGES: [&str; 5] = ["capture", "detect", "track", "control", "recorder"];
/// Control's autopilot link in the pipeline benchmark: listen on a port the OS picks.
const BENCH_CONTROL_LINK: &str = "udpin:127.0.0.1:0";
/// Niceness of the synthetic camera in the pipeline benchmark (see `pipeline_one`).
const SYNTHETIC_CAMERA_NICE: i32 = 10;
/// Frames the benchmark's camera renders and then plays in a loop (one second at 30 fps; 190 MB
/// at 1920x1080), unless `--render-every-frame`.
const BENCH_CAMERA_CACHED_FRAMES: u32 = 30;
/// Linux's clock tick for the CPU times in /proc (USER_HZ).
const USER_HZ: f64 = 100.0;
/// The detect stage's process name in /proc (`comm`, 15 characters).
const DETECT_PROCESS: &str = "hubtrack-detect";
/// Longest solo detect measurement around each pipeline run (a third of the run otherwise).
const DETECT_ALONE_MAX_SECONDS: f64 = 20.0;

/// Arguments of `hubtrack bench pipeline`.
#[derive(clap::Args)]
pub struct PipelineBenchArgs {
    /// Seconds per configuration.
    #[arg(long, default_value_t = 60.0, value_parser = hubtrack_runtime::cli::seconds)]
    pub seconds: f64,
    /// Only the 1920x1080 at 30 fps configuration (skip 640x480 at 60 fps).
    #[arg(long)]
    pub only_hd: bool,
    /// Pipeline runs per configuration, each followed by detect alone on the same frames; the
    /// comparison's median over rounds is printed (this machine's pace moves by a quarter from
    /// one minute to the next: more rounds, steadier figure).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub rounds: u32,
    /// CPU list to pin the pipeline to (taskset syntax).
    #[arg(long, default_value = "0,1")]
    pub cpus: String,
    /// Render every frame in the synthetic camera (most of a core at 1920x1080, work a real
    /// camera does in hardware). By default the camera renders its first
    /// `BENCH_CAMERA_CACHED_FRAMES` frames and plays them again, costing a copy per frame.
    #[arg(long)]
    pub render_every_frame: bool,
    /// Override one key of the benchmarked pipeline's config, after the benchmark's own, e.g.
    /// `--set recorder.compression="none"` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// Arguments of `hubtrack bench detect-alone`.
#[derive(clap::Args)]
pub struct DetectAloneArgs {
    /// Lens / frame size: gopro (1920x1080) or usb (640x480).
    #[arg(long, default_value = "gopro", value_parser = ["gopro", "usb"])]
    pub camera: String,
    /// Frame rate the detector is paced at (as the camera paces the detect stage).
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Seconds of detection, after one warm-up pass over the frames.
    #[arg(long, default_value_t = 20.0, value_parser = hubtrack_runtime::cli::seconds)]
    pub seconds: f64,
    /// One JSON object instead of the table line.
    #[arg(long)]
    pub json: bool,
    /// Override one key of the config, after the benchmark camera's, as for the pipeline
    /// (`bench pipeline` passes its own `--set` on; repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// Detect alone: its time per frame on the frames the pipeline benchmark's camera plays.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct DetectAlone {
    /// Median, ms.
    pub p50_ms: f64,
    /// 90th percentile, ms.
    pub p90_ms: f64,
    /// CPU time of the process per frame, ms (all its threads; on a virtual machine without
    /// the time its virtual CPUs were stolen by the host, which the wall clock includes).
    pub cpu_ms_per_frame: f64,
    /// Frames timed.
    pub frames: usize,
}

/// The config overrides that make `hubtrack run` (and the solo detector) use the benchmark's
/// camera: the same lens, rate and looped frames.
fn bench_camera_overrides(camera: &str, fps: f64, cached_frames: u32) -> Vec<String> {
    vec![
        format!("capture.synthetic.camera={camera}"),
        format!("capture.fps={fps}"),
        format!("capture.synthetic.cache_frames={cached_frames}"),
    ]
}

/// `hubtrack bench detect-alone`: the detector with the detect stage's config on the frames the
/// pipeline benchmark's camera plays, paced at the camera's rate, with the hints the stage has
/// there (the tracker's hub and distance, here the truth; no roll: no autopilot). The solo
/// figure that detect's time inside the pipeline compares with; `bench pipeline` runs it pinned
/// to the same cores before and after each configuration.
pub fn detect_alone(args: DetectAloneArgs) -> anyhow::Result<()> {
    let r = detect_alone_measure(&args)?;
    if args.json {
        println!("{}", serde_json::to_string(&r)?);
    } else {
        println!(
            "detect alone: {} at {} fps, {} frames: p50 {:.2} ms, p90 {:.2} ms, CPU {:.2} ms per frame",
            args.camera, args.fps, r.frames, r.p50_ms, r.p90_ms, r.cpu_ms_per_frame
        );
    }
    Ok(())
}

fn detect_alone_measure(args: &DetectAloneArgs) -> anyhow::Result<DetectAlone> {
    use hubtrack_detect::{Detector, Hints, ImageView};
    // The pipeline's camera overrides first, as `bench pipeline` gives them to `hubtrack run`.
    let mut overrides = bench_camera_overrides(&args.camera, args.fps, BENCH_CAMERA_CACHED_FRAMES);
    overrides.extend(args.set.iter().cloned());
    let config = crate::config::load(&hubtrack_runtime::config::ConfigArgs {
        overrides,
        ..Default::default()
    })?;
    let mut source = SyntheticSource::new(&config.capture.synthetic, args.fps)?;
    let (width, height) = source.size();
    let bytes = width as usize * height as usize * 3;
    let mut frames = Vec::new();
    for index in 0..u64::from(BENCH_CAMERA_CACHED_FRAMES) {
        let mut pixels = vec![0u8; bytes];
        let truth = source.render_index(index, &mut pixels)?;
        let hints = Hints {
            roll_rad: None,
            predicted_hub_px: truth.hub_px.filter(|_| truth.turbine_in_view),
            hub_distance_m: Some(truth.distance_m),
        };
        frames.push((pixels, hints));
    }
    let mut detector = Detector::new(config.detect.clone())?;
    let period = Duration::from_secs_f64(1.0 / args.fps);
    let warm_up = frames.len();
    let total = warm_up + (args.seconds * args.fps).ceil() as usize;
    let mut ms = Vec::with_capacity(total);
    let mut cpu_ticks_at_warm = None;
    let start = Instant::now();
    for (i, (pixels, hints)) in frames.iter().cycle().take(total).enumerate() {
        if i == warm_up {
            cpu_ticks_at_warm = proc_sample(std::process::id()).map(|s| s.cpu_ticks);
        }
        if let Some(wait) = (start + period * i as u32).checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let image = ImageView {
            width,
            height,
            stride: width as usize * 3,
            format: hubtrack_types::PixelFormat::Bgr8,
            data: pixels,
        };
        let t = Instant::now();
        detector.detect(&image, hints)?;
        if i >= warm_up {
            ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    let cpu_ticks = cpu_ticks_at_warm
        .zip(proc_sample(std::process::id()))
        .map_or(0, |(t0, s)| s.cpu_ticks.saturating_sub(t0));
    ms.sort_by(f64::total_cmp);
    Ok(DetectAlone {
        p50_ms: quantile(&ms, 0.5),
        p90_ms: quantile(&ms, 0.9),
        cpu_ms_per_frame: cpu_ticks as f64 * 1e3 / USER_HZ / ms.len() as f64,
        frames: ms.len(),
    })
}

/// Runs `hubtrack bench detect-alone` pinned to `cpus` (a child, so that the pinning and the
/// detector's threads are exactly the detect stage's).
fn detect_alone_pinned(
    taskset: Option<&str>,
    bench: &PipelineBenchArgs,
    camera: &str,
    fps: f64,
    seconds: f64,
) -> anyhow::Result<DetectAlone> {
    let lab = std::env::current_exe()?;
    let sets = bench
        .set
        .iter()
        .flat_map(|kv| ["--set".to_string(), kv.clone()]);
    let args = [
        "bench".to_string(),
        "detect-alone".into(),
        "--camera".into(),
        camera.into(),
        "--fps".into(),
        fps.to_string(),
        "--seconds".into(),
        seconds.to_string(),
        "--json".into(),
    ]
    .into_iter()
    .chain(sets);
    let mut cmd = match taskset {
        Some(ts) => {
            let mut c = Command::new(ts);
            c.arg("-c").arg(&bench.cpus).arg(&lab);
            c
        }
        None => Command::new(&lab),
    };
    let out = cmd
        .args(args)
        .stderr(Stdio::inherit())
        .output()
        .context("running bench detect-alone")?;
    anyhow::ensure!(
        out.status.success(),
        "bench detect-alone failed: {}",
        out.status
    );
    let line = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(line.trim()).context("reading bench detect-alone's result")
}

/// CPU time and peak memory of one process, from /proc.
#[derive(Debug, Clone, Copy, Default)]
struct ProcSample {
    cpu_ticks: u64,
    peak_rss_kb: u64,
}

fn proc_sample(pid: u32) -> Option<ProcSample> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let cpu_ticks = f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?;
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let peak_rss_kb = status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    Some(ProcSample {
        cpu_ticks,
        peak_rss_kb,
    })
}

fn children(pid: u32) -> Vec<u32> {
    let mut out = Vec::new();
    if let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) {
        for t in tasks.flatten() {
            if let Ok(c) = std::fs::read_to_string(t.path().join("children")) {
                out.extend(c.split_whitespace().filter_map(|p| p.parse::<u32>().ok()));
            }
        }
    }
    out
}

fn proc_name(pid: u32) -> String {
    std::fs::read_to_string(format!("/proc/{pid}/comm"))
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

/// Runs the pipeline benchmark: each configuration pinned to `--cpus`, recorder on.
pub fn pipeline(args: PipelineBenchArgs) -> anyhow::Result<()> {
    let mut configs = vec![("gopro", 30.0)];
    if !args.only_hd {
        configs.push(("usb", 60.0));
    }
    for (camera, fps) in configs {
        pipeline_one(&args, camera, fps)?;
    }
    Ok(())
}

/// One configuration: `--rounds` pipeline runs, detect alone on the same frames and cores
/// before the first and after each (the machine's pace drifts: each run is compared with the
/// solo runs on either side of it), then detect's median inside the pipeline against alone.
fn pipeline_one(args: &PipelineBenchArgs, camera: &str, fps: f64) -> anyhow::Result<()> {
    let taskset = ["/usr/bin/taskset", "/bin/taskset"]
        .into_iter()
        .find(|p| Path::new(p).exists());
    let solo_seconds = (args.seconds / 3.0).clamp(5.0, DETECT_ALONE_MAX_SECONDS);
    let alone = |when: &str| {
        eprintln!("[bench] detect alone on the same frames for {solo_seconds:.0} s ({when}) ...");
        detect_alone_pinned(taskset, args, camera, fps, solo_seconds)
    };
    let mut before = alone("before round 1")?;
    let (mut wall_ratios, mut cpu_ratios) = (Vec::new(), Vec::new());
    let mut rows = Vec::new();
    for round in 1..=args.rounds {
        let last = round == args.rounds;
        let inside = pipeline_round(args, camera, fps, taskset, last)?;
        let after = alone(&format!("after round {round}"))?;
        let wall = inside.p50_ms / ((before.p50_ms + after.p50_ms) / 2.0);
        let cpu =
            inside.cpu_ms_per_frame / ((before.cpu_ms_per_frame + after.cpu_ms_per_frame) / 2.0);
        wall_ratios.extend(Some(wall).filter(|r| r.is_finite()));
        cpu_ratios.extend(Some(cpu).filter(|r| r.is_finite()));
        rows.push((round, inside, before, after, wall, cpu));
        before = after;
    }
    println!(
        "\ndetect, {camera} at {fps} fps: in the pipeline against alone (same frames, config, hints, pace and cores; `hubtrack bench detect-alone`); wall = median time per frame, CPU = the process's CPU time per frame"
    );
    println!(
        "  {:<7}{:>17}{:>18}{:>18}{:>11}{:>11}",
        "round", "pipeline wall/CPU", "alone before", "alone after", "wall", "CPU"
    );
    let pair = |w: f64, c: f64| format!("{w:.2} / {c:.2} ms");
    for (round, inside, b, a, wall, cpu) in rows {
        println!(
            "  {round:<7}{:>17}{:>18}{:>18}{:>+10.0}%{:>+10.0}%",
            pair(inside.p50_ms, inside.cpu_ms_per_frame),
            pair(b.p50_ms, b.cpu_ms_per_frame),
            pair(a.p50_ms, a.cpu_ms_per_frame),
            (wall - 1.0) * 100.0,
            (cpu - 1.0) * 100.0
        );
    }
    if let (Some(wall), Some(cpu)) = (median(&mut wall_ratios), median(&mut cpu_ratios)) {
        println!(
            "  median over {} round(s): pipeline against alone, wall {:+.0} %, CPU {:+.0} %",
            wall_ratios.len(),
            (wall - 1.0) * 100.0,
            (cpu - 1.0) * 100.0
        );
    }
    Ok(())
}

/// The median (the mean of the middle two of an even count); `None` when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some((v[n / 2 - 1] + v[n / 2]) / 2.0),
    }
}

/// One pipeline run of one configuration, its table printed; returns detect's time inside the
/// pipeline (NaN without detections).
fn pipeline_round(
    args: &PipelineBenchArgs,
    camera: &str,
    fps: f64,
    taskset: Option<&str>,
    with_socket_baseline: bool,
) -> anyhow::Result<DetectInside> {
    let domain = format!("bench-pipe-{}", std::process::id());
    let dir = std::env::temp_dir().join(&domain);
    std::fs::create_dir_all(&dir)?;
    let rec = dir.join("pipeline.mcap");
    let exe = flight_binary()?;
    let run_args: Vec<String> = vec![
        "run".into(),
        "--record".into(),
        rec.display().to_string(),
        "--duration".into(),
        args.seconds.to_string(),
        "--set".into(),
        format!("run.stages={PIPELINE_STAGES:?}"),
        // No autopilot: control still publishes every setpoint (not sent), and its link listens
        // on a port the OS picks, so it cannot collide with a live pipeline's autopilot link.
        "--set".into(),
        format!("control.link=\"{BENCH_CONTROL_LINK}\""),
        // The synthetic camera renders frames in software, work a real camera does in
        // hardware. It runs at the recorder's niceness: it loads the machine without standing
        // in front of the flight stages.
        "--set".into(),
        format!("run.nice.capture={SYNTHETIC_CAMERA_NICE}"),
    ];
    let cached = if args.render_every_frame {
        0
    } else {
        BENCH_CAMERA_CACHED_FRAMES
    };
    let run_args: Vec<String> = run_args
        .into_iter()
        .chain(
            bench_camera_overrides(camera, fps, cached)
                .iter()
                .chain(&args.set)
                .flat_map(|kv| ["--set".to_string(), kv.clone()]),
        )
        .collect();
    let mut cmd = match taskset {
        Some(ts) => {
            let mut c = Command::new(ts);
            c.arg("-c").arg(&args.cpus).arg(&exe).args(&run_args);
            c
        }
        None => {
            eprintln!("[bench] taskset not found: running unpinned");
            let mut c = Command::new(&exe);
            c.args(&run_args);
            c
        }
    };
    eprintln!(
        "[bench] {camera} at {fps} fps for {} s, pinned to cpus {} ...",
        args.seconds, args.cpus
    );
    let mut run = cmd
        .env(hubtrack_runtime::ipc::DOMAIN_ENV, &domain)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()?;
    let run_pid = run.id();
    // The copying baseline's frame (sent after the run: see below).
    let mut source = SyntheticSource::new(
        &SyntheticConfig {
            camera: if camera == "usb" {
                SyntheticCamera::Usb
            } else {
                SyntheticCamera::Gopro
            },
            ..Default::default()
        },
        fps,
    )?;
    let (w, h) = source.size();
    let mut frame = vec![0u8; w as usize * h as usize * 3];
    source.render_index(0, &mut frame)?;
    // Sample every process of the run once a second; keep the last sample of each pid.
    let mut first: BTreeMap<u32, (String, ProcSample, Instant)> = BTreeMap::new();
    let mut last: BTreeMap<u32, (ProcSample, Instant)> = BTreeMap::new();
    while run.try_wait()?.is_none() {
        let mut pids = vec![run_pid];
        pids.extend(children(run_pid));
        let all: Vec<u32> = pids
            .iter()
            .flat_map(|p| std::iter::once(*p).chain(children(*p)))
            .collect();
        for pid in all {
            if let Some(s) = proc_sample(pid) {
                let name = proc_name(pid);
                first.entry(pid).or_insert((name, s, Instant::now()));
                // The peak of all samples: an exiting process (zombie) reports no VmHWM.
                let peak = last
                    .get(&pid)
                    .map_or(0, |(p, _)| p.peak_rss_kb)
                    .max(s.peak_rss_kb);
                last.insert(
                    pid,
                    (
                        ProcSample {
                            peak_rss_kb: peak,
                            ..s
                        },
                        Instant::now(),
                    ),
                );
            }
        }
        std::thread::sleep(Duration::from_millis(500));
    }
    // The copying baseline: the same frames at the same rate over a Unix socket, alone after
    // the run, so that neither measurement loads the other.
    let uds = if with_socket_baseline {
        eprintln!(
            "[bench] Unix-socket copy of the same frames for {:.0} s ...",
            (args.seconds - 3.0).max(1.0)
        );
        Some(socket_hop(&frame, fps, (args.seconds - 3.0).max(1.0))?)
    } else {
        None
    };
    let mut per_name: BTreeMap<String, (f64, u64)> = BTreeMap::new();
    let mut detect_cpu_s = 0.0;
    for (pid, (name, s0, t0)) in &first {
        if let Some((s1, t1)) = last.get(pid) {
            let secs = t1.duration_since(*t0).as_secs_f64().max(1e-3);
            let cpu_s = (s1.cpu_ticks - s0.cpu_ticks) as f64 / USER_HZ;
            let e = per_name.entry(name.clone()).or_insert((0.0, 0));
            e.0 += cpu_s / secs * 100.0;
            e.1 = e.1.max(s1.peak_rss_kb);
            if name == DETECT_PROCESS {
                detect_cpu_s += cpu_s;
            }
        }
    }
    let report = hubtrack_record::latency::analyze(&rec)?;
    let info = hubtrack_record::inspect(&rec)?;
    println!(
        "\npipeline: {camera} {w}x{h} at {fps} fps for {} s, {}, pinned to cpus {}, camera {}{}",
        args.seconds,
        PIPELINE_STAGES.join("+"),
        args.cpus,
        if args.render_every_frame {
            "rendering every frame".to_string()
        } else {
            format!("playing {BENCH_CAMERA_CACHED_FRAMES} rendered frames in a loop")
        },
        if args.set.is_empty() {
            " (default settings: JPEG frames)".to_string()
        } else {
            format!(", with {}", args.set.join(" "))
        }
    );
    hubtrack_record::latency::print(&report);
    println!("{:<22}{:>10}{:>16}", "process", "CPU %", "peak RSS MB");
    let mut flight = 0.0;
    for (name, (cpu, rss)) in &per_name {
        println!("  {:<20}{:>10.1}{:>16.1}", name, cpu, *rss as f64 / 1024.0);
        if name != "hubtrack-captur" && name != "taskset" {
            flight += cpu;
        }
    }
    println!("  flight stages (all but the synthetic camera): {flight:.1} % of one core");
    if let (Some(uds), Some(hop)) = (
        &uds,
        report.hops.iter().find(|h| h.name == "capture->detect"),
    ) {
        let mut l = uds.latency_us.clone();
        let (u50, u99, _) = percentiles(&mut l);
        println!(
            "frames hop capture->detect: iceoryx2 p50 {:.0} us, p99 {:.0} us | Unix-socket copy (after the run): p50 {:.0} us, p99 {:.0} us | ratio p50 {:.1}x",
            hop.p50_us, hop.p99_us, u50, u99, u50 / hop.p50_us
        );
    }
    println!(
        "recorded: {} frames, {} detections, {} track states, {} setpoints; file {:.0} MB",
        info.topic_counts.get("/frames").copied().unwrap_or(0),
        info.topic_counts.get("/detections").copied().unwrap_or(0),
        info.topic_counts.get("/track").copied().unwrap_or(0),
        info.topic_counts.get("/setpoints").copied().unwrap_or(0),
        info.size_bytes as f64 / 1e6
    );
    println!(
        "recording: {:.0} MB per minute",
        info.size_bytes as f64 / 1e6 / (args.seconds / 60.0)
    );
    match hubtrack_record::channels::read(&rec).ok().and_then(|c| c.recorder) {
        Some(r) => println!(
            "recorder: {} frames received, {} recorded, {} dropped (writer behind), {} lost in shared memory, {} not encodable",
            r.frames_received, r.frames_recorded, r.frames_dropped_queue, r.frames_lost, r.frames_encode_failed
        ),
        None => println!("recorder: no /recorder counters in the file"),
    }
    let _ = std::fs::remove_file(&rec);
    let _ = std::fs::remove_dir(&dir);
    let detect = report.stages.iter().find(|s| s.name == "detect");
    Ok(DetectInside {
        p50_ms: detect.map_or(f64::NAN, |s| s.p50_us / 1e3),
        cpu_ms_per_frame: detect.map_or(f64::NAN, |s| detect_cpu_s * 1e3 / s.count as f64),
    })
}

/// Detect's time inside one pipeline run.
struct DetectInside {
    /// Median time in the stage (receive to publish), ms.
    p50_ms: f64,
    /// CPU time of the detect process over the run per frame it detected, ms.
    cpu_ms_per_frame: f64,
}

/// The flight command `hubtrack` beside this binary: the benchmarks drive it as an operator would.
fn flight_binary() -> anyhow::Result<std::path::PathBuf> {
    let exe = std::env::current_exe()?.with_file_name("hubtrack");
    anyhow::ensure!(
        exe.is_file(),
        "{} not found beside hubtrack-lab",
        exe.display()
    );
    Ok(exe)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&mut []), None);
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        // Two rounds, -5 % and +37 %: their mean, not the upper one.
        let two = median(&mut [1.37, 0.95]).unwrap();
        assert!((two - 1.16).abs() < 1e-12, "{two}");
    }
}
