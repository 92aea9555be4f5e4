//! `hubtrack fly --random-setup`: each seed flies its own camera and turbine, drawn from the
//! seed, written as a calibration file and a turbine profile that every stage (the simulator's
//! world, detect, track) is given, as an operator would give theirs.

use hubtrack_render::dataset::held_out_cameras;
use hubtrack_render::Camera;
use hubtrack_types::mutate::Rng;
use hubtrack_types::setup::TurbineSetup;
use std::path::{Path, PathBuf};

/// Seed mix of the setup draws (independent of the scenario's own draws).
const SETUP_SEED_MIX: u64 = 0x0005_E70F_F1E5;
/// Tower top diameters drawn, metres (real fleets).
const TOWER_TOP_M: (f64, f64) = (1.8, 3.5);
/// Tower base over top diameter.
const TAPER: (f64, f64) = (1.4, 2.2);
/// Rotor radii drawn, metres.
const ROTOR_RADIUS_M: (f64, f64) = (25.0, 63.0);
/// Spinner diameters drawn, metres.
const SPINNER_M: (f64, f64) = (2.4, 4.6);
/// Hub overhangs drawn, metres.
const OVERHANG_M: (f64, f64) = (3.0, 7.0);
/// Hub height over the rotor radius (the rotor clears the ground), metres, and its spread.
const HUB_ABOVE_ROTOR_M: (f64, f64) = (25.0, 45.0);
/// Hub heights above the tower top drawn, metres (half the nacelle's height: 0.8–1.5 times the
/// thesis turbine's).
const HUB_ABOVE_TOWER_TOP_M: (f64, f64) = (1.4, 2.6);
/// Nacelle width, length and front setback factors drawn, each over the thesis turbine's (the
/// profile defaults) scaled by the drawn hub height above the tower top over its own.
const NACELLE_WIDTH_FACTOR: (f64, f64) = (0.85, 1.2);
const NACELLE_LENGTH_FACTOR: (f64, f64) = (0.8, 1.25);
const NACELLE_FRONT_FACTOR: (f64, f64) = (0.6, 1.5);
/// The drawn nacelle's rear face lies at least this far behind the tower axis, metres.
const NACELLE_MIN_REAR_BEHIND_TOWER_M: f64 = 1.0;

/// One seed's camera and turbine, as files.
pub struct FlightSetup {
    /// What was drawn, for the flight's line.
    pub camera: String,
    /// The turbine drawn, one line.
    pub turbine: String,
    /// `--set` overrides that give the stages the two files.
    pub overrides: Vec<String>,
}

fn uniform(r: &mut Rng, (lo, hi): (f64, f64)) -> f64 {
    lo + (hi - lo) * ((r.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
}

/// The cameras a seed may fly: the two built-in ones and the held-out set of the cross-domain
/// evaluation (other sizes, fields of view, plumb_bob and fisheye lenses).
fn cameras() -> Vec<(&'static str, Camera)> {
    let mut all = vec![
        ("gopro hero3 wide 1080p", Camera::gopro_hero3()),
        ("usb narrow 640x480", Camera::usb_narrow()),
    ];
    all.extend(held_out_cameras());
    all
}

/// Draws seed `seed`'s camera and turbine and writes them into `dir`.
pub fn draw(seed: u64, dir: &Path) -> anyhow::Result<FlightSetup> {
    let mut r = Rng::new(seed ^ SETUP_SEED_MIX);
    let cams = cameras();
    let (cam_name, cam) = cams[r.below(cams.len())];
    let top = uniform(&mut r, TOWER_TOP_M);
    let base = top * uniform(&mut r, TAPER);
    let rotor = uniform(&mut r, ROTOR_RADIUS_M);
    let hub_height = rotor + uniform(&mut r, HUB_ABOVE_ROTOR_M);
    let spinner = uniform(&mut r, SPINNER_M);
    let overhang = uniform(&mut r, OVERHANG_M);
    let above_top = uniform(&mut r, HUB_ABOVE_TOWER_TOP_M);
    let thesis = TurbineSetup::default();
    let k = above_top / thesis.hub_above_tower_top_m;
    let nacelle_width = thesis.nacelle_width_m * k * uniform(&mut r, NACELLE_WIDTH_FACTOR);
    let nacelle_front =
        thesis.nacelle_front_behind_hub_m * k * uniform(&mut r, NACELLE_FRONT_FACTOR);
    let nacelle_length = (thesis.nacelle_length_m * k * uniform(&mut r, NACELLE_LENGTH_FACTOR))
        .max(overhang - nacelle_front + NACELLE_MIN_REAR_BEHIND_TOWER_M);
    let turbine = format!(
        "rotor {rotor:.1} m, hub {hub_height:.0} m, tower {top:.2}-{base:.2} m, spinner {spinner:.2} m, overhang {overhang:.2} m, hub {above_top:.2} m above the tower, nacelle {nacelle_width:.2} x {nacelle_length:.1} m from {nacelle_front:.2} m behind the hub"
    );
    let profile = format!(
        "# Drawn by `hubtrack fly --random-setup` for seed {seed}.\n\
         name = \"seed {seed}: {turbine}\"\n\
         hub_height_m = {hub_height}\n\
         rotor_radius_m = {rotor}\n\
         tower_top_diameter_m = {top}\n\
         tower_base_diameter_m = {base}\n\
         hub_overhang_m = {overhang}\n\
         hub_above_tower_top_m = {above_top}\n\
         spinner_diameter_m = {spinner}\n\
         nacelle_width_m = {nacelle_width}\n\
         nacelle_length_m = {nacelle_length}\n\
         nacelle_front_behind_hub_m = {nacelle_front}\n"
    );
    let write = |name: String, text: String| -> anyhow::Result<PathBuf> {
        let path = dir.join(name);
        std::fs::write(&path, text)
            .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))?;
        Ok(path)
    };
    let profile_path = write(format!("turbine-seed{seed}.toml"), profile)?;
    let calibration_path = write(
        format!("camera-seed{seed}.yaml"),
        cam.to_ros_yaml(&cam_name.replace(' ', "_")),
    )?;
    Ok(FlightSetup {
        camera: cam_name.to_string(),
        turbine,
        overrides: vec![
            format!(
                "camera.calibration={:?}",
                calibration_path.display().to_string()
            ),
            format!("turbine.profile={:?}", profile_path.display().to_string()),
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_seed_draws_the_same_setup_and_the_files_load() {
        let dir = std::env::temp_dir().join(format!("hubtrack-fly-setup-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let a = draw(7, &dir).unwrap();
        let b = draw(7, &dir).unwrap();
        assert_eq!((&a.camera, &a.turbine), (&b.camera, &b.turbine));
        let cam = Camera::load(&dir.join("camera-seed7.yaml")).unwrap();
        assert!(cam.width > 0);
        let text = std::fs::read_to_string(dir.join("turbine-seed7.toml")).unwrap();
        let t: TurbineSetup = toml::from_str(&text).unwrap();
        t.validate().unwrap();
        assert!(t.hub_height_m > t.rotor_radius_m);
        // Over many seeds every camera comes up, and every turbine drawn is a valid profile
        // (the nacelle on its tower).
        let names: std::collections::BTreeSet<String> = (0..200)
            .map(|s| {
                let setup = draw(s, &dir).unwrap();
                let text = std::fs::read_to_string(dir.join(format!("turbine-seed{s}.toml")));
                let t: hubtrack_types::setup::TurbineSetup =
                    toml::from_str(&text.unwrap()).unwrap();
                t.validate().unwrap_or_else(|e| panic!("seed {s}: {e}"));
                setup.camera
            })
            .collect();
        assert_eq!(names.len(), cameras().len());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
