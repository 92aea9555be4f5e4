//! Render timing: median and p99 per scene variant and camera, single-threaded.
//!
//! `cargo bench -p hubtrack-render` (plain `Instant`, no criterion). Optional first argument:
//! number of frames per variant (default 50).

use std::time::Instant;

use hubtrack_render::{Camera, CameraPose, Distractor, Ground, Renderer, Scene, Sky};

fn main() {
    let frames: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(50);
    let base = Scene::default_clear();
    let variants: Vec<(&str, Scene)> = vec![
        ("default (noise on)", base.clone()),
        (
            "no effects",
            Scene {
                noise_sigma: 0.0,
                ..base.clone()
            },
        ),
        (
            "clouds + sea",
            Scene {
                sky: Sky::Clouds,
                ground: Ground::Sea,
                ..base.clone()
            },
        ),
        (
            "overcast + hills",
            Scene {
                sky: Sky::Overcast,
                ground: Ground::Hills,
                ..base.clone()
            },
        ),
        (
            "all extras",
            Scene {
                second_turbine: true,
                propellers_in_view: true,
                distractor: Distractor::PowerLines,
                ..base.clone()
            },
        ),
        (
            "blur",
            Scene {
                blur: true,
                ..base.clone()
            },
        ),
        (
            "jpeg q75",
            Scene {
                jpeg_quality: Some(75),
                ..base.clone()
            },
        ),
        (
            "blur + jpeg q75",
            Scene {
                blur: true,
                jpeg_quality: Some(75),
                ..base.clone()
            },
        ),
    ];
    let cameras = [
        ("gopro 1920x1080", Camera::gopro_hero3()),
        ("usb 640x480", Camera::usb_narrow()),
    ];
    println!(
        "{:<22} {:<17} {:>10} {:>10}",
        "scene variant", "camera", "median ms", "p99 ms"
    );
    for (cam_name, cam) in cameras {
        let mut r = Renderer::new(cam);
        let mut buf = vec![0u8; cam.frame_bytes()];
        for (name, scene) in &variants {
            let mut times = Vec::with_capacity(frames);
            for i in 0..frames + 3 {
                // Move the camera a little each frame (an approach), rotate the rotor.
                let pose = CameraPose {
                    roll_deg: 2.0,
                    ..CameraPose::looking_at_hub(120.0 - i as f64, 5.0, -10.0)
                };
                let s = Scene {
                    rotor_angle_deg: i as f64 * 3.0,
                    frame: i as u64,
                    ..scene.clone()
                };
                let t0 = Instant::now();
                let truth = r.render(&s, &pose, &mut buf);
                let dt = t0.elapsed().as_secs_f64() * 1e3;
                assert!(truth.is_ok());
                if i >= 3 {
                    times.push(dt); // skip warm-up frames
                }
            }
            times.sort_by(|a, b| a.total_cmp(b));
            let median = times[times.len() / 2];
            let p99 = times[((times.len() as f64 * 0.99).ceil() as usize).min(times.len()) - 1];
            println!("{name:<22} {cam_name:<17} {median:>10.2} {p99:>10.2}");
        }
    }
}
