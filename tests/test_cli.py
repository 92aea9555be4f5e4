"""Command-line contracts relied on by outside evaluation: `hubtrack detect` and `hubtrack track`."""

import json
import math

import pytest
from conftest import SHARED_DATA

REQUIRED_DETECT_KEYS = {"path": str, "width": int, "height": int, "detected": bool, "confidence": float, "ms": float}
# Real photos the default detector found within 1 % of height (a margin below the 3 % hit limit)
# when it was last accepted: a regression guard that protects what works (the full evaluation is
# `hubtrack eval`). Re-baselined when the pair/spinner detector was accepted (it traded real-photo
# hits, 36 -> 23 %, for half the false positives and twice the synthetic hit rate), and again for
# the orientation-restricted Hough (23 -> 30 % hits, false positives 3 of 8 -> 0 of 8; three
# photos of the old set moved to candidates on the tower, see the notes).
REGRESSION_SET = ["wta_envA_07t.jpg", "wta_envA_21.jpg", "wta_envA_29.jpg", "wta_envA_37.jpg",
                  "wta_envA_41.jpg", "wta_envA_45.jpg", "wta_envB_30.jpg", "wta_envB_39.jpg"]
REGRESSION_MIN_HITS = 7
# Over the whole development set (3 % hits among photos with a visible hub; detections on the
# negatives) the shipped detector finds 43 of 53 with 0 of 8 false positives (CHANGELOG.md has
# how that grew); the floor leaves three hits of slack for other CPUs' floating point.
ALL_MIN_HITS = 40
ALL_MAX_FALSE = 1


def needs_shared():
    if not (SHARED_DATA / "real-dev" / "truth.jsonl").is_file():
        pytest.skip(f"{SHARED_DATA} is absent: the real-photo tests need ../shared beside the repository")


def check_detect_line(line):
    for key, ty in REQUIRED_DETECT_KEYS.items():
        assert isinstance(line[key], ty) or (ty is float and isinstance(line[key], int)), (key, line)
    for key in ("hub", "distance_m", "yaw_deg"):
        assert key in line
    if line["detected"]:
        x, y = line["hub"]
        assert 0 <= x < line["width"] and 0 <= y < line["height"]
    else:
        assert line["hub"] is None


def test_detect_prints_one_json_object_per_image_and_goes_on_after_errors(runner, tmp_path):
    folder = tmp_path / "imgs"
    folder.mkdir()
    res = runner.run("hubtrack", "render", "--frames", 3, "-o", folder, "--set", "capture.synthetic.camera=usb")
    assert res.returncode == 0, res.stderr
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png")
    ann = tmp_path / "ann"
    for mode in ("thesis", "default"):
        res = runner.run("hubtrack", "detect", "--mode", mode, "--annotate", ann, folder, bad, tmp_path / "missing.jpg")
        assert res.returncode == 0, res.stderr
        lines = [json.loads(l) for l in res.stdout.splitlines()]
        assert len(lines) == 5
        for l in lines[:3]:
            check_detect_line(l)
            assert (l["width"], l["height"]) == (640, 480)
        assert lines[3]["path"].endswith("bad.png") and "cannot be read" in lines[3]["error"]
        assert lines[4]["path"].endswith("missing.jpg") and "error" in lines[4]
    assert sorted(p.name for p in ann.iterdir()) == ["frame_000000.png", "frame_000001.png", "frame_000002.png"]


def seg_dist(p, a, b):
    dx, dy = b[0] - a[0], b[1] - a[1]
    l2 = dx * dx + dy * dy
    t = 0.0 if l2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2))
    return math.hypot(p[0] - (a[0] + t * dx), p[1] - (a[1] + t * dy))


def test_detect_regression_on_real_photos(runner):
    needs_shared()
    truth = {}
    for l in (SHARED_DATA / "real-dev" / "truth.jsonl").read_text().splitlines():
        t = json.loads(l)
        truth[t["file"].split("/")[-1]] = t
    paths = [SHARED_DATA / "real-dev" / "images" / n for n in REGRESSION_SET]
    res = runner.run("hubtrack", "detect", *paths)
    assert res.returncode == 0, res.stderr
    hits = []
    for l in map(json.loads, res.stdout.splitlines()):
        check_detect_line(l)
        t = truth[l["path"].split("/")[-1]]
        assert (l["width"], l["height"]) == (t["width"], t["height"])
        if l["detected"] and seg_dist(l["hub"], t["axis_point"], t["hub"]) <= 0.03 * t["height"]:
            hits.append(l["path"])
    assert len(hits) >= REGRESSION_MIN_HITS, f"only {len(hits)} hits: {hits}"


def test_detect_hit_rate_on_all_real_photos(runner):
    needs_shared()
    truth = {}
    for l in (SHARED_DATA / "real-dev" / "truth.jsonl").read_text().splitlines():
        t = json.loads(l)
        truth[t["file"].split("/")[-1]] = t
    paths = [SHARED_DATA / "real-dev" / t["file"] for t in truth.values()]
    res = runner.run("hubtrack", "detect", *paths)
    assert res.returncode == 0, res.stderr
    hits = false = visible = 0
    for l in map(json.loads, res.stdout.splitlines()):
        t = truth[l["path"].split("/")[-1]]
        if t["set"] != "positive":
            false += l["detected"]
        elif t["hub_visible"]:
            visible += 1
            hits += l["detected"] and seg_dist(l["hub"], t["axis_point"], t["hub"]) <= 0.03 * t["height"]
    assert visible > 0
    assert hits >= ALL_MIN_HITS and false <= ALL_MAX_FALSE, f"{hits} hits of {visible}, {false} false detections"


def render_at(runner, folder, frames, distance_m):
    """`frames` rendered frames `distance_m` from the hub into `folder`; their truth."""
    folder.mkdir()
    res = runner.run("hubtrack", "render", "--frames", frames, "-o", folder,
                     "--set", f"capture.synthetic.start_distance_m={distance_m}",
                     "--set", f"capture.synthetic.end_distance_m={distance_m}")
    assert res.returncode == 0, res.stderr
    return [json.loads(l)["truth"] for l in res.stdout.splitlines()]


def test_track_prints_one_json_object_per_frame(runner, tmp_path):
    folder = tmp_path / "seq"
    render_at(runner, folder, 30, 30)
    res = runner.run("hubtrack", "track", "--fps", 10, folder)
    assert res.returncode == 0, res.stderr
    lines = [json.loads(l) for l in res.stdout.splitlines()]
    assert len(lines) == 30
    for l in lines:
        for key in ("path", "detected", "hub", "mode", "distance_m", "yaw_deg"):
            assert key in l
        assert l["mode"] in ("acquiring", "tracking", "coasting", "lost")
    assert [l["path"] for l in lines] == sorted(l["path"] for l in lines), "file-name order"
    res = runner.run("hubtrack", "track", "--fps", 0, folder)
    assert res.returncode != 0 and "--fps" in res.stderr


def test_detect_reports_the_hubs_distance(runner, tmp_path):
    # 12 frames 20 m from the hub: the hub's distance, not the tower axis's (4.2 m behind it).
    folder = tmp_path / "at20"
    truth = [t["distance_m"] for t in render_at(runner, folder, 12, 20)]
    res = runner.run("hubtrack", "detect", folder)
    assert res.returncode == 0, res.stderr
    ratios = sorted(json.loads(l)["distance_m"] / t for l, t in zip(res.stdout.splitlines(), truth)
                    if json.loads(l)["distance_m"] is not None)
    assert len(ratios) >= 8 and abs(ratios[len(ratios) // 2] - 1) < 0.12, ratios


def test_render_says_what_it_cannot_write(runner, tmp_path):
    res = runner.run("hubtrack", "render", "-o", tmp_path / "nodir" / "x.png")
    assert res.returncode == 1 and f"no folder {tmp_path / 'nodir'}" in res.stderr, res.stderr
    res = runner.run("hubtrack", "render", "-o", tmp_path / "one.png", "--frames", 3)
    assert res.returncode == 1 and "holds one frame" in res.stderr and not (tmp_path / "one.png").exists()
    res = runner.run("hubtrack", "render", "-o", f"{tmp_path / 'new'}/", "--frames", 2)
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in (tmp_path / "new").iterdir()) == ["frame_000000.png", "frame_000001.png"]


def test_inputs_that_give_nothing_to_detect_or_track_are_errors(runner, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "readme.txt").write_text("no images here")
    for folder in (empty, tmp_path / "notes"):
        for cmd in (["detect"], ["track", "--fps", 10]):
            res = runner.run("hubtrack", *cmd, folder)
            assert res.returncode == 1 and f"{folder} holds no images" in res.stderr, (cmd, res.stderr)
    missing, bad = tmp_path / "missing.png", tmp_path / "bad.png"
    bad.write_bytes(b"not a png")
    res = runner.run("hubtrack", "track", "--fps", 10, missing, bad)
    lines = [json.loads(l) for l in res.stdout.splitlines()]
    assert lines[0]["error"] == "no such file" and "cannot be read" in lines[1]["error"], lines
    assert res.returncode == 1 and "none of the 2 input(s) could be read" in res.stderr, res.stderr
    for hint, value, reason in (("--hint-distance", "nan", "positive number of metres"),
                                ("--hint-distance", "0", "positive number of metres"),
                                ("--hint-roll", "1e300", "within ±180"),
                                ("--hint-hub", "nan,1", "expected X,Y")):
        res = runner.run("hubtrack", "detect", hint, value, bad)
        assert res.returncode == 2 and reason in res.stderr, (hint, value, res.stderr)


def test_detect_hints_find_the_tower_at_close_range(runner, tmp_path):
    """The tower at close range (8 m), where its top and edges lie outside the fixed search window
    and a blade often stands beside it: a regression guard for the gradient scan and the width
    rules, and for `--hint-*` (what the detect stage gets from the tracker), which must not lose
    towers."""
    frames = []
    # 36 views at 8 m: six relative yaws (−15° … 15°) × six scenes (rotor angle, sky, ground, sun).
    for yaw in (-15, -8, -3, 3, 8, 15):
        for scene in range(1, 7):
            out = tmp_path / f"y{yaw}_s{scene}.png"
            # The scripted yaw swing peaks at frame 196 and is most negative at frame 589.
            res = runner.run("hubtrack", "render", "-o", out, "--seq", 196 if yaw > 0 else 589,
                             "--set", "capture.synthetic.start_distance_m=8", "--set", "capture.synthetic.end_distance_m=8",
                             "--set", "capture.synthetic.lateral_sway_m=0", "--set", f"capture.synthetic.yaw_swing_deg={abs(yaw)}",
                             "--set", f"capture.synthetic.seed={7 * scene + 8}")
            assert res.returncode == 0, res.stderr
            frames.append((out, json.loads(res.stdout.splitlines()[-1])["truth"]))

    def towers_found(with_hints):
        good = 0
        for path, truth in frames:
            args = ["hubtrack", "detect", path]
            if with_hints:
                hx, hy = truth["hub_px"]
                args += ["--hint-hub", f"{hx},{hy}", "--hint-distance", truth["distance_m"], "--hint-roll", 0]
            res = runner.run(*args)
            assert res.returncode == 0, res.stderr
            line = json.loads(res.stdout)
            check_detect_line(line)
            # The tower axis within 1 % of the image width of the truth.
            if line["tower_top"] is not None and abs(line["tower_top"][0] - truth["tower_top_px"][0]) < 0.01 * line["width"]:
                good += 1
        return good

    without, with_hints = towers_found(False), towers_found(True)
    # The shipped detector finds about 21 without hints and 20 with. The one frame hints lose
    # (y8_s5): with the hub and distance hinted, the spinner (r 42 working px) is not among the
    # circle search's accumulator peaks in the box around the hint, while the box around an
    # unhinted candidate 25 px away finds it. Hence one frame of slack.
    assert without >= 14 and with_hints >= 18 and with_hints >= without - 1, (without, with_hints)
    # A malformed hint is a clear error, not a silent default.
    res = runner.run("hubtrack", "detect", "--hint-hub", "12", frames[0][0])
    assert res.returncode != 0 and "X,Y" in res.stderr


def test_dataset_writes_the_heatmap_training_set(runner, tmp_path):
    """`hubtrack dataset` (the learned heatmap's training set): grey PNGs at the network's input
    size, one label line per frame with the hub as fractions of the frame (null without one)."""
    import struct
    out = tmp_path / "ds"
    res = runner.run("hubtrack", "dataset", "-o", out, "--seed", 9, "--per-class", 4, "--flights", 1,
                     "--flight-frames", 10, "--flight-step", 5, "--beyond", 4)
    assert res.returncode == 0, res.stderr
    labels = [json.loads(l) for l in (out / "labels.jsonl").read_text().splitlines()]
    # 4 per class and 1 negative each, 4 beyond and 1 negative, 2 flight frames.
    assert len(labels) == 3 * 5 + 5 + 2, len(labels)
    assert len({l["file"] for l in labels}) == len(labels)
    with_hub = [l for l in labels if l["hub"] is not None]
    assert len(with_hub) >= 12, labels
    for l in labels:
        png = (out / l["file"]).read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        width, height, depth, colour = struct.unpack(">IIBB", png[16:26])
        assert (width, height, depth, colour) == (192, 128, 8, 0), (l["file"], width, height, depth, colour)
        if l["hub"] is not None:
            assert all(0.0 <= v <= 1.0 for v in l["hub"]), l
    negatives = [l for l in labels if "_far_00004" in l["file"] or "_beyond_00004" in l["file"]]
    assert len(negatives) == 2 and all(l["hub"] is None for l in negatives), negatives
    res = runner.run("hubtrack", "dataset", "-o", tmp_path / "x", "--set", "detect.default.pyramid_max_side_px=-1")
    assert res.returncode != 0 and "pyramid_max_side_px" in res.stderr
    # --working (the hub crop network's set): the whole working level (the default pyramid's
    # 200-500 px), the same labels.
    work = tmp_path / "work"
    res = runner.run("hubtrack", "dataset", "-o", work, "--seed", 9, "--per-class", 4, "--flights", 0, "--working")
    assert res.returncode == 0, res.stderr
    work_labels = [json.loads(l) for l in (work / "labels.jsonl").read_text().splitlines()]
    assert [l["hub"] for l in work_labels] == [l["hub"] for l in labels[:15]]
    for l in work_labels:
        png = (work / l["file"]).read_bytes()
        width, height, depth, colour = struct.unpack(">IIBB", png[16:26])
        assert depth == 8 and colour == 0, l["file"]
        assert 200 <= max(width, height) <= 500 and (width, height) != (192, 128), (l["file"], width, height)


def test_photo_like_views_are_rendered_for_training_and_scored_as_stills(runner, tmp_path):
    """`--photo-like N` (the renderer's stand-in for drone photos): `hubtrack dataset` writes N
    frames plus a quarter as many negatives, with the hub where it is in view; `hubtrack eval`
    scores N views plus a twelfth as many negatives as still photos, in its own table."""
    out = tmp_path / "photo"
    res = runner.run("hubtrack", "dataset", "-o", out, "--seed", 9, "--per-class", 0, "--flights", 0, "--photo-like", 8)
    assert res.returncode == 0, res.stderr
    labels = [json.loads(l) for l in (out / "labels.jsonl").read_text().splitlines()]
    assert len(labels) == 10 and all("_photo_" in l["file"] for l in labels), labels
    assert all(l["hub"] is None for l in labels[8:]), labels[8:]
    with_hub = [l for l in labels[:8] if l["hub"] is not None]
    assert len(with_hub) >= 5, labels
    # 12-250 m over the ground, seen from up to 50° above: at most 250 / cos 50° ≈ 389 m away.
    distances = sorted(l["distance_m"] for l in with_hub)
    assert distances[0] >= 12.0 and distances[-1] <= 390.0, distances
    res = runner.run("hubtrack", "eval", "--no-photos", "--synthetic", 0, "--photo-like", 12, "--seed", 3)
    assert res.returncode == 0, res.stderr
    rows = {l.split()[0]: l.split() for l in res.stdout.splitlines() if l.strip()}
    assert "photo-like rendered views: 12, seed 3, as still photos" in res.stdout, res.stdout
    assert rows["photo-like"][1] == "12" and rows["negatives"][1] == "1", res.stdout


def test_eval_negatives_sets_the_frames_without_a_turbine(runner):
    """`hubtrack eval --negatives N`: N frames without a turbine (spread over the distance
    classes' scenes) instead of a quarter of `--synthetic`, enough to state a false-positive
    rate of a few per cent."""
    res = runner.run("hubtrack", "eval", "--no-photos", "--synthetic", 3, "--negatives", 6, "--seed", 3)
    assert res.returncode == 0, res.stderr
    rows = {l.split()[0]: l.split() for l in res.stdout.splitlines() if l.strip()}
    assert [rows[f"distance:{c}"][1] for c in ("far", "medium", "close")] == ["3"] * 3, res.stdout
    assert rows["negatives"][1] == "6", res.stdout


def test_cross_domain_eval_prints_one_table_per_held_out_set(runner, tmp_path):
    """`hubtrack eval --cross-domain`: the in-domain table, then one per held-out camera, the
    held-out turbines and the held-out scenes (chimneys, motion blur), each with its frames
    without a turbine; `--misses` writes each set's misses to a folder of its own."""
    misses = tmp_path / "misses"
    res = runner.run(
        "hubtrack", "eval", "--no-photos", "--synthetic", 2, "--negatives", 3, "--seed", 3,
        "--cross-domain", "--misses", misses,
    )
    assert res.returncode == 0, res.stderr
    titles = [l for l in res.stdout.splitlines() if l.startswith("cross-domain ")]
    assert len(titles) == 6, res.stdout
    assert titles[-2].startswith("cross-domain turbines") and titles[-1].startswith("cross-domain scenes"), titles
    assert "chimneys" in titles[-1] and "motion blur" in titles[-1], titles[-1]
    assert (misses / "cross-domain-scenes" / "misses.jsonl").exists(), sorted(p.name for p in misses.iterdir())
    negatives = [l.split() for l in res.stdout.splitlines() if l.startswith("negatives")]
    assert len(negatives) == 7 and all(row[1] == "3" for row in negatives), negatives


def test_each_miss_reruns_through_hubtrack_detect_as_it_was_scored(runner, tmp_path):
    """`hubtrack eval --misses`: each miss's `rerun` (a `hubtrack detect` command line, with
    `--as-frame` and the roll for video frames and the held-out camera's calibration written
    beside the misses) gives back the detection the table scored; detected as a still photo
    instead, some of the same frames come out otherwise."""
    import json
    import shlex

    misses = tmp_path / "the crew's misses"  # a space and a quote: the rerun is one shell line
    res = runner.run(
        "hubtrack", "eval", "--no-photos", "--synthetic", 8, "--negatives", 6, "--seed", 3,
        "--cross-domain", "--misses", misses, timeout=300,
    )
    assert res.returncode == 0, res.stderr
    lines = [json.loads(l) for f in sorted(misses.rglob("misses.jsonl")) for l in f.read_text().splitlines()]
    assert len(lines) >= 5, f"too few misses to check: {len(lines)}"
    cameras = sorted(misses.glob("cross-domain-*/camera.yaml"))
    assert len(cameras) == 4, cameras
    assert all("--as-frame" in l["rerun"] and "--hint-roll" in l["rerun"] for l in lines), lines[0]
    assert any("--camera" in l["rerun"] for l in lines), [l["rerun"] for l in lines]
    as_still = 0
    for line in lines:
        args = shlex.split(line["rerun"])
        assert args[:2] == ["hubtrack", "detect"], args
        again = runner.run("hubtrack", *args[1:])
        assert again.returncode == 0, again.stderr
        got, scored = json.loads(again.stdout.splitlines()[-1]), line["result"]
        assert got["detected"] == scored["detected"], (line["name"], got, scored)
        if scored["detected"]:
            assert max(abs(a - b) for a, b in zip(got["hub"], scored["hub"])) < 0.5, (line["name"], got, scored)
        still = runner.run("hubtrack", *[a for a in args[1:] if a != "--as-frame"])
        as_still += json.loads(still.stdout.splitlines()[-1])["hub"] != scored["hub"]
    assert as_still > 0, "the still-photo path gave every miss's detection too: --as-frame checks nothing"


def test_sequence_eval_films_flights_in_held_out_scenes(runner):
    """`hubtrack eval --sequence --held-out-scenes`: the rendered flights in the held-out scenes,
    each flight's chimney and blur named on stderr; the option needs --sequence."""
    res = runner.run(
        "hubtrack", "eval", "--sequence", "--held-out-scenes", "--flights", 2, "--frames", 4, "--seed", 3,
    )
    assert res.returncode == 0, res.stderr
    assert "held-out scenes (chimneys, motion blur)" in res.stdout, res.stdout
    named = [l for l in res.stderr.splitlines() if l.startswith("[eval] flight ")]
    assert len(named) == 2 and all("chimney" in l and "motion blur" in l for l in named), res.stderr
    res = runner.run("hubtrack", "eval", "--held-out-scenes", "--no-photos", "--synthetic", 1)
    assert res.returncode != 0 and "--sequence" in res.stderr, res.stderr


def test_synthetic_frames_can_be_scored_as_stills(runner):
    """`hubtrack eval --as-stills` scores the `--synthetic` frames as `hubtrack detect` sees an
    image (no attitude, both pyramid levels): the path outside evaluation takes on renders."""
    res = runner.run("hubtrack", "eval", "--no-photos", "--synthetic", 12, "--as-stills", "--seed", 3)
    assert res.returncode == 0, res.stderr
    assert "synthetic frames: 12 per distance class, seed 3, as still photos" in res.stdout, res.stdout
    rows = {l.split()[0]: l.split() for l in res.stdout.splitlines() if l.strip()}
    assert [rows[f"distance:{c}"][1] for c in ("far", "medium", "close")] == ["12"] * 3, res.stdout
    assert rows["negatives"][1] == "3", res.stdout
    res = runner.run("hubtrack", "eval", "--no-photos", "--synthetic", 12, "--seed", 3)
    assert res.returncode == 0 and "synthetic frames: 12 per distance class, seed 3\n" in res.stdout, res.stdout
