"""The operator's camera and turbine as inputs: `--camera CAL.yaml` (ROS camera_info) and
`--turbine T.toml` on the lab and flight commands, reaching detect, track and the stages `run`
starts; files that cannot describe the frames are refused with the reason."""

import json

from conftest import ROOT

GOPRO = ROOT / "config" / "cameras" / "gopro_hero3_wide_1080p.yaml"
USB = ROOT / "config" / "cameras" / "usb_narrow_640x480.yaml"


def rendered_frames(runner, tmp_path, n=30, *options, name="frames"):
    out = tmp_path / name
    out.mkdir()
    res = runner.run("hubtrack", "render", "--frames", str(n), "-o", out, *options, timeout=120)
    assert res.returncode == 0, res.stderr[-2000:]
    truth = [json.loads(line)["truth"] for line in res.stdout.splitlines() if line.strip()]
    return out, truth


def last_track(runner, frames, *options):
    res = runner.run("hubtrack", "track", "--fps", "30", *options, frames, timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    return [json.loads(line) for line in res.stdout.splitlines() if line.strip()][-1]


def test_the_turbine_profile_and_the_calibration_reach_the_tracked_distance(runner, tmp_path):
    frames, truth = rendered_frames(runner, tmp_path)
    base = last_track(runner, frames, "--camera", GOPRO)
    assert base["detected"] and base["distance_m"] > 0, base
    # The tracked distance is within 20 % of the renderer's truth with the right lens and turbine.
    # (These 30 frames read it long throughout, 1.13x before the tower width was taken back to
    # the tower top by the taper and 1.17x since: the first detection's tower and a spinner
    # circle found on the nose, not the rim, both say farther. A known error, in the CHANGELOG.)
    true_d = truth[-1]["distance_m"]
    assert abs(base["distance_m"] / true_d - 1) < 0.20, (base["distance_m"], true_d)
    # A turbine 1.5 times as large in every dimension seen the same size is 1.5 times as far.
    big = tmp_path / "big.toml"
    big.write_text('name = "x1.5"\nhub_height_m = 96.0\nrotor_radius_m = 53.25\n'
                   "tower_top_diameter_m = 3.3\ntower_base_diameter_m = 6.45\n"
                   "hub_overhang_m = 6.3\nspinner_diameter_m = 4.8\n")
    scaled = last_track(runner, frames, "--camera", GOPRO, "--turbine", big)
    assert abs(scaled["distance_m"] / base["distance_m"] - 1.5) < 0.03, (scaled, base)
    # --set wins over the profile's keys: each set back to the built-in turbine's value gives
    # that turbine's track exactly.
    over = last_track(runner, frames, "--camera", GOPRO, "--turbine", big,
                      "--set", "turbine.hub_height_m=64",
                      "--set", "turbine.rotor_radius_m=35.5",
                      "--set", "turbine.tower_top_diameter_m=2.2",
                      "--set", "turbine.tower_base_diameter_m=4.3",
                      "--set", "turbine.spinner_diameter_m=3.2",
                      "--set", "turbine.hub_overhang_m=4.2")
    assert abs(over["distance_m"] / base["distance_m"] - 1) < 1e-9, (over, base)


def test_the_synthetic_camera_films_through_the_calibration_and_the_turbine_given(runner, tmp_path):
    import cv2

    # The calibration's lens and size: 640x480 frames through the USB camera's calibration.
    usb, _ = rendered_frames(runner, tmp_path, 2, "--camera", USB, name="usb")
    first = sorted(usb.iterdir())[0]
    assert cv2.imread(str(first)).shape == (480, 640, 3)
    # The profile's turbine: the NREL 5 MW (a 3.87 m tower top against the built-in turbine's
    # 2.2 m) filmed on the same path and tracked with its profile reads the true distance; the
    # built-in turbine's profile on the same frames reads about 2.2 / 3.87 of it.
    nrel = ROOT / "config" / "turbines" / "nrel_5mw.toml"
    frames, truth = rendered_frames(runner, tmp_path, 30, "--turbine", nrel, name="nrel")
    track = last_track(runner, frames, "--camera", GOPRO, "--turbine", nrel)
    assert abs(track["distance_m"] / truth[-1]["distance_m"] - 1) < 0.20, (track, truth[-1])
    builtin = last_track(runner, frames, "--camera", GOPRO)
    assert builtin["distance_m"] < 0.75 * track["distance_m"], (builtin, track)


def test_frames_the_calibration_cannot_describe_are_refused_naming_both_sizes(runner, tmp_path):
    frames, _ = rendered_frames(runner, tmp_path, n=2)
    for cmd in (["detect"], ["track", "--fps", "30"]):
        res = runner.run("hubtrack", *cmd, "--camera", USB, frames, timeout=120)
        assert res.returncode == 1, (cmd, res.stdout, res.stderr[-2000:])
        assert "1920x1080 does not match the camera calibration (640x480)" in res.stdout + res.stderr, \
            (cmd, res.stdout, res.stderr[-2000:])


def test_bad_calibration_and_profile_files_are_named(runner, tmp_path):
    cases = {
        "missing.yaml": (None, "cannot open"),
        "short.yaml": ("image_width: 640\nimage_height: 480\n", "camera_matrix"),
        "nan.yaml": (USB.read_text().replace("692.820323027551, 0.0, 319.5", ".nan, 0.0, 319.5"), "NaN"),
        "model.yaml": (USB.read_text().replace("plumb_bob", "rational_polynomial"), "not supported"),
        # A 1.8° telephoto: valid as a lens, outside what the estimators are built for.
        "tele.yaml": (USB.read_text().replace("692.820323027551, 0.0, 319.5", "20000.0, 0.0, 319.5")
                      .replace("692.820323027551, 239.5", "20000.0, 239.5"), "fx / image_width"),
    }
    for name, (text, reason) in cases.items():
        path = tmp_path / name
        if text is not None:
            path.write_text(text)
        res = runner.run("hubtrack", "config", "--camera", path, timeout=60)
        assert res.returncode == 1, (name, res.stdout, res.stderr)
        assert "camera.calibration" in res.stderr and reason in res.stderr, (name, res.stderr)
        # A file that cannot be used is said so, not called a value out of range.
        assert ("out of range" in res.stderr) == (name == "tele.yaml"), (name, res.stderr)
    typo = tmp_path / "typo.toml"
    typo.write_text("tower_top_diamter_m = 3.0\n")
    res = runner.run("hubtrack", "config", "--turbine", typo, timeout=60)
    assert res.returncode == 1 and "typo.toml" in res.stderr and "tower_top_diamter_m" in res.stderr, res.stderr


def test_the_stage_binaries_read_the_files_passed_on(runner):
    # `hubtrack config` asks every stage binary to check its sections with the options `run`
    # would pass them: the files reach each stage.
    res = runner.run("hubtrack", "config", "--camera", GOPRO,
                     "--turbine", ROOT / "config" / "turbines" / "nrel_5mw.toml", timeout=60)
    assert res.returncode == 0, res.stderr
    res = runner.run("hubtrack", "config", "--print", "--camera", GOPRO,
                     "--turbine", ROOT / "config" / "turbines" / "nrel_5mw.toml", timeout=60)
    assert res.returncode == 0, res.stderr
    assert 'name = "NREL 5 MW reference"' in res.stdout and "tower_top_diameter_m = 3.87" in res.stdout, \
        res.stdout[:3000]
    assert str(GOPRO) in res.stdout, res.stdout[:3000]
