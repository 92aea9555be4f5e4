"""The product's shape as an operator meets it: the flight file, the flight and lab commands, and
whole-file config checks done by the stage binaries that own each section."""

from conftest import BIN, ROOT


def test_flight_config_without_a_camera_ends_the_run_naming_the_device(runner, tmp_path):
    rec = tmp_path / "flight.mcap"
    res = runner.run("hubtrack", "run", "--config", ROOT / "config" / "flight.toml",
                     "--record", rec, "--set", "run.restart.backoff_initial_ms=50", timeout=60)
    assert res.returncode == 1, res.stderr[-2000:]
    last = res.stderr.strip().splitlines()[-1]
    assert last.startswith("error: the frame source capture was given up on"), last
    assert "camera device /dev/video0 does not exist" in last, last


def test_flight_binary_links_no_opencv_and_hands_lab_commands_over(runner):
    import subprocess
    ldd = subprocess.run(["ldd", str(BIN / "hubtrack")], capture_output=True, text=True).stdout
    assert "opencv" not in ldd, ldd
    res = runner.run("hubtrack", "detect", "--help", timeout=30)
    assert res.returncode == 0 and "--mode" in res.stdout, res.stderr
    res = runner.run("hubtrack", "evla", timeout=30)
    assert res.returncode != 0 and "unknown command `evla`" in res.stderr, res.stderr


def test_whole_file_check_names_the_key_of_any_stage(runner, tmp_path):
    res = runner.run("hubtrack", "config", "--config", ROOT / "config" / "flight.toml", timeout=60)
    assert res.returncode == 0 and res.stdout.strip().endswith(": ok"), res.stderr
    for override, named in [("track.filter.dampnig=0.5", "track.filter.dampnig"),
                            ("detect.default.canny_low_ratio=7", "detect.default.canny_low_ratio"),
                            ("control.approach.target_distance_m=500", "control.approach.target_distance_m"),
                            ("detcet.mode=thesis", "detcet")]:
        res = runner.run("hubtrack", "config", "--set", override, timeout=60)
        assert res.returncode == 1 and named in res.stderr, (override, res.stderr)
    # The lens and the turbine have one home, which detect and track both read.
    for override, named in [("camera.hfov_deg=500", "camera.hfov_deg"),
                            ("turbine.hub_overhang_m=0", "turbine.hub_overhang_m"),
                            ("track.distance.tower_diameter_m=3.0", "track.distance.tower_diameter_m"),
                            ("detect.camera.hfov_deg=90", "detect.camera")]:
        res = runner.run("hubtrack", "config", "--set", override, timeout=60)
        assert res.returncode == 1 and named in res.stderr, (override, res.stderr)


def test_printed_config_has_every_section_and_reads_back(runner, tmp_path):
    res = runner.run("hubtrack", "config", "--print", timeout=60)
    assert res.returncode == 0, res.stderr
    import tomllib
    printed = tomllib.loads(res.stdout)
    assert set(printed) == {"run", "camera", "turbine", "capture", "recorder", "detect", "track",
                            "control", "live", "sim"}
    assert printed["turbine"]["hub_overhang_m"] == 4.2 and "camera" not in printed["detect"]
    assert printed["detect"]["default"]["canny_low_ratio"] == 0.5
    full = tmp_path / "full.toml"
    full.write_text(res.stdout)
    res = runner.run("hubtrack", "config", "--config", full, timeout=60)
    assert res.returncode == 0, res.stderr


def test_bad_numbers_and_unreadable_inputs_are_refused(runner, tmp_path):
    for args in (["run", "--duration", "nan"], ["run", "--duration", "inf"], ["run", "--duration", "1e300"],
                 ["echo", "status", "--duration", "nan"], ["status", "--listen", "inf"],
                 ["bench", "frames", "--seconds", "nan"]):
        res = runner.run("hubtrack", *args, timeout=30)
        assert res.returncode == 2 and "outside (0, 10000000] s" in res.stderr, (args, res.stderr)
    bad = tmp_path / "a.jpg"
    bad.write_bytes(b"not an image")
    res = runner.run("hubtrack", "detect", bad, tmp_path / "missing.png", timeout=60)
    assert res.returncode == 1 and "none of the 2 input(s) could be read" in res.stderr, res.stderr
    assert len(res.stdout.strip().splitlines()) == 2, res.stdout
    # A photo detected with any roll hint: the hint is dropped, never the detector.
    from conftest import SHARED_DATA
    import pytest
    photos = sorted((SHARED_DATA / "real-dev" / "images").glob("*.jpg")) if SHARED_DATA.exists() else []
    if not photos:
        pytest.skip(f"no photos under {SHARED_DATA}: ../shared/data is absent")
    res = runner.run("hubtrack", "detect", "--hint-roll=90", photos[0], timeout=60)
    assert res.returncode == 0 and '"error"' not in res.stdout, res.stdout + res.stderr
