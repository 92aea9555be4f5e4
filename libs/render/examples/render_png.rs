//! Render a few example frames to PNG files.
//!
//! Usage: `cargo run -p hubtrack-render --release --example render_png -- OUT_DIR`
//!
//! Writes front_far, oblique_close, overcast_horizon, no_turbine, a chimney with motion blur (and
//! a few more variants) and
//! prints each frame's truth. The truth hub is marked with a small red cross in `*_marked.png`.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use hubtrack_render::{Camera, CameraPose, Distractor, Ground, Renderer, Scene, Sky, Truth};

fn write_png(path: &Path, cam: &Camera, bgr: &[u8]) -> Result<(), Box<dyn std::error::Error>> {
    let rgb: Vec<u8> = bgr
        .chunks_exact(3)
        .flat_map(|p| [p[2], p[1], p[0]])
        .collect();
    let mut enc = png::Encoder::new(BufWriter::new(File::create(path)?), cam.width, cam.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()?.write_image_data(&rgb)?;
    Ok(())
}

fn mark(cam: &Camera, bgr: &mut [u8], p: Option<[f64; 2]>, col: [u8; 3]) {
    let Some(p) = p else { return };
    let (x, y) = (p[0].round() as i64, p[1].round() as i64);
    for d in -6i64..=6 {
        for (px, py) in [(x + d, y), (x, y + d)] {
            if px >= 0 && py >= 0 && (px as u32) < cam.width && (py as u32) < cam.height {
                let i = (py as usize * cam.width as usize + px as usize) * 3;
                bgr[i..i + 3].copy_from_slice(&col);
            }
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).ok_or("usage: render_png OUT_DIR")?;
    let dir = Path::new(&dir);
    std::fs::create_dir_all(dir)?;

    let gopro = Camera::gopro_hero3();
    let usb = Camera::usb_narrow();
    let base = Scene::default_clear();

    let frames: Vec<(&str, Camera, Scene, CameraPose)> = vec![
        (
            "front_far",
            gopro,
            base.clone(),
            CameraPose::looking_at_hub(150.0, 0.0, -20.0),
        ),
        (
            "oblique_close",
            gopro,
            Scene {
                rotor_angle_deg: 35.0,
                sun_azimuth_deg: -50.0,
                ..base.clone()
            },
            CameraPose {
                yaw_deg: 5.0,
                roll_deg: 4.0,
                ..CameraPose::looking_at_hub(30.0, 28.0, 6.0)
            },
        ),
        (
            "overcast_horizon",
            gopro,
            Scene {
                sky: Sky::Overcast,
                rotor_angle_deg: 60.0,
                seed: 7,
                ..base.clone()
            },
            CameraPose::front(90.0),
        ),
        (
            "no_turbine",
            gopro,
            Scene {
                turbine_present: false,
                distractor: Distractor::Mast,
                sky: Sky::Clouds,
                seed: 3,
                ..base.clone()
            },
            CameraPose::looking_at_hub(120.0, 10.0, -15.0),
        ),
        (
            "sea_clouds",
            gopro,
            Scene {
                sky: Sky::Clouds,
                ground: Ground::Sea,
                sun_azimuth_deg: 170.0,
                sun_elevation_deg: 25.0,
                seed: 11,
                second_turbine: true,
                ..base.clone()
            },
            CameraPose::looking_at_hub(80.0, -20.0, -10.0),
        ),
        (
            "chimney_motion_blur",
            gopro,
            Scene {
                distractor: Distractor::Chimney,
                motion_blur_frac: 0.004,
                seed: 9,
                ..base.clone()
            },
            CameraPose::looking_at_hub(120.0, 15.0, -12.0),
        ),
        (
            "chimney_no_turbine",
            gopro,
            Scene {
                turbine_present: false,
                distractor: Distractor::Chimney,
                sky: Sky::Overcast,
                seed: 4,
                ..base.clone()
            },
            CameraPose::looking_at_hub(120.0, 10.0, -15.0),
        ),
        (
            "hills_powerlines",
            gopro,
            Scene {
                ground: Ground::Hills,
                distractor: Distractor::PowerLines,
                second_turbine: true,
                propellers_in_view: true,
                seed: 5,
                rotor_angle_deg: 90.0,
                ..base.clone()
            },
            CameraPose {
                pitch_deg: -8.0,
                ..CameraPose::looking_at_hub(200.0, 30.0, 10.0)
            },
        ),
        (
            "usb_close_effects",
            usb,
            Scene {
                blur: true,
                jpeg_quality: Some(60),
                noise_sigma: 3.0,
                rotor_angle_deg: 10.0,
                ..base.clone()
            },
            CameraPose::looking_at_hub(60.0, 10.0, -5.0),
        ),
        (
            "tower_edge_distortion",
            gopro,
            Scene {
                nacelle_yaw_deg: 20.0,
                blade_pitch_deg: 80.0,
                ..base.clone()
            },
            CameraPose {
                yaw_deg: 52.0,
                pitch_deg: -25.0,
                ..CameraPose::looking_at_hub(60.0, 0.0, -10.0)
            },
        ),
    ];

    for (name, cam, scene, pose) in frames {
        let mut r = Renderer::new(cam);
        let mut buf = vec![0u8; cam.frame_bytes()];
        let t0 = std::time::Instant::now();
        let truth: Truth = r.render(&scene, &pose, &mut buf)?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        write_png(&dir.join(format!("{name}.png")), &cam, &buf)?;
        mark(&cam, &mut buf, truth.hub_px, [0, 0, 255]);
        mark(&cam, &mut buf, truth.nose_px, [0, 255, 0]);
        mark(&cam, &mut buf, truth.tower_top_px, [255, 0, 0]);
        if let (Some(row), Some(_)) = (truth.tower_width_row, truth.tower_width_px) {
            mark(&cam, &mut buf, Some([cam.cx, row]), [0, 255, 255]);
        }
        write_png(&dir.join(format!("{name}_marked.png")), &cam, &buf)?;
        println!("{name}: {ms:.1} ms  {truth:?}");
    }
    Ok(())
}
