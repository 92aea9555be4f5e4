"""The real ArduCopter firmware (SITL) in the loop.

`hubtrack fly --autopilot ardupilot` flies a whole approach with ArduCopter SITL coupled through
its JSON physics interface. The safety behaviours are checked against the firmware itself, with
its own physics (`--model +`): the stages (synthetic camera → detect → track → control) command
the vehicle over MAVLink as in flight, and a pymavlink ground station — the test — plays the
pilot (GUIDED, arm, take-off, LOITER) and watches what the vehicle does.

SITL binds its ports on every interface, so everything here runs in a private network namespace
with only loopback (`unshare -n`; needs root). The tests skip with a message when the SITL build
(`../shared/tools/ardupilot/arducopter`) is absent.
"""

import ctypes
import json
import math
import os
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest

from conftest import ROOT, Runner, wait_until

SITL_DIR = Path(os.environ.get("HUBTRACK_ARDUPILOT_DIR", ROOT.parent / "shared" / "tools" / "ardupilot"))
SITL = SITL_DIR / "arducopter"
PARAMS = ROOT / "config" / "ardupilot" / "sitl.parm"
pytestmark = pytest.mark.skipif(
    not SITL.is_file(), reason=f"ArduCopter SITL not available: {SITL} is missing (../shared/tools/ardupilot)")

GUIDED, LOITER = 4, 5
# SITL runs this many times faster than real time for the safety tests (its own physics); the
# guided timeout (GUID_TIMEOUT, 3 s of firmware time) is judged on the firmware's clock.
SPEEDUP = 4
GUID_TIMEOUT_S = 3.0
CLONE_NEWNET = 0x40000000


def fly(*args, timeout=900):
    r = subprocess.run([str(ROOT / "target" / "release" / "hubtrack"), "fly", "--json", "--autopilot", "ardupilot",
                        "--ardupilot-dir", str(SITL_DIR), *args],
                       capture_output=True, text=True, timeout=timeout,
                       env={**os.environ, "HUBTRACK_DOMAIN": f"test-ap-{os.getpid()}-{time.monotonic_ns()}"})
    assert r.returncode == 0, r.stderr[-4000:]
    return [json.loads(l) for l in r.stdout.splitlines()]


def test_a_full_approach_flown_by_the_firmware_and_the_same_seed_again():
    first = fly("--seeds", "1", "--first-seed", "5")[0]
    assert first["autopilot"] == "ardupilot"
    assert first["success"], first
    assert abs(first["final_distance_m"] - 5.0) <= 0.5 and abs(first["final_yaw_deg"]) <= 5.0, first
    assert first["min_rotor_plane_m"] >= 3.0, first
    again = fly("--seeds", "1", "--first-seed", "5")[0]
    assert again["success"], again
    # Lockstepped: the same flight again, up to the pipeline's reading of the firmware's
    # telemetry between two frames (measured differences: centimetres).
    assert abs(again["final_distance_m"] - first["final_distance_m"]) < 0.2, (first, again)


# --------------------------------------------------------------------------------------------
# Safety behaviours: one SITL boot shared by the tests below, in file order.

class PrivateNetwork:
    """This test process's main thread in a new network namespace with only loopback up; the
    processes it starts inherit it."""

    def __init__(self):
        self.libc = ctypes.CDLL(None, use_errno=True)
        self.holder = subprocess.Popen(["unshare", "-n", "sleep", "3600"])
        own = os.readlink("/proc/thread-self/ns/net")
        wait_until(lambda: self.holder.poll() is not None or os.readlink(f"/proc/{self.holder.pid}/ns/net") != own,
                   timeout=5, what="the private network")
        if self.holder.poll() is not None:
            pytest.skip("cannot make a private network (`unshare -n` needs root or CAP_SYS_ADMIN)")
        subprocess.run(["nsenter", "-t", str(self.holder.pid), "-n", "ip", "link", "set", "lo", "up"], check=True)
        self.own = os.open("/proc/thread-self/ns/net", os.O_RDONLY)
        fd = os.open(f"/proc/{self.holder.pid}/ns/net", os.O_RDONLY)
        try:
            if self.libc.setns(fd, CLONE_NEWNET) != 0:
                pytest.skip(f"cannot enter the private network: errno {ctypes.get_errno()}")
        finally:
            os.close(fd)

    def close(self):
        self.libc.setns(self.own, CLONE_NEWNET)
        os.close(self.own)
        self.holder.kill()
        self.holder.wait()


class GroundStation:
    """The pilot: pymavlink on SITL's SERIAL1, keeping the newest message of each type."""

    def __init__(self):
        from pymavlink import mavutil
        self.mavutil = mavutil
        # SITL opens its TCP ports a moment after it starts (longer on a loaded machine).
        wait_until(self.port_open, timeout=60, interval=0.2, what="SITL's SERIAL1 (TCP 5762)")
        # When the autopilot restarts, the link reconnects for as long as the first connection may
        # wait (pymavlink's default gives up after 3 s, shorter than a restart on a loaded machine).
        self.m = mavutil.mavlink_connection("tcp:127.0.0.1:5762", source_system=255, source_component=190,
                                            autoreconnect=True, retries=60, reconnect_delay=1)
        self.last = {}
        self.texts = []
        # The pilot's throttle stick: centred once airborne (in LOITER a low stick descends).
        self.hold_throttle = False
        self.last_stick = 0.0

    @staticmethod
    def port_open():
        try:
            socket.create_connection(("127.0.0.1", 5762), timeout=1).close()
            return True
        except OSError:
            return False

    def stick(self):
        # RC_CHANNELS_OVERRIDE: channel 3 (throttle) at mid stick, the others left alone (UINT16_MAX);
        # repeated well within RC_OVERRIDE_TIME (3 s of firmware time).
        if self.hold_throttle and time.monotonic() - self.last_stick > 0.1:
            self.last_stick = time.monotonic()
            keep = 65535
            self.m.mav.rc_channels_override_send(1, 1, keep, keep, 1500, keep, keep, keep, keep, keep)

    def pump(self, seconds=0.05):
        end = time.monotonic() + seconds
        while True:
            self.stick()
            try:
                msg = self.m.recv_match(blocking=True, timeout=max(0.0, end - time.monotonic()))
            except (ConnectionResetError, BrokenPipeError):
                # The autopilot restarted and reset the link: pymavlink has already reconnected
                # (autoreconnect) but re-raises the reset, where a closed link (EOF) it does not.
                msg = None
            # Only the autopilot's own messages: the firmware also routes control's HEARTBEAT here.
            if (msg is not None and msg.get_type() != "BAD_DATA"
                    and (msg.get_srcSystem(), msg.get_srcComponent()) == (1, 1)):
                self.last[msg.get_type()] = msg
                if msg.get_type() == "STATUSTEXT":
                    self.texts.append(msg.text)
            if time.monotonic() >= end:
                return

    def wait(self, pred, timeout, what):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.pump(0.1)
            if pred():
                return
        raise AssertionError(f"timed out after {timeout}s waiting for {what}; autopilot said: {self.texts[-10:]}")

    def command(self, cmd, *params):
        p = list(params) + [0.0] * (7 - len(params))
        self.m.mav.command_long_send(1, 1, cmd, 0, *p)

    def streams(self):
        mav = self.mavutil.mavlink
        for msg_id, hz in ((mav.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 10), (mav.MAVLINK_MSG_ID_ATTITUDE, 10)):
            self.command(mav.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 1e6 / hz)

    def mode(self):
        hb = self.last.get("HEARTBEAT")
        return None if hb is None else hb.custom_mode

    def armed(self):
        hb = self.last.get("HEARTBEAT")
        return hb is not None and bool(hb.base_mode & self.mavutil.mavlink.MAV_MODE_FLAG_SAFETY_ARMED)

    def set_mode(self, mode):
        self.command(self.mavutil.mavlink.MAV_CMD_DO_SET_MODE, 1, mode)

    def speed(self):
        lp = self.last.get("LOCAL_POSITION_NED")
        return None if lp is None else math.hypot(lp.vx, lp.vy)

    def take_off(self, alt=80.0, climb=True):
        mav = self.mavutil.mavlink
        self.hold_throttle = False  # arming needs the stick released (the override lapses)
        self.wait(lambda: self.mode() is not None, 60, "HEARTBEAT")
        self.streams()

        # Asked again until it holds: during its start-up the firmware falls back to STABILIZE once.
        def guided():
            self.set_mode(GUIDED)
            self.pump(0.5)
            return self.mode() == GUIDED

        self.wait(guided, 30, "GUIDED")

        def arm():
            if self.mode() != GUIDED:
                self.set_mode(GUIDED)
            self.command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
            self.pump(1.0)
            return self.armed()

        self.wait(arm, 120, "arming (the EKF needs GPS first)")
        if not climb:
            return
        self.command(mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, alt)
        self.wait(lambda: (self.last.get("LOCAL_POSITION_NED") is not None
                           and -self.last["LOCAL_POSITION_NED"].z > alt - 1.0), 60, f"the climb to {alt} m")
        self.hold_throttle = True
        self.streams()


class Flight:
    """SITL with its own physics, a pilot, and the stages commanding it."""

    def __init__(self, workdir: Path):
        self.net = PrivateNetwork()
        self.workdir = workdir
        self.runner = Runner(workdir)
        self.control_port = 14650
        self.sitl = None
        self.start_sitl(wipe=True)
        self.gcs = GroundStation()
        self.gcs.take_off()
        sets = ["--set", "capture.fps=15", "--set", "capture.synthetic.camera=\"usb\""]
        self.sets = sets
        # The synthetic camera does not move with the vehicle, so control's commands are not
        # closing a loop here; a small vertical limit keeps the vehicle from wandering into the
        # ground over the tests.
        self.control_sets = ["--set", "control.approach.max_vertical_m_s=0.05"]
        self.runner.start("hubtrack-capture", *sets, label="capture")
        self.runner.start("hubtrack-detect", *sets, label="detect")
        self.track = self.runner.start("hubtrack-track", *sets, label="track")
        self.control = None
        self.start_control()

    def start_sitl(self, wipe):
        # No telemetry streams configured on control's port (SRn_* 0, as on a flight controller
        # nobody set up): control has to ask for what it reads.
        no_streams = self.workdir / "no-streams.parm"
        no_streams.write_text("SR0_EXTRA1 0\nSR0_POSITION 0\n")
        args = [str(SITL), "--model", "+", "--speedup", str(SPEEDUP), "-I0", "--home", "63.4,10.4,50,0",
                "--defaults", f"{SITL_DIR / 'copter.parm'},{PARAMS},{no_streams}",
                "--serial0", f"udpclient:127.0.0.1:{self.control_port}"]
        if wipe:
            args.append("-w")
        self.sitl_log = open(self.workdir / "sitl.log", "ab")
        self.sitl = subprocess.Popen(args, cwd=self.workdir, stdout=self.sitl_log, stderr=subprocess.STDOUT)

    def start_control(self):
        self.control = self.runner.start(
            "hubtrack-control", *self.sets, *self.control_sets,
            "--set", f"control.link=\"udpin:127.0.0.1:{self.control_port}\"",
            label=f"control-{time.monotonic_ns()}")

    def setpoints(self, seconds):
        """Control's published setpoints for `seconds` (hubtrack echo)."""
        echo = self.runner.start("hubtrack", "echo", "setpoints", "--duration", str(seconds),
                                 label=f"echo-{time.monotonic_ns()}")
        end = time.monotonic() + seconds + 5
        while echo.alive() and time.monotonic() < end:
            self.gcs.pump(0.2)
        echo.wait(10)
        return echo.json_lines()

    def commanding(self):
        """Control sent setpoints within a 2 s window."""
        return any(s["sent"] for s in self.setpoints(2.0))

    def moving(self):
        return self.gcs.speed() is not None and self.gcs.speed() > 0.3

    def close(self):
        self.runner.cleanup()
        if self.sitl and self.sitl.poll() is None:
            self.sitl.kill()
            self.sitl.wait()
        self.net.close()


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    f = Flight(tmp_path_factory.mktemp("sitl-flight"))
    yield f
    f.close()


def test_control_commands_the_firmware_which_flies(flight):
    flight.gcs.wait(flight.moving, 60, "the vehicle moving under control's setpoints")
    sent = [s for s in flight.setpoints(2.0) if s["sent"]]
    assert sent, "control sent nothing"
    out = flight.control.stderr()
    assert "autopilot found" in out and "MAV_AUTOPILOT_ARDUPILOTMEGA" in out
    # Attitude and position reach control only because it asked for them.
    r = flight.runner.run("hubtrack", "echo", "vehicle", "--count", "3", "--duration", "10")
    states = [json.loads(l) for l in r.stdout.splitlines() if l.startswith("{")]
    assert states, r.stderr
    v = states[-1]
    assert v["link_ok"] and v["armed"] and v["custom_mode"] == GUIDED, v
    assert v["attitude_valid"] and v["position_valid"], v


def test_pilot_loiter_silences_control_and_it_never_takes_guided_back(flight):
    flight.gcs.wait(flight.commanding, 60, "control commanding")
    flight.gcs.set_mode(LOITER)
    flight.gcs.wait(lambda: flight.gcs.mode() == LOITER, 10, "LOITER")
    flight.gcs.pump(1.0)
    during = flight.setpoints(3.0)
    assert during, "control published nothing (tracks should still flow)"
    assert not any(s["sent"] for s in during), "control commanded in LOITER"
    assert flight.gcs.mode() == LOITER, "control took the vehicle back"
    flight.gcs.wait(lambda: not flight.moving(), 20, "LOITER holding")
    # The pilot, not control, gives GUIDED back; then control commands again.
    flight.gcs.set_mode(GUIDED)
    flight.gcs.wait(lambda: flight.gcs.mode() == GUIDED, 10, "GUIDED")
    flight.gcs.wait(flight.commanding, 30, "control commanding again")


def test_track_lost_control_goes_silent_and_the_vehicle_holds(flight):
    flight.gcs.wait(flight.commanding, 60, "control commanding")
    flight.track.signal(signal.SIGKILL)
    flight.track.wait(5)
    flight.gcs.wait(lambda: not flight.moving(), GUID_TIMEOUT_S + 20, "the vehicle to stop")
    flight.gcs.pump(1.0)  # control.input_timeout_ms = 500
    during = flight.setpoints(2.0)
    assert not any(s["sent"] for s in during), "control commanded without a track"
    assert "stale" in flight.control.stderr()
    flight.track = flight.runner.start("hubtrack-track", *flight.sets, label="track-again")
    flight.gcs.wait(flight.commanding, 30, "control commanding again")


def test_control_killed_the_firmware_stops_the_vehicle_by_its_guided_timeout(flight):
    gcs = flight.gcs
    gcs.wait(flight.moving, 90, "the vehicle moving under control's setpoints")
    flight.control.signal(signal.SIGKILL)
    flight.control.wait(5)
    t_kill = gcs.last["LOCAL_POSITION_NED"].time_boot_ms / 1000.0
    samples = []
    end = time.monotonic() + (GUID_TIMEOUT_S + 8) / SPEEDUP + 10
    while time.monotonic() < end:
        gcs.pump(0.05)
        lp = gcs.last["LOCAL_POSITION_NED"]
        samples.append((lp.time_boot_ms / 1000.0 - t_kill, math.hypot(lp.vx, lp.vy)))
    # Still flying the last setpoint well within the timeout, stopped after it. The last setpoint
    # is whatever control sent as it died: moving (over 0.3 m/s) when killed, the vehicle may be
    # settling to a slower one (T2's sideways step after T3's forward one: 0.28 m/s). A vehicle
    # that stopped at once is near 0 by 0.5 s.
    early = [v for t, v in samples if 0.5 <= t <= GUID_TIMEOUT_S - 1.0]
    late = [v for t, v in samples if t >= GUID_TIMEOUT_S + 4.0]
    assert early and min(early) > 0.15, samples[:40]
    assert late and max(late) < 0.2, samples[-40:]
    flight.start_control()
    gcs.wait(flight.commanding, 30, "a new control commanding")


def test_autopilot_restart_no_commands_until_guided_and_armed_again(flight):
    gcs = flight.gcs
    gcs.wait(flight.commanding, 60, "control commanding")
    flight.sitl.kill()
    flight.sitl.wait()
    flight.start_sitl(wipe=False)
    # Back disarmed in its boot mode: control must not command it.
    gcs.wait(lambda: gcs.mode() is not None and not gcs.armed(), 60, "the restarted autopilot")
    after = flight.setpoints(3.0)
    assert after, "control published nothing"
    assert not any(s["sent"] for s in after), "control commanded a disarmed, restarted autopilot"
    err = flight.control.stderr()
    assert "link lost" in err or "rebooted" in err, err[-2000:]
    # The pilot arms it in GUIDED again: from then on control commands it. (Landed, the firmware
    # disarms again after DISARM_DELAY unless a climb comes, so watch from before arming.)
    echo = flight.runner.start("hubtrack", "echo", "setpoints", "--duration", "60", label="echo-rearm")
    gcs.take_off(climb=False)
    armed_at = time.monotonic()

    def sent_lines():
        lines = []
        for line in echo.stdout().splitlines():
            try:
                lines.append(json.loads(line))
            except ValueError:
                pass  # the line being written
        return [s for s in lines if s.get("sent")]

    gcs.wait(lambda: sent_lines(), 20, "control commanding after GUIDED and armed again")
    assert time.monotonic() - armed_at < 5.0
    echo.stop()
