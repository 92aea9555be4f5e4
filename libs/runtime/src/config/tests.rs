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
        config: None,
        overrides: o.iter().map(|s| s.to_string()).collect(),
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
