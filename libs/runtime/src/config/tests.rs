use super::*;

fn run_of(text: &str) -> Result<RunConfig, ConfigError> {
    Ok(ConfigDoc::parse(text, "t.toml")?
        .sections::<RunSections>()?
        .run)
}

#[test]
fn unknown_key_is_named_with_its_path_and_file() {
    let msg = run_of("[run.restart]\nmax_restart = 3\n")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("run.restart.max_restart"), "{msg}");
    assert!(
        msg.contains("unknown field") && msg.contains("t.toml"),
        "{msg}"
    );
}

#[test]
fn other_sections_are_left_to_their_stages() {
    let run = run_of("[capture]\nwhatever = 1\n[run]\nstop_timeout_ms = 200\n").unwrap();
    assert_eq!(run.stop_timeout_ms, 200);
}

#[test]
fn an_unknown_section_is_named() {
    let doc = ConfigDoc::parse("[detcet]\nmode = \"thesis\"\n", "t.toml").unwrap();
    let msg = doc.check_section_names().unwrap_err().to_string();
    assert!(
        msg.contains("detcet") && msg.contains("unknown section"),
        "{msg}"
    );
    assert!(ConfigDoc::parse("[run]\n[sim]\n", "t")
        .unwrap()
        .check_section_names()
        .is_ok());
}

#[test]
fn out_of_range_names_key_and_range() {
    let msg = run_of("[run]\nstop_timeout_ms = 5\n")
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("run.stop_timeout_ms") && msg.contains("[100, 60000]"),
        "{msg}"
    );
}

#[test]
fn stage_niceness_defaults_overrides_and_range() {
    let d = RunConfig::default();
    assert_eq!((d.nice_of("recorder"), d.nice_of("detect")), (10, 0));
    // Naming one stage keeps the other stages' defaults.
    let c = run_of("[run.nice]\ncapture = 5\n").unwrap();
    assert_eq!(
        (
            c.nice_of("capture"),
            c.nice_of("recorder"),
            c.nice_of("track")
        ),
        (5, 10, 0)
    );
    let err = run_of("[run.nice]\ndetect = 25\n").unwrap_err().to_string();
    assert!(
        err.contains("run.nice.detect") && err.contains("[-20, 19]"),
        "{err}"
    );
    let err = run_of("[run.nice]\ncamera = 1\n").unwrap_err().to_string();
    assert!(err.contains("run.nice.camera"), "{err}");
}

#[test]
fn wrong_type_names_key() {
    let err = run_of("[run]\nstop_timeout_ms = \"long\"\n").unwrap_err();
    assert!(err.to_string().contains("run.stop_timeout_ms"), "{err}");
}

#[test]
fn unknown_stage_and_two_frame_sources_are_rejected() {
    let err = run_of("[run]\nstages = [\"capture\", \"detcet\"]\n").unwrap_err();
    assert!(err.to_string().contains("run.stages"), "{err}");
    let err = run_of("[run]\nstages = [\"capture\", \"sim\"]\n").unwrap_err();
    assert!(err.to_string().contains("both publish frames"), "{err}");
}

#[test]
fn cross_key_limits_name_both_keys() {
    let err = run_of("[run.restart]\nbackoff_initial_ms = 1000\nbackoff_max_ms = 500\n")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("run.restart.backoff_max_ms") && err.contains("[1000,"),
        "{err}"
    );
    let err = run_of("[run]\nstatus_interval_ms = 1000\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains("run.restart.liveness_timeout_ms"), "{err}");
}

#[test]
fn overrides_apply_and_validate() {
    let args = |o: &[&str]| ConfigArgs {
        overrides: o.iter().map(|s| s.to_string()).collect(),
        ..Default::default()
    };
    let run = args(&["run.stop_timeout_ms=200", "run.record_dir=flights"])
        .load::<RunSections>()
        .unwrap()
        .run;
    assert_eq!(
        (run.stop_timeout_ms, run.record_dir),
        (200, PathBuf::from("flights"))
    );
    assert!(args(&["run.nope=1"]).load::<RunSections>().is_err());
    assert!(args(&["run.stop_timeout_ms=1"])
        .load::<RunSections>()
        .is_err());
    let err = args(&["run"])
        .load::<RunSections>()
        .unwrap_err()
        .to_string();
    assert!(err.contains("KEY=VALUE"), "{err}");
    let err = args(&["run..x=1"])
        .load::<RunSections>()
        .unwrap_err()
        .to_string();
    assert!(err.contains("dotted key"), "{err}");
}

#[test]
fn a_huge_file_is_refused_without_reading_it_all() {
    let err = ConfigDoc::load(Path::new("/dev/zero"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("/dev/zero") && err.contains("larger than"),
        "{err}"
    );
}

#[test]
fn a_huge_bad_value_is_not_echoed_whole() {
    let long = "x".repeat(50_000);
    let err = run_of(&format!("[run]\nstop_timeout_ms = \"{long}\"\n"))
        .unwrap_err()
        .to_string();
    assert!(err.len() < 1_000, "{} bytes", err.len());
}

crate::sections! {
    /// The camera and turbine sections, as detect and track read them.
    struct SetupSections {
        camera: hubtrack_types::setup::CameraSetup,
        turbine: hubtrack_types::setup::TurbineSetup,
    }
}

fn shipped(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../config")
        .join(path)
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hubtrack-files-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_turbine_profile_fills_the_section_and_set_keys_win() {
    let args = ConfigArgs {
        turbine: Some(shipped("turbines/nrel_5mw.toml")),
        overrides: vec!["turbine.hub_overhang_m=5.5".into()],
        ..Default::default()
    };
    let s: SetupSections = args.load().unwrap();
    assert_eq!(s.turbine.name, "NREL 5 MW reference");
    assert_eq!(s.turbine.tower_top_diameter_m, 3.87);
    assert_eq!(s.turbine.rotor_radius_m, 63.0);
    assert_eq!(s.turbine.hub_overhang_m, 5.5, "--set wins over the profile");
    assert!(Path::new(&s.turbine.profile).is_absolute());
}

#[test]
fn every_shipped_turbine_profile_reads() {
    let mut n = 0;
    for entry in std::fs::read_dir(shipped("turbines")).unwrap() {
        let path = entry.unwrap().path();
        let args = ConfigArgs {
            turbine: Some(path.clone()),
            ..Default::default()
        };
        let s: SetupSections = args
            .load()
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(!s.turbine.name.is_empty());
        n += 1;
    }
    assert!(n >= 3, "{n} profiles");
}

/// A profile stating the keys every profile states.
const PROFILE: &str = "hub_height_m = 80.0\nrotor_radius_m = 40.0\ntower_top_diameter_m = 3.0\n\
                       tower_base_diameter_m = 4.0\nspinner_diameter_m = 3.0\nhub_overhang_m = 4.0\n";

#[test]
fn a_profile_replaces_the_config_files_turbine_keys() {
    let dir = temp_dir("replace");
    std::fs::write(dir.join("p.toml"), PROFILE).unwrap();
    // A relative profile path in a config file is relative to the file.
    std::fs::write(
        dir.join("c.toml"),
        "[turbine]\nprofile = \"p.toml\"\ntower_top_diameter_m = 2.0\nnacelle_width_m = 2.5\n",
    )
    .unwrap();
    let args = ConfigArgs {
        config: Some(dir.join("c.toml")),
        ..Default::default()
    };
    let s: SetupSections = args.load().unwrap();
    assert_eq!(s.turbine.tower_top_diameter_m, 3.0);
    assert_eq!(
        s.turbine.nacelle_width_m, 2.5,
        "keys the profile lacks stay"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_profiles_and_calibrations_are_named() {
    let dir = temp_dir("bad");
    std::fs::write(dir.join("typo.toml"), "tower_top_diamter_m = 3.0\n").unwrap();
    std::fs::write(
        dir.join("range.toml"),
        PROFILE.replace("spinner_diameter_m = 3.0", "spinner_diameter_m = 99.0"),
    )
    .unwrap();
    std::fs::write(
        dir.join("short.toml"),
        PROFILE.replace("hub_overhang_m = 4.0\n", ""),
    )
    .unwrap();
    std::fs::write(dir.join("cal.yaml"), "image_width: 640\n").unwrap();
    let err = |args: ConfigArgs| args.load::<SetupSections>().unwrap_err().to_string();
    let typo = err(ConfigArgs {
        turbine: Some(dir.join("typo.toml")),
        ..Default::default()
    });
    assert!(
        typo.contains("typo.toml") && typo.contains("tower_top_diamter_m"),
        "{typo}"
    );
    let short = err(ConfigArgs {
        turbine: Some(dir.join("short.toml")),
        ..Default::default()
    });
    assert!(
        short.contains("short.toml") && short.contains("`hub_overhang_m`: missing"),
        "{short}"
    );
    let range = err(ConfigArgs {
        turbine: Some(dir.join("range.toml")),
        ..Default::default()
    });
    assert!(range.contains("turbine.spinner_diameter_m"), "{range}");
    let missing = err(ConfigArgs {
        turbine: Some(dir.join("absent.toml")),
        ..Default::default()
    });
    assert!(missing.contains("absent.toml"), "{missing}");
    let cal = err(ConfigArgs {
        camera: Some(dir.join("cal.yaml")),
        ..Default::default()
    });
    assert!(
        cal.contains("camera.calibration") && cal.contains("image_height"),
        "{cal}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_profiles_keys_hubtrack_does_not_use_are_left_out() {
    let dir = temp_dir("datasheet");
    let text = format!("{PROFILE}manufacturer = \"Acme\"\nrated_power_kw = 2000\n");
    std::fs::write(dir.join("p.toml"), text).unwrap();
    let args = ConfigArgs {
        turbine: Some(dir.join("p.toml")),
        ..Default::default()
    };
    let s: SetupSections = args.load().unwrap();
    assert_eq!(s.turbine.hub_height_m, 80.0);
    assert_eq!(s.turbine.tower_top_diameter_m, 3.0);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_calibration_given_on_the_command_line_reaches_the_section() {
    let args = ConfigArgs {
        camera: Some(shipped("cameras/usb_narrow_640x480.yaml")),
        ..Default::default()
    };
    let s: SetupSections = args.load().unwrap();
    let cam = s.camera.calibrated().unwrap().unwrap();
    assert_eq!((cam.width, cam.height), (640, 480));
    // Children get absolute paths.
    let child = args.to_args();
    let at = child.iter().position(|a| a == "--camera").unwrap();
    assert!(Path::new(&child[at + 1]).is_absolute());
}

#[test]
fn a_syntax_error_on_a_long_line_keeps_its_reason() {
    let text = format!("fps = {}\nfoo = [1, 2\n", "3".repeat(400));
    let err = ConfigDoc::parse(&text, "long.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("long.toml") && err.contains("(syntax)"),
        "{err}"
    );
    assert!(
        err.lines().last().is_some_and(|l| !l.contains('…')),
        "the reason is cut off: {err}"
    );
    assert!(err.len() < 1000, "{err}");
}
