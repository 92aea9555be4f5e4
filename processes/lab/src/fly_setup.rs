//! `hubtrack fly --random-setup`: each seed flies its own camera and turbine, drawn from the
//! seed, written as a calibration file and a turbine profile that every stage (the simulator's
//! world, detect, track) is given, as an operator would give theirs.

use crate::turbine_family::{self, Family};
use hubtrack_render::dataset::held_out_cameras;
use hubtrack_render::Camera;
use hubtrack_types::mutate::Rng;
use std::path::{Path, PathBuf};

/// Seed mix of the setup draws (independent of the scenario's own draws).
const SETUP_SEED_MIX: u64 = 0x0005_E70F_F1E5;

/// One seed's camera and turbine, as files.
pub struct FlightSetup {
    /// What was drawn, for the flight's line.
    pub camera: String,
    /// The turbine drawn, one line.
    pub turbine: String,
    /// Whether the turbine lies in the learned yaw networks' training family or outside it:
    /// see [`turbine_family`].
    pub turbine_family: Family,
    /// `--set` overrides that give the stages the two files.
    pub overrides: Vec<String>,
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
    let t = turbine_family::draw(&mut r, &turbine_family::FLEET);
    let family = Family::of_fleet_turbine(&t);
    let profile = format!(
        "# Drawn by `hubtrack fly --random-setup` for seed {seed}.\n\
         name = \"seed {seed}: {}\"\n\
         hub_height_m = {}\n\
         rotor_radius_m = {}\n\
         tower_top_diameter_m = {}\n\
         tower_base_diameter_m = {}\n\
         hub_overhang_m = {}\n\
         hub_above_tower_top_m = {}\n\
         spinner_diameter_m = {}\n\
         nacelle_width_m = {}\n\
         nacelle_length_m = {}\n\
         nacelle_front_behind_hub_m = {}\n",
        t.name,
        t.hub_height_m,
        t.rotor_radius_m,
        t.tower_top_diameter_m,
        t.tower_base_diameter_m,
        t.hub_overhang_m,
        t.hub_above_tower_top_m,
        t.spinner_diameter_m,
        t.nacelle_width_m,
        t.nacelle_length_m,
        t.nacelle_front_behind_hub_m
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
        turbine: t.name,
        turbine_family: family,
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
    use hubtrack_types::setup::TurbineSetup;

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
                let t: TurbineSetup = toml::from_str(&text.unwrap()).unwrap();
                t.validate().unwrap_or_else(|e| panic!("seed {s}: {e}"));
                setup.camera
            })
            .collect();
        assert_eq!(names.len(), cameras().len());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
