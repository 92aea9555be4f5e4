"""Hostile and unlucky inputs (issue 45): damaged recordings, output paths that are inputs, a
second supervisor in the same IPC domain, a full disk."""

import os
import random
import struct

import pytest
from mcap.reader import make_reader

STAGES = ["--set", 'run.stages=["capture","detect","track","recorder"]']
MAGIC = b"\x89MCAP0\r\n"
# The tools that read recordings, each with the arguments after the file.
READERS = [("latency", []), ("diagnose", []), ("recover", None)]


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    from conftest import Runner
    tmp = tmp_path_factory.mktemp("hostile")
    r = Runner(tmp)
    rec = tmp / "live.mcap"
    res = r.run("hubtrack", "run", "--record", rec, "--duration", "60", *STAGES,
                "--set", "capture.fps=10", "--set", "capture.max_frames=30", timeout=200)
    assert res.returncode == 0, res.stderr[-3000:]
    yield r, rec
    r.cleanup()


def run_reader(r, tool, path, tmp_path):
    if tool == "recover":
        out = tmp_path / f"{path.name}.{random.random()}.recovered.mcap"
        return r.run("hubtrack", "recover", path, out, timeout=60), out
    return r.run("hubtrack", tool, path, timeout=60), None


def crashed(res):
    """Killed by a signal (abort, segfault) or a Rust panic (exit 101)."""
    return res.returncode < 0 or res.returncode == 101 or "panicked" in res.stderr


def test_declared_lengths_and_garbage_give_clear_errors_in_every_reader(recording, tmp_path):
    r, _ = recording
    files = {
        "u64max": MAGIC + b"\x01" + struct.pack("<Q", 2**64 - 1) + bytes(90),
        "4gib": MAGIC + b"\x01" + struct.pack("<Q", 4 << 30) + bytes(90),
        "3gib": MAGIC + b"\x06" + struct.pack("<Q", 3 << 30) + bytes(97),
        "random": MAGIC + random.Random(45).randbytes(4000),
        "empty": b"",
        "text": b"not a recording at all\n",
    }
    for name, data in files.items():
        path = tmp_path / f"{name}.mcap"
        path.write_bytes(data)
        for tool, _ in READERS:
            res, out = run_reader(r, tool, path, tmp_path)
            assert not crashed(res), (name, tool, res.returncode, res.stderr[-2000:])
            assert res.returncode == 1, (name, tool, res.returncode, res.stdout, res.stderr)
            assert str(path) in res.stderr, (name, tool, res.stderr)
            if out is not None:
                assert not out.exists(), "nothing recovered: no output left behind"


def test_a_flipped_bit_is_reported_by_recover_not_laundered(recording, tmp_path):
    r, rec = recording
    data = bytearray(rec.read_bytes())
    # A bit in the middle of the data section: inside some chunk's compressed bytes.
    i = len(data) // 3
    data[i] ^= 0x04
    bad = tmp_path / "flipped.mcap"
    bad.write_bytes(bytes(data))
    out = tmp_path / "out.mcap"
    res = r.run("hubtrack", "recover", bad, out, timeout=60)
    assert res.returncode == 0, res.stderr
    assert "the input was complete" not in res.stdout, res.stdout
    assert "reading stopped at" in res.stdout and str(bad) in res.stdout, res.stdout
    with open(out, "rb") as f:
        recovered = sum(1 for _ in make_reader(f).iter_messages())
    with open(rec, "rb") as f:
        total = sum(1 for _ in make_reader(f).iter_messages())
    assert 0 < recovered < total, (recovered, total)


def test_mutants_of_a_real_recording_never_crash_a_reader(recording, tmp_path):
    r, rec = recording
    seed = rec.read_bytes()
    rng = random.Random(45)
    crashes = []
    for k in range(24):
        data = bytearray(seed)
        for _ in range(rng.choice([1, 4, 16])):
            i = rng.randrange(len(data))
            if rng.random() < 0.5:
                data[i] ^= 1 << rng.randrange(8)
            else:
                data[i:i + 8] = struct.pack("<Q", rng.choice([2**64 - 1, 4 << 30, 3 << 30, 2**31]))
        path = tmp_path / f"mutant{k}.mcap"
        path.write_bytes(bytes(data))
        for tool, _ in READERS:
            res, _ = run_reader(r, tool, path, tmp_path)
            if crashed(res):
                crashes.append((k, tool, res.returncode, res.stderr[-500:]))
        path.unlink()
    assert crashes == []


def test_replay_never_writes_over_its_input_or_an_existing_file(recording, tmp_path):
    r, rec = recording
    before = rec.read_bytes()
    for out in (rec, rec.parent / "." / rec.name):
        res = r.run("hubtrack", "replay", rec, "--into", "detect", "-o", out, "--force", timeout=60)
        assert res.returncode == 1 and "is the recording being replayed" in res.stderr, res.stderr
    link = tmp_path / "link.mcap"
    os.link(rec, link)
    res = r.run("hubtrack", "replay", rec, "--into", "detect", "-o", link, timeout=60)
    assert res.returncode == 1 and "is the recording being replayed" in res.stderr, res.stderr
    assert rec.read_bytes() == before
    existing = tmp_path / "existing.mcap"
    existing.write_bytes(b"keep me")
    res = r.run("hubtrack", "replay", rec, "--into", "detect", "-o", existing, timeout=60)
    assert res.returncode == 1 and "already exists" in res.stderr and "--force" in res.stderr, res.stderr
    assert existing.read_bytes() == b"keep me"
    res = r.run("hubtrack", "replay", rec, "--into", "detect", "-o", existing, "--force", timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    assert not (tmp_path / "existing.mcap.partial").exists()
    with open(existing, "rb") as f:
        topics = {c.topic for _, c, _ in make_reader(f).iter_messages()}
    assert "/detections" in topics, topics
    assert rec.read_bytes() == before
