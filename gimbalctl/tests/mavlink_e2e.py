#!/usr/bin/env python3
"""End-to-end test of `gimbalctl mavlink --sim` with pymavlink playing the autopilot.

It behaves as ArduPilot and PX4 do towards a MAVLink gimbal (gimbal protocol v2) and camera:
heartbeats at 1 Hz, AUTOPILOT_STATE_FOR_GIMBAL_DEVICE at 50 Hz, GLOBAL_POSITION_INT when the
gimbal asks for it, information requests (broadcast and addressed) every second until
answered, setpoints at 20 Hz in both yaw frames and as rates, and the camera's commands. It
checks that the attitude status stays fresh throughout, that setpoints reach the simulated
gimbal and come back in the status within 2 degrees, that a rate stops within the dead-man
once its stream stops, and that every command gets the right ACK.

Usage: mavlink_e2e.py PATH/TO/gimbalctl
Ends with a line "N passed, M failed"; exit status 0 only if nothing failed.
"""

import math
import os
import subprocess
import sys
import time

os.environ["MAVLINK20"] = "1"  # before pymavlink is imported: MAVLink 2 framing
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mav  # noqa: E402

AP_SYSTEM, AP_COMPONENT = 1, 1
GIMBAL, CAMERA = 154, 100
VEHICLE_YAW = 30.0  # degrees, what the "autopilot" says its heading is
# The simulated gimbal slews at 60 deg/s and reports every 500 ms: 10 s is ample for any
# move here; the status is expected every 100 ms.
STEP_TIMEOUT = 10.0
STATUS_MAX_GAP = 1.0  # ArduPilot's health threshold
ANGLE_TOL = 2.0  # the tolerance; the wire's resolution is 0.1 degree


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


class Autopilot:
    def __init__(self, port):
        self.m = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{port}",
            source_system=AP_SYSTEM,
            source_component=AP_COMPONENT,
            dialect="common",
        )
        self.start = time.monotonic()
        self.next_hb = 0.0
        self.next_state = 0.0
        self.next_pos = None  # set once the gimbal asks for GLOBAL_POSITION_INT
        self.pos_interval = None
        self.setpoint = None  # a function returning (flags, q, rates) or None
        self.next_setpoint = 0.0
        self.last_status = None
        self.status = None
        self.status_gaps = []
        self.messages = []  # (time, msg) of everything received since the last clear
        self.passed = 0
        self.failed = 0

    def now(self):
        return time.monotonic() - self.start

    def boot_ms(self):
        return int(self.now() * 1000)

    def tick(self):
        t = self.now()
        if t >= self.next_hb:
            self.next_hb = t + 1.0
            self.m.mav.heartbeat_send(
                mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, mav.MAV_STATE_ACTIVE
            )
        if t >= self.next_state:
            self.next_state = t + 0.02
            half = math.radians(VEHICLE_YAW) / 2
            self.m.mav.autopilot_state_for_gimbal_device_send(
                AP_SYSTEM, GIMBAL, self.boot_ms() * 1000,
                [math.cos(half), 0, 0, math.sin(half)], 0, 0, 0, 0, 0, 0, 0, 4, 0,
            )
        if self.next_pos is not None and t >= self.next_pos:
            self.next_pos = t + self.pos_interval
            self.m.mav.global_position_int_send(
                self.boot_ms(), 473977420, 85455940, 488000, 38000, 0, 0, 0, int(VEHICLE_YAW * 100)
            )
        if self.setpoint is not None and t >= self.next_setpoint:
            self.next_setpoint = t + 0.05
            flags, q, rates = self.setpoint()
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
                if self.last_status is not None:
                    self.status_gaps.append(t - self.last_status)
                self.last_status = t
                self.status = msg
            elif kind == "COMMAND_LONG" and msg.command == mav.MAV_CMD_SET_MESSAGE_INTERVAL:
                # The gimbal asks for our position.
                self.m.mav.command_ack_send(msg.command, mav.MAV_RESULT_ACCEPTED)
                if int(msg.param1) == mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT and msg.param2 > 0:
                    self.pos_interval = msg.param2 / 1e6
                    self.next_pos = t
        time.sleep(0.002)

    def wait(self, what, cond, timeout=STEP_TIMEOUT):
        deadline = self.now() + timeout
        while self.now() < deadline:
            self.tick()
            found = cond()
            if found:
                return found
        return None

    def check(self, ok, what):
        print(("  ok   " if ok else "  FAIL ") + what, flush=True)
        if ok:
            self.passed += 1
        else:
            self.failed += 1
        return ok

    def find(self, kind, pred=lambda m: True, since=0.0):
        for t, m in self.messages:
            if t >= since and m.get_type() == kind and pred(m):
                return m
        return None

    def command(self, target_component, command, *params, expect=None, reply=None):
        """COMMAND_LONG every second until its ACK arrives; returns (ack, reply message)."""
        params = list(params) + [0.0] * (7 - len(params))
        sent_at = self.now()
        retry = 0.0
        ack = None
        while self.now() - sent_at < STEP_TIMEOUT:
            if self.now() >= retry:
                retry = self.now() + 1.0
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
    earth = bool(s.flags & mav.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME)
    return yaw, pitch, earth


def main():
    gimbalctl = sys.argv[1]
    proc = subprocess.Popen(
        [gimbalctl, "mavlink", "--sim", "--listen", "127.0.0.1:0", "--exit-after-ms", "120000"],
        stdout=subprocess.PIPE, stderr=sys.stderr, text=True,
    )
    ap = None
    try:
        line = proc.stdout.readline()
        port = int(line.split("listening on ")[1].split(",")[0].rsplit(":", 1)[1])
        ap = Autopilot(port)
        print(f"mavlink_e2e: gimbalctl mavlink on UDP {port}", flush=True)

        # Information: PX4 asks the broadcast component, ArduPilot the gimbal's, every second
        # until answered. ArduPilot sends no setpoint before it.
        for target in (0, GIMBAL):
            _, info = ap.command(target, mav.MAV_CMD_REQUEST_MESSAGE,
                                 mav.MAVLINK_MSG_ID_GIMBAL_DEVICE_INFORMATION,
                                 expect=mav.MAV_RESULT_ACCEPTED, reply="GIMBAL_DEVICE_INFORMATION")
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
        ap.check(ap.wait("position asked", lambda: ap.next_pos is not None) is not None,
                 "the gimbal asked for GLOBAL_POSITION_INT")

        def settle(what, flags, yaw, pitch, want_yaw, want_earth):
            q = axis_quaternion(yaw, pitch)
            ap.setpoint = lambda: (flags, q, [math.nan] * 3)

            def reached():
                a = status_angles(ap)
                return a is not None and abs(a[1] - pitch) <= ANGLE_TOL \
                    and abs(angle_diff(a[0], want_yaw)) <= ANGLE_TOL and a[2] == want_earth and a
            got = ap.wait(what, reached)
            ap.check(bool(got), f"{what}: status {status_angles(ap)}")

        # Earth frame: yaw 90 (north-referenced on CAN while the autopilot state flows).
        settle("setpoint yaw 90 (earth) pitch -30", mav.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME,
               90, -30, 90, True)
        # Vehicle frame: 20 right of a nose at 30 = 50 from north.
        settle("setpoint yaw 20 (vehicle) pitch -60", mav.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME,
               20, -60, 50, True)
        # Flags 0, as ArduPilot sends: vehicle frame; pitch past vertical.
        settle("setpoint yaw 0 (flags 0) pitch -100", 0, 0, -100, 30, True)
        settle("setpoint yaw 45 (YAW_LOCK: earth) pitch 20", mav.GIMBAL_DEVICE_FLAGS_YAW_LOCK,
               45, 20, 45, True)

        # Rate: 20 deg/s of yaw for 1 s, then the stream stops: the core's dead-man (250 ms)
        # stops the gimbal.
        ap.setpoint = lambda: (0, [math.nan] * 4, [0.0, 0.0, math.radians(20)])
        before = status_angles(ap)
        ap.wait("rate hold", lambda: False, timeout=1.5)
        during = status_angles(ap)
        ap.setpoint = None
        ap.wait("dead-man", lambda: False, timeout=1.2)
        stopped = status_angles(ap)
        ap.wait("still", lambda: False, timeout=1.2)
        still = status_angles(ap)
        turned = angle_diff(during[0], before[0]) if before and during else 0
        ap.check(turned > 10, f"rate setpoints turned the gimbal ({turned:.1f} deg)")
        ap.check(stopped is not None and still is not None and abs(angle_diff(still[0], stopped[0])) < 0.5,
                 f"stopped after the stream stopped ({stopped} then {still})")

        gaps = ap.status_gaps
        worst = max(gaps) if gaps else math.inf
        ap.check(len(gaps) > 50 and worst < STATUS_MAX_GAP,
                 f"attitude status fresh throughout: {len(gaps)} gaps, worst {worst * 1000:.0f} ms")

        # The camera.
        for target, cmd, p1 in ((0, mav.MAV_CMD_REQUEST_MESSAGE, mav.MAVLINK_MSG_ID_CAMERA_INFORMATION),
                                (CAMERA, mav.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1)):
            _, info = ap.command(target, cmd, p1, expect=mav.MAV_RESULT_ACCEPTED, reply="CAMERA_INFORMATION")
        if info is not None:
            ap.check(info.gimbal_device_id == GIMBAL
                     and info.flags & mav.CAMERA_CAP_FLAGS_CAPTURE_IMAGE
                     and info.flags & mav.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM,
                     "camera information: images, video stream, gimbal 154")
        ap.command(CAMERA, mav.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, 1,
                   expect=mav.MAV_RESULT_ACCEPTED, reply="CAMERA_IMAGE_CAPTURED")
        _, status = ap.command(CAMERA, mav.MAV_CMD_VIDEO_START_CAPTURE, 0, 0,
                               expect=mav.MAV_RESULT_ACCEPTED, reply="CAMERA_CAPTURE_STATUS")
        ap.check(status is not None and status.video_status == 1, "recording")
        ap.command(CAMERA, mav.MAV_CMD_VIDEO_STOP_CAPTURE, 0, expect=mav.MAV_RESULT_ACCEPTED)
        _, settings = ap.command(CAMERA, mav.MAV_CMD_SET_CAMERA_ZOOM, mav.ZOOM_TYPE_RANGE, 50,
                                 expect=mav.MAV_RESULT_ACCEPTED, reply="CAMERA_SETTINGS")
        ap.check(settings is not None and abs(settings.zoomLevel - 50) < 0.01, "zoom level 50 %")
        _, stream = ap.command(CAMERA, mav.MAV_CMD_REQUEST_VIDEO_STREAM_INFORMATION, 1,
                               expect=mav.MAV_RESULT_ACCEPTED, reply="VIDEO_STREAM_INFORMATION")
        ap.check(stream is not None and stream.uri.startswith("rtsp://") and stream.type == mav.VIDEO_STREAM_TYPE_RTSP,
                 f"stream URI {stream.uri if stream else None}")

        # Bad commands get the right ACK, never silence.
        ap.command(GIMBAL, mav.MAV_CMD_DO_SET_MODE, 1, expect=mav.MAV_RESULT_UNSUPPORTED)
        ap.command(CAMERA, mav.MAV_CMD_SET_CAMERA_ZOOM, mav.ZOOM_TYPE_RANGE, 150, expect=mav.MAV_RESULT_DENIED)
        ap.command(CAMERA, mav.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 0, expect=mav.MAV_RESULT_DENIED)
    except Exception as e:  # a crash is a failure with its reason, not a traceback only
        print(f"  FAIL mavlink_e2e crashed: {e!r}", flush=True)
        if ap is None:
            ap = type("R", (), {"passed": 0, "failed": 1})()
        else:
            ap.failed += 1
    finally:
        proc.kill()
        proc.wait()
    print(f"mavlink_e2e: {ap.passed} passed, {ap.failed} failed")
    return 0 if ap.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
