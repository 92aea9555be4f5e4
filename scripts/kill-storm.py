#!/usr/bin/env python3
"""Kill storm: random `kill -9`s of detect, track and recorder while `hubtrack run` runs the
synthetic pipeline with recording. Prints the counts and checks that the camera kept its process,
that every recording segment holds its frames without a gap in seq, and that every stage is back.

    .venv/bin/python scripts/kill-storm.py --minutes 10 --kills 500 --out /tmp/storm

Exit status 0 when every check holds. Needs the release binaries (`cargo build --release`) and
the Python `mcap` package (tests/requirements.txt).
"""

import argparse
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VICTIMS = ("detect", "track", "recorder")
STAGES = ("capture",) + VICTIMS


def stage_pids(run_pid):
    """The stage processes started by the supervisor `run_pid`: {stage: pid}."""
    pids = {}
    try:
        children = Path(f"/proc/{run_pid}/task/{run_pid}/children").read_text().split()
    except OSError:
        return pids
    for c in children:
        try:
            argv0 = Path(f"/proc/{c}/cmdline").read_bytes().split(b"\0")[0].decode()
            state = Path(f"/proc/{c}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue
        name = Path(argv0).name.removeprefix("hubtrack-")
        if name in STAGES and state != "Z":
            pids[name] = int(c)
    return pids


def segment_gaps(path):
    """(frames, gaps inside the segment) of one recording segment, read with the Python reader;
    a segment cut by `kill -9` is read as far as it is intact."""
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    seqs, channels = [], {}
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False, emit_chunks=False).records:
                if isinstance(record, Channel):
                    channels[record.id] = record.topic
                elif isinstance(record, Message) and channels.get(record.channel_id) == "/frames/header":
                    seqs.append(record.sequence)
        except Exception:  # noqa: BLE001 - a killed recorder leaves an incomplete last record
            pass
    gaps = sum(b - a - 1 for a, b in zip(seqs, seqs[1:]) if b > a + 1)
    disorder = sum(1 for a, b in zip(seqs, seqs[1:]) if b <= a)
    return len(seqs), gaps + disorder


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--kills", type=int, default=500, help="kills spread over the time")
    ap.add_argument("--out", type=Path, default=Path("/tmp/hubtrack-kill-storm"))
    ap.add_argument("--seed", type=int, default=45)
    ap.add_argument("--bin", type=Path, default=ROOT / "target" / "release")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="more configuration overrides for `hubtrack run`")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rng = random.Random(args.seed)
    env = dict(os.environ)
    env.setdefault("HUBTRACK_DOMAIN", f"storm{os.getpid()}")
    rec = args.out / "storm.mcap"
    seconds = args.minutes * 60
    # Restarts are never given up on here (the storm kills each stage every few seconds, far
    # beyond the crash-loop limit meant for a stage that cannot start).
    cmd = [str(args.bin / "hubtrack"), "run", "--record", str(rec), "--duration", str(seconds + 30),
           "--set", 'run.stages=["capture","detect","track","recorder"]',
           "--set", "capture.synthetic.camera=usb", "--set", "capture.fps=10",
           "--set", "run.restart.max_restarts=1000", "--set", "run.restart.window_s=1",
           "--set", "run.restart.backoff_initial_ms=100"]
    for kv in args.set:
        cmd += ["--set", kv]
    log = open(args.out / "run.stderr", "wb")
    run = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=log)
    t_end = time.monotonic() + 30
    while set(stage_pids(run.pid)) != set(STAGES):
        if time.monotonic() > t_end or run.poll() is not None:
            sys.exit(f"the pipeline did not start: see {args.out / 'run.stderr'}")
        time.sleep(0.2)
    time.sleep(2.0)
    camera = stage_pids(run.pid)["capture"]
    kills = {v: 0 for v in VICTIMS}
    back_s = {v: [] for v in VICTIMS}
    pending = {}  # stage -> (old pid, kill time): waiting for its new process
    t0 = time.monotonic()
    interval = seconds / args.kills
    next_kill = t0
    while time.monotonic() - t0 < seconds:
        now = time.monotonic()
        pids = stage_pids(run.pid)
        for v, (old, t) in list(pending.items()):
            if v in pids and pids[v] != old:
                back_s[v].append(now - t)
                del pending[v]
        if now >= next_kill:
            v = rng.choice([x for x in VICTIMS if x not in pending] or [None])
            if v is not None and v in pids:
                try:
                    os.kill(pids[v], signal.SIGKILL)
                    kills[v] += 1
                    pending[v] = (pids[v], now)
                except ProcessLookupError:
                    pass
            next_kill += rng.uniform(0.5, 1.5) * interval
        time.sleep(0.01)
    # Every stage must be back once the storm is over.
    t_end = time.monotonic() + 15
    while pending and time.monotonic() < t_end:
        pids = stage_pids(run.pid)
        for v, (old, t) in list(pending.items()):
            if v in pids and pids[v] != old:
                back_s[v].append(time.monotonic() - t)
                del pending[v]
        time.sleep(0.05)
    final = stage_pids(run.pid)
    run.send_signal(signal.SIGINT)
    summary, _ = run.communicate(timeout=300)
    log.close()

    segments = sorted(args.out.glob("storm*.mcap"), key=lambda p: (len(p.name), p.name))
    frames = gaps = 0
    bad = []
    for s in segments:
        n, g = segment_gaps(s)
        frames += n
        gaps += g
        if g:
            bad.append(s.name)
    total = sum(kills.values())
    print(f"kill storm: {total} kill -9 in {seconds / 60:.1f} min "
          f"({', '.join(f'{v} {n}' for v, n in kills.items())})")
    for v in VICTIMS:
        b = sorted(back_s[v])
        if b:
            print(f"  {v:<9} back {len(b)}/{kills[v]} times, median {b[len(b) // 2]:.2f} s, max {b[-1]:.2f} s")
    print(f"  camera    pid {camera} -> {final.get('capture')} ({'unchanged' if final.get('capture') == camera else 'CHANGED'})")
    print(f"  stages    running at the end: {', '.join(sorted(final))}; never back: {sorted(pending) or 'none'}")
    print(f"  recording {len(segments)} segments, {frames} frames, {gaps} seq gaps inside segments"
          + (f" (in {bad[:5]})" if bad else ""))
    print(f"  run       exit status {run.returncode}")
    ok = (total >= args.kills * 0.9 and final.get("capture") == camera and not pending
          and set(final) == set(STAGES) and gaps == 0)
    print("PASS" if ok else "FAIL")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
