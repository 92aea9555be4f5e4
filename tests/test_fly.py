"""Closed-loop flights: `hubtrack fly` through the real processes (sim → detect → track →
control → MAVLink → sim), read back with independent tools.

The quality target (19 of 20 seeds in hover at 5 ± 0.5 m, |yaw| ≤ 5°) is measured by
`hubtrack fly --seeds 20` (see the README); these tests check the contract, determinism, the
safety margin and the recording, and take a few minutes.
"""

import json
import math
import os
import signal

import pytest

from conftest import ROOT, wait_until, read_mcap_messages

KEYS = {"seed": int, "success": bool, "final_distance_m": float, "final_yaw_deg": float,
        "final_lateral_m": float, "time_s": float, "min_rotor_plane_m": float, "lockstep_misses": int}


def fly(runner, *args, timeout=900):
    r = runner.run("hubtrack", "fly", "--json", *args, timeout=timeout)
    assert r.returncode == 0, r.stderr[-4000:]
    lines = [json.loads(l) for l in r.stdout.splitlines()]
    assert all(l.startswith("{") for l in r.stdout.splitlines()), "stdout must be JSON lines only"
    return lines


def test_fly_prints_one_json_object_per_seed_and_a_seed_flies_the_same_flight_again(runner, tmp_path):
    # Seeds 5 and 6 are ordinary approaches (the tower shows beside the blades). Seeds whose
    # rotor has a blade pointing down hide the tower, and with it the yaw cue: they are part of
    # the 20-seed quality measurement, not of this contract test.
    runs = fly(runner, "--seeds", "2", "--first-seed", "5")
    assert [r["seed"] for r in runs] == [5, 6]
    for r in runs:
        for key, kind in KEYS.items():
            assert isinstance(r[key], kind) or (kind is float and isinstance(r[key], int)), (key, r)
        # Safety: never closer than 3 m to the rotor plane before the final hold.
        assert r["min_rotor_plane_m"] >= 3.0, r
        assert 0.0 < r["time_s"] <= 120.5, r
        # The approach got somewhere: from 25–40 m to within a few metres of the target.
        assert r["final_distance_m"] < 15.0, r
    again = fly(runner, "--seeds", "1", "--first-seed", "5", "--record", str(tmp_path / "again.mcap"))[0]
    if again["lockstep_misses"] or runs[0]["lockstep_misses"]:
        # A lockstep wait timed out (the machine was overloaded): the simulator went on without
        # an answer, so this run is not the seed's deterministic flight.
        pytest.skip(f"lockstep waits timed out ({runs[0]['lockstep_misses']}, {again['lockstep_misses']}): "
                    "no determinism to compare on this loaded machine")
    for key in ("success", "final_distance_m", "final_yaw_deg", "final_lateral_m", "time_s", "path_length_m",
                "min_rotor_plane_m"):
        assert again[key] == runs[0][key], (key, again[key], runs[0][key])


def test_a_recorded_flight_has_every_channel_and_the_loop_is_closed(runner, tmp_path):
    path = tmp_path / "flight.mcap"
    run = fly(runner, "--seeds", "1", "--first-seed", "1", "--record", str(path))[0]
    assert run["recording"] == str(path)
    msgs = read_mcap_messages(path)
    topics = {t for t, _ in msgs}
    for t in ("/frames", "/frames/header", "/detections", "/track", "/setpoints", "/vehicle", "/frames/overlay"):
        assert t in topics, (t, topics)
    headers = [json.loads(m.data) for t, m in msgs if t == "/frames/header"]
    assert headers and all(h["source"] == "Sim" or h["source"] == "sim" for h in headers), headers[0]["source"]
    assert all(h["truth"]["valid"] for h in headers)
    # Every frame got an answer from control, in order (lockstep), and commands were sent.
    setpoints = [json.loads(m.data) for t, m in msgs if t == "/setpoints"]
    seqs = [s["stamps"]["seq"] for s in setpoints]
    assert set(range(len(headers))) <= set(seqs), "a frame without a setpoint"
    assert sum(s["sent"] for s in setpoints) > 0.9 * len(headers)
    tasks = {s["task"] for s in setpoints}
    assert {"centre_hub", "approach"} <= tasks, tasks
    # The vehicle state came back over MAVLink from the simulated autopilot: armed, GUIDED.
    vehicle = [json.loads(m.data) for t, m in msgs if t == "/vehicle"]
    assert vehicle and vehicle[-1]["link_ok"] and vehicle[-1]["armed"] and vehicle[-1]["custom_mode"] == 4
    # The recorded truth agrees with the outcome: the final frame is where the flight ended.
    assert abs(headers[-1]["truth"]["distance_m"] - run["final_distance_m"]) < 1.0

    # `hubtrack diagnose` compares the estimates with the truth; its numbers match what this
    # independent reader computes from the same messages.
    r = runner.run("hubtrack", "diagnose", "--json", str(path), timeout=120)
    assert r.returncode == 0, r.stderr[-3000:]
    report = json.loads(r.stdout)
    everything = report["bands"][-1]
    assert everything["name"] == "all"
    in_view = {h["seq"]: h for h in headers if h["truth"]["turbine_in_view"]}
    dets = {d["stamps"]["seq"]: d for t, m in msgs if t == "/detections" for d in [json.loads(m.data)]}
    assert everything["frames"] == len(in_view)
    detected = sum(1 for s in in_view if dets.get(s, {}).get("detected"))
    assert abs(everything["detected_pct"] - 100.0 * detected / len(in_view)) < 1e-6
    tracks = {t["stamps"]["seq"]: t for tp, m in msgs if tp == "/track" for t in [json.loads(m.data)]}
    ratios = sorted(tracks[s]["distance_m"] / h["truth"]["distance_m"] for s, h in in_view.items()
                    if s in tracks and tracks[s]["distance_valid"])
    assert abs(everything["distance_ratio"][1] - ratios[int((len(ratios) - 1) * 0.5 + 0.5)]) < 1e-9
    assert sum(report["task_frames"].values()) == len(setpoints)
    assert report["last"]["seq"] == max(in_view)
    # The spinner's looming (no truth needed): the circle's growth over the last 2 m (or 20 %)
    # flown toward the hub gives the distance; recomputed here from the circles and /vehicle.
    vehicles = sorted(vehicle, key=lambda v: v["recv_ns"])
    sights, k = [], 0
    for h in headers:
        while k < len(vehicles) and vehicles[k]["recv_ns"] <= h["capture_ns"]:
            k += 1
        v = vehicles[k - 1] if k and vehicles[k - 1]["position_valid"] and vehicles[k - 1]["attitude_valid"] else None
        t, d = tracks.get(h["seq"]), dets.get(h["seq"], {})
        sights.append(dict(
            pos=v["position_ned_m"][:2] if v else None,
            los=(v["yaw_rad"] if v else 0.0) + math.radians(t["hub_bearing_deg"][0] if t else 0.0),
            r=d["circle"][2] if d.get("detected") and d.get("circle_found") else None,
            trk=t["distance_m"] if t and t["distance_valid"] and t["mode"] == "tracking" else None,
        ))

    def radius(i):
        half = min(3, i, len(sights) - 1 - i)
        rs = sorted(s["r"] for s in sights[i - half:i + half + 1] if s["r"] is not None)
        return rs[len(rs) // 2] if rs else None

    def looming(i):
        s = sights[i]
        if s["trk"] is None or s["pos"] is None:
            return None
        for j in range(i - 1, max(-1, i - 301), -1):
            if sights[j]["pos"] is None:
                continue
            flown = ((s["pos"][0] - sights[j]["pos"][0]) * math.cos(s["los"])
                     + (s["pos"][1] - sights[j]["pos"][1]) * math.sin(s["los"]))
            if flown >= max(2.0, 0.2 * s["trk"]):
                r1, r2 = radius(j), radius(i)
                return flown * r1 / (r2 - r1) if r1 and r2 and r2 > r1 else None
        return None

    seq_index = {h["seq"]: i for i, h in enumerate(headers)}
    with_looming = sum(1 for s in in_view if looming(seq_index[s]) is not None)
    assert with_looming > 0.2 * len(in_view), (with_looming, len(in_view))
    assert abs(everything["looming_pct"] - 100.0 * with_looming / len(in_view)) < 1e-6, (everything, with_looming)
    # A recording without truth is refused with the cause named.
    bad = runner.run("hubtrack", "diagnose", str(path.parent / "missing.mcap"), timeout=60)
    assert bad.returncode != 0 and "missing.mcap" in bad.stderr


def test_a_spinner_wider_than_a_narrow_lens_sees_flies_its_last_metres_on_the_odometry(runner, tmp_path):
    # The shipped 640x480 USB calibration sees 38 degrees across its height; a 4.4 m spinner
    # spans 47 degrees at the 5 m target. Control says so at start-up and flies the last metres
    # on the autopilot's position (control.approach.odometry_leg_*, docs/control.md).
    profile = tmp_path / "big_spinner.toml"
    profile.write_text(
        'name = "thesis turbine, 4.4 m spinner"\nhub_height_m = 64.0\nrotor_radius_m = 35.5\n'
        'tower_top_diameter_m = 2.2\ntower_base_diameter_m = 4.3\nhub_overhang_m = 4.2\n'
        'spinner_diameter_m = 4.4\n')
    path = tmp_path / "overfill.mcap"
    r = runner.run("hubtrack", "fly", "--json", "--seeds", "1", "--first-seed", "2",
                   "--camera", ROOT / "config" / "cameras" / "usb_narrow_640x480.yaml",
                   "--turbine", profile, "--record", str(path), timeout=600)
    assert r.returncode == 0, r.stderr[-4000:]
    run = json.loads(r.stdout)
    warning = [l for l in r.stderr.splitlines() if "camera and turbine" in l]
    assert warning and "WARN" in warning[0] and "on the autopilot's position" in warning[0], warning
    setpoints = [json.loads(m.data) for _, m in read_mcap_messages(path, topics={"/setpoints"})]
    reasons = [s["reason"] for s in setpoints]
    leg = [i for i, why in enumerate(reasons) if "by odometry (spinner overfills view)" in why]
    assert leg, sorted(set(reasons))[:20]
    # Once on the leg, the track no longer steers: forward on the odometry, then done there.
    after = setpoints[leg[0]:]
    assert {s["task"] for s in after} <= {"approach", "done"}, {s["task"] for s in after}
    assert after[-1]["task"] == "done" and "by odometry" in after[-1]["reason"], after[-1]
    assert run["end_reason"] == "done", run
    assert abs(run["final_distance_m"] - 5.0) <= 0.5 and run["min_distance_m"] >= 4.5, run


def children(pid):
    """Pids of the live processes whose parent is `pid` (from /proc)."""
    kids = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = open(f"/proc/{entry}/stat").read()
            except OSError:
                continue
            fields = stat[stat.rindex(")") + 2:].split()
            if int(fields[1]) == pid and fields[0] != "Z":
                kids.append(int(entry))
    return kids


def alive(pid):
    try:
        stat = open(f"/proc/{pid}/stat").read()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2:].split()[0] != "Z"


def test_a_killed_fly_leaves_no_stage_running(runner):
    # `kill -9` of `hubtrack fly` (a CI timeout, a closed terminal): the kernel's parent-death
    # signal (`run.stop_with_supervisor`, which fly sets) stops every stage, instead of leaving
    # a simulated flight running against nobody.
    fly = runner.start("hubtrack", "fly", "--json", "--seeds", "5", "--first-seed", "5", label="fly")
    wait_until(lambda: len(children(fly.pid)) >= 4, timeout=60, what="fly's four stages running")
    stages = children(fly.pid)
    fly.signal(signal.SIGKILL)
    fly.wait(10)
    wait_until(lambda: not any(alive(p) for p in stages), timeout=10,
               what=f"stages {stages} to stop after their supervisor was killed")
