#!/usr/bin/env python3
"""End-to-end test of `gimbalctl mavlink --sim` with pymavlink playing the autopilot and a
ground station: two sessions, each against a fresh bridge, with the reader beside each:

- PX4 on a port in mode Normal (PX4 src/modules/mavlink/mavlink_main.cpp, configure_streams):
  no AUTOPILOT_STATE_FOR_GIMBAL_DEVICE until the gimbal asks for it (it is streamed only in
  mode Gimbal), setpoints at 5 Hz until asked for more, GIMBAL_DEVICE_INFORMATION asked of
  the broadcast component every second until answered (src/modules/gimbal/output_mavlink.cpp),
  setpoint flags YAW_LOCK | YAW_IN_EARTH_FRAME or YAW_IN_VEHICLE_FRAME;
- ArduPilot (libraries/AP_Mount/AP_Mount_Gremsy.cpp, the MAVLink gimbal v2 backend):
  AUTOPILOT_STATE_FOR_GIMBAL_DEVICE at 50 Hz from the start, GIMBAL_DEVICE_INFORMATION asked of
  component 154 every second and no setpoint before it, setpoints at 50 Hz with flags 0 (body
  frame) or ROLL|PITCH|YAW_LOCK (earth frame), retract as a NaN quaternion with zero rates;
  it reads the status the way AP_Mount does (3-2-1 Euler yaw taken as body frame, earth yaw
  = that + the vehicle's) and needs it fresher than 1 s; take_picture with count 1 and
  sequence numbers from 1 (libraries/AP_Camera/AP_Camera_MAVLinkCamV2.cpp);
- a QGroundControl-like reader beside each (src/Gimbal/GimbalController.cc): earth yaw from
  the status's frame flags and the vehicle heading (delta_yaw), checked against the heading
  the simulated gimbal was steered to;
- then ArduPilot on a TELEM port: the autopilot on a pseudo-terminal (`--autopilot-serial`),
  the gimbal on its UART (`sim --pty`, `--serial`), as on a companion computer.

It also checks the rate hold and its dead-man, image capture at an interval, and that every
command gets the right ACK.

Usage: mavlink_e2e.py PATH/TO/gimbalctl
Ends with a line "N passed, M failed"; exit status 0 only if nothing failed.
"""

import collections
import math
import os
import subprocess
import sys
import termios
import time
import tty

os.environ["MAVLINK20"] = "1"  # before pymavlink is imported: MAVLink 2 framing
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mav  # noqa: E402

from checks import Checks, sim_options  # noqa: E402

AP_SYSTEM, AP_COMPONENT = 1, 1
GCS_SYSTEM, GCS_COMPONENT = 255, 190
GIMBAL, CAMERA = 154, 100
VEHICLE_YAW = 30.0  # degrees, what the "autopilot" says its heading is
ID_AUTOPILOT_STATE = 286
ID_SETPOINT = 284
# The simulated gimbal slews at 60 deg/s and reports every 500 ms: 10 s is ample for any
# move here; the status is expected every 100 ms.
STEP_TIMEOUT = 10.0
STATUS_MAX_GAP = 1.0  # ArduPilot's health threshold
ANGLE_TOL = 2.0  # the tolerance asked of the bridge; the wire's resolution is 0.1 degree


def axis_quaternion(yaw_deg, pitch_deg):
    """q_yaw * q_pitch, written out independently of the bridge (w, x, y, z)."""
    cy, sy = math.cos(math.radians(yaw_deg) / 2), math.sin(math.radians(yaw_deg) / 2)
    cp, sp = math.cos(math.radians(pitch_deg) / 2), math.sin(math.radians(pitch_deg) / 2)
    # Hamilton product of (cy, 0, 0, sy) and (cp, 0, sp, 0).
    return [cy * cp, -sy * sp, cy * sp, sy * cp]


def yaw_pitch(q):
    """The forward axis of q: yaw and pitch, as a camera points (valid for |pitch| < 90)."""
    w, x, y, z = q
    fx = 1 - 2 * (y * y + z * z)
    fy = 2 * (x * y + w * z)
    fz = 2 * (x * z - w * y)
    return math.degrees(math.atan2(fy, fx)), math.degrees(math.asin(max(-1, min(1, -fz))))


def pitch_past_vertical(q):
    """Pitch read from the camera's up axis too, so -100 reads as -100, not -80."""
    w, x, y, z = q
    fz = 2 * (x * z - w * y)  # forward axis, down component
    uz = 1 - 2 * (x * x + y * y)  # body z (down) axis, down component: negative when upside down
    return math.degrees(math.atan2(-fz, uz))


def angle_diff(a, b):
    return (a - b + 180) % 360 - 180



def euler_yaw(q):
    """ArduPilot's reading of a quaternion's yaw (Quaternion::to_euler, 3-2-1), degrees."""
    w, x, y, z = q
    return math.degrees(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


class Gcs:
    """A ground station beside the autopilot, reading the status as QGroundControl does
    (GimbalController.cc): the yaw is in the vehicle frame when YAW_IN_VEHICLE_FRAME is set
    (or neither frame flag nor YAW_LOCK), and the earth yaw is then that plus the vehicle
    heading; here the heading is the status's own delta_yaw."""

    def __init__(self, port):
        self.m = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{port}", source_system=GCS_SYSTEM,
            source_component=GCS_COMPONENT, dialect="common")
        self.next_hb = 0.0
        self.status = None

    def tick(self, t):
        if t >= self.next_hb:
            self.next_hb = t + 1.0
            self.m.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, mav.MAV_STATE_ACTIVE)
        while True:
            msg = self.m.recv_match(blocking=False)
            if msg is None:
                break
            if msg.get_type() == "GIMBAL_DEVICE_ATTITUDE_STATUS":
                self.status = msg

    def earth_yaw(self):
        s = self.status
        if s is None or math.isnan(s.q[0]):
            return None
        f = s.flags
        in_vehicle = bool(f & mav.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME) or (
            not f & mav.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME and not f & mav.GIMBAL_DEVICE_FLAGS_YAW_LOCK)
        yaw = euler_yaw(s.q)
        if not in_vehicle:
            return yaw
        if math.isnan(s.delta_yaw):
            return None
        return angle_diff(yaw + math.degrees(s.delta_yaw), 0)


class PtyLink:
    """pymavlink over the master side of a pseudo-terminal: the autopilot's TELEM port, whose
    other side (a path) the bridge opens with --autopilot-serial. Offers what Autopilot uses
    of a mavutil connection: `.mav` to send and `recv_match(blocking=False)`."""

    def __init__(self):
        self.fd, slave = os.openpty()
        tty.setraw(slave)
        self.path = os.ttyname(slave)
        # The bridge opens the path itself; keeping the slave open here would hold back a
        # hang-up, and close the port under it at exit.
        os.close(slave)
        os.set_blocking(self.fd, False)
        self.mav = mav.MAVLink(self, srcSystem=AP_SYSTEM, srcComponent=AP_COMPONENT)
        self.pending = collections.deque()

    def write(self, buf):
        os.write(self.fd, buf)

    def recv_match(self, blocking=False):
        if not self.pending:
            try:
                data = os.read(self.fd, 4096)
            except (BlockingIOError, OSError):
                data = b""
            if data:
                self.pending.extend(self.mav.parse_buffer(data) or [])
        return self.pending.popleft() if self.pending else None


class Autopilot:
    """An autopilot as `persona` ("px4-normal" or "ardupilot") behaves towards the gimbal:
    on UDP `port`, with a ground station beside it, or on `link` (a PtyLink) alone."""

    def __init__(self, port, persona, results, link=None):
        self.port = port
        self.persona = persona
        self.r = results
        if link is None:
            self.m = mavutil.mavlink_connection(
                f"udpout:127.0.0.1:{port}",
                source_system=AP_SYSTEM,
                source_component=AP_COMPONENT,
                dialect="common",
            )
            self.gcs = Gcs(port)
        else:
            self.m = link
            self.gcs = None
        self.start = time.monotonic()
        self.next_hb = 0.0
        # ArduPilot streams the autopilot state at 50 Hz to a MAVLink gimbal by itself
        # (AP_Mount_Gremsy.cpp, set_message_interval 20000 us); PX4 in mode Normal only
        # once asked.
        self.state_interval = 0.02 if persona == "ardupilot" else None
        self.next_state = 0.0
        self.state_asked = False
        # Setpoints: ArduPilot 50 Hz; PX4 mode Normal 5 Hz until asked.
        self.setpoint_interval = 0.02 if persona == "ardupilot" else 0.2
        self.setpoint_asked = False
        self.setpoint_times = []
        self.next_pos = None  # set once the gimbal asks for GLOBAL_POSITION_INT
        self.pos_interval = None
        self.setpoint = None  # a function returning (flags, q, rates) or None
        self.next_setpoint = 0.0
        self.last_status = None
        self.status = None
        self.status_gaps = []
        self.messages = []  # (time, msg) of everything received since the last clear

    def check(self, ok, what):
        return self.r.check(ok, f"[{self.persona}] {what}")

    def now(self):
        return time.monotonic() - self.start

    def boot_ms(self):
        return int(self.now() * 1000)

    def tick(self):
        t = self.now()
        if self.gcs is not None:
            self.gcs.tick(t)
        if t >= self.next_hb:
            self.next_hb = t + 1.0
            autopilot = mav.MAV_AUTOPILOT_ARDUPILOTMEGA if self.persona == "ardupilot" else mav.MAV_AUTOPILOT_PX4
            self.m.mav.heartbeat_send(mav.MAV_TYPE_QUADROTOR, autopilot, 0, 0, mav.MAV_STATE_ACTIVE)
        if self.state_interval is not None and t >= self.next_state:
            self.next_state = t + self.state_interval
            half = math.radians(VEHICLE_YAW) / 2
            # Both autopilots address it to the whole system (target component 0).
            self.m.mav.autopilot_state_for_gimbal_device_send(
                AP_SYSTEM, 0, self.boot_ms() * 1000,
                [math.cos(half), 0, 0, math.sin(half)], 0, 0, 0, 0, 0, 0, 0, 4, 0,
            )
        if self.next_pos is not None and t >= self.next_pos:
            self.next_pos = t + self.pos_interval
            self.m.mav.global_position_int_send(
                self.boot_ms(), 473977420, 85455940, 488000, 38000, 0, 0, 0, int(VEHICLE_YAW * 100)
            )
        if self.setpoint is not None and t >= self.next_setpoint:
            self.next_setpoint = t + self.setpoint_interval
            flags, q, rates = self.setpoint()
            self.setpoint_times.append(t)
            self.m.mav.gimbal_device_set_attitude_send(AP_SYSTEM, GIMBAL, flags, q, *rates)
        while True:
            msg = self.m.recv_match(blocking=False)
            if msg is None:
                break
            if msg.get_type() == "BAD_DATA":
                self.check(False, f"bad data from the bridge: {msg}")
                continue
            self.messages.append((t, msg))
            kind = msg.get_type()
            if kind == "GIMBAL_DEVICE_ATTITUDE_STATUS":
                # On the bridge's clock (time_boot_ms, when it sent each): what an autopilot
                # beside it on the loopback sees, without this script's own stalls.
                if self.last_status is not None:
                    self.status_gaps.append(((msg.time_boot_ms - self.last_status) % 2**32) / 1000)
                self.last_status = msg.time_boot_ms
                self.status = msg
            elif kind == "COMMAND_LONG" and msg.command == mav.MAV_CMD_SET_MESSAGE_INTERVAL:
                self.interval_asked(t, msg)
        time.sleep(0.002)

    def interval_asked(self, t, msg):
        """The gimbal asks for a stream; each autopilot answers as it would."""
        what, interval = int(msg.param1), msg.param2 / 1e6
        if what == mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT and interval > 0:
            self.m.mav.command_ack_send(msg.command, mav.MAV_RESULT_ACCEPTED)
            self.pos_interval = interval
            self.next_pos = t
        elif what == ID_AUTOPILOT_STATE and interval > 0:
            self.m.mav.command_ack_send(msg.command, mav.MAV_RESULT_ACCEPTED)
            self.state_asked = True
            self.state_interval = interval
        elif what == ID_SETPOINT and interval > 0 and self.persona == "px4-normal":
            # PX4's GIMBAL_DEVICE_SET_ATTITUDE stream re-sends the latest setpoint at the
            # rate asked for.
            self.m.mav.command_ack_send(msg.command, mav.MAV_RESULT_ACCEPTED)
            self.setpoint_asked = True
            self.setpoint_interval = interval
        elif what == ID_SETPOINT:
            # ArduPilot has no stream of its setpoints to re-time: it denies the ask (and
            # its SITL tells the ground station, GCS_Common.cpp set_message_interval).
            self.setpoint_asked = True
            self.m.mav.command_ack_send(msg.command, mav.MAV_RESULT_DENIED)
        else:
            self.m.mav.command_ack_send(msg.command, mav.MAV_RESULT_FAILED)

    def wait(self, what, cond, timeout=STEP_TIMEOUT):
        deadline = self.now() + timeout
        while self.now() < deadline:
            self.tick()
            found = cond()
            if found:
                return found
        return None

    def find(self, kind, pred=lambda m: True, since=0.0):
        for t, m in self.messages:
            if t >= since and m.get_type() == kind and pred(m):
                return m
        return None

    def find_all(self, kind, since=0.0):
        return [m for t, m in self.messages if t >= since and m.get_type() == kind]

    def command(self, target_component, command, *params, expect=None, reply=None, retry_s=1.0):
        """COMMAND_LONG every `retry_s` until its ACK arrives; returns (ack, reply message)."""
        params = list(params) + [0.0] * (7 - len(params))
        sent_at = self.now()
        retry = 0.0
        ack = None
        while self.now() - sent_at < STEP_TIMEOUT:
            if self.now() >= retry:
                retry = self.now() + retry_s
                self.m.mav.command_long_send(AP_SYSTEM, target_component, command, 0, *params)
            self.tick()
            ack = self.find("COMMAND_ACK", lambda m: m.command == command, since=sent_at)
            got = self.find(reply, since=sent_at) if reply else True
            if ack is not None and got:
                break
        got = self.find(reply, since=sent_at) if reply else None
        name = mav.enums["MAV_CMD"][command].name
        if expect is not None:
            result = None if ack is None else mav.enums["MAV_RESULT"][ack.result].name
            self.check(ack is not None and ack.result == expect,
                       f"{name} to {target_component}: ACK {result}")
        if reply is not None:
            self.check(got is not None, f"{name} to {target_component}: {reply} received")
        return ack, got

    def ask_information(self, target):
        _, info = self.command(target, mav.MAV_CMD_REQUEST_MESSAGE,
                               mav.MAVLINK_MSG_ID_GIMBAL_DEVICE_INFORMATION,
                               expect=mav.MAV_RESULT_ACCEPTED, reply="GIMBAL_DEVICE_INFORMATION")
        return info

    def settle(self, what, flags, yaw, pitch, want_earth_yaw):
        """Steers with angle setpoints until the status (read as this autopilot and as the
        ground station read it) shows the gimbal there."""
        q = axis_quaternion(yaw, pitch)
        self.setpoint = lambda: (flags, q, [math.nan] * 3)

        def reached():
            a = status_angles(self)
            if a is None or abs(a[1] - pitch) > ANGLE_TOL:
                return None
            # ArduPilot's reading: body-frame yaw + the vehicle's yaw.
            ap_earth = angle_diff(euler_yaw(self.status.q) + VEHICLE_YAW, 0) if abs(pitch) < 90 else a[0] + VEHICLE_YAW
            # The ground station's reading; on a serial port, the status's own yaw + delta_yaw.
            qgc_earth = self.gcs.earth_yaw() if self.gcs is not None else (
                angle_diff(euler_yaw(self.status.q) + math.degrees(self.status.delta_yaw), 0)
                if not math.isnan(self.status.delta_yaw) else None)
            if qgc_earth is None or abs(angle_diff(qgc_earth, want_earth_yaw)) > ANGLE_TOL:
                return None
            if abs(angle_diff(ap_earth, want_earth_yaw)) > ANGLE_TOL:
                return None
            return (a, ap_earth, qgc_earth)
        got = self.wait(what, reached)
        s = self.status
        self.check(bool(got), f"{what}: earth yaw {want_earth_yaw} as AP_Mount and QGC read it: {got or status_angles(self)}")
        self.check(s is not None and s.flags & mav.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME
                   and not s.flags & mav.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME
                   and abs(math.degrees(s.delta_yaw) - VEHICLE_YAW) < 0.01,
                   f"{what}: vehicle frame, delta_yaw the vehicle heading "
                   f"({math.degrees(s.delta_yaw) if s else None})")

    def status_fresh(self, min_gaps=50):
        """The status kept coming (at 10 Hz: `min_gaps` gaps take 5 s at least) and none of
        its gaps reached ArduPilot's 1 s health limit. The status is watched on until the
        window holds more than `min_gaps` gaps (for at most three times as long as that takes
        at 10 Hz): a session's steps end sooner or later with the machine's load, and the
        count must not depend on that."""
        end = time.monotonic() + 3 * (min_gaps + 1) / 10
        while len(self.status_gaps) <= min_gaps and time.monotonic() < end:
            self.tick()
            time.sleep(0.005)
        gaps = self.status_gaps
        worst = max(gaps) if gaps else math.inf
        self.check(len(gaps) > min_gaps and worst < STATUS_MAX_GAP,
                   f"attitude status fresh throughout: {len(gaps)} gaps, worst {worst * 1000:.0f} ms")


def status_angles(ap):
    s = ap.status
    if s is None or math.isnan(s.q[0]):
        return None
    yaw, _ = yaw_pitch(s.q)
    pitch = pitch_past_vertical(s.q)
    if pitch < -90 or pitch > 90:
        # Past vertical the forward axis's yaw is turned by 180: the gimbal's yaw is the
        # other way round.
        yaw = (yaw + 180) % 360
    return yaw, pitch


def px4_normal(ap):
    # PX4 asks the broadcast component for the information every second until answered.
    info = ap.ask_information(0)
    if info is not None:
        ap.check(abs(math.degrees(info.pitch_min) + 100) < 0.01
                 and abs(math.degrees(info.pitch_max) - 60) < 0.01,
                 f"pitch limits {math.degrees(info.pitch_min):.1f}..{math.degrees(info.pitch_max):.1f}")
        ap.check(info.cap_flags & mav.GIMBAL_DEVICE_CAP_FLAGS_HAS_YAW_AXIS
                 and not info.cap_flags & mav.GIMBAL_DEVICE_CAP_FLAGS_HAS_ROLL_AXIS,
                 "yaw and pitch axes, no roll")
    hb = ap.wait("heartbeats", lambda: ap.find("HEARTBEAT", lambda m: m.type == mav.MAV_TYPE_GIMBAL)
                 and ap.find("HEARTBEAT", lambda m: m.type == mav.MAV_TYPE_CAMERA))
    ap.check(hb is not None, "heartbeats from the gimbal (154) and the camera (100)")
    # Mode Normal streams no autopilot state: the gimbal asks for it, and for the position.
    ap.check(ap.wait("state asked", lambda: ap.state_asked) is not None,
             "the gimbal asked for AUTOPILOT_STATE_FOR_GIMBAL_DEVICE")
    ap.check(ap.wait("position asked", lambda: ap.next_pos is not None) is not None,
             "the gimbal asked for GLOBAL_POSITION_INT")
    # New PX4: YAW_LOCK | YAW_IN_EARTH_FRAME for ROI and yaw lock; refused without the
    # vehicle's heading, followed with it.
    earth = mav.GIMBAL_DEVICE_FLAGS_YAW_LOCK | mav.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME
    ap.settle("setpoint yaw 90 (earth) pitch -30", earth, 90, -30, 90)
    ap.check(ap.setpoint_asked and ap.setpoint_interval <= 0.05,
             f"the gimbal asked for setpoints at 20 Hz (now every {ap.setpoint_interval * 1000:.0f} ms)")
    # What this script then sends: its own loop, so only a floor (a loaded machine may
    # slow it); that PX4 was asked for 20 Hz is checked above.
    recent = [t for t in ap.setpoint_times if t > ap.now() - 1.0]
    ap.check(len(recent) >= 10, f"setpoints now at {len(recent)} a second")
    ap.settle("setpoint yaw 20 (vehicle) pitch -60", mav.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME, 20, -60, 50)

    # Rate: 20 deg/s of yaw for 1 s, then the stream stops: the core's dead-man (250 ms)
    # stops the gimbal.
    ap.setpoint = lambda: (mav.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME, [math.nan] * 4,
                           [0.0, 0.0, math.radians(20)])
    before = status_angles(ap)
    ap.wait("rate hold", lambda: False, timeout=1.5)
    during = status_angles(ap)
    ap.setpoint = None
    # 250 ms of dead-man, a postback (every 500 ms) and a status (every 100): 850 ms, and
    # room for a late tick on a loaded machine.
    ap.wait("dead-man", lambda: False, timeout=2.0)
    stopped = status_angles(ap)
    ap.wait("still", lambda: False, timeout=1.2)
    still = status_angles(ap)
    turned = angle_diff(during[0], before[0]) if before and during else 0
    ap.check(turned > 10, f"rate setpoints turned the gimbal ({turned:.1f} deg)")
    ap.check(stopped is not None and still is not None and abs(angle_diff(still[0], stopped[0])) < 0.5,
             f"stopped after the stream stopped ({stopped} then {still})")
    ap.status_fresh()

    # The camera.
    for target, cmd, p1 in ((0, mav.MAV_CMD_REQUEST_MESSAGE, mav.MAVLINK_MSG_ID_CAMERA_INFORMATION),
                            (CAMERA, mav.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1)):
        _, info = ap.command(target, cmd, p1, expect=mav.MAV_RESULT_ACCEPTED, reply="CAMERA_INFORMATION")
    if info is not None:
        ap.check(info.gimbal_device_id == GIMBAL
                 and info.flags & mav.CAMERA_CAP_FLAGS_CAPTURE_IMAGE
                 and info.flags & mav.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM,
                 "camera information: images, video stream, gimbal 154")
    _, status = ap.command(CAMERA, mav.MAV_CMD_VIDEO_START_CAPTURE, 0, 0,
                           expect=mav.MAV_RESULT_ACCEPTED, reply="CAMERA_CAPTURE_STATUS")
    ap.check(status is not None and status.video_status == 1, "recording")
    ap.command(CAMERA, mav.MAV_CMD_VIDEO_STOP_CAPTURE, 0, expect=mav.MAV_RESULT_ACCEPTED)
    _, settings = ap.command(CAMERA, mav.MAV_CMD_SET_CAMERA_ZOOM, mav.ZOOM_TYPE_RANGE, 50,
                             expect=mav.MAV_RESULT_ACCEPTED, reply="CAMERA_SETTINGS")
    ap.check(settings is not None and abs(settings.zoomLevel - 50) < 0.01, "zoom level 50 %")
    # Continuous zoom is a rate: half speed in is accepted.
    ap.command(CAMERA, mav.MAV_CMD_SET_CAMERA_ZOOM, mav.ZOOM_TYPE_CONTINUOUS, 0.5,
               expect=mav.MAV_RESULT_ACCEPTED)
    _, stream = ap.command(CAMERA, mav.MAV_CMD_REQUEST_VIDEO_STREAM_INFORMATION, 1,
                           expect=mav.MAV_RESULT_ACCEPTED, reply="VIDEO_STREAM_INFORMATION")
    ap.check(stream is not None and stream.uri.startswith("rtsp://") and stream.type == mav.VIDEO_STREAM_TYPE_RTSP,
             f"stream URI {stream.uri if stream else None}")
    # Images at an interval: 3 images 0.5 s apart, each reported when taken.
    since = ap.now()
    # Sent once: a second start (a resend after a late ACK) would begin a new series.
    ap.command(CAMERA, mav.MAV_CMD_IMAGE_START_CAPTURE, 0, 0.5, 3, 0, expect=mav.MAV_RESULT_ACCEPTED,
               retry_s=STEP_TIMEOUT)
    ap.wait("three images", lambda: len(ap.find_all("CAMERA_IMAGE_CAPTURED", since)) >= 3, timeout=3.0)
    ap.wait("no fourth", lambda: False, timeout=1.0)
    # Spaced by the bridge's own clock (time_boot_ms, when each was taken), not by when
    # this script happened to read them. Each is due on the series' grid, taken at the
    # first tick after: the three span 1 s within 0.1, and a tick late by up to 0.3 s
    # on a loaded machine moves one image, never the rest.
    images = [(m.time_boot_ms / 1000, m.image_index) for t, m in ap.messages
              if t >= since and m.get_type() == "CAMERA_IMAGE_CAPTURED"]
    spacing = [b[0] - a[0] for a, b in zip(images, images[1:])]
    ap.check([i for _, i in images] == [0, 1, 2] and all(0.2 < d < 0.8 for d in spacing)
             and abs(sum(spacing) - 1.0) <= 0.1,
             f"three images 0.5 s apart, consecutive indexes: {[(round(t - images[0][0], 3), i) for t, i in images]}")

    # Bad commands get the right ACK, never silence.
    ap.command(GIMBAL, mav.MAV_CMD_DO_SET_MODE, 1, expect=mav.MAV_RESULT_UNSUPPORTED)
    ap.command(CAMERA, mav.MAV_CMD_SET_CAMERA_ZOOM, mav.ZOOM_TYPE_RANGE, 150, expect=mav.MAV_RESULT_DENIED)
    ap.command(CAMERA, mav.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 0, expect=mav.MAV_RESULT_DENIED)


def ardupilot(ap):
    # No setpoint before the information, asked of component 154 every second.
    ap.ask_information(GIMBAL)
    ap.check(ap.wait("state", lambda: ap.status is not None) is not None, "status streamed unasked")
    # Flags 0: body frame. 20 right of a nose at 30 = 50 from north.
    ap.settle("setpoint yaw 20 (flags 0) pitch -45", 0, 20, -45, 50)
    locks = mav.GIMBAL_DEVICE_FLAGS_ROLL_LOCK | mav.GIMBAL_DEVICE_FLAGS_PITCH_LOCK | mav.GIMBAL_DEVICE_FLAGS_YAW_LOCK
    ap.settle("setpoint yaw 120 (ROLL|PITCH|YAW_LOCK: earth) pitch -10", locks, 120, -10, 120)
    ap.settle("setpoint yaw -60 (earth, across north) pitch 20", locks, -60, 20, -60)
    ap.check(ap.next_pos is not None, "the gimbal asked ArduPilot for GLOBAL_POSITION_INT")
    ap.check(not ap.setpoint_asked, "setpoints not asked of ArduPilot (it sends them unasked, and denies)")
    # Retract: a NaN quaternion, zero rates, RETRACT: the gimbal looks down, and says so.
    ap.setpoint = lambda: (mav.GIMBAL_DEVICE_FLAGS_RETRACT, [math.nan] * 4, [0.0, 0.0, 0.0])
    down = ap.wait("retracted", lambda: (a := status_angles(ap)) is not None and abs(a[1] + 90) < ANGLE_TOL
                   and ap.status.flags & mav.GIMBAL_DEVICE_FLAGS_RETRACT)
    ap.check(bool(down), f"retract: looking down, RETRACT in the status ({status_angles(ap)})")
    ap.setpoint = None
    ap.status_fresh()
    # take_picture: count 1, sequence image_index + 1; a re-sent command takes no second.
    since = ap.now()
    for seq in (1, 1, 2):
        ap.command(CAMERA, mav.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, seq, expect=mav.MAV_RESULT_ACCEPTED)
    ap.wait("settle", lambda: False, timeout=0.5)
    indexes = [m.image_index for m in ap.find_all("CAMERA_IMAGE_CAPTURED", since)]
    ap.check(indexes == [0, 1], f"sequence 1, 1 again, 2: images {indexes}")
    # Another system's component 1 beating (a second autopilot, a multi-vehicle network or
    # a forged heartbeat): the gimbal keeps the autopilot it follows, which it hears.
    rogue = mavutil.mavlink_connection(f"udpout:127.0.0.1:{ap.port}", source_system=42,
                                       source_component=1, dialect="common")
    since = ap.now()
    for _ in range(4):
        rogue.mav.heartbeat_send(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0,
                                 mav.MAV_STATE_ACTIVE)
        ap.wait("a second", lambda: False, timeout=0.5)
    systems = sorted({m.get_srcSystem() for m in ap.find_all("HEARTBEAT", since)
                      if m.get_srcComponent() == GIMBAL})
    ap.check(systems == [AP_SYSTEM], f"system 42's heartbeats do not take the system id: the gimbal's "
             f"heartbeats from {systems}")
    ap.command(GIMBAL, mav.MAV_CMD_REQUEST_MESSAGE, 283, expect=mav.MAV_RESULT_ACCEPTED)
    rogue.close()


def session(gimbalctl, persona, run, results):
    proc = subprocess.Popen(
        [gimbalctl, "mavlink", "--sim", *sim_options(), "--listen", "127.0.0.1:0", "--exit-after-ms", "120000"],
        stdout=subprocess.PIPE, stderr=sys.stderr, text=True,
    )
    try:
        line = proc.stdout.readline()
        port = int(line.split("listening on ")[1].split(",")[0].rsplit(":", 1)[1])
        print(f"mavlink_e2e: {persona} against gimbalctl mavlink on UDP {port}", flush=True)
        ap = Autopilot(port, persona, results)
        run(ap)
        # pymavlink counts a gap in a source's sequence numbers as loss, per system and
        # component (mavutil.mavfile.post_message): on the loopback none, each of the
        # bridge's components numbering its own frames.
        ap.check(ap.m.mav_loss == 0, f"no frame of the gimbal's or the camera's lost to pymavlink's count "
                 f"({ap.m.mav_loss} lost, {ap.m.mav_count} received)")
    except Exception as e:  # a crash is a failure with its reason, not a traceback only
        results.check(False, f"[{persona}] crashed: {e!r}")
    finally:
        proc.kill()
        proc.wait()


def serial_session(gimbalctl, results):
    """ArduPilot on a TELEM port: the gimbal on its UART (`sim --pty`), the autopilot on a
    second pseudo-terminal (`--autopilot-serial`), as on a companion computer."""
    persona = "ardupilot-serial"
    sim = subprocess.Popen([gimbalctl, "sim", "--pty", "--exit-after-ms", "60000"],
                           stdout=subprocess.PIPE, stderr=sys.stderr, text=True)
    bridge = None
    try:
        sim_path = sim.stdout.readline().split()[-1]
        link = PtyLink()
        bridge = subprocess.Popen(
            [gimbalctl, "mavlink", "--serial", sim_path, "--autopilot-serial", f"{link.path}:921600",
             "--exit-after-ms", "60000"], stdout=subprocess.PIPE, stderr=sys.stderr, text=True)
        print(f"mavlink_e2e: {persona}: gimbal on {sim_path}, autopilot on {link.path}", flush=True)
        ap = Autopilot(None, "ardupilot", results, link=link)
        ap.persona = persona
        ap.ask_information(GIMBAL)
        # On the UART the gimbal's headings are nose-referenced: setpoints in either frame
        # are converted with the vehicle's heading from the autopilot state.
        ap.settle("setpoint yaw 20 (flags 0) pitch -45", 0, 20, -45, 50)
        locks = mav.GIMBAL_DEVICE_FLAGS_ROLL_LOCK | mav.GIMBAL_DEVICE_FLAGS_PITCH_LOCK | mav.GIMBAL_DEVICE_FLAGS_YAW_LOCK
        ap.settle("setpoint yaw 80 (earth) pitch -10", locks, 80, -10, 80)
        ap.setpoint = None
        # A shorter session: 20 gaps are 2 s of status.
        ap.status_fresh(min_gaps=20)
    except Exception as e:  # a crash is a failure with its reason, not a traceback only
        results.check(False, f"[{persona}] crashed: {e!r}")
    finally:
        for p in (bridge, sim):
            if p is not None:
                p.kill()
                p.wait()


def main():
    gimbalctl = sys.argv[1]
    results = Checks()
    session(gimbalctl, "px4-normal", px4_normal, results)
    session(gimbalctl, "ardupilot", ardupilot, results)
    serial_session(gimbalctl, results)
    return results.summary("mavlink_e2e")


if __name__ == "__main__":
    sys.exit(main())
