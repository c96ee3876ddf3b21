#!/usr/bin/env python3
"""MAVProxy (1.8.75, its `camera` module, headless) as the ground station of `gimbalctl
mavlink --sim`, on UDP loopback, through a stand-in ArduPilot that routes between them.

    python3 gimbalctl/tests/mavproxy_camera.py target/debug/gimbalctl

MAVProxy runs as the operator runs it, `python3 -m MAVProxy.mavproxy --master ...
--load-module camera,message`, its commands written to its stdin and its console read from
its stdout (`--non-interactive` reads no stdin). It needs a vehicle: MAVProxy takes a link
only from a component-1 heartbeat, and the bridge takes its system id from the autopilot's.
So the script is the autopilot as ArduPilot is to both: HEARTBEAT from 1/1 (quadrotor,
ArduPilot), GLOBAL_POSITION_INT, ATTITUDE and AUTOPILOT_STATE_FOR_GIMBAL_DEVICE, and a
router: what is addressed to it (1/1) it keeps and answers, everything else goes on to the
other side (ArduPilot's GCS_MAVLink routing); MAVProxy's `camera mount` (its
MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW to the autopilot's gimbal manager) becomes a 50 Hz
GIMBAL_DEVICE_SET_ATTITUDE stream to the gimbal (154), as ArduPilot's AP_Mount_MAVLink does.
The router also reads every message on its way, which is how the script sees what MAVProxy
sent and what the bridge answered.

What each case drives through MAVProxy's own commands, and checks in what MAVProxy prints
and in what the bridge and the simulated gimbal did (its stderr):

1. Discovery: MAVProxy detects the camera (100) and the gimbal (154) and its `camera info`
   shows the identity, the gimbal association and `mftp://camera.xml`, version 1.
2. The camera definition over MAVLink FTP (MAVProxy's ftp module, which the camera module
   drives): "loaded N settings" with N the parameters of the file in
   idu-gimbal-mavlink/camera-definitions/, never "MAVFTP definition download failed"; the
   bytes the bridge sent in its FTP replies are the file's, and the session ends ACKed.
3. Settings: `camera params` shows every parameter read with the file's default;
   `camera param NAME VALUE` reaches the gimbal and reads back.
4. Capture: `camera photo` (one), `camera photo 0.5 3` (three, 0.5 s apart), `camera photo
   0.5 0` then `camera stopphotos`; each image printed by MAVProxy, its CAMERA_IMAGE_CAPTURED
   at the vehicle's position, the count in CAMERA_CAPTURE_STATUS.
5. Record: `camera record start|stop`, with `camera info` and CAMERA_CAPTURE_STATUS.
6. Zoom and mode: `camera zoom 50|in|stop`, `camera mode video|photo`, in CAMERA_SETTINGS
   and `camera info`.
7. Focus: `camera focus out|stop|in|auto` reach the gimbal, `camera focus 50` is refused.
8. Source: `camera source thermal|rgb`, accepted on the dual light, refused on a zoom camera.
9. Tracking: the camera module has no tracking command, so MAVProxy's generic `message
   COMMAND_LONG` starts and stops it and sets the status interval, and its `status
   CAMERA_TRACKING_IMAGE_STATUS` shows the status.
10. The footprint: with `--camera-fov` and `--camera-resolution`, `camera projection` shows
    the streams' resolution and field of view at the zoom set and the gimbal's attitude after
    `camera mount angle`; headless MAVProxy draws no polygon (`_show_camera_fov` returns
    without wxPython), so the script computes it with MAVProxy's own
    `camera_projection.CameraProjection` from what MAVProxy received, and checks that it
    contains the ground point of the bridge's CAMERA_FOV_STATUS.

Two families: the dual light (the thermal stream, the definition with the palette, the
infrared source) and the X3 (zoom only: the other definition file, the infrared source
refused). The vehicle does not turn here, so the lock behaviour (GIMBALCTL_SIM_LOCK_HOLDS)
changes nothing MAVProxy sees; it is still passed on.

Needs MAVProxy, numpy and OpenCV (`cv2`) importable by this Python. Ends with a line
"mavproxy_camera: N passed, M failed"; exit status 0 only if nothing failed.
"""

import math
import os
import re
import select
import socket
import subprocess
import sys
import tempfile
import threading
import time
import xml.etree.ElementTree as ET

os.environ["MAVLINK20"] = "1"  # before pymavlink is imported: MAVLink 2 framing
from pymavlink.dialects.v20 import common as mav  # noqa: E402

from checks import Checks, served_definition, sim_options  # noqa: E402

AP_SYSTEM, AP_COMPONENT = 1, 1
GIMBAL, CAMERA = 154, 100
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFINITIONS = os.path.join(REPO, "idu-gimbal-mavlink", "camera-definitions")
SAID = "gimbalctl mavlink: simulated gimbal: "

# The vehicle: where it is (mavlink_e2e.py's), level, heading 30°.
LAT, LON = 473977420, 85455940  # degE7
ALT_MM, REL_ALT_MM = 488000, 38000  # AMSL and above home: the ground at 450 m
VEHICLE_YAW = 30.0  # degrees
# The field of view given to the bridge for the footprint (a 1× zoom camera of 16:9).
HFOV, VFOV = 60.0, 35.0
WIDTH, HEIGHT = 1920, 1080

# MAVProxy's start: its imports (numpy, OpenCV) and the first heartbeats take seconds on a
# loaded machine; the camera's heartbeat starts once the simulated gimbal's postback gave
# its type (500 ms). 30 s bounds it.
START_TIMEOUT = 30.0
# MAVProxy's definition download: the ftp module's burst read of a 2 KB file on loopback
# takes tens of ms; its retries are 1 s apart (mavproxy_ftp.py). 15 s bounds it.
DEFINITION_TIMEOUT = 15.0
# MAVProxy's parameter reads retry every 3.5 s, three times (parameters.py RETRY_INTERVAL,
# MAX_ATTEMPTS): all settings read within 11 s.
PARAM_TIMEOUT = 11.0
# A command through MAVProxy (stdin, its input queue, its main loop at ~100 Hz, loopback)
# and the bridge's ACK: milliseconds; 5 s on a loaded machine. Also what MAVProxy prints.
REPLY_TIMEOUT = 5.0
# The simulated gimbal says a change in the bridge's tick that made it: milliseconds.
EFFECT_TIMEOUT = 3.0
# After a refused command: nothing said for this long (hundreds of the bridge's ticks).
QUIET = 0.5

CHECKS = Checks()
check = CHECKS.check


def result_name(value):
    return None if value is None else mav.enums["MAV_RESULT"][value].name


# --- the bridge ------------------------------------------------------------------------


class Bridge:
    """`gimbalctl mavlink --sim`, sending to the router's camera side; its stderr kept."""

    def __init__(self, gimbalctl, family, to_port, extra):
        self.proc = subprocess.Popen(
            [gimbalctl, "mavlink", "--sim", *sim_options(), "--camera", family, *extra,
             "--listen", "127.0.0.1:0", "--to", f"127.0.0.1:{to_port}", "--exit-after-ms", "150000"],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.said = []
        self.lock = threading.Lock()
        threading.Thread(target=self._read_stderr, daemon=True).start()
        line = self.proc.stdout.readline()
        if "listening on " not in line:  # it refused its options, or failed to start
            self.proc.wait()
            time.sleep(0.1)  # the rest of its stderr
            raise RuntimeError(f"gimbalctl mavlink did not start (exit {self.proc.returncode}): "
                               f"{' / '.join(self.said[-3:])}")
        self.port = int(line.split("listening on ")[1].split(",")[0].rsplit(":", 1)[1])

    def _read_stderr(self):
        for line in self.proc.stderr:
            print(line, end="", file=sys.stderr, flush=True)
            with self.lock:
                self.said.append(line.strip())

    def mark(self):
        with self.lock:
            return len(self.said)

    def wait_said(self, since, what, timeout=EFFECT_TIMEOUT):
        """The first line after `since` that starts with SAID + `what` (or one of them),
        without SAID; or None."""
        prefixes = tuple(SAID + w for w in ((what,) if isinstance(what, str) else what))
        end = time.monotonic() + timeout
        while True:
            with self.lock:
                got = [l for l in self.said[since:] if l.startswith(prefixes)]
            if got or time.monotonic() >= end:
                return got[0][len(SAID):] if got else None
            time.sleep(0.01)

    def said_since(self, since):
        with self.lock:
            return [l[len(SAID):] for l in self.said[since:] if l.startswith(SAID)]

    def stop(self):
        self.proc.kill()
        self.proc.wait()


# --- the stand-in ArduPilot: vehicle, gimbal manager and router --------------------------


class Autopilot(threading.Thread):
    """Two UDP sockets: `cam` (the bridge's --to) and `gcs` (MAVProxy's --master udpout).
    Each side's address is learnt from its first datagram. Messages are parsed, kept (with
    their arrival time) and routed: addressed to 1/1 they stay here, anything else is sent
    on, byte for byte."""

    def __init__(self):
        super().__init__(daemon=True)
        self.cam = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.cam.bind(("127.0.0.1", 0))
        self.gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.gcs.bind(("127.0.0.1", 0))
        self.cam_port = self.cam.getsockname()[1]
        self.gcs_port = self.gcs.getsockname()[1]
        self.bridge_addr = None
        self.mavproxy_addr = None
        self.from_cam = mav.MAVLink(None)
        self.from_gcs = mav.MAVLink(None)
        self.from_cam.robust_parsing = self.from_gcs.robust_parsing = True
        out = self

        class Out:
            def write(self, buf):
                out.send_both(buf)
        self.mav = mav.MAVLink(Out(), srcSystem=AP_SYSTEM, srcComponent=AP_COMPONENT)
        self.lock = threading.Lock()
        self.bridge_msgs = []  # (time, message) from the bridge
        self.mavproxy_msgs = []  # (time, message) from MAVProxy
        self.bad = []
        self.setpoint = None  # (flags, q) streamed to the gimbal once MAVProxy asks
        self.stopping = threading.Event()

    def send_both(self, buf):
        for sock, addr in ((self.cam, self.bridge_addr), (self.gcs, self.mavproxy_addr)):
            if addr is not None:
                try:
                    sock.sendto(buf, addr)
                except OSError:
                    pass

    def send_to(self, side, msg):
        """One message from 1/1 to one side only (an ACK to who asked)."""
        buf = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) % 256
        sock, addr = (self.cam, self.bridge_addr) if side == "cam" else (self.gcs, self.mavproxy_addr)
        if addr is not None:
            sock.sendto(buf, addr)

    def run(self):
        start = time.monotonic()
        next_hb = next_pos = next_att = next_state = next_set = 0.0
        while not self.stopping.is_set():
            ready, _, _ = select.select([self.cam, self.gcs], [], [], 0.005)
            for sock in ready:
                data, addr = sock.recvfrom(65536)
                if sock is self.cam:
                    self.bridge_addr = addr
                    self._route(data, self.from_cam, self.bridge_msgs, "cam")
                else:
                    self.mavproxy_addr = addr
                    self._route(data, self.from_gcs, self.mavproxy_msgs, "gcs")
            now = time.monotonic()
            boot_ms = int((now - start) * 1000)
            half = math.radians(VEHICLE_YAW) / 2
            if now >= next_hb:
                next_hb = now + 1.0
                self.mav.heartbeat_send(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                        mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 0, mav.MAV_STATE_ACTIVE)
            if now >= next_pos:  # ArduPilot's SRn_POSITION: 5 Hz here
                next_pos = now + 0.2
                self.mav.global_position_int_send(boot_ms, LAT, LON, ALT_MM, REL_ALT_MM, 0, 0, 0,
                                                  int(VEHICLE_YAW * 100))
            if now >= next_att:  # ArduPilot's SRn_EXTRA1: 10 Hz here
                next_att = now + 0.1
                self.mav.attitude_send(boot_ms, 0.0, 0.0, math.radians(VEHICLE_YAW), 0.0, 0.0, 0.0)
            if now >= next_state:  # AP_Mount_MAVLink streams it to the gimbal at 50 Hz
                next_state = now + 0.02
                self.mav.autopilot_state_for_gimbal_device_send(
                    AP_SYSTEM, 0, boot_ms * 1000, [math.cos(half), 0, 0, math.sin(half)],
                    0, 0, 0, 0, 0, 0, 0, 4, 0)
            if self.setpoint is not None and now >= next_set:  # and its setpoints at 50 Hz
                next_set = now + 0.02
                flags, q = self.setpoint
                self.send_to("cam", mav.MAVLink_gimbal_device_set_attitude_message(
                    AP_SYSTEM, GIMBAL, flags, q, math.nan, math.nan, math.nan))

    def _route(self, data, parser, kept, side):
        try:
            msgs = parser.parse_buffer(data) or []
        except Exception as e:  # a bad frame is a failure of whoever sent it
            self.bad.append((side, repr(e)))
            return
        other = (self.gcs, self.mavproxy_addr) if side == "cam" else (self.cam, self.bridge_addr)
        for m in msgs:
            if m.get_type() == "BAD_DATA":
                self.bad.append((side, repr(m)))
                continue
            t = time.monotonic()
            with self.lock:
                kept.append((t, m))
            target = (getattr(m, "target_system", 0), getattr(m, "target_component", 0))
            if target == (AP_SYSTEM, AP_COMPONENT):
                self._for_me(m, side)
            elif other[1] is not None:
                other[0].sendto(bytes(m.get_msgbuf()), other[1])

    def _for_me(self, m, side):
        """What ArduPilot answers itself."""
        if m.get_type() != "COMMAND_LONG":
            return
        if m.command == mav.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW and side == "gcs":
            # AP_Mount: pitch and yaw in degrees, yaw in the vehicle frame unless YAW_LOCK.
            pitch, yaw, flags = m.param1, m.param2, int(m.param5)
            if math.isfinite(pitch) and math.isfinite(yaw):
                earth = bool(flags & mav.GIMBAL_MANAGER_FLAGS_YAW_LOCK)
                dflags = (mav.GIMBAL_DEVICE_FLAGS_ROLL_LOCK | mav.GIMBAL_DEVICE_FLAGS_PITCH_LOCK
                          | (mav.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME | mav.GIMBAL_DEVICE_FLAGS_YAW_LOCK
                             if earth else mav.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME))
                self.setpoint = (dflags, euler_q(0.0, math.radians(pitch), math.radians(yaw)))
                result = mav.MAV_RESULT_ACCEPTED
            else:
                result = mav.MAV_RESULT_DENIED
        elif m.command == mav.MAV_CMD_SET_MESSAGE_INTERVAL:
            result = mav.MAV_RESULT_ACCEPTED  # streamed anyway (the rates above)
        else:
            result = mav.MAV_RESULT_UNSUPPORTED
        self.send_to(side, mav.MAVLink_command_ack_message(
            m.command, result, 0, 0, m.get_srcSystem(), m.get_srcComponent()))

    def mark(self):
        with self.lock:
            return len(self.bridge_msgs), len(self.mavproxy_msgs)

    def bridge(self, since, kind, component=CAMERA):
        with self.lock:
            return [(t, m) for t, m in self.bridge_msgs[since[0]:]
                    if m.get_type() == kind and m.get_srcComponent() == component]

    def mavproxy(self, since, kind):
        with self.lock:
            return [(t, m) for t, m in self.mavproxy_msgs[since[1]:] if m.get_type() == kind]

    def wait_bridge(self, since, kind, pred=lambda m: True, timeout=REPLY_TIMEOUT, component=CAMERA):
        end = time.monotonic() + timeout
        while True:
            got = [m for _, m in self.bridge(since, kind, component) if pred(m)]
            if got or time.monotonic() >= end:
                return got[0] if got else None
            time.sleep(0.01)

    def _after_ack(self, since, command, kind):
        """Each `kind` from the camera (arrival time, message) that follows its ACK of
        `command`, in the order the bridge sent them (one socket keeps it)."""
        with self.lock:
            msgs = [(t, m) for t, m in self.bridge_msgs[since[0]:] if m.get_srcComponent() == CAMERA]
        acked, after = False, []
        for t, m in msgs:
            if m.get_type() == "COMMAND_ACK" and m.command == command:
                acked = True
            elif acked and m.get_type() == kind:
                after.append((t, m))
        return after

    def after_ack(self, since, command, kind, timeout=REPLY_TIMEOUT):
        """The first `kind` from the camera that follows its ACK of `command` (the reply a
        command produces comes after its ACK; one MAVProxy asked for earlier may come
        between the command and the ACK)."""
        end = time.monotonic() + timeout
        while True:
            after = self._after_ack(since, command, kind)
            if after or time.monotonic() >= end:
                return after[0][1] if after else None
            time.sleep(0.01)

    def stamps_after_ack(self, since, command, kind, count, timeout=REPLY_TIMEOUT):
        """The arrival times of the first `count` `kind` from the camera after its ACK of
        `command` (fewer if they do not come within `timeout`)."""
        end = time.monotonic() + timeout
        while True:
            stamps = [t for t, _ in self._after_ack(since, command, kind)]
            if len(stamps) >= count or time.monotonic() >= end:
                return stamps[:count]
            time.sleep(0.01)

    def ack(self, since, command, timeout=REPLY_TIMEOUT):
        """The camera's COMMAND_ACK for `command` after `since`, and the COMMAND_LONG MAVProxy
        sent for it (the first after `since`)."""
        ack = self.wait_bridge(since, "COMMAND_ACK", lambda m: m.command == command, timeout)
        sent = [m for _, m in self.mavproxy(since, "COMMAND_LONG") if m.command == command]
        return ack, (sent[0] if sent else None)


def euler_q(roll, pitch, yaw):
    """[w, x, y, z] of the ZYX (yaw, pitch, roll) rotation, radians."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy]


# --- MAVProxy --------------------------------------------------------------------------


class MAVProxy:
    """`python3 -m MAVProxy.mavproxy`, interactive, in a home of its own (no startup
    scripts or keys of the user's, no logs left): commands on stdin, its console on stdout."""

    def __init__(self, gcs_port):
        home = tempfile.mkdtemp(prefix="mavproxy-home-")
        env = dict(os.environ, HOME=home, PYTHONUNBUFFERED="1")
        env.pop("DISPLAY", None)  # headless, whatever the machine
        env.pop("MAVLINK20", None)  # MAVProxy picks the version from what it hears
        # Modules: ftp (the camera module downloads the definition with it) and message (the
        # generic COMMAND_LONG); not terrain (it would fetch elevation tiles), param, etc.,
        # which a vehicle with no parameters needs not.
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "MAVProxy.mavproxy", "--master", f"udpout:127.0.0.1:{gcs_port}",
             "--target-system", str(AP_SYSTEM), "--default-modules", "ftp",
             "--load-module", "camera,message", "--no-state", "--state-basedir", home],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
            env=env, cwd=home)
        self.lines = []
        self.lock = threading.Lock()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stdout:
            line = line.rstrip("\n")
            # The prompt ("MAV> ") is written without a newline before each line read.
            line = re.sub(r"^(\S*> )+", "", line)
            print("  mavproxy| " + line, flush=True)
            with self.lock:
                self.lines.append(line)

    def mark(self):
        with self.lock:
            return len(self.lines)

    def send(self, command):
        """Types `command`; returns the mark before it."""
        since = self.mark()
        print("  mavproxy< " + command, flush=True)
        self.proc.stdin.write(command + "\n")
        self.proc.stdin.flush()
        return since

    def since(self, since):
        with self.lock:
            return list(self.lines[since:])

    def wait(self, since, pattern, timeout=REPLY_TIMEOUT):
        """The first match of the regular expression after `since`, or None."""
        end = time.monotonic() + timeout
        while True:
            for line in self.since(since):
                m = re.search(pattern, line)
                if m:
                    return m
            if time.monotonic() >= end:
                return None
            time.sleep(0.02)

    def ask(self, command, pattern, timeout=REPLY_TIMEOUT):
        """Types `command` and waits for `pattern` in what follows."""
        return self.wait(self.send(command), pattern, timeout)

    def poll(self, command, pattern, timeout, every=0.5):
        """Types `command` every `every` s until its output matches (for state that MAVProxy
        learns asynchronously); the last match or None."""
        end = time.monotonic() + timeout
        while True:
            m = self.ask(command, pattern, min(every, max(0.05, end - time.monotonic())))
            if m or time.monotonic() >= end:
                return m

    def stop(self):
        try:
            self.proc.stdin.close()  # its input loop ends at EOF
        except OSError:
            pass
        try:
            self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


# --- expectations from the definition files ------------------------------------------------


def definition_file(family, model):
    """The definition served: the family's file with CAMERA_INFORMATION's model filled in."""
    name = "idu-dual-light.xml" if family == "dual-light" else "idu-zoom.xml"
    data = served_definition(name, model)
    params = [(p.get("name"), int(p.get("default"))) for p in ET.fromstring(data).iter("parameter")]
    return data, params


# --- the cases ---------------------------------------------------------------------------


def discovery(mpx, ap, family):
    m = mpx.wait(0, r"Detected vehicle 1:100 on link", START_TIMEOUT)
    check(m is not None, "MAVProxy detects the camera 1:100 (its heartbeat, MAV_TYPE_CAMERA)")
    m = mpx.wait(0, r"Detected vehicle 1:154 on link", START_TIMEOUT)
    check(m is not None, "MAVProxy detects the gimbal 1:154")
    info = mpx.poll("camera info", r"^(IDU .*) \(1:100\) firmware=\S+ resolution=\d+x\d+ flags=0x([0-9a-f]+) gimbal=(\d+)",
                    START_TIMEOUT)
    check(info is not None and info.group(3) == str(GIMBAL),
          f"camera info: IDU's camera 1:100, its gimbal {GIMBAL}: {info and info.group(0)!r}")
    flags = int(info.group(2), 16) if info else 0
    thermal = getattr(mav, "CAMERA_CAP_FLAGS_HAS_THERMAL_RANGE", 4096)
    want = (mav.CAMERA_CAP_FLAGS_CAPTURE_VIDEO | mav.CAMERA_CAP_FLAGS_CAPTURE_IMAGE
            | mav.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM | mav.CAMERA_CAP_FLAGS_HAS_BASIC_ZOOM
            | mav.CAMERA_CAP_FLAGS_HAS_BASIC_FOCUS | mav.CAMERA_CAP_FLAGS_HAS_TRACKING_POINT
            | mav.CAMERA_CAP_FLAGS_HAS_TRACKING_RECTANGLE)
    check(flags & want == want and not flags & thermal,
          f"camera info flags 0x{flags:x}: capture, video, stream, zoom, focus, tracking; no thermal range")
    # The files' own version.
    with open(os.path.join(DEFINITIONS, "idu-zoom.xml"), "rb") as f:
        version = re.search(rb'<definition version="(\d+)"', f.read()).group(1).decode()
    m = mpx.ask("camera info", r"definition: (\S+) \(version (\d+)\)")
    check(m is not None and m.groups() == ("mftp://camera.xml", version),
          f"camera info: definition mftp://camera.xml version {version}: {m and m.group(0)!r}")
    # The label is "<vendor> <model>" (mavproxy_camera/__init__.py CameraDevice.label).
    return info.group(1)[len("IDU "):] if info else None


def definition(mpx, ap, family, model, since):
    data, params = definition_file(family, model)
    m = mpx.wait(0, r"Camera .*\(1:100\): (loaded (\d+) settings|Definition load failed: .*)", DEFINITION_TIMEOUT)
    check(m is not None and m.group(2) == str(len(params)),
          f"definition over MAVLink FTP: MAVProxy loaded {len(params)} settings: {m and m.group(0)!r}")
    failed = [l for l in mpx.since(0) if "MAVFTP definition download failed" in l or "load failed" in l]
    check(not failed, f"no download or load failure printed: {failed}")
    # What went over the link: MAVProxy's OpenFileRO of /camera.xml, the bridge's data
    # replies (burst or plain reads) laid at their offsets, its session ended with an ACK.
    sent = [bytes(msg.payload) for _, msg in ap.mavproxy(since, "FILE_TRANSFER_PROTOCOL")]
    opens = [p for p in sent if p[3] == 4]
    path = opens[0][12:12 + opens[0][4]] if opens else None
    check(path == b"/camera.xml", f"MAVProxy opens /camera.xml (mftp://camera.xml as a path): {path!r}")
    # MAVProxy prints "loaded" once it has read the file, and may end the session after:
    # its ACK is waited for.
    end = time.monotonic() + REPLY_TIMEOUT
    while True:
        image = bytearray()
        terminate_acked = False
        for _, msg in ap.bridge(since, "FILE_TRANSFER_PROTOCOL"):
            p = bytes(msg.payload)
            opcode, size, req, offset = p[3], p[4], p[5], int.from_bytes(p[8:12], "little")
            if opcode == 128 and req in (5, 15) and size:  # ACK of ReadFile / BurstReadFile
                if len(image) < offset + size:
                    image.extend(b"\0" * (offset + size - len(image)))
                image[offset:offset + size] = p[12:12 + size]
            if opcode == 128 and req == 1:
                terminate_acked = True
        if terminate_acked or time.monotonic() >= end:
            break
        time.sleep(0.02)
    check(bytes(image) == data, f"the bytes served are {os.path.basename(DEFINITIONS)}'s file ({len(image)} of {len(data)} bytes)")
    check(terminate_acked, "MAVProxy's TerminateSession is ACKed")
    return params


def settings(mpx, ap, bridge, family, params):
    # Every parameter read (PARAM_EXT_REQUEST_LIST), each at the file's default.
    want = {name: str(default) for name, default in params}

    def table():
        since = mpx.send("camera params")
        time.sleep(0.5)
        got = {}
        for line in mpx.since(since):
            m = re.match(r"^\s*([A-Z_]+) (\S+)\s", line)
            if m and m.group(1) in want:
                got[m.group(1)] = m.group(2)
        return got, "\n".join(mpx.since(since))

    end = time.monotonic() + PARAM_TIMEOUT
    while True:
        got, text = table()
        if got == want or time.monotonic() >= end:
            break
    check(got == want, f"camera params: every setting read, at the file's default {want}: {got}")
    # The value set and what the simulated gimbal says of it, then of the default again.
    name, value, effect, back = (("IR_PALETTE", 10, "palette ice-blue", "palette black-hot")
                                 if family == "dual-light" else ("CAM_FOCUS", 1, "focusing +", "focus held"))
    since, mark = ap.mark(), bridge.mark()
    mpx.send(f"camera param {name} {value}")
    ack = ap.wait_bridge(since, "PARAM_EXT_ACK", lambda m: m.param_id == name)
    sets = [m for _, m in ap.mavproxy(since, "PARAM_EXT_SET") if m.param_id == name]
    check(sets and sets[0].param_value == chr(value) and sets[0].param_type == mav.MAV_PARAM_EXT_TYPE_UINT8,
          f"camera param {name} {value}: PARAM_EXT_SET uint8 {value} sent")
    check(ack is not None and ack.param_result == mav.PARAM_ACK_ACCEPTED and ack.param_value == chr(value),
          f"{name}: PARAM_EXT_ACK ACCEPTED with {value}: {ack and (ack.param_result, ack.param_value)}")
    said = bridge.wait_said(mark, effect.split(" ")[0])
    check(said == effect, f"{name} {value} reaches the gimbal: said {said!r}")
    end = time.monotonic() + PARAM_TIMEOUT
    while True:
        got, text = table()
        if (got.get(name) == str(value) and "[pending]" not in text) or time.monotonic() >= end:
            break
    check(got.get(name) == str(value) and "[pending]" not in text,
          f"camera params: {name} reads back {value}, nothing pending: {got}")
    # Back to the default, for the cases after (the focus case expects a held focus).
    mark = bridge.mark()
    default = dict(params)[name]
    mpx.send(f"camera param {name} {default}")
    said = bridge.wait_said(mark, back.split(" ")[0])
    check(said == back, f"{name} back to {default}: the gimbal says {back!r}: {said!r}")


def image_lines(mpx, since):
    return [int(m.group(1)) for m in (re.search(r"Camera 100 image (\d+) captured", l) for l in mpx.since(since)) if m]


def capture(mpx, ap):
    since, msince = ap.mark(), mpx.mark()
    mpx.send("camera photo")
    ack, sent = ap.ack(since, mav.MAV_CMD_IMAGE_START_CAPTURE)
    check(sent is not None and (sent.param2, sent.param3, sent.param4) == (0, 1, 0),
          f"camera photo: IMAGE_START_CAPTURE interval 0, count 1: {sent and (sent.param2, sent.param3, sent.param4)}")
    check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, f"camera photo: ACK {result_name(ack and ack.result)}")
    m = mpx.wait(msince, r"Camera 100 image (\d+) captured")
    check(m is not None and m.group(1) == "0", f"MAVProxy prints image 0 captured: {m and m.group(0)!r}")
    img = ap.wait_bridge(since, "CAMERA_IMAGE_CAPTURED")
    check(img is not None and img.image_index == 0 and img.capture_result == 1
          and (img.lat, img.lon, img.alt, img.relative_alt) == (LAT, LON, ALT_MM, REL_ALT_MM),
          f"CAMERA_IMAGE_CAPTURED 0, taken, at the vehicle's position: "
          f"{img and (img.image_index, img.capture_result, img.lat, img.lon, img.alt, img.relative_alt)}")
    st = ap.wait_bridge(since, "CAMERA_CAPTURE_STATUS", lambda m: m.image_count == 1)
    check(st is not None, "CAMERA_CAPTURE_STATUS image_count 1")

    # Three at 0.5 s. The bridge stamps each image with its own clock (time_boot_ms) in the
    # tick it takes it (1 ms loop), each at its deadline: 500 ms apart, ±150 ms for a late
    # tick (a process starved on a loaded machine wakes tens of ms late, once 60), which
    # still tells 0.5 s from none or 1 s.
    since, msince = ap.mark(), mpx.mark()
    mpx.send("camera photo 0.5 3")
    ack, sent = ap.ack(since, mav.MAV_CMD_IMAGE_START_CAPTURE)
    check(sent is not None and (sent.param2, sent.param3) == (0.5, 3) and ack is not None
          and ack.result == mav.MAV_RESULT_ACCEPTED,
          f"camera photo 0.5 3: interval 0.5, count 3, ACK {result_name(ack and ack.result)}")
    end = time.monotonic() + 1.0 + REPLY_TIMEOUT
    while len(image_lines(mpx, msince)) < 3 and time.monotonic() < end:
        time.sleep(0.05)
    time.sleep(0.8)  # one more interval: no fourth
    check(image_lines(mpx, msince) == [1, 2, 3], f"MAVProxy prints images 1, 2, 3: {image_lines(mpx, msince)}")
    stamps = [m.time_boot_ms for _, m in ap.bridge(since, "CAMERA_IMAGE_CAPTURED")]
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    check(len(stamps) == 3 and all(abs(g - 500) <= 150 for g in gaps), f"three images 500 ms apart: gaps {gaps} ms")

    # Until stopped, then none.
    since, msince = ap.mark(), mpx.mark()
    mpx.send("camera photo 0.5 0")
    ack, sent = ap.ack(since, mav.MAV_CMD_IMAGE_START_CAPTURE)
    check(sent is not None and (sent.param2, sent.param3) == (0.5, 0) and ack is not None
          and ack.result == mav.MAV_RESULT_ACCEPTED,
          f"camera photo 0.5 0 (until stopped): ACK {result_name(ack and ack.result)}")
    st = ap.wait_bridge(since, "CAMERA_CAPTURE_STATUS", lambda m: m.image_status == 3)
    check(st is not None and abs(st.image_interval - 0.5) < 1e-6,
          f"CAMERA_CAPTURE_STATUS: interval capture in progress, 0.5 s: {st and (st.image_status, st.image_interval)}")
    time.sleep(1.2)  # images at 0, 0.5 and 1.0 s
    since2 = ap.mark()
    mpx.send("camera stopphotos")
    ack, _ = ap.ack(since2, mav.MAV_CMD_IMAGE_STOP_CAPTURE)
    check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, f"camera stopphotos: ACK {result_name(ack and ack.result)}")
    st = ap.after_ack(since2, mav.MAV_CMD_IMAGE_STOP_CAPTURE, "CAMERA_CAPTURE_STATUS")
    check(st is not None and st.image_status == 0, f"CAMERA_CAPTURE_STATUS idle after the stop: {st and st.image_status}")
    # The bridge sends an image before the ACK of a stop it handles after it, on one socket:
    # none may come after the ACK.
    acked = [t for t, a in ap.bridge(since2, "COMMAND_ACK") if a.command == mav.MAV_CMD_IMAGE_STOP_CAPTURE]
    time.sleep(1.2)
    late = [m.image_index for t, m in ap.bridge(since, "CAMERA_IMAGE_CAPTURED") if acked and t > acked[0]]
    taken = image_lines(mpx, msince)
    check(len(taken) >= 3 and taken == list(range(4, 4 + len(taken))) and not late,
          f"images from 4 on, at least 3 in 1.2 s, none after the stop's ACK: {taken}, after: {late}")


def record(mpx, ap):
    for action, status, shown in (("start", 1, "yes"), ("stop", 0, "no")):
        since = ap.mark()
        mpx.send(f"camera record {action}")
        command = mav.MAV_CMD_VIDEO_START_CAPTURE if action == "start" else mav.MAV_CMD_VIDEO_STOP_CAPTURE
        ack, sent = ap.ack(since, command)
        check(sent is not None and ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED,
              f"camera record {action}: {'VIDEO_START' if status else 'VIDEO_STOP'}_CAPTURE, ACK {result_name(ack and ack.result)}")
        st = ap.after_ack(since, command, "CAMERA_CAPTURE_STATUS")
        check(st is not None and st.video_status == status,
              f"CAMERA_CAPTURE_STATUS video_status {status}: {st and st.video_status}")
        # MAVProxy asks for the status again 0.5 s after the command (recording_verify_at)
        # and shows it in `camera info`.
        m = mpx.poll("camera info", r"recording=(\w+) photos=(\d+)", REPLY_TIMEOUT)
        check(m is not None and m.group(1) == shown, f"camera info: recording={shown}: {m and m.group(0)!r}")
        if status:
            acked = [t for t, a in ap.bridge(since, "COMMAND_ACK") if a.command == command][0]
            time.sleep(1.0)
            since = ap.mark()
            mpx.send("camera for 1:100 discover")  # asks CAMERA_CAPTURE_STATUS among others
            st = ap.wait_bridge(since, "CAMERA_CAPTURE_STATUS")
            got = [t for t, m in ap.bridge(since, "CAMERA_CAPTURE_STATUS") if m is st]
            # The time recorded is the bridge's, from the command's tick to the status's;
            # here, from the ACK's arrival to the status's: the same to the difference of two
            # arrival delays (the bridge's tick, this process's receiving thread), each up
            # to 100 ms on a loaded machine.
            elapsed_ms = (got[0] - acked) * 1000 if got else None
            check(st is not None and st.video_status == 1 and abs(st.recording_time_ms - elapsed_ms) <= 200,
                  f"recording_time_ms is the time since the start ({elapsed_ms and round(elapsed_ms)} ms): "
                  f"{st and st.recording_time_ms}")


def zoom(mpx, ap):
    since = ap.mark()
    mpx.send("camera zoom 50")
    ack, sent = ap.ack(since, mav.MAV_CMD_SET_CAMERA_ZOOM)
    check(sent is not None and (sent.param1, sent.param2) == (mav.ZOOM_TYPE_RANGE, 50),
          f"camera zoom 50: ZOOM_TYPE_RANGE 50: {sent and (sent.param1, sent.param2)}")
    check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, f"camera zoom 50: ACK {result_name(ack and ack.result)}")
    # The level is the share of the zoom range: 50 % of it, whatever the range (float32).
    st = ap.after_ack(since, mav.MAV_CMD_SET_CAMERA_ZOOM, "CAMERA_SETTINGS")
    check(st is not None and abs(st.zoomLevel - 50.0) < 1e-3, f"CAMERA_SETTINGS zoomLevel 50: {st and st.zoomLevel}")
    m = mpx.poll("camera info", r"mode=\d+ zoom=50\.0% focus=", REPLY_TIMEOUT)
    check(m is not None, "camera info: zoom=50.0%")
    for word, rate in (("in", 1.0), ("stop", 0.0)):
        since = ap.mark()
        mpx.send(f"camera zoom {word}")
        ack, sent = ap.ack(since, mav.MAV_CMD_SET_CAMERA_ZOOM)
        check(sent is not None and (sent.param1, sent.param2) == (mav.ZOOM_TYPE_CONTINUOUS, rate)
              and ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED,
              f"camera zoom {word}: ZOOM_TYPE_CONTINUOUS {rate}, ACK {result_name(ack and ack.result)}")
        # Where a continuous zoom ends is not reported: the level is unknown (NaN) after.
        st = ap.after_ack(since, mav.MAV_CMD_SET_CAMERA_ZOOM, "CAMERA_SETTINGS")
        check(st is not None and math.isnan(st.zoomLevel), f"CAMERA_SETTINGS zoomLevel unknown: {st and st.zoomLevel}")
    since = ap.mark()
    mpx.send("camera zoom 0")
    st = ap.after_ack(since, mav.MAV_CMD_SET_CAMERA_ZOOM, "CAMERA_SETTINGS")
    check(st is not None and st.zoomLevel == 0.0, f"camera zoom 0: zoomLevel 0: {st and st.zoomLevel}")


def mode(mpx, ap):
    for word, want in (("video", mav.CAMERA_MODE_VIDEO), ("photo", mav.CAMERA_MODE_IMAGE)):
        since = ap.mark()
        mpx.send(f"camera mode {word}")
        ack, sent = ap.ack(since, mav.MAV_CMD_SET_CAMERA_MODE)
        check(sent is not None and sent.param2 == want and ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED,
              f"camera mode {word}: SET_CAMERA_MODE {want}, ACK {result_name(ack and ack.result)}")
        st = ap.after_ack(since, mav.MAV_CMD_SET_CAMERA_MODE, "CAMERA_SETTINGS")
        check(st is not None and st.mode_id == want, f"CAMERA_SETTINGS mode_id {want}: {st and st.mode_id}")
        m = mpx.poll("camera info", rf"mode={want} zoom=", REPLY_TIMEOUT)
        check(m is not None, f"camera info: mode={want}")


def focus(mpx, ap, bridge):
    # MAVProxy: out is +1, in is −1 (common.xml: positive towards infinity); the bridge
    # takes positive as the gimbal's focus +.
    for word, line in (("out", "focusing +"), ("stop", "focus held"), ("in", "focusing -"), ("auto", "auto-focus")):
        since, mark = ap.mark(), bridge.mark()
        mpx.send(f"camera focus {word}")
        ack, sent = ap.ack(since, mav.MAV_CMD_SET_CAMERA_FOCUS)
        check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED,
              f"camera focus {word}: {sent and (sent.param1, sent.param2)} ACK {result_name(ack and ack.result)}")
        said = bridge.wait_said(mark, ("focus", "auto-focus"))
        check(said == line, f"camera focus {word}: the gimbal says {line!r}: {said!r}")
    since, mark, msince = ap.mark(), bridge.mark(), mpx.mark()
    mpx.send("camera focus 50")
    ack, sent = ap.ack(since, mav.MAV_CMD_SET_CAMERA_FOCUS)
    check(ack is not None and ack.result == mav.MAV_RESULT_DENIED, f"camera focus 50 (range): ACK {result_name(ack and ack.result)}")
    m = mpx.wait(msince, r"Camera command MAV_CMD_SET_CAMERA_FOCUS rejected by 1:100 \(MAV_RESULT_DENIED\)")
    check(m is not None, "MAVProxy prints the focus range rejected (DENIED)")
    time.sleep(QUIET)
    check(not bridge.said_since(mark), f"camera focus 50: the gimbal told nothing: {bridge.said_since(mark)}")


def source(mpx, ap, family):
    thermal = family == "dual-light"
    since, msince = ap.mark(), mpx.mark()
    mpx.send("camera source thermal")
    ack, sent = ap.ack(since, mav.MAV_CMD_SET_CAMERA_SOURCE)
    want = mav.MAV_RESULT_ACCEPTED if thermal else mav.MAV_RESULT_DENIED
    check(sent is not None and (sent.param2, sent.param3) == (mav.CAMERA_SOURCE_IR, 0)
          and ack is not None and ack.result == want,
          f"camera source thermal: CAMERA_SOURCE_IR, ACK {result_name(want)}: {result_name(ack and ack.result)}")
    if not thermal:
        m = mpx.wait(msince, r"Camera command MAV_CMD_SET_CAMERA_SOURCE rejected by 1:100 \(MAV_RESULT_DENIED\)")
        check(m is not None, "MAVProxy prints the infrared source rejected on a camera without one")
    return since


def tracking(mpx, ap, bridge, family):
    # MAV_CMD_CAMERA_TRACK_POINT (2004) at the centre, radius 0.02 of the width: the
    # document's box (docs/mavlink.md, Tracking): centre × 8191 rounded, 0.5 × 8191 = 4095.5
    # → 4096; sides 2 × radius (at least 1/32) × 8192 = 327.68 units, sent /16 rounded:
    # 20 × 16 = 320.
    box = "tracking a 320x320 box at (4096, 4096)"
    since, mark, msince = ap.mark(), bridge.mark(), mpx.mark()
    mpx.send(f"message COMMAND_LONG {AP_SYSTEM} {CAMERA} {mav.MAV_CMD_CAMERA_TRACK_POINT} 0 0.5 0.5 0.02 0 0 0 0")
    ack, _ = ap.ack(since, mav.MAV_CMD_CAMERA_TRACK_POINT)
    check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, f"TRACK_POINT through `message`: ACK {result_name(ack and ack.result)}")
    m = mpx.wait(msince, r"Got COMMAND_ACK: CAMERA_TRACK_POINT: (\w+)")
    check(m is not None and m.group(1) == "ACCEPTED", f"MAVProxy prints the ACK: {m and m.group(0)!r}")
    said = bridge.wait_said(mark, "tracking")
    check(said == box, f"the gimbal tracks {box!r}: {said!r}")
    # The status at 200 ms (MAV_CMD_SET_MESSAGE_INTERVAL, 511, for message 275).
    since = ap.mark()
    mpx.send(f"message COMMAND_LONG {AP_SYSTEM} {CAMERA} {mav.MAV_CMD_SET_MESSAGE_INTERVAL} 0 "
             f"{mav.MAVLINK_MSG_ID_CAMERA_TRACKING_IMAGE_STATUS} 200000 0 0 0 0 0")
    ack, _ = ap.ack(since, mav.MAV_CMD_SET_MESSAGE_INTERVAL)
    check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, f"SET_MESSAGE_INTERVAL tracking status 200 ms: ACK {result_name(ack and ack.result)}")
    # The postback's tracking flag comes every 500 ms, the status every 200: ACTIVE in
    # 0.7 s, waited for as any reply (MAVProxy reads its input before its link).
    pattern = (r"CAMERA_TRACKING_IMAGE_STATUS \{tracking_status : (\d+), tracking_mode : (\d+), "
               r"target_data : (\d+), point_x : ([-\d.e]+|nan), point_y : ([-\d.e]+|nan), radius : ([-\d.e]+|nan)")
    end = time.monotonic() + REPLY_TIMEOUT
    while True:
        m = mpx.poll("status CAMERA_TRACKING_IMAGE_STATUS", pattern, 0.5)
        ok = m is not None and (int(m.group(1)), int(m.group(2))) == (
            mav.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE, mav.CAMERA_TRACKING_MODE_POINT)
        if ok or time.monotonic() >= end:
            break
    check(ok and float(m.group(4)) == 0.5 and float(m.group(5)) == 0.5 and abs(float(m.group(6)) - 0.02) < 1e-6,
          f"status CAMERA_TRACKING_IMAGE_STATUS: ACTIVE, point mode, at (0.5, 0.5), radius 0.02: {m and m.group(0)!r}")
    # The statuses that follow the interval's ACK: the first of the 200 ms series comes at
    # the bridge's next poll after it. One before the ACK is from the default series
    # (tracking started: a status at once), which may reach here after `since`.
    stamps = ap.stamps_after_ack(since, mav.MAV_CMD_SET_MESSAGE_INTERVAL, "CAMERA_TRACKING_IMAGE_STATUS", 6)
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    # 200 ms on the bridge's clock, received here. The next is due a period after the tick
    # that sent one, so a late tick lengthens the series and nothing shortens it: on average
    # 190 to 240 ms over five gaps (a 200 ms stall in a second), each within ±150 ms (a
    # late tick of the bridge or of this thread on a loaded machine). The default is 500.
    check(len(gaps) == 5 and 0.19 <= sum(gaps) / len(gaps) <= 0.24 and all(0.05 <= g <= 0.35 for g in gaps),
          f"the status every 200 ms: {[round(g, 3) for g in gaps]}")
    since, mark = ap.mark(), bridge.mark()
    mpx.send(f"message COMMAND_LONG {AP_SYSTEM} {CAMERA} {mav.MAV_CMD_CAMERA_STOP_TRACKING} 0 0 0 0 0 0 0 0")
    ack, _ = ap.ack(since, mav.MAV_CMD_CAMERA_STOP_TRACKING)
    check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED, f"STOP_TRACKING: ACK {result_name(ack and ack.result)}")
    said = bridge.wait_said(mark, "tracking stopped")
    check(said == "tracking stopped", f"the gimbal stops tracking: {said!r}")
    m = mpx.poll("status CAMERA_TRACKING_IMAGE_STATUS", r"CAMERA_TRACKING_IMAGE_STATUS \{tracking_status : 0,", 3.0)
    check(m is not None, "status CAMERA_TRACKING_IMAGE_STATUS: IDLE after the stop")
    mpx.send(f"message COMMAND_LONG {AP_SYSTEM} {CAMERA} {mav.MAV_CMD_SET_MESSAGE_INTERVAL} 0 "
             f"{mav.MAVLINK_MSG_ID_CAMERA_TRACKING_IMAGE_STATUS} -1 0 0 0 0 0")


def optical(angle, ratio):
    """The field of view at zoom `ratio` of a lens of `angle` degrees at 1×: the image's
    half-width scales as tan(angle / 2) / ratio (a thin lens, the focal length × ratio)."""
    return math.degrees(2 * math.atan(math.tan(math.radians(angle / 2)) / ratio))


def latest(ap, kind, component):
    got = ap.bridge((0, 0), kind, component)
    return got[-1][1] if got else None


def contains(polygon, lat, lon):
    """Whether (lat, lon) is inside the closed polygon of (lat, lon), by ray casting on a
    local flat projection (metres; the footprint spans tens of metres)."""
    k = math.cos(math.radians(lat))
    pts = [((p[1] - lon) * k, p[0] - lat) for p in polygon]
    inside = False
    for (x1, y1), (x2, y2) in zip(pts, pts[1:]):
        if (y1 > 0) != (y2 > 0) and 0 < x1 + (0 - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def metres(a, b):
    """Distance between two (lat, lon) a few metres apart (equirectangular)."""
    k = math.cos(math.radians(a[0]))
    return math.hypot((a[0] - b[0]) * 111319.49, (a[1] - b[1]) * 111319.49 * k)


def footprint(mpx, ap, family):
    """`camera mount angle`, then `camera projection`, and the footprint computed with
    MAVProxy's CameraProjection from what MAVProxy received, against CAMERA_FOV_STATUS."""
    from MAVProxy.modules.lib import camera_projection, mp_util
    from MAVProxy.modules.mavproxy_camera import _FlatElevationModel, _quaternion_to_euler

    pitch_cmd = -45.0
    since = ap.mark()
    mpx.send(f"camera mount angle {pitch_cmd:g} 0")
    sent = None
    end = time.monotonic() + REPLY_TIMEOUT
    while sent is None and time.monotonic() < end:
        got = [m for _, m in ap.mavproxy(since, "COMMAND_LONG") if m.command == mav.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW]
        sent = got[0] if got else None
        time.sleep(0.02)
    check(sent is not None and (sent.param1, sent.param2, sent.target_component) == (pitch_cmd, 0, AP_COMPONENT),
          f"camera mount angle -45 0: GIMBAL_MANAGER_PITCHYAW -45, 0 to the autopilot: "
          f"{sent and (sent.param1, sent.param2, sent.param7, sent.target_component)}")
    # The simulated gimbal turns at its own speed (tens of degrees a second); the aim holds
    # within the core's tolerance (0.2° dead-band): 0.5° within 10 s.
    status = ap.wait_bridge(since, "GIMBAL_DEVICE_ATTITUDE_STATUS",
                            lambda m: abs(math.degrees(_quaternion_to_euler(m.q)[1]) - pitch_cmd) < 0.5,
                            timeout=10.0, component=GIMBAL)
    check(status is not None, "the gimbal reaches pitch -45 (GIMBAL_DEVICE_ATTITUDE_STATUS)")
    time.sleep(0.5)  # steady

    for zoom_percent in (0, 50):
        since = ap.mark()
        mpx.send(f"camera zoom {zoom_percent}")
        st = ap.after_ack(since, mav.MAV_CMD_SET_CAMERA_ZOOM, "CAMERA_SETTINGS")
        check(st is not None and abs(st.zoomLevel - zoom_percent) < 1e-3,
              f"camera zoom {zoom_percent}: zoomLevel {st and st.zoomLevel}")
        # The zoom range of the simulated gimbal's type: 30× (docs/mavlink.md, zoom_max_of).
        ratio = 1 + zoom_percent / 100 * (30 - 1)
        want_h, want_v = optical(HFOV, ratio), optical(VFOV, ratio)
        since = ap.mark()
        mpx.send("camera for 1:100 discover")  # CAMERA_SETTINGS, the streams, ... again
        infos = {}
        end = time.monotonic() + REPLY_TIMEOUT
        while len(infos) < 3 and time.monotonic() < end:  # both families have three streams
            infos = {m.stream_id: m for _, m in ap.bridge(since, "VIDEO_STREAM_INFORMATION")}
            time.sleep(0.02)
        since = ap.mark()
        mpx.send(f"message COMMAND_LONG {AP_SYSTEM} {CAMERA} {mav.MAV_CMD_REQUEST_MESSAGE} 0 "
                 f"{mav.MAVLINK_MSG_ID_CAMERA_FOV_STATUS} 0 0 0 0 0 0")
        fov = ap.wait_bridge(since, "CAMERA_FOV_STATUS")
        thermal = {i for i, s in infos.items() if s.flags & mav.VIDEO_STREAM_STATUS_FLAGS_THERMAL}
        want = {str(i): (f"{WIDTH}x{HEIGHT}/{round(want_h):.1f}" if i not in thermal else None) for i in infos}

        def drawn(shown):
            return (all(want[k] is None or shown.get(k) == want[k] for k in want)
                    and all(float(shown.get(str(i), "0/nan").split("/")[1]) == 0.0 for i in thermal))
        # Asked until the streams' information has reached MAVProxy's camera module (it
        # reads its input before its link: a backlog shows the zoom before).
        end = time.monotonic() + REPLY_TIMEOUT
        while True:
            since_out = mpx.send("camera projection")
            m = mpx.wait(since_out, r"position: ([-\d.]+) ([-\d.]+) AMSL=([-\d.]+)m relative=([-\d.]+)m")
            text = mpx.since(since_out)
            streams = next((l for l in text if l.startswith(" streams: ") or l.startswith("streams: ")), "")
            shown = dict(re.findall(r"(\d+)=(\d+x\d+/[\d.]+)deg", streams))
            if drawn(shown) or time.monotonic() >= end:
                break
            time.sleep(0.1)
        check(infos and drawn(shown),
              f"zoom {zoom_percent} % (×{ratio:g}): camera projection shows the visible streams at "
              f"{WIDTH}x{HEIGHT}, hfov {round(want_h)}° (2 atan(tan({HFOV:g}°/2)/{ratio:g}) = {want_h:.2f}° rounded), "
              f"the thermal one 0: {streams.strip()!r}")
        att = next((re.search(r"attitude: roll=([-\d.]+) pitch=([-\d.]+) earth-yaw=([-\d.]+)", l) for l in text
                    if "attitude: roll=" in l), None)
        # What MAVProxy's _fov_attitude computes: the device's quaternion (vehicle frame)
        # with the vehicle's ATTITUDE yaw added. The last ones it received:
        gimbal = latest(ap, "GIMBAL_DEVICE_ATTITUDE_STATUS", GIMBAL)
        if not check(gimbal is not None, "GIMBAL_DEVICE_ATTITUDE_STATUS from the gimbal"):
            return
        roll, pitch, yaw = (math.degrees(a) for a in _quaternion_to_euler(gimbal.q))
        yaw = mp_util.wrap_180(yaw + VEHICLE_YAW)
        # Printed with one decimal: ±0.05, and the gimbal's few hundredths of a degree of
        # motion between the print and the last status.
        check(att is not None and all(abs(float(a) - b) <= 0.15 for a, b in zip(att.groups(), (roll, pitch, yaw))),
              f"camera projection: the camera's attitude (roll, pitch, earth yaw) "
              f"({roll:.2f}, {pitch:.2f}, {yaw:.2f}): {att and att.group(0)!r}")
        check(m is not None and all(abs(float(a) - b) < 1e-9 for a, b in zip(
                  m.groups(), (LAT * 1e-7, LON * 1e-7, ALT_MM / 1000, REL_ALT_MM / 1000))),
              f"camera projection: the vehicle's position: {m and m.group(0)!r}")
        if fov is None:
            check(False, "CAMERA_FOV_STATUS answered to MAV_CMD_REQUEST_MESSAGE")
            continue
        # Its fields: the vehicle's position, angles at the zoom (float32), the image centre
        # on flat ground at the home altitude.
        check((fov.lat_camera, fov.lon_camera, fov.alt_camera) == (LAT, LON, ALT_MM)
              and abs(fov.hfov - want_h) < 1e-3 and abs(fov.vfov - want_v) < 1e-3
              and fov.alt_image == ALT_MM - REL_ALT_MM,
              f"CAMERA_FOV_STATUS: camera at the vehicle, hfov {want_h:.3f}, vfov {want_v:.3f}, ground at "
              f"{(ALT_MM - REL_ALT_MM) / 1000:g} m: {(fov.lat_camera, fov.lon_camera, fov.alt_camera)}, "
              f"{fov.hfov:.3f}, {fov.vfov:.3f}, {fov.alt_image}")
        fr, fp, fy = (math.degrees(a) for a in _quaternion_to_euler(fov.q))
        check(abs(fp - pitch) < 0.1 and abs(mp_util.wrap_180(fy - yaw)) < 0.1,
              f"CAMERA_FOV_STATUS q: pitch {fp:.2f}, earth yaw {fy:.2f} (the gimbal's {pitch:.2f}, {yaw:.2f})")
        point = (fov.lat_image * 1e-7, fov.lon_image * 1e-7)
        # MAVProxy's own footprint, as _show_camera_fov computes it (headless, it is never
        # drawn): CameraParams from the stream's resolution and hfov, the flat model at
        # alt − relative_alt, the attitude above, the camera at the vehicle's AMSL altitude.
        visible = min(i for i in infos if i not in thermal)
        hfov_rx = float(infos[visible].hfov)
        params = camera_projection.CameraParams(xresolution=WIDTH, yresolution=HEIGHT, FOV=hfov_rx)
        projection = camera_projection.CameraProjection(
            params, elevation_model=_FlatElevationModel((ALT_MM - REL_ALT_MM) / 1000))
        polygon = projection.get_projection(LAT * 1e-7, LON * 1e-7, ALT_MM / 1000, roll, pitch, yaw, max_range=10000)
        centre = projection.get_latlonalt_for_pixel(WIDTH / 2, HEIGHT / 2, LAT * 1e-7, LON * 1e-7, ALT_MM / 1000,
                                                    roll, pitch, yaw)
        sane = (polygon is not None and len(polygon) >= 5 and polygon[0] == polygon[-1]
                and all(metres(p, (LAT * 1e-7, LON * 1e-7)) < 500 for p in polygon))
        check(sane, f"MAVProxy's CameraProjection gives a closed footprint within 500 m of the vehicle: "
              f"{polygon and len(polygon)} points")
        check(sane and contains(polygon, *point),
              f"the footprint contains CAMERA_FOV_STATUS's ground point {point[0]:.7f}, {point[1]:.7f}")
        # The centre pixel by MAVProxy's projection against the bridge's: the same geometry
        # (flat ground 38 m below, the same attitude), so metres apart at most from the
        # attitude's motion between the two messages (0.05° at 54 m slant range: 0.1 m)
        # and the bridge's float32 arithmetic on WGS84 (a float32 degree near 47° is 4e-6°,
        # 0.4 m); 1 m.
        d = metres(point, centre[:2]) if centre else None
        check(d is not None and d < 1.0, f"the image centre by MAVProxy's projection is CAMERA_FOV_STATUS's: "
              f"{d and round(d, 2)} m apart")
    mpx.send("camera zoom 0")


def unknown_fov(mpx, ap):
    """Without --camera-fov and --camera-resolution: every stream 0x0 and 0°, which MAVProxy
    skips (`_show_camera_fov`: width, height > 0 and 0 < hfov < 180)."""
    since = ap.mark()
    mpx.send("camera for 1:100 discover")
    ap.wait_bridge(since, "VIDEO_STREAM_INFORMATION")
    time.sleep(0.5)
    since_out = mpx.send("camera projection")
    m = mpx.wait(since_out, r"streams: (.*)")
    shown = re.findall(r"(\d+)=(\d+x\d+/[\d.]+)deg", m.group(1)) if m else []
    check(len(shown) == 3 and all(s == "0x0/0.0" for _, s in shown),
          f"no field of view configured: camera projection shows every stream 0x0, 0°: {m and m.group(0)!r}")


def run_family(gimbalctl, family, fov):
    print(f"--- MAVProxy against --camera {family}" + (" with a field of view" if fov else ""), flush=True)
    started = time.monotonic()
    ap = Autopilot()
    ap.start()
    extra = ["--camera-fov", f"{HFOV:g},{VFOV:g}", "--camera-resolution", f"{WIDTH}x{HEIGHT}"] if fov else []
    try:
        bridge = Bridge(gimbalctl, family, ap.cam_port, extra)
    except RuntimeError as e:
        check(False, f"--camera {family} {' '.join(extra)}: {e}")
        ap.stopping.set()
        return
    mpx = MAVProxy(ap.gcs_port)
    try:
        since = (0, 0)
        model = discovery(mpx, ap, family)
        if model is None:
            return  # no camera: every case after would only time out
        params = definition(mpx, ap, family, model, since)
        settings(mpx, ap, bridge, family, params)
        capture(mpx, ap)
        record(mpx, ap)
        zoom(mpx, ap)
        mode(mpx, ap)
        focus(mpx, ap, bridge)
        source(mpx, ap, family)
        tracking(mpx, ap, bridge, family)
        if family == "dual-light":
            since = ap.mark()
            mpx.send("camera source rgb")
            ack, sent = ap.ack(since, mav.MAV_CMD_SET_CAMERA_SOURCE)
            check(sent is not None and sent.param2 == mav.CAMERA_SOURCE_RGB and ack is not None
                  and ack.result == mav.MAV_RESULT_ACCEPTED,
                  f"camera source rgb: CAMERA_SOURCE_RGB, ACK {result_name(ack and ack.result)}")
        if fov:
            footprint(mpx, ap, family)
        else:
            unknown_fov(mpx, ap)
        check(not ap.bad, f"no bad frames on either side: {ap.bad[:3]}")
    finally:
        mpx.stop()
        ap.stopping.set()
        bridge.stop()
    print(f"--- {family}: {time.monotonic() - started:.1f} s", flush=True)


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    gimbalctl = sys.argv[1]
    # The dual light with its field of view given (the footprint), the X3 without (unknown).
    run_family(gimbalctl, "dual-light", fov=True)
    run_family(gimbalctl, "x3", fov=False)
    return CHECKS.summary("mavproxy_camera")


if __name__ == "__main__":
    sys.exit(main())
