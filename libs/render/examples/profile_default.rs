//! Render scene variants repeatedly, for profiling with `perf record` or comparing costs.
//!
//! Usage: `profile_default [FRAMES] [VARIANT...]` with variants default, sea, hills, extras,
//! jpeg, blur. Frames of all given variants are interleaved (fair under a noisy machine) and
//! the median per variant is printed.
use hubtrack_render::{Camera, CameraPose, Distractor, Ground, Renderer, Scene, Sky};

fn scene_for(variant: &str) -> Scene {
    let base = Scene::default_clear();
    match variant {
        "sea" => Scene {
            sky: Sky::Clouds,
            ground: Ground::Sea,
            ..base
        },
        "hills" => Scene {
            sky: Sky::Overcast,
            ground: Ground::Hills,
            ..base
        },
        "extras" => Scene {
            second_turbine: true,
            propellers_in_view: true,
            distractor: Distractor::PowerLines,
            ..base
        },
        "jpeg" => Scene {
            jpeg_quality: Some(75),
            ..base
        },
        "blur" => Scene { blur: true, ..base },
        _ => base,
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(100);
    let mut variants: Vec<String> = args.collect();
    if variants.is_empty() {
        variants.push("default".into());
    }
    let cam = Camera::gopro_hero3();
    let mut r = Renderer::new(cam);
    let mut buf = vec![0u8; cam.frame_bytes()];
    let mut times = vec![Vec::with_capacity(n); variants.len()];
    for i in 0..n {
        for (k, v) in variants.iter().enumerate() {
            let pose = CameraPose {
                roll_deg: 2.0,
                ..CameraPose::looking_at_hub(120.0 - (i % 50) as f64, 5.0, -10.0)
            };
            let s = Scene {
                rotor_angle_deg: i as f64 * 3.0,
                frame: i as u64,
                ..scene_for(v)
            };
            let t0 = std::time::Instant::now();
            if let Err(e) = r.render(&s, &pose, &mut buf) {
                eprintln!("render failed: {e}");
                return;
            }
            times[k].push(t0.elapsed().as_secs_f64() * 1e3);
        }
    }
    for (v, t) in variants.iter().zip(&mut times) {
        t.sort_by(|a, b| a.total_cmp(b));
        println!("{v}: median {:.2} ms, min {:.2} ms", t[t.len() / 2], t[0]);
    }
}
