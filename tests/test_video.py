"""Compressed video in the recording, and channels the viewers open (issue 46).

Checked with independent parts: the schemas against the subset Foxglove and Lichtblick parse,
the annotation types against the published `foxglove-schemas-protobuf` enums, the JPEG frames
decoded by OpenCV's Python build against the renderer's frames.
"""

import json
import time

import pytest
from conftest import read_mcap_messages

VIEWER_TYPES = {"object", "array", "string", "number", "integer", "boolean"}
REJECTED = {"$ref", "$defs", "definitions", "oneOf", "anyOf", "allOf"}
USB = ["--set", "capture.synthetic.camera=usb"]


def viewer_subset_errors(node, path="$"):
    """Where a JSON schema leaves the subset the viewers parse (empty list: inside it)."""
    if not isinstance(node, dict):
        return [f"{path}: not an object"]
    errors = [f"{path}: uses {k}" for k in REJECTED & node.keys()]
    t = node.get("type")
    if not isinstance(t, str) or t not in VIEWER_TYPES:
        return errors + [f"{path}: type {t!r} is not one of {sorted(VIEWER_TYPES)}"]
    if "enum" in node and not (t == "string" and node["enum"] and all(isinstance(v, str) for v in node["enum"])):
        errors.append(f"{path}: enum must be strings on a string")
    if t == "object":
        props = node.get("properties")
        if not isinstance(props, dict):
            errors.append(f"{path}: object without properties")
        else:
            for k, v in props.items():
                errors += viewer_subset_errors(v, f"{path}.{k}")
    if t == "array":
        errors += viewer_subset_errors(node.get("items"), f"{path}[]")
    return errors


def test_subset_checker_rejects_what_the_viewers_reject():
    assert viewer_subset_errors({"type": "object", "properties": {"a": {"$ref": "#/$defs/A"}}})
    assert viewer_subset_errors({"type": "object", "properties": {"a": {"oneOf": [{"const": "x"}]}}})
    assert viewer_subset_errors({"type": "object", "properties": {"a": {"type": ["number", "null"]}}})
    assert not viewer_subset_errors({"type": "object", "properties": {"a": {"type": "string", "enum": ["x"]}}})


def run(runner, tmp_path, frames, *extra):
    rec = tmp_path / "video.mcap"
    res = runner.run("hubtrack", "run", "--record", rec, "--duration", "120",
                     "--set", 'run.stages=["capture","detect","track","recorder"]',
                     "--set", "capture.fps=10", "--set", f"capture.max_frames={frames}", *USB, *extra, timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    return rec


@pytest.fixture(scope="module")
def jpeg_run(tmp_path_factory):
    from conftest import Runner
    tmp = tmp_path_factory.mktemp("video")
    r = Runner(tmp)
    try:
        yield r, run(r, tmp, 30)
    finally:
        r.cleanup()


def test_every_schema_is_in_the_viewers_subset_and_annotations_use_official_types(jpeg_run):
    from foxglove_schemas_protobuf.PointsAnnotation_pb2 import PointsAnnotation
    from mcap.reader import make_reader

    _, rec = jpeg_run
    with open(rec, "rb") as f:
        summary = make_reader(f).get_summary()
    json_schemas = [s for s in summary.schemas.values() if s.encoding == "jsonschema"]
    assert len(json_schemas) >= 8, [s.name for s in json_schemas]
    for s in json_schemas:
        errors = viewer_subset_errors(json.loads(s.data))
        assert not errors, f"{s.name}: {errors[:5]}"
    # Every channel's messages carry the types the schema says (a viewer reads them by it).
    official = dict(PointsAnnotation.Type.items())
    overlays = [json.loads(m.data) for _, m in read_mcap_messages(rec, topics={"/frames/overlay"})]
    assert overlays
    types = {p["type"] for o in overlays for p in o["points"]}
    assert types and types <= set(official.values()), types
    # Overlay segments are independent lines: pairs of points, LINE_LIST in the official enum.
    assert types == {official["LINE_LIST"]}
    assert all(len(p["points"]) % 2 == 0 for o in overlays for p in o["points"])


def test_compressed_frames_follow_the_official_schema(jpeg_run):
    from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage
    from google.protobuf.descriptor_pb2 import FileDescriptorSet
    from mcap.reader import make_reader

    _, rec = jpeg_run
    with open(rec, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        frames_ch = next(c for c in summary.channels.values() if c.topic == "/frames")
        schema = summary.schemas[frames_ch.schema_id]
        assert (schema.name, schema.encoding, frames_ch.message_encoding) == (
            "foxglove.CompressedImage", "protobuf", "protobuf")
        fds = FileDescriptorSet.FromString(schema.data)
        ours = {f.name: (f.number, f.type) for fd in fds.file for m in fd.message_type
                if m.name == "CompressedImage" for f in m.field}
        theirs = {f.name: (f.number, f.type) for f in CompressedImage.DESCRIPTOR.fields}
        assert ours == theirs
        msgs = [(m.sequence, CompressedImage.FromString(m.data)) for _, _, m in reader.iter_messages(topics=["/frames"])]
    assert [s for s, _ in msgs] == list(range(30))
    assert all(i.format == "jpeg" and i.frame_id == "camera" and i.data[:2] == b"\xff\xd8" for _, i in msgs)


def test_a_cameras_own_jpeg_is_recorded_as_it_came(runner, tmp_path):
    """Frames that come as JPEG (a V4L2 MJPG camera; here JPEG files, the same path through
    capture) are recorded byte for byte, not encoded again; a PNG's frame is encoded. Read back
    with the Python mcap reader and the official CompressedImage type."""
    import cv2
    import numpy as np
    from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage

    folder = tmp_path / "images"
    folder.mkdir()
    rng = np.random.default_rng(7)
    files = []
    for i in range(4):
        img = cv2.GaussianBlur(rng.integers(0, 255, (240, 320, 3), dtype=np.uint8), (9, 9), 3)
        path = folder / (f"{i}.png" if i == 2 else f"{i}.jpg")
        assert cv2.imwrite(str(path), img, [cv2.IMWRITE_JPEG_QUALITY, 88])
        files.append(path)
    rec = tmp_path / "camera-jpeg.mcap"
    res = runner.run("hubtrack", "run", "--record", rec, "--duration", "60",
                     "--set", 'run.stages=["capture","recorder"]', "--set", "capture.source=images",
                     "--set", f'capture.images.path="{folder}"', "--set", "capture.loop=false",
                     "--set", "capture.fps=10", timeout=120)
    assert res.returncode == 0, res.stderr[-3000:]
    msgs = {m.sequence: CompressedImage.FromString(m.data) for _, m in read_mcap_messages(rec, topics={"/frames"})}
    assert sorted(msgs) == [0, 1, 2, 3]
    for seq, path in enumerate(files):
        data = msgs[seq].data
        if path.suffix == ".jpg":
            assert data == path.read_bytes(), f"frame {seq}: the file's own JPEG"
        else:
            assert data != path.read_bytes() and data[:2] == b"\xff\xd8", "the PNG's pixels, encoded"
            got = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
            assert psnr(got, cv2.imread(str(path))) >= 32.0
    stats = [json.loads(m.data) for _, m in read_mcap_messages(rec, topics={"/recorder"})]
    assert stats[-1]["frames_camera_jpeg"] == 3, stats[-1]


def psnr(a, b):
    import numpy as np
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255.0 ** 2 / mse)


@pytest.mark.parametrize("camera,frames,size", [("usb", 40, (640, 480)), ("gopro", 8, (1920, 1080))])
def test_jpeg_frames_decode_in_order_close_to_the_renderer(runner, tmp_path, camera, frames, size):
    """Default settings: every frame on /frames, in order, within 32 dB PSNR of the rendered pixels."""
    import cv2
    import numpy as np
    from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage

    cfg = ["--set", f"capture.synthetic.camera={camera}", "--set", f"capture.max_frames={frames}"]
    rec = tmp_path / "jpeg.mcap"
    res = runner.run("hubtrack", "run", "--duration", "60", "--record", rec, *cfg, timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    msgs = [(m.sequence, CompressedImage.FromString(m.data)) for _, m in read_mcap_messages(rec, topics={"/frames"})]
    assert [s for s, _ in msgs] == list(range(frames)), "every frame, in order"
    w, h = size
    raw = tmp_path / "expected.raw"
    worst = float("inf")
    for seq, img in msgs:
        if camera == "usb" and seq % 4:
            continue  # rendering each frame again costs more than the check needs
        res = runner.run("hubtrack", "render", "--seq", seq, "-o", raw, *cfg)
        assert res.returncode == 0, res.stderr
        expected = np.frombuffer(raw.read_bytes(), np.uint8).reshape(h, w, 3)
        got = cv2.imdecode(np.frombuffer(img.data, np.uint8), cv2.IMREAD_COLOR)
        assert got is not None and got.shape == (h, w, 3)
        worst = min(worst, psnr(got, expected))
    print(f"[jpeg {camera}] {len(msgs)} frames, {rec.stat().st_size / len(msgs) / 1e3:.0f} kB/frame, worst PSNR {worst:.1f} dB")
    assert worst >= 32.0


def test_raw_copies_beside_jpeg_are_the_captured_pixels(runner, tmp_path):
    from mcap_protobuf.decoder import DecoderFactory  # noqa: F401 - the peer that decodes RawImage
    from foxglove_schemas_protobuf.RawImage_pb2 import RawImage

    rec = run(runner, tmp_path, 12, "--set", "recorder.raw_every=5")
    raws = [(m.sequence, RawImage.FromString(m.data)) for _, m in read_mcap_messages(rec, topics={"/frames/raw"})]
    assert [s for s, _ in raws] == [0, 5, 10]
    out = tmp_path / "expected.raw"
    res = runner.run("hubtrack", "render", "--seq", 5, "-o", out, *USB, "--set", "capture.fps=10")
    assert res.returncode == 0, res.stderr
    assert raws[1][1].data == out.read_bytes()
    assert len(read_mcap_messages(rec, topics={"/frames"})) == 12


def test_a_raw_window_on_request_records_every_frame_raw_for_its_length(runner, tmp_path):
    """`hubtrack raw-window --seconds 1` while the pipeline runs: every frame of one second of
    capture time also goes raw to /frames/raw (10 frames at 10 fps, consecutive, bit-exact),
    none before or after; the recorder counts them; asking with no recorder is an error."""
    from foxglove_schemas_protobuf.RawImage_pb2 import RawImage
    from mcap.reader import make_reader

    res = runner.run("hubtrack", "raw-window", "--wait", "0.3")
    assert res.returncode != 0 and "no recorder is running" in res.stderr, res.stderr

    rec = tmp_path / "window.mcap"
    pipeline = runner.start("hubtrack", "run", "--record", rec, "--duration", "120",
                            "--set", 'run.stages=["capture","detect","track","recorder"]',
                            "--set", "capture.fps=10", "--set", "capture.max_frames=60", *USB)
    time.sleep(2.0)
    res = runner.run("hubtrack", "raw-window", "--seconds", "1", "--wait", "20")
    assert res.returncode == 0, res.stderr
    assert pipeline.wait(timeout=120) == 0, pipeline.stderr()[-3000:]

    raws = [(m.sequence, m) for _, m in read_mcap_messages(rec, topics={"/frames/raw"})]
    seqs = [s for s, _ in raws]
    assert seqs, "no raw frames"
    # One second of capture time at 10 fps: 10 or 11 frames (both ends), consecutive.
    assert 10 <= len(seqs) <= 11 and seqs == list(range(seqs[0], seqs[0] + len(seqs))), seqs
    assert 0 < seqs[0] and seqs[-1] < 59, seqs
    assert len(read_mcap_messages(rec, topics={"/frames"})) == 60
    with open(rec, "rb") as f:
        summary = make_reader(f).get_summary()
    schemas = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
    assert schemas["/frames/raw"] == "foxglove.RawImage" and schemas["/frames"] == "foxglove.CompressedImage"
    out = tmp_path / "expected.raw"
    seq = seqs[len(seqs) // 2]
    res = runner.run("hubtrack", "render", "--seq", seq, "-o", out, *USB, "--set", "capture.fps=10")
    assert res.returncode == 0, res.stderr
    assert RawImage.FromString(dict(raws)[seq].data).data == out.read_bytes()
    stats = [json.loads(m.data) for _, m in read_mcap_messages(rec, topics={"/recorder"})]
    assert stats[-1]["frames_raw_copies"] == len(seqs), stats[-1]


def rewrite_frames(src, dst, message_type, damage, drop=()):
    """Copies the recording `src` to `dst` with the Python mcap writer: the `/frames` message
    of each seq in `damage` gets its `data` replaced by `damage[seq](data)`; seqs in `drop`
    are left out."""
    from mcap.reader import make_reader
    from mcap.writer import Writer

    with open(src, "rb") as f, open(dst, "wb") as out:
        reader = make_reader(f)
        w = Writer(out)
        w.start()
        schemas, channels = {}, {}
        for schema, channel, m in reader.iter_messages(log_time_order=False):
            if channel.id not in channels:
                if schema.id not in schemas:
                    schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
                channels[channel.id] = w.register_channel(channel.topic, channel.message_encoding,
                                                          schemas[schema.id], channel.metadata)
            data = m.data
            if channel.topic == "/frames" and m.sequence in drop:
                continue
            if channel.topic == "/frames" and m.sequence in damage:
                msg = message_type.FromString(data)
                msg.data = damage[m.sequence](msg.data)
                data = msg.SerializeToString()
            w.add_message(channels[channel.id], m.log_time, data, m.publish_time, m.sequence)
        w.finish()


def test_replay_decodes_jpeg_frames_and_skips_corrupt_ones(jpeg_run, tmp_path):
    from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage

    runner, rec = jpeg_run
    res = runner.run("hubtrack", "replay", rec, "--into", "detect", "--compare", "-o", tmp_path / "r.mcap", timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    assert "decoded from JPEG" in res.stdout and "expected from the compression" in res.stdout, res.stdout
    res = runner.run("hubtrack", "latency", rec, "--json")
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["stages"][0]["count"] == 30

    # Three frames damaged: cut to its first bytes, garbage after the JPEG marker, not JPEG.
    bad = tmp_path / "bad.mcap"
    damage = {3: lambda d: d[:12], 7: lambda d: b"\xff\xd8" + bytes(range(256)) * 4, 11: lambda d: b"PNG?"}
    rewrite_frames(rec, bad, CompressedImage, damage)
    res = runner.run("hubtrack", "replay", bad, "--into", "detect", "-o", tmp_path / "rb.mcap", timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    assert "panicked" not in res.stderr
    assert "3 frames whose image did not decode" in res.stdout, res.stdout


def test_sample_flight_has_every_channel_in_viewer_form():
    from conftest import ROOT
    from mcap.reader import make_reader

    path = ROOT / "recordings" / "flight.mcap"
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    counts = {summary.channels[c].topic: n for c, n in summary.statistics.channel_message_counts.items()}
    for topic in ("/frames", "/frames/overlay", "/frames/header", "/detections", "/track", "/setpoints",
                  "/vehicle", "/status", "/recorder"):
        assert counts.get(topic, 0) > 0, (topic, counts)
    assert counts["/frames"] == counts["/frames/header"]
    assert path.stat().st_size < 10e6, "a few MB"
    for s in summary.schemas.values():
        if s.encoding == "jsonschema":
            assert not viewer_subset_errors(json.loads(s.data)), s.name


H264 = ["--set", 'recorder.frame_encoding="h264"']


@pytest.mark.parametrize("camera,frames,size", [("usb", 40, (640, 480)), ("gopro", 8, (1920, 1080))])
def test_h264_frames_decode_in_order_close_to_the_renderer(runner, tmp_path, camera, frames, size):
    """recorder.frame_encoding = "h264": foxglove.CompressedVideo per the official schema, one
    Annex B access unit per frame, keyframes at the configured interval; PyAV (FFmpeg's decoder)
    finds every frame, in order, within 32 dB PSNR of the rendered pixels."""
    import av
    import numpy as np
    from av.video.frame import PictureType
    from foxglove_schemas_protobuf.CompressedVideo_pb2 import CompressedVideo
    from google.protobuf.descriptor_pb2 import FileDescriptorSet
    from mcap.reader import make_reader

    interval = 5
    cfg = ["--set", f"capture.synthetic.camera={camera}", "--set", f"capture.max_frames={frames}"]
    rec = tmp_path / "h264.mcap"
    res = runner.run("hubtrack", "run", "--duration", "60", "--record", rec, *cfg, *H264,
                     "--set", f"recorder.keyframe_interval={interval}", timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    with open(rec, "rb") as f:
        summary = make_reader(f).get_summary()
    ch = next(c for c in summary.channels.values() if c.topic == "/frames")
    schema = summary.schemas[ch.schema_id]
    assert (schema.name, schema.encoding, ch.message_encoding) == ("foxglove.CompressedVideo", "protobuf", "protobuf")
    ours = {f.name: (f.number, f.type) for fd in FileDescriptorSet.FromString(schema.data).file
            for m in fd.message_type if m.name == "CompressedVideo" for f in m.field}
    assert ours == {f.name: (f.number, f.type) for f in CompressedVideo.DESCRIPTOR.fields}

    msgs = [(m.sequence, CompressedVideo.FromString(m.data)) for _, m in read_mcap_messages(rec, topics={"/frames"})]
    assert [s for s, _ in msgs] == list(range(frames)), "every frame, in order"
    assert all(v.format == "h264" and v.frame_id == "camera" and v.data[:4] == b"\0\0\0\1" for _, v in msgs)

    codec = av.CodecContext.create("h264", "r")
    decoded = []
    for seq, v in msgs:
        # Each message on its own is one packet for FFmpeg's decoder: a picture comes out at once.
        pics = list(codec.decode(av.Packet(v.data)))
        assert len(pics) == 1, f"frame {seq}: one access unit, one picture ({len(pics)})"
        assert pics[0].key_frame == (seq % interval == 0), seq
        assert PictureType(pics[0].pict_type) in (PictureType.I, PictureType.P), "no B-frames"
        decoded.append((seq, pics[0].to_ndarray(format="bgr24")))
    assert not list(codec.decode(None)), "no picture held back: the stream has no reordering"

    w, h = size
    raw = tmp_path / "expected.raw"
    worst = float("inf")
    for seq, got in decoded:
        if camera == "usb" and seq % 4:
            continue  # rendering each frame again costs more than the check needs
        res = runner.run("hubtrack", "render", "--seq", seq, "-o", raw, *cfg)
        assert res.returncode == 0, res.stderr
        expected = np.frombuffer(raw.read_bytes(), np.uint8).reshape(h, w, 3)
        assert got.shape == (h, w, 3)
        worst = min(worst, psnr(got, expected))
    print(f"[h264 {camera}] {len(msgs)} frames, {rec.stat().st_size / len(msgs) / 1e3:.0f} kB/frame, worst PSNR {worst:.1f} dB")
    assert worst >= 32.0


def test_replay_decodes_h264_and_resumes_at_the_next_keyframe(runner, tmp_path):
    from foxglove_schemas_protobuf.CompressedVideo_pb2 import CompressedVideo

    rec = run(runner, tmp_path, 30, *H264, "--set", "recorder.keyframe_interval=10")
    res = runner.run("hubtrack", "replay", rec, "--into", "detect", "--compare", "-o", tmp_path / "r.mcap", timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    assert "30 of the frames were decoded from JPEG/H.264" in res.stdout, res.stdout
    assert "expected from the compression" in res.stdout, res.stdout
    res = runner.run("hubtrack", "latency", rec, "--json")
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["stages"][0]["count"] == 30

    # Frame 3 cut short, frame 12 garbage, frame 25 dropped from the file: every frame after a
    # damaged one is skipped up to the next keyframe (10, 20), then replay resumes.
    bad = tmp_path / "bad.mcap"
    damage = {3: lambda d: d[: len(d) // 4], 12: lambda d: b"\0\0\0\1" + bytes(range(7, 250))}
    rewrite_frames(rec, bad, CompressedVideo, damage, drop={25})
    res = runner.run("hubtrack", "replay", bad, "--into", "detect", "-o", tmp_path / "rb.mcap", timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    assert "panicked" not in res.stderr
    # A cut access unit may still give a (damaged) picture; what follows a refused one waits for
    # the keyframe. Frames 12..19 never decode; frame 25 has no image, so 26..29 (after the gap
    # in the decoder's frame numbers) wait for a keyframe that the file no longer has.
    import re
    m = re.search(r"(\d+) frames whose image did not decode", res.stdout)
    assert m, res.stdout
    skipped = int(m.group(1))
    assert 12 <= skipped <= 12 + 7, res.stdout  # 12..19 and 26..29, plus 3..9 if the cut frame is refused
    assert re.search(r"(\d+) of the frames were decoded", res.stdout), res.stdout
    fed = int(re.search(r"(\d+) of the frames were decoded", res.stdout).group(1))
    assert fed == 30 - 1 - skipped, res.stdout
