//! Frame encoders for the recorder, on the synthetic camera's frames (sensor noise included):
//! time per frame on one core, bytes per frame, MB per minute at the camera's rate, and the
//! share of one core the encoding takes at that rate.
//!
//! `cargo bench -p hubtrack-record --bench encode`. `ENCODE_BENCH_FRAMES=N` sets the frames per
//! row (default 60).

use hubtrack_capture::config::{SyntheticCamera, SyntheticConfig};
use hubtrack_capture::synthetic::SyntheticSource;
use hubtrack_record::encoder::{Codec, EncodedFormat, EncoderSettings, FrameEncoder};
use hubtrack_record::video::VideoDecoder;
use hubtrack_types::{FrameHeader, PixelFormat};
use std::time::Instant;

fn pct(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: u64 = std::env::var("ENCODE_BENCH_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(60);
    println!("{n} synthetic frames per row; ms per frame on one core; MB/min and core share at the camera's rate");
    println!(
        "{:<10} {:>4} {:<18} {:>8} {:>8} {:>9} {:>8} {:>7} {:>8}",
        "size", "fps", "encoder", "median", "p99", "KB/frame", "MB/min", "core %", "PSNR dB"
    );
    for (camera, fps) in [(SyntheticCamera::Gopro, 30.0), (SyntheticCamera::Usb, 60.0)] {
        let cfg = SyntheticConfig {
            camera,
            ..SyntheticConfig::default()
        };
        let mut source = SyntheticSource::new(&cfg, fps)?;
        let (w, h) = source.size();
        let mut frames = Vec::new();
        for seq in 0..n {
            let mut px = vec![0u8; w as usize * h as usize * 3];
            source.render_index(seq, &mut px)?;
            frames.push(px);
        }
        let header = |seq| FrameHeader {
            seq,
            width: w,
            height: h,
            stride: w * 3,
            format: PixelFormat::Bgr8,
            capture_ns: (seq as f64 * 1e9 / fps) as u64,
            ..Default::default()
        };
        let mut rows: Vec<(String, Vec<f64>, f64, f64)> = Vec::new();
        let mut candidates = vec![
            (
                "jpeg-encoder q65".to_string(),
                settings(Codec::JpegRust, 65, 0, fps),
            ),
            (
                "turbojpeg q50".to_string(),
                settings(Codec::Jpeg, 50, 0, fps),
            ),
            (
                "turbojpeg q55".to_string(),
                settings(Codec::Jpeg, 55, 0, fps),
            ),
            (
                "turbojpeg q60".to_string(),
                settings(Codec::Jpeg, 60, 0, fps),
            ),
            (
                "turbojpeg q65".to_string(),
                settings(Codec::Jpeg, 65, 0, fps),
            ),
            (
                "turbojpeg q75".to_string(),
                settings(Codec::Jpeg, 75, 0, fps),
            ),
        ];
        let rates: &[u32] = if w >= 1280 {
            &[2000, 4000, 8000]
        } else {
            &[1000, 2000, 4000]
        };
        for &kbps in rates {
            candidates.push((
                format!("h264 {kbps} kb/s"),
                settings(Codec::H264, 0, kbps, fps),
            ));
        }
        for (name, s) in candidates {
            let mut enc = FrameEncoder::new(&s)?;
            let mut video = VideoDecoder::new();
            let (mut times, mut bytes, mut psnr) = (Vec::new(), 0usize, Vec::new());
            for (seq, px) in frames.iter().enumerate() {
                let h = header(seq as u64);
                let t = Instant::now();
                let e = enc.encode(&h, px)?;
                times.push(t.elapsed().as_secs_f64() * 1e3);
                bytes += e.data.len();
                let back = match e.format {
                    EncodedFormat::Jpeg => hubtrack_record::jpeg::decode(&e.data, &h)?,
                    EncodedFormat::H264 => video.decode(&e.data, &h)?,
                };
                psnr.push(psnr_db(px, &back));
            }
            let mean_psnr = psnr.iter().sum::<f64>() / psnr.len() as f64;
            rows.push((name, times, bytes as f64 / n as f64, mean_psnr));
        }
        // The raw alternative: lz4 over the pixels, as the MCAP writer compresses raw frames.
        let (mut times, mut bytes) = (Vec::new(), 0usize);
        for px in &frames {
            let t = Instant::now();
            let c = lz4_flex_free(px);
            times.push(t.elapsed().as_secs_f64() * 1e3);
            bytes += c;
        }
        rows.push((
            "raw + lz4".into(),
            times,
            bytes as f64 / n as f64,
            f64::INFINITY,
        ));
        for (name, mut times, per_frame, psnr) in rows {
            let median = pct(&mut times, 0.5);
            println!(
                "{:<10} {:>4} {:<18} {:>8.2} {:>8.2} {:>9.0} {:>8.0} {:>7.0} {:>8.1}",
                format!("{w}x{h}"),
                fps,
                name,
                median,
                pct(&mut times, 0.99),
                per_frame / 1e3,
                per_frame * fps * 60.0 / 1e6,
                median * fps / 10.0,
                psnr
            );
        }
    }
    Ok(())
}

fn settings(codec: Codec, jpeg_quality: u32, h264_bitrate_kbps: u32, fps: f64) -> EncoderSettings {
    EncoderSettings {
        codec,
        jpeg_quality,
        h264_bitrate_kbps,
        keyframe_interval: fps as u32,
        max_fps: fps as f32,
    }
}

/// PSNR of `b` against `a` over all bytes, dB.
fn psnr_db(a: &[u8], b: &[u8]) -> f64 {
    let mse = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
        .sum::<f64>()
        / a.len() as f64;
    10.0 * (255.0f64 * 255.0 / mse.max(1e-12)).log10()
}

/// Bytes of `px` after the MCAP writer's lz4 (frame format, as in a chunk).
fn lz4_flex_free(px: &[u8]) -> usize {
    let mut out = Vec::with_capacity(px.len() / 2);
    let mut enc = lz4::EncoderBuilder::new()
        .level(0)
        .build(&mut out)
        .expect("lz4 encoder");
    std::io::Write::write_all(&mut enc, px).expect("in memory");
    let (_, r) = enc.finish();
    r.expect("in memory");
    out.len()
}
