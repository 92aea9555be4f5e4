"""The control stage against pymavlink, an independent MAVLink implementation.

A Python "autopilot" built on pymavlink speaks to the real `hubtrack-control` process over UDP
and over a pseudo-terminal serial pair, while the real capture → detect → track stages feed it
track states over iceoryx2. pymavlink decodes every message control sends; control's view of the
autopilot is read back from the vehicle service with `hubtrack echo`.
"""

import hashlib
import os
import random
import re
import select
import signal
import socket
import struct
import threading
import time

import pytest

from conftest import wait_until

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import ardupilotmega as mav2  # noqa: E402

GUIDED, LOITER = 4, 5
ARMED = mav2.MAV_MODE_FLAG_SAFETY_ARMED | mav2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
DISARMED = mav2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
TYPE_MASK_VELOCITY_YAW_RATE = 1479
MAV_FRAME_BODY_OFFSET_NED = 9


class UdpTransport:
    """The autopilot end of a UDP link: sends to control's `udpin` port, receives its replies."""

    def __init__(self, port):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.setblocking(False)
        self.addr = ("127.0.0.1", port)

    def write(self, data):
        self.sock.sendto(data, self.addr)

    def read(self):
        try:
            return self.sock.recv(65536)
        except BlockingIOError:
            return b""

    def fileno(self):
        return self.sock.fileno()

    def close(self):
        self.sock.close()


class PtyTransport:
    """The autopilot end of a serial link: the master side of a pseudo-terminal pair."""

    def __init__(self):
        import tty

        self.master, self.slave = os.openpty()
        tty.setraw(self.master)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self.slave)

    def write(self, data):
        os.write(self.master, data)

    def read(self):
        try:
            return os.read(self.master, 65536)
        except (BlockingIOError, OSError):
            return b""

    def fileno(self):
        return self.master

    def close(self):
        os.close(self.master)
        os.close(self.slave)


def sign(mav, key, link_id):
    """MAVLink 2 signing on a pymavlink MAVLink object, as mavutil's setup_signing does: outgoing
    frames signed, incoming unsigned ones refused (no allow_unsigned_callback)."""
    mav.signing.secret_key = key
    mav.signing.sign_outgoing = True
    mav.signing.link_id = link_id
    mav.signing.timestamp = int((time.time() - 1420070400) * 100_000)  # 10 us units since 2015


class FakeAutopilot:
    """ArduCopter as far as control can tell: HEARTBEAT 1 Hz, ATTITUDE 20 Hz, LOCAL_POSITION_NED
    10 Hz from system 1 component 1; records every message control sends (decoded by pymavlink)."""

    def __init__(self, transport, custom_mode=GUIDED, armed=True, system_id=1, signing_key=None):
        self.t = transport
        # The identity is fixed before the sending thread starts: a stranger that sent even one
        # frame as system 1 would be the autopilot as far as anyone can tell.
        self.mav = mav2.MAVLink(None, srcSystem=system_id, srcComponent=1)
        if signing_key is not None:
            sign(self.mav, signing_key, link_id=1)
        self.custom_mode = custom_mode
        self.armed = armed
        self.heartbeats = True
        self.boot = time.monotonic()
        self.received = []  # (monotonic time, message)
        self.lock = threading.Lock()
        self.attitude = (0.05, -0.02, 1.2, 0.01, 0.02, 0.03)
        self.position = (3.0, -4.0, -20.0, 0.1, 0.2, -0.3)
        self._stop = False
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def time_boot_ms(self):
        return int((time.monotonic() - self.boot) * 1000) & 0xFFFFFFFF

    def send(self, msg):
        self.t.write(msg.pack(self.mav))

    def reboot(self):
        self.boot = time.monotonic()

    def _run(self):
        next_hb = next_att = next_pos = 0.0
        while not self._stop:
            now = time.monotonic()
            if self.heartbeats and now >= next_hb:
                base = ARMED if self.armed else DISARMED
                self.send(self.mav.heartbeat_encode(mav2.MAV_TYPE_QUADROTOR, mav2.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                                    base, self.custom_mode, mav2.MAV_STATE_ACTIVE))
                next_hb = now + 1.0
            if self.heartbeats and now >= next_att:
                self.send(self.mav.attitude_encode(self.time_boot_ms(), *self.attitude))
                next_att = now + 0.05
            if self.heartbeats and now >= next_pos:
                self.send(self.mav.local_position_ned_encode(self.time_boot_ms(), *self.position))
                next_pos = now + 0.1
            r, _, _ = select.select([self.t], [], [], 0.01)
            if r:
                data = self.t.read()
                if data:
                    try:
                        msgs = self.mav.parse_buffer(data) or []
                    except mav2.MAVError:
                        msgs = []
                    with self.lock:
                        self.received.extend((time.monotonic(), m) for m in msgs)

    def messages(self, kind, since=0.0):
        with self.lock:
            return [m for (t, m) in self.received if t >= since and m.get_type() == kind]

    def close(self):
        self._stop = True
        self._thread.join(timeout=2)
        self.t.close()


def free_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def start_pipeline(runner, link, *extra):
    """capture (synthetic) → detect → track → control, control on `link`."""
    sets = ["--set", "capture.fps=15", "--set", "capture.synthetic.camera=\"usb\""]
    runner.start("hubtrack-capture", *sets, label="capture")
    runner.start("hubtrack-detect", *sets, label="detect")
    track = runner.start("hubtrack-track", *sets, label="track")
    control = runner.start("hubtrack-control", *sets, "--set", f"control.link=\"{link}\"",
                           "--set", "control.link_timeout_ms=1500", *extra, label="control")
    return track, control


def setpoints_arrive(ap, since, n=5, timeout=15.0):
    wait_until(lambda: len(ap.messages("SET_POSITION_TARGET_LOCAL_NED", since)) >= n, timeout=timeout,
               what=f"{n} SET_POSITION_TARGET_LOCAL_NED")


def no_setpoints_during(ap, seconds):
    t0 = time.monotonic()
    time.sleep(seconds)
    return ap.messages("SET_POSITION_TARGET_LOCAL_NED", t0)


@pytest.fixture
def udp_autopilot(runner):
    port = free_port()
    ap = FakeAutopilot(UdpTransport(port))
    yield ap, f"udpin:127.0.0.1:{port}"
    ap.close()


def test_pymavlink_decodes_everything_control_sends_and_control_parses_pymavlink(runner, udp_autopilot):
    ap, link = udp_autopilot
    _, control = start_pipeline(runner, link)
    echo = runner.start("hubtrack", "echo", "setpoints", "--duration", "30", label="echo-setpoints")
    t0 = time.monotonic()
    setpoints_arrive(ap, t0, n=30, timeout=30)

    # Control's HEARTBEAT: an onboard controller, not an autopilot, component 191.
    hbs = ap.messages("HEARTBEAT")
    assert hbs, "no HEARTBEAT from control"
    hb = hbs[-1]
    assert hb.type == mav2.MAV_TYPE_ONBOARD_CONTROLLER and hb.autopilot == mav2.MAV_AUTOPILOT_INVALID
    assert hb.get_srcComponent() == 191 and hb.get_srcSystem() == 1

    sps = ap.messages("SET_POSITION_TARGET_LOCAL_NED", t0)
    for sp in sps:
        assert sp.type_mask == TYPE_MASK_VELOCITY_YAW_RATE
        assert sp.coordinate_frame == MAV_FRAME_BODY_OFFSET_NED
        assert (sp.target_system, sp.target_component) == (1, 1)
        assert all(abs(v) < 5.0 for v in (sp.vx, sp.vy, sp.vz)), sp
    # At least 10 Hz while commanding.
    times = [t for (t, m) in ap.received if m.get_type() == "SET_POSITION_TARGET_LOCAL_NED" and t >= t0]
    span = times[-1] - times[0]
    assert (len(times) - 1) / span >= 10.0, f"{len(times)} setpoints in {span:.2f} s"

    # The values pymavlink decoded are the ones control published (as float32).
    echo.stop()
    published = [s for s in echo.json_lines() if s["sent"]]
    assert published, "control published no sent setpoint"
    f32 = lambda x: struct.unpack("f", struct.pack("f", x))[0]  # noqa: E731
    keys = {(f32(s["vx_m_s"]), f32(s["vy_m_s"]), f32(s["vz_m_s"]), f32(s["yaw_rate_rad_s"])) for s in published}
    decoded = {(sp.vx, sp.vy, sp.vz, sp.yaw_rate) for sp in sps}
    assert decoded & keys, "no MAVLink setpoint matches a published one"
    assert len(decoded - keys) <= len(decoded) // 4, "MAVLink setpoints that control never published"

    # Control parsed HEARTBEAT, ATTITUDE and LOCAL_POSITION_NED from pymavlink.
    out = runner.run("hubtrack", "echo", "vehicle", "--count", "3", "--duration", "10")
    states = [__import__("json").loads(l) for l in out.stdout.splitlines() if l.startswith("{")]
    assert states, out.stderr
    v = states[-1]
    assert v["link_ok"] and v["armed"] and v["custom_mode"] == GUIDED
    assert v["attitude_valid"] and v["position_valid"]
    for got, sent in zip([v["roll_rad"], v["pitch_rad"], v["yaw_rad"], *v["body_rates_rad_s"]], ap.attitude):
        assert got == pytest.approx(f32(sent), abs=1e-7)
    assert v["position_ned_m"] == pytest.approx([f32(x) for x in ap.position[:3]], abs=1e-6)
    assert v["velocity_ned_m_s"] == pytest.approx([f32(x) for x in ap.position[3:]], abs=1e-6)
    assert control.alive()


def test_no_setpoints_unless_guided_and_armed(runner, udp_autopilot):
    ap, link = udp_autopilot
    ap.custom_mode, ap.armed = LOITER, True
    start_pipeline(runner, link)
    wait_until(lambda: ap.messages("HEARTBEAT"), timeout=15, what="control's heartbeat")
    time.sleep(2.0)  # tracks flow by now
    assert not no_setpoints_during(ap, 2.0), "setpoints sent in LOITER"
    ap.custom_mode, ap.armed = GUIDED, False
    time.sleep(1.2)
    assert not no_setpoints_during(ap, 2.0), "setpoints sent while disarmed"
    ap.armed = True
    setpoints_arrive(ap, time.monotonic(), n=5)


def test_link_loss_stops_commands_and_a_rebooted_autopilot_is_followed(runner, udp_autopilot):
    ap, link = udp_autopilot
    _, control = start_pipeline(runner, link)
    setpoints_arrive(ap, 0.0, n=10, timeout=30)
    ap.heartbeats = False  # the autopilot goes silent
    time.sleep(2.0)  # control.link_timeout_ms = 1500
    assert not no_setpoints_during(ap, 2.0), "setpoints sent after the link was lost"
    ap.reboot()  # comes back with time_boot_ms from 0
    ap.heartbeats = True
    setpoints_arrive(ap, time.monotonic(), n=5)
    err = control.stderr().lower()
    assert "lost" in err and "reboot" in err, err[-2000:]


def test_silence_on_stale_track_and_recovery(runner, udp_autopilot):
    ap, link = udp_autopilot
    track, control = start_pipeline(runner, link)
    setpoints_arrive(ap, 0.0, n=10, timeout=30)
    track.signal(signal.SIGKILL)
    track.wait(5)
    time.sleep(1.0)  # control.input_timeout_ms = 500
    assert not no_setpoints_during(ap, 2.0), "setpoints sent on stale input"
    assert "stale" in control.stderr()
    runner.start("hubtrack-track", "--set", "capture.synthetic.camera=\"usb\"", label="track-again")
    setpoints_arrive(ap, time.monotonic(), n=5, timeout=20)


def test_garbage_on_the_link_is_counted_and_skipped(runner, udp_autopilot):
    ap, link = udp_autopilot
    _, control = start_pipeline(runner, link)
    setpoints_arrive(ap, 0.0, n=5, timeout=30)
    rng = random.Random(7)
    good = mav2.MAVLink(None, srcSystem=1, srcComponent=1)
    frame = good.heartbeat_encode(mav2.MAV_TYPE_QUADROTOR, mav2.MAV_AUTOPILOT_ARDUPILOTMEGA, ARMED, GUIDED,
                                  mav2.MAV_STATE_ACTIVE).pack(good)
    for _ in range(200):
        kind = rng.randrange(4)
        if kind == 0:
            ap.t.write(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 300))))
        elif kind == 1:
            ap.t.write(frame[: rng.randrange(1, len(frame))])  # truncated
        elif kind == 2:
            bad = bytearray(frame)
            bad[rng.randrange(10, len(bad))] ^= 0xFF  # corrupted: CRC fails
            ap.t.write(bytes(bad))
        else:
            ap.t.write(b"\xfd\x04\x00\x00\x07\x01\x01\xf8\x2a\x00" + b"\x01\x02\x03\x04" + b"\x00\x00")  # unknown id
    assert control.alive(), control.stderr()[-2000:]
    setpoints_arrive(ap, time.monotonic(), n=5)
    control.stop()
    last = [l for l in control.stderr().splitlines() if "garbage bytes" in l][-1]
    numbers = [int(w) for w in last.replace(",", " ").split() if w.isdigit()]
    assert any(n > 0 for n in numbers[2:]), last


def test_serial_link_over_a_pseudo_terminal(runner):
    pty = PtyTransport()
    ap = FakeAutopilot(pty)
    try:
        start_pipeline(runner, f"serial:{pty.path}:115200")
        setpoints_arrive(ap, 0.0, n=10, timeout=30)
        sp = ap.messages("SET_POSITION_TARGET_LOCAL_NED")[-1]
        assert sp.type_mask == TYPE_MASK_VELOCITY_YAW_RATE and sp.coordinate_frame == MAV_FRAME_BODY_OFFSET_NED
        assert ap.messages("HEARTBEAT"), "no HEARTBEAT over serial"
    finally:
        ap.close()


def test_missing_serial_port_is_a_clear_error(runner):
    r = runner.run("hubtrack-control", "--set", "control.link=\"serial:/dev/ttyNOPE9:57600\"", timeout=30)
    assert r.returncode != 0
    assert "/dev/ttyNOPE9" in r.stderr, r.stderr


def test_bad_link_string_names_the_key(runner):
    r = runner.run("hubtrack-control", "--set", "control.link=\"tcp:nowhere\"", timeout=30)
    assert r.returncode != 0
    assert "control.link" in r.stderr, r.stderr
    # What is wrong and the forms it takes, once each; not a value out of range.
    assert 'unknown transport "tcp"' in r.stderr and "out of range" not in r.stderr, r.stderr
    assert r.stderr.count("udpin:ADDR:PORT") == 1, r.stderr


def test_a_second_system_cannot_redirect_or_receive_setpoints(runner, udp_autopilot):
    """A stranger (system 99) on the udpin port sends garbage and autopilot heartbeats, also
    while the real autopilot is silent: it never receives a setpoint, and the autopilot does."""
    ap, link = udp_autopilot
    _, control = start_pipeline(runner, link)
    setpoints_arrive(ap, 0.0, n=5, timeout=30)
    stranger = FakeAutopilot(UdpTransport(ap.t.addr[1]), system_id=99)
    spoof_comp = mav2.MAVLink(None, srcSystem=1, srcComponent=42)
    try:
        rng = random.Random(45)
        for _ in range(50):
            stranger.t.write(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 100))))
            stranger.t.write(spoof_comp.heartbeat_encode(
                mav2.MAV_TYPE_QUADROTOR, mav2.MAV_AUTOPILOT_ARDUPILOTMEGA, ARMED, GUIDED,
                mav2.MAV_STATE_ACTIVE).pack(spoof_comp))
            time.sleep(0.02)
        setpoints_arrive(ap, time.monotonic(), n=5)
        # The autopilot falls silent past control.link_timeout_ms; the stranger keeps talking.
        ap.heartbeats = False
        time.sleep(3.0)
        ap.heartbeats = True
        setpoints_arrive(ap, time.monotonic(), n=5, timeout=20)
        assert stranger.messages("SET_POSITION_TARGET_LOCAL_NED") == [], "a stranger received setpoints"
        assert control.alive(), control.stderr()[-2000:]
        assert "system 99" not in control.stderr(), "the stranger was adopted as the autopilot"
    finally:
        stranger.close()


def signing_key_file(tmp_path, passphrase, mode=0o600):
    """A key file as `hubtrack signing-key` writes it: SHA-256 of the passphrase as hex."""
    key = hashlib.sha256(passphrase.encode()).digest()
    path = tmp_path / f"{passphrase}.key"
    path.write_text(key.hex() + "\n")
    path.chmod(mode)
    return key, path


def test_signing_refuses_unsigned_and_wrongly_signed_spoofers(runner, tmp_path):
    """With control.signing_key_file, spoofers using the autopilot's own ids (system 1 component
    1) send HEARTBEATs (disarmed, LOITER) and ATTITUDEs (roll 1 rad), unsigned and signed with
    another key: control's vehicle state never shows them, setpoints keep going to the autopilot
    only, signed (pymavlink verifies them), and the refusals are counted and logged once per
    cause."""
    key, key_path = signing_key_file(tmp_path, "hubtrack-45")
    port = free_port()
    ap = FakeAutopilot(UdpTransport(port), signing_key=key)
    spoofers = []
    try:
        _, control = start_pipeline(runner, f"udpin:127.0.0.1:{port}",
                                    "--set", f"control.signing_key_file=\"{key_path}\"")
        setpoints_arrive(ap, 0.0, n=10, timeout=30)
        echo = runner.start("hubtrack", "echo", "vehicle", "--duration", "8", label="echo-vehicle")
        time.sleep(1.0)
        unsigned = mav2.MAVLink(None, srcSystem=1, srcComponent=1)
        wrong = mav2.MAVLink(None, srcSystem=1, srcComponent=1)
        sign(wrong, hashlib.sha256(b"guess").digest(), link_id=1)
        spoofers = [(UdpTransport(port), unsigned), (UdpTransport(port), wrong)]
        t0 = time.monotonic()
        boot = 0
        while time.monotonic() - t0 < 4.0:
            boot += 20
            for t, mav in spoofers:
                t.write(mav.heartbeat_encode(mav2.MAV_TYPE_QUADROTOR, mav2.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                             DISARMED, LOITER, mav2.MAV_STATE_ACTIVE).pack(mav))
                t.write(mav.attitude_encode(boot, 1.0, 0.5, -2.0, 0.0, 0.0, 0.0).pack(mav))
            time.sleep(0.02)
        during = ap.messages("SET_POSITION_TARGET_LOCAL_NED", t0)
        assert len(during) >= 30, f"{len(during)} setpoints in 4 s of spoofing: the spoofer was believed"
        echo.wait(timeout=15)
        states = echo.json_lines()
        assert states, echo.stderr()
        spoofed = [v for v in states if abs(v["roll_rad"] - 1.0) < 1e-6 or not v["armed"] or v["custom_mode"] != GUIDED]
        assert not spoofed, f"{len(spoofed)} of {len(states)} vehicle states carry the spoofer's values: {spoofed[0]}"
        for t, _ in spoofers:
            data = b"".join(iter(t.read, b""))
            got = mav2.MAVLink(None).parse_buffer(data) or []
            assert not [m for m in got if m.get_type() == "SET_POSITION_TARGET_LOCAL_NED"], "a spoofer received setpoints"
        # Everything control sent was signed with the key: pymavlink refused nothing.
        sps = ap.messages("SET_POSITION_TARGET_LOCAL_NED")
        assert sps and all(m._signed for m in sps)
        assert ap.mav.signing.goodsig_count > 0
        assert (ap.mav.signing.badsig_count, ap.mav.signing.reject_count) == (0, 0)
        assert control.alive(), control.stderr()[-2000:]
        control.stop()
        err = control.stderr()
        assert "MAVLink 2 signing on" in err, err[-2000:]
        refusals = [l for l in err.splitlines() if "MAVLink signing: refused" in l]
        assert len(refusals) == 2 and any("unsigned" in l for l in refusals) and any("wrong signature" in l for l in refusals), refusals
        last = [l for l in err.splitlines() if "refused by signing" in l][-1]
        m = re.search(r"refused by signing: (\d+) unsigned, (\d+) bad signatures", last)
        # 4 s at 50 Hz, HEARTBEAT and ATTITUDE, per spoofer.
        assert m and int(m[1]) >= 200 and int(m[2]) >= 200, last
    finally:
        ap.close()
        for t, _ in spoofers:
            t.close()


def test_signing_key_file_open_to_others_is_refused(runner, tmp_path):
    _, key_path = signing_key_file(tmp_path, "open", mode=0o644)
    r = runner.run("hubtrack-control", "--set", f"control.signing_key_file=\"{key_path}\"", timeout=30)
    assert r.returncode != 0
    assert str(key_path) in r.stderr and "0644" in r.stderr and "control.signing_key_file" in r.stderr, r.stderr
    bad = tmp_path / "short.key"
    bad.write_text("abcd\n")
    bad.chmod(0o600)
    r = runner.run("hubtrack-control", "--set", f"control.signing_key_file=\"{bad}\"", timeout=30)
    assert r.returncode != 0 and str(bad) in r.stderr and "64 hexadecimal digits" in r.stderr, r.stderr


def test_signing_key_command_writes_the_mavproxy_key(tmp_path):
    """`hubtrack signing-key FILE` makes the key MAVProxy's `signing setup PASSPHRASE` gives the
    autopilot (SHA-256 of the passphrase), mode 0600, and never replaces a file."""
    import subprocess
    from conftest import binary
    out = tmp_path / "vehicle.key"
    r = subprocess.run([str(binary("hubtrack")), "signing-key", str(out)], input="correct horse\n",
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stderr
    assert out.read_text().strip() == hashlib.sha256(b"correct horse").hexdigest()
    assert out.stat().st_mode & 0o777 == 0o600
    r = subprocess.run([str(binary("hubtrack")), "signing-key", str(out)], input="other\n",
                       capture_output=True, text=True, timeout=30)
    assert r.returncode != 0 and str(out) in r.stderr
    assert out.read_text().strip() == hashlib.sha256(b"correct horse").hexdigest()
