//! Render the default scene repeatedly (for profiling with perf).
use hubtrack_render::{Camera, CameraPose, Renderer, Scene};
fn main() {
    let n: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(100);
    let cam = Camera::gopro_hero3();
    let mut r = Renderer::new(cam);
    let mut buf = vec![0u8; cam.frame_bytes()];
    let scene = Scene::default_clear();
    let t0 = std::time::Instant::now();
    for i in 0..n {
        let pose = CameraPose { roll_deg: 2.0, ..CameraPose::looking_at_hub(120.0 - (i % 50) as f64, 5.0, -10.0) };
        let s = Scene { rotor_angle_deg: i as f64 * 3.0, frame: i as u64, ..scene.clone() };
        r.render(&s, &pose, &mut buf).expect("render");
    }
    println!("{:.2} ms/frame wall", t0.elapsed().as_secs_f64() * 1e3 / n as f64);
}
