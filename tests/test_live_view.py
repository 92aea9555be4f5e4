"""The live view (issue 46): `hubtrack run --live` serves the pipeline through the Foxglove
WebSocket protocol; an independent client (tests/foxglove_ws_client.py, the `websockets` package)
receives the video and the track at the configured rates, then disconnects abruptly, and a second
one stalls; detect processes every frame at the same speed throughout."""

import json
import socket
import statistics
import sys
import time
from pathlib import Path

import pytest
from conftest import read_mcap_messages, wait_until

pytest.importorskip("websockets", reason="the live-view client needs `websockets` (tests/requirements.txt)")
cv2 = pytest.importorskip("cv2", reason="decoding the video needs opencv-python-headless")
CompressedImage = pytest.importorskip(
    "foxglove_schemas_protobuf.CompressedImage_pb2",
    reason="decoding the video needs foxglove-schemas-protobuf").CompressedImage

CLIENT = Path(__file__).resolve().parent / "foxglove_ws_client.py"
# The synthetic USB camera (640x480): light enough to keep its rate on a busy 2-core machine.
CAMERA_FPS = 20.0
MAX_FPS = 5.0           # live.max_fps (the default)
MESSAGE_HZ = 5.0        # live.max_message_hz
MAX_WIDTH = 320         # live.max_width: 640x480 frames go out shrunk by 2, 320x240
WINDOW_S = 10.0


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def connectable(port):
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=0.2):
            return True
    except OSError:
        return False


def detect_window(headers, dets, t0, t1):
    """For frames captured in [t0, t1) (wall-clock ns): how many, how many detect skipped (its
    own count, `frames_skipped`), and detect's median time per frame in ms."""
    seqs = {h["seq"] for h in headers if t0 <= h["capture_realtime_ns"] < t1}
    inside = [d for d in dets if d["stamps"]["seq"] in seqs]
    times = [(d["stamps"]["publish_ns"] - d["stamps"]["recv_ns"]) / 1e6 for d in inside]
    skipped = inside[-1]["frames_skipped"] - inside[0]["frames_skipped"] if inside else 0
    return len(seqs), skipped, statistics.median(times) if times else float("nan")


def rate(arrivals):
    """Messages per second between the first and the last arrival."""
    return (len(arrivals) - 1) / (arrivals[-1] - arrivals[0]) if len(arrivals) > 1 else 0.0


def rss_kib(pid):
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


def live_pid(run):
    for line in run.stderr().splitlines():
        if "started live (pid" in line:
            return int(line.split("started live (pid")[1].split(",")[0])
    return None


LAYOUT = Path(__file__).resolve().parent.parent / "config" / "foxglove" / "hubtrack-layout.json"


def schema_fields(schema, path):
    """Whether the dotted `path` names a field of the JSON schema."""
    node = schema
    for part in path.split("."):
        node = node.get("properties", {}).get(part)
        if node is None:
            return False
    return True


def check_layout(advertised, rec):
    """Every topic the shipped layout shows is served live and recorded, with the same schema,
    and every plotted field exists in the recorded channel's JSON schema."""
    from mcap.reader import make_reader
    with open(rec, "rb") as f:
        summary = make_reader(f).get_summary()
    recorded = {ch.topic: summary.schemas[ch.schema_id] for ch in summary.channels.values()}
    layout = json.loads(LAYOUT.read_text())
    used = []
    for panel_id, cfg in layout["configById"].items():
        if panel_id.startswith("Image!"):
            used.append((cfg["imageMode"]["imageTopic"], None))
            used += [(t, None) for t in cfg["imageMode"]["annotations"]]
        elif panel_id.startswith("Plot!"):
            for p in cfg["paths"]:
                topic = max((t for t in recorded if p["value"].startswith(t + ".")), key=len)
                used.append((topic, p["value"][len(topic) + 1:]))
        elif panel_id.startswith("RawMessages!"):
            used.append((cfg["topicPath"], None))
    for topic, field in used:
        assert topic in recorded, f"layout topic {topic} is not recorded"
        assert advertised.get(topic) == recorded[topic].name, f"{topic}: live {advertised.get(topic)}"
        if field:
            schema = json.loads(recorded[topic].data)
            assert schema_fields(schema, field), f"{topic}: no field {field} in {recorded[topic].name}"


def test_live_view_serves_video_and_track_and_costs_detect_nothing(runner, tmp_path):
    port = free_port()
    rec = tmp_path / "live.mcap"
    run = runner.start(
        "hubtrack", "run", "--record", rec, "--duration", "90", "--live", f"127.0.0.1:{port}",
        "--set", 'run.stages=["capture", "detect", "track", "recorder"]',
        "--set", "capture.synthetic.camera=usb", "--set", f"capture.fps={CAMERA_FPS}",
        "--set", f"live.max_message_hz={MESSAGE_HZ}", "--set", f"live.max_width={MAX_WIDTH}",
        label="run")
    wait_until(lambda: connectable(port) or not run.alive(), timeout=30, what="the live view to listen")
    assert run.alive(), run.stderr()[-3000:]
    url = f"ws://127.0.0.1:{port}"

    # Window A: nobody connected.
    time.sleep(2.0)
    a0 = time.time_ns()
    time.sleep(WINDOW_S)
    a1 = time.time_ns()

    # Window B: a client receives the video, its overlay and the track for WINDOW_S.
    stats_path = tmp_path / "client.json"
    client = runner.start(sys.executable, CLIENT, url, "--topics", "/frames,/frames/overlay,/track",
                          "--seconds", str(WINDOW_S), "--out", stats_path, label="client")
    wait_until(lambda: '"subscribed"' in client.stdout() or not client.alive(), timeout=15,
               what="the client to subscribe")
    b0 = time.time_ns()
    wait_until(lambda: stats_path.exists() and '"done"' in client.stdout() or not client.alive(),
               timeout=WINDOW_S + 15, what="the client to finish")
    b1 = time.time_ns()
    assert stats_path.exists(), client.stderr()[-3000:]
    client.p.kill()  # abrupt: the socket closes without a WebSocket close frame
    client.p.wait()

    # Window C: a client subscribes and never reads.
    pid = live_pid(run)
    assert pid, run.stderr()[-3000:]
    rss_before = rss_kib(pid)
    stalled = runner.start(sys.executable, CLIENT, url, "--topics", "/frames,/track", "--mode", "stall",
                           label="stalled")
    wait_until(lambda: '"subscribed"' in stalled.stdout() or not stalled.alive(), timeout=15,
               what="the stalled client to subscribe")
    c0 = time.time_ns()
    time.sleep(WINDOW_S)
    c1 = time.time_ns()
    rss_stalled = rss_kib(pid)
    stalled.p.kill()
    stalled.p.wait()

    # Window D: nobody connected again (a second baseline: the machine's load drifts).
    time.sleep(1.0)
    d0 = time.time_ns()
    time.sleep(WINDOW_S)
    d1 = time.time_ns()
    assert run.alive(), run.stderr()[-3000:]
    assert rss_kib(pid) > 0, "the live view survived both clients"
    assert run.stop(timeout=30) == 0, run.stderr()[-4000:]

    # What the client received: rates, bitrate, one decodable JPEG at the configured width.
    s = json.loads(stats_path.read_text())
    video, track, overlay = (s["topics"][t] for t in ("/frames", "/track", "/frames/overlay"))
    fps, track_hz = rate(video["arrivals"]), rate(track["arrivals"])
    kbps = video["bytes"] * 8 / 1000 / WINDOW_S
    print(f"[live] video {fps:.2f} fps, {kbps:.0f} kbit/s; track {track_hz:.2f} Hz; "
          f"overlay {overlay['count'] / WINDOW_S:.2f} Hz")
    assert abs(fps - MAX_FPS) <= 0.15 * MAX_FPS, f"video {fps:.2f} fps, configured {MAX_FPS}"
    assert abs(track_hz - MESSAGE_HZ) <= 0.2 * MESSAGE_HZ, f"track {track_hz:.2f} Hz, configured {MESSAGE_HZ}"
    assert kbps <= 2000 * 1.1, f"{kbps:.0f} kbit/s above live.max_kbps"
    assert s["schemas"]["/frames"] == {"encoding": "protobuf", "schemaName": "foxglove.CompressedImage",
                                       "schemaEncoding": "protobuf"}
    img = CompressedImage()
    img.ParseFromString(bytes.fromhex(s["last_video"]))
    assert img.format == "jpeg" and img.frame_id == "camera"
    import numpy as np
    pixels = cv2.imdecode(np.frombuffer(img.data, np.uint8), cv2.IMREAD_UNCHANGED)
    assert pixels is not None, "the JPEG decodes"
    assert pixels.shape[:2] == (240, MAX_WIDTH), pixels.shape
    # Each overlay is drawn on the frame it belongs to: its time is a frame's capture time.
    stamped = [t for t in overlay.get("timestamps", []) if t is not None]
    assert overlay["count"] >= 0.5 * video["count"], "overlays follow the video frames"

    # The pipeline while the clients came, received, stalled and went: detect processed every
    # frame, at the same speed as with nobody connected.
    t = {}
    for topic, m in read_mcap_messages(rec, topics={"/frames/header", "/detections"}):
        t.setdefault(topic, []).append(json.loads(m.data))
    check_layout(s["advertised"], rec)
    headers, dets = t["/frames/header"], t["/detections"]
    video_times = {h["capture_realtime_ns"] for h in headers}
    assert stamped and all(ts in video_times for ts in stamped), "overlay times are frame times"
    windows = {"none": detect_window(headers, dets, a0, a1),
               "client": detect_window(headers, dets, b0, b1),
               "stalled": detect_window(headers, dets, c0, c1),
               "none again": detect_window(headers, dets, d0, d1)}
    print("[live] detect per window (frames, skipped by detect, p50 ms):", windows,
          f"live-view RSS {rss_before} -> {rss_stalled} KiB while stalled")
    base_skipped = max(windows["none"][1], windows["none again"][1])
    base_p50 = max(windows["none"][2], windows["none again"][2])
    for name, (frames, skipped, p50) in windows.items():
        assert frames >= 0.9 * CAMERA_FPS * WINDOW_S, f"{name}: {frames} frames captured"
        assert skipped <= base_skipped + 1, f"{name}: detect skipped {skipped} frames, {base_skipped} without client"
        # A gross bound only: wall-clock medians on a shared 2-core machine swing by a third
        # between windows with nothing changed (`hubtrack bench pipeline` measures the cost in
        # ratios within one run). Work moved into detect's process (encoding the video there)
        # would cost it several times its own time.
        assert p50 <= 2.0 * base_p50 + 1.0, f"{name}: detect p50 {p50:.2f} ms, {base_p50:.2f} ms without client"
    assert rss_stalled - rss_before < 64 * 1024, "a stalled client does not grow the live view's memory"


def test_bad_live_address_is_refused_naming_the_key(runner):
    for bad in ("vehicle:8765", "127.0.0.1", "127.0.0.1:99999"):
        res = runner.run("hubtrack", "run", "--live", bad, "--duration", "1",
                         "--set", 'run.stages=["capture"]', timeout=60)
        assert res.returncode != 0, res.stdout
        assert "live.address" in res.stderr and "IP:PORT" in res.stderr, res.stderr[-2000:]
        assert "panicked" not in res.stderr
