"""Hostile and unlucky inputs (issue 45): damaged recordings, output paths that are inputs, a
second supervisor in the same IPC domain, a full disk."""

import os
import time
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
    folder = tmp_path / "out"
    folder.mkdir()
    res = r.run("hubtrack", "replay", rec, "--into", "detect", "-o", folder, "--force", timeout=60)
    assert res.returncode == 1 and f"-o {folder} is a folder" in res.stderr, res.stderr
    assert not list(tmp_path.glob("out.partial*")) and not list(folder.iterdir())
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


def stage_children(pid):
    """{stage: pid} of the processes `pid` started."""
    out = {}
    try:
        children = open(f"/proc/{pid}/task/{pid}/children").read().split()
    except OSError:
        return out
    for c in children:
        try:
            argv0 = open(f"/proc/{c}/cmdline", "rb").read().split(b"\0")[0].decode()
        except OSError:
            continue
        out[os.path.basename(argv0).removeprefix("hubtrack-")] = int(c)
    return out


def alive(pid):
    try:
        state = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in ("Z", "X")


def test_an_ipc_domain_that_cannot_prefix_a_service_is_named(runner):
    runner.env["HUBTRACK_DOMAIN"] = "d" * 300
    for cmd in (["status"], ["echo", "detections"]):
        res = runner.run("hubtrack", *cmd, timeout=30)
        assert res.returncode == 1, (cmd, res.stderr[-2000:])
        assert 'HUBTRACK_DOMAIN="ddd' in res.stderr and "ExceedsMaximumLength" in res.stderr, (cmd, res.stderr)
        assert "panicked" not in res.stderr


def test_an_empty_config_variable_says_what_to_do(runner):
    runner.env["HUBTRACK_CONFIG"] = ""
    res = runner.run("hubtrack", "config", timeout=30)
    assert res.returncode == 2, res.stderr
    assert "unset HUBTRACK_CONFIG for the built-in defaults" in res.stderr, res.stderr


def test_one_run_per_domain_and_orphans_of_a_killed_supervisor_are_stopped(runner, tmp_path):
    import signal
    from conftest import read_mcap_messages, wait_until
    first = runner.start("hubtrack", "run", "--record", tmp_path / "a.mcap", "--duration", "60", *STAGES,
                         "--set", "capture.synthetic.camera=usb", "--set", "run.stop_with_supervisor=false",
                         label="first")
    wait_until(lambda: set(stage_children(first.pid)) >= {"capture", "detect", "track", "recorder"},
               timeout=30, what="first run's stages")
    second = runner.run("hubtrack", "run", "--record", tmp_path / "b.mcap", "--duration", "5", *STAGES, timeout=30)
    assert second.returncode == 1, second.stderr[-2000:]
    assert "another hubtrack run is active in this IPC domain" in second.stderr, second.stderr[-2000:]
    assert f"supervisor pid {first.pid}" in second.stderr
    assert not (tmp_path / "b.mcap").exists()
    assert first.alive()

    orphans = stage_children(first.pid)
    first.signal(signal.SIGKILL)
    first.wait(timeout=10)
    time.sleep(0.5)
    assert all(alive(p) for p in orphans.values()), "stop_with_supervisor=false: the stages outlive it"
    third = runner.start("hubtrack", "run", "--record", tmp_path / "c.mcap", "--duration", "6", *STAGES,
                         "--set", "capture.synthetic.camera=usb", label="third")
    assert third.wait(timeout=60) == 0, third.stderr()[-3000:]
    err = third.stderr()
    assert "left running in this IPC domain by an earlier supervisor" in err, err[-3000:]
    for name, pid in orphans.items():
        assert f"{name} (pid {pid})" in err, (name, pid, err[-3000:])
        assert not alive(pid), f"orphaned {name} (pid {pid}) still running"
    seqs = [m.sequence for _, m in read_mcap_messages(tmp_path / "c.mcap", topics={"/frames/header"})]
    # One camera only: its seqs from 0, strictly increasing (two cameras interleave two series;
    # a frame dropped by a loaded recorder is counted there, not here).
    assert seqs and seqs[0] == 0 and all(b > a for a, b in zip(seqs, seqs[1:])), seqs[:50]


@pytest.fixture
def small_disk(tmp_path):
    """A 20 MiB file system (tmpfs): needs root to mount; skipped otherwise."""
    import subprocess
    d = tmp_path / "small"
    d.mkdir()
    res = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=20m", "tmpfs", str(d)], capture_output=True)
    if res.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs (needs root): {res.stderr.decode().strip()}")
    yield d
    subprocess.run(["umount", "-l", str(d)])


def test_a_full_disk_is_named_counted_and_fails_the_run(runner, small_disk):
    rec = small_disk / "full.mcap"
    res = runner.run("hubtrack", "run", "--record", rec, "--duration", "4",
                     "--set", 'run.stages=["capture","recorder"]', "--set", "recorder.min_free_mib=0",
                     "--set", 'recorder.compression="none"',
                     # Raw frames fill 20 MiB within the run; JPEG ones would not.
                     "--set", 'recorder.frame_encoding="raw"', timeout=60)
    assert res.returncode == 1, (res.returncode, res.stdout, res.stderr[-3000:])
    assert "No space left on device" in res.stderr
    assert "writing " + str(rec) + " failed" in res.stderr
    last = res.stderr.strip().splitlines()[-1]
    assert "recorder" in last and "No space left on device" in last, last
    line = next(l for l in res.stdout.splitlines() if l.strip().startswith("recorder "))
    assert "0 errors" not in line and "No space left on device" in line, line
    # What reached the disk is readable by an independent reader, up to the cut.
    from conftest import read_mcap_messages
    frames = read_mcap_messages(rec, topics={"/frames/header"}, tolerate_truncation=True)
    assert len(frames) >= 1


def test_every_stage_given_up_on_is_named_and_retried_later(runner, tmp_path):
    from conftest import BIN
    stage_dir = tmp_path / "bin"
    stage_dir.mkdir()
    (stage_dir / "hubtrack-capture").symlink_to(BIN / "hubtrack-capture")
    for name in ("detect", "track"):
        fake = stage_dir / f"hubtrack-{name}"
        fake.write_text("#!/bin/sh\ncase \"$*\" in *-config*) exit 0;; esac\n"
                        f"echo '{name} cannot start' >&2\nexit 3\n")
        fake.chmod(0o755)
    runner.env["HUBTRACK_STAGE_DIR"] = str(stage_dir)
    res = runner.run("hubtrack", "run", "--duration", "6", "--set", "capture.synthetic.camera=usb",
                     "--set", 'run.stages=["capture","detect","track"]',
                     "--set", "run.restart.max_restarts=2", "--set", "run.restart.backoff_initial_ms=50",
                     "--set", "run.restart.retry_after_s=2", timeout=60)
    assert res.returncode == 1
    last = res.stderr.strip().splitlines()[-1]
    assert "stage detect was given up on" in last and "stage track was given up on" in last, last
    assert "trying again in 2 s" in res.stderr
    # Retried after 2 s: started again (3 starts before the first give-up, more after).
    for name in ("detect", "track"):
        assert res.stderr.count(f"started {name} ") >= 4, res.stderr[-3000:]


def png_claiming(width, height):
    """A valid PNG signature and header declaring `width` x `height` RGB, and one small IDAT."""
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
            + chunk(b"IDAT", zlib.compress(bytes(200_000))) + chunk(b"IEND", b""))


def test_an_image_bomb_is_refused_by_its_header(runner, tmp_path):
    import resource
    bomb = tmp_path / "bomb.png"
    bomb.write_bytes(png_claiming(20000, 20000))
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    res = runner.run("hubtrack", "detect", bomb, timeout=60)
    peak_kib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    assert res.returncode == 1, (res.returncode, res.stderr[-2000:])
    # One JSON line per input: the image's error names the cause.
    assert "declares 20000x20000 pixels" in res.stdout and "refused before decoding" in res.stdout, res.stdout
    assert str(bomb) in res.stdout
    assert max(before, peak_kib) < 600 * 1024, f"peak RSS of a child {peak_kib / 1024:.0f} MiB"


def test_fuzz_command_runs_every_target_from_the_corpus_without_a_crash(runner):
    from conftest import ROOT
    res = subprocess_in(ROOT, runner, "hubtrack", "fuzz", "--executions", "3000")
    assert res.returncode == 0, res.stdout + res.stderr[-2000:]
    targets = ("mcap", "mavlink", "config", "calibration", "detect")
    rows = {l.split()[0]: l.split() for l in res.stdout.splitlines() if l.split() and l.split()[0] in targets}
    assert set(rows) == set(targets), res.stdout
    for name, row in rows.items():
        assert int(row[2]) == 3000 and int(row[4]) == 0, (name, row)
    assert "0 crashes" in res.stdout and "peak memory" in res.stdout


def subprocess_in(cwd, runner, name, *args):
    import subprocess
    from conftest import binary
    return subprocess.run([str(binary(name)), *map(str, args)], cwd=cwd, env=runner.env,
                          capture_output=True, text=True, timeout=300)


def test_a_recorder_that_falls_behind_logs_and_counts_the_frames_it_lost(runner, tmp_path):
    """The camera never waits: a recorder stopped (SIGSTOP) longer than the frames service's
    buffer loses frames. The loss is logged when it happens and counted, the gap is in the file,
    and recording goes on."""
    import signal

    from conftest import read_mcap_messages, wait_until

    usb = ["--set", "capture.synthetic.camera=usb", "--set", "capture.fps=30"]
    rec = tmp_path / "behind.mcap"
    recorder = runner.start("hubtrack-recorder", "--output", rec, *usb, label="recorder")
    wait_until(lambda: "recording to" in recorder.stderr(), what="recorder start")
    capture = runner.start("hubtrack-capture", *usb, label="capture")
    wait_until(lambda: "publishing at" in capture.stderr(), what="capture start")
    time.sleep(1.0)
    recorder.signal(signal.SIGSTOP)
    time.sleep(1.0)  # 30 frames, far more than the buffer holds
    recorder.signal(signal.SIGCONT)
    time.sleep(1.0)
    assert capture.alive() and recorder.alive()
    assert recorder.stop() == 0
    capture.stop()
    err = recorder.stderr()
    lines = [l for l in err.splitlines() if "overwritten in shared memory before the recorder read them" in l]
    assert lines, err[-2000:]
    lost = int(lines[0].split("WARN", 1)[-1].split("frame(s)")[0].split()[-1])
    seqs = [m.sequence for _, m in read_mcap_messages(rec, topics={"/frames"})]
    gaps = sum(b - a - 1 for a, b in zip(seqs, seqs[1:]) if b > a + 1)
    assert gaps >= lost >= 15, (gaps, lost, lines)
    assert f"{gaps} lost: overwritten before read" in err, err[-1500:]
