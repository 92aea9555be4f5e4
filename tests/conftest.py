"""Shared fixtures for hubtrack's multi-process integration tests.

The tests start the real release binaries (built by the test command before pytest runs) as
separate processes talking over iceoryx2, and check what they produce with independent readers
(the Python `mcap` package, pymavlink). Each test gets its own IPC domain (HUBTRACK_DOMAIN), so
tests never see each other's services, nor a pipeline running on the same machine.
"""

import json
import os
import signal
import subprocess
import time
import uuid
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(os.environ.get("HUBTRACK_BIN_DIR", ROOT / "target" / "release"))
SHARED_DATA = ROOT.parent / "shared" / "data"


def binary(name: str) -> Path:
    path = BIN / name
    if not path.is_file():
        pytest.fail(f"{path} is missing: build first with `cargo build --release --workspace`")
    return path


class Proc:
    """A started process whose stdout/stderr go to files (never a full pipe that blocks it)."""

    def __init__(self, args, env, workdir: Path, name: str):
        self.name = name
        self.out_path = workdir / f"{name}.stdout"
        self.err_path = workdir / f"{name}.stderr"
        self._out = open(self.out_path, "wb")
        self._err = open(self.err_path, "wb")
        self.p = subprocess.Popen([str(a) for a in args], stdout=self._out, stderr=self._err, env=env)

    @property
    def pid(self) -> int:
        return self.p.pid

    def alive(self) -> bool:
        return self.p.poll() is None

    def stdout(self) -> str:
        self._out.flush()
        return self.out_path.read_text(errors="replace")

    def stderr(self) -> str:
        self._err.flush()
        return self.err_path.read_text(errors="replace")

    def json_lines(self):
        return [json.loads(l) for l in self.stdout().splitlines() if l.startswith("{")]

    def signal(self, sig):
        if self.alive():
            os.kill(self.p.pid, sig)

    def wait(self, timeout=30.0) -> int:
        try:
            return self.p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.p.kill()
            self.p.wait()
            raise AssertionError(f"{self.name} did not exit within {timeout}s\nstderr:\n{self.stderr()[-3000:]}")

    def stop(self, timeout=10.0) -> int:
        self.signal(signal.SIGTERM)
        return self.wait(timeout)

    def close(self):
        if self.alive():
            self.p.kill()
            self.p.wait()
        self._out.close()
        self._err.close()


class Runner:
    """Starts hubtrack processes in one private IPC domain and cleans them up."""

    def __init__(self, workdir: Path):
        self.workdir = workdir
        self.env = dict(os.environ)
        self.env["HUBTRACK_DOMAIN"] = "test-" + uuid.uuid4().hex[:12]
        self.env.setdefault("RUST_BACKTRACE", "1")
        self.procs = []

    def start(self, name: str, *args, label=None) -> Proc:
        label = label or f"{name}-{len(self.procs)}"
        proc = Proc([binary(name), *args], self.env, self.workdir, label)
        self.procs.append(proc)
        return proc

    def run(self, name: str, *args, timeout=120.0) -> subprocess.CompletedProcess:
        return subprocess.run([str(binary(name)), *map(str, args)], env=self.env, capture_output=True,
                              text=True, timeout=timeout)

    def cleanup(self):
        for p in self.procs:
            p.close()


@pytest.fixture
def runner(tmp_path):
    r = Runner(tmp_path)
    yield r
    r.cleanup()


def wait_until(predicate, timeout=10.0, interval=0.05, what="condition"):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(interval)
    raise AssertionError(f"timed out after {timeout}s waiting for {what}")


def read_mcap_messages(path: Path, topics=None, tolerate_truncation=False):
    """All messages of a recording with the independent Python reader, in file order.

    With tolerate_truncation, the file is read linearly (no footer needed) and reading stops at
    the first incomplete record, as for a file whose writer was killed.
    """
    from mcap.stream_reader import StreamReader
    from mcap.records import Channel, Message, Schema

    out = []
    channels = {}
    with open(path, "rb") as f:
        reader = StreamReader(f, skip_magic=False, emit_chunks=False)
        try:
            for record in reader.records:
                if isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Message):
                    ch = channels[record.channel_id]
                    if topics is None or ch.topic in topics:
                        out.append((ch.topic, record))
        except Exception:  # noqa: BLE001 - a cut file ends in an incomplete record
            if not tolerate_truncation:
                raise
    return out
