"""The benchmark commands run and print their tables (timings are not asserted: benchmarks, not
timed tests; their numbers go into the README and the issue notes)."""


def test_bench_frames_prints_both_hops(runner):
    res = runner.run("hubtrack", "bench", "frames", "--seconds", "2", "--camera", "usb", timeout=120)
    assert res.returncode == 0, res.stderr[-3000:]
    out = res.stdout
    for row in ("iceoryx2 (zero-copy)", "Unix socket (copy)", "frames published", "frames recorded (MCAP)",
                "publish -> receive p50 [us]", "publish -> receive p99 [us]", "renderer per 640x480 frame"):
        assert row in out, out
    published = int(out.split("frames published")[1].split()[0])
    received = int(out.split("frames received by a reader")[1].split()[0])
    assert published >= 30 and received == published


def test_bench_pipeline_prints_latency_cpu_and_memory(runner):
    res = runner.run("hubtrack", "bench", "pipeline", "--seconds", "4", "--only-hd", timeout=180)
    assert res.returncode == 0, res.stderr[-3000:]
    out = res.stdout
    assert "capture+detect+track+control+recorder" in out, out
    for row in ("capture->detect", "detect->track", "track->control", "capture->track", "CPU %", "peak RSS MB",
                "hubtrack-detect", "hubtrack-record", "hubtrack-contro", "flight stages", "Unix-socket copy"):
        assert row in out, out
    # Control answered the frames end to end: capture -> setpoint has samples (no autopilot, so
    # none was sent, but every track state gets a published setpoint).
    row = next(l for l in out.splitlines() if l.split()[:1] == ["capture->setpoint"])
    p50, p90, p99, mx, count, dropped = row.split()[1:7]
    assert int(count) >= 30 and 0 < float(p50) <= float(p99), row
    setpoints = int(out.split("track states, ")[1].split()[0])
    assert setpoints >= int(count), out
    # The recording's size per minute and the recorder's own counters (JPEG frames by default).
    assert float(out.split("recording: ")[1].split()[0]) > 0, out
    rec = next(l for l in out.splitlines() if l.startswith("recorder: "))
    received, recorded = int(rec.split()[1]), int(rec.split("received, ")[1].split()[0])
    assert received >= recorded > 0 and "not encodable" in rec, rec
