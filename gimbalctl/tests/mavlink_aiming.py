#!/usr/bin/env python3
"""Closed-loop aiming end to end: pymavlink as the autopilot (PX4's flags and rates) and a
QGroundControl-like reader beside it, against `gimbalctl mavlink --sim`, once for each
behaviour of the simulated gimbal in lock (`--sim-lock-holds north`: it holds its north
heading while the vehicle turns; `motor`: it holds its motor angle, turning with the
vehicle). The vendor document does not say which the real gimbal does: the bridge must be
right either way.

    python3 gimbalctl/tests/mavlink_aiming.py PATH/TO/gimbalctl [north|motor ...]

Cases, each against an expectation computed here from the setpoint (not from the bridge):

1. An earth-frame yaw (PX4's yaw lock and ROI: YAW_LOCK | YAW_IN_EARTH_FRAME,
   src/modules/gimbal/output_mavlink.cpp) held while the vehicle turns 30 -> 120 at 30 deg/s:
   the status read with its delta_yaw and as QGroundControl and ArduPilot read it (the
   vehicle-frame yaw plus the vehicle's heading now: src/Gimbal/GimbalController.cc, AP_Mount)
   stays on the setpoint, and ends -20 from the nose.
2. A vehicle-frame yaw (flags 0, ArduPilot's body frame) kept from the nose through a turn,
   and the earth yaw both readings make of it turning with the vehicle.
3. Both streams starting in one datagram: the first AUTOPILOT_STATE_FOR_GIMBAL_DEVICE (heading
   30) and the first setpoint (40 from the nose) in one UDP write, to a bridge that has seen
   neither: the camera ends 40 from the nose, not 70.
4. A gimbal that reboots mid-hold (`reboot` on the bridge's stdin: 3 s without postbacks,
   back at rest): the status comes back to the setpoint.
5. The flags: YAW_LOCK while an earth yaw is held, not while the yaw follows the vehicle
   (PX4 copies them into GIMBAL_MANAGER_STATUS, src/modules/gimbal/input_mavlink.cpp).
6. The image attitude: CAMERA_IMAGE_CAPTURED.q is the camera's attitude in the earth frame.

Ends with a line "mavlink_aiming: N passed, M failed"; exit status 0 only if nothing failed.
"""

import math
import os
import subprocess
import sys
import time

os.environ["MAVLINK20"] = "1"  # before pymavlink is imported: MAVLink 2 framing
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mav  # noqa: E402

from checks import Checks  # noqa: E402
from mavlink_e2e import angle_diff, axis_quaternion, euler_yaw, pitch_past_vertical  # noqa: E402

AP_SYSTEM, AP_COMPONENT = 1, 1
GIMBAL, CAMERA = 154, 100
EARTH = mav.GIMBAL_DEVICE_FLAGS_YAW_LOCK | mav.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME
# The wire's 0.1 degree and the postback's 0.01, with room for a reader that sees the
# status a postback late: a settled gimbal is within this of its setpoint.
SETTLED = 0.5
# While the vehicle turns at TURN_DPS the status may be off by: the gimbal acting on a
# vehicle heading up to 170 ms old and slewing to catch up (255 ms of turn), the status
# giving the motor angle and heading as of its sending (the heading within the 20 ms of the
# state's stream, the status up to 100 ms old when read), and this script's own stream of
# the heading, late by up to 200 ms on a loaded machine, or by the longest this script
# stalled during the turn, whose heading then jumps by that much turn at once: half a
# second of turn or more.
TURN_DPS = 30.0


def during_turn(stall):
    """What the status may be off by during a turn in which the script stalled `stall` s."""
    return TURN_DPS * (0.3 + max(0.2, stall))
SETTLE_S = 6.0  # 180 degrees at the simulator's 60 deg/s, then postbacks to see it


class Autopilot:
    """An autopilot streaming its state at 50 Hz and a setpoint at 20 Hz (what the bridge asks
    of PX4), its heartbeat at 1 Hz, and reading the bridge's messages as the ground station
    beside it would."""

    def __init__(self, port):
        self.m = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{port}", source_system=AP_SYSTEM,
            source_component=AP_COMPONENT, dialect="common")
        self.start = time.monotonic()
        self.yaw = 30.0
        self.turn_to = None
        self.setpoint = None  # (flags, yaw, pitch)
        self.next_hb = self.next_state = self.next_set = 0.0
        self.last_tick = None
        self.stall = 0.0  # the longest between two ticks during the last turn, s
        self.status = None
        self.images = []

    def now(self):
        return time.monotonic() - self.start

    def state_msg(self):
        # As PX4 sends it (src/modules/mavlink/streams/AUTOPILOT_STATE_FOR_GIMBAL_DEVICE.hpp:
        # the message zero-initialised, angular_velocity_z never set): no yaw rate, so the
        # bridge has the turn's from the yaws and time_boot_us.
        half = math.radians(self.yaw) / 2
        return self.m.mav.autopilot_state_for_gimbal_device_encode(
            AP_SYSTEM, 0, int(self.now() * 1e6), [math.cos(half), 0, 0, math.sin(half)],
            0, 0, 0, 0, 0, 0, 0, 4, 0.0)

    def set_msg(self):
        flags, yaw, pitch = self.setpoint
        return self.m.mav.gimbal_device_set_attitude_encode(
            AP_SYSTEM, GIMBAL, flags, axis_quaternion(yaw, pitch), math.nan, math.nan, math.nan)

    def tick(self):
        t = self.now()
        if self.last_tick is not None and self.turn_to is not None:
            self.stall = max(self.stall, t - self.last_tick)
            step = TURN_DPS * (t - self.last_tick)
            d = self.turn_to - self.yaw
            self.yaw = self.turn_to if abs(d) <= step else self.yaw + math.copysign(step, d)
            if self.yaw == self.turn_to:
                self.turn_to = None
        self.last_tick = t
        if t >= self.next_hb:
            self.next_hb = t + 1.0
            self.m.mav.heartbeat_send(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_PX4, 0, 0, mav.MAV_STATE_ACTIVE)
        if t >= self.next_state:
            self.next_state = t + 0.02
            self.m.mav.send(self.state_msg())
        if self.setpoint is not None and t >= self.next_set:
            self.next_set = t + 0.05
            self.m.mav.send(self.set_msg())
        while True:
            msg = self.m.recv_match(blocking=False)
            if msg is None:
                break
            kind = msg.get_type()
            if kind == "GIMBAL_DEVICE_ATTITUDE_STATUS":
                self.status = msg
            elif kind == "CAMERA_IMAGE_CAPTURED":
                self.images.append(msg)
            elif kind == "COMMAND_LONG" and msg.command == mav.MAV_CMD_SET_MESSAGE_INTERVAL:
                self.m.mav.command_ack_send(msg.command, mav.MAV_RESULT_ACCEPTED)
        time.sleep(0.002)

    def run(self, seconds, each=None):
        end = self.now() + seconds
        while self.now() < end:
            self.tick()
            if each is not None:
                each()

    def turn(self, to, each=None):
        self.turn_to = to
        self.stall = 0.0
        while self.turn_to is not None:
            self.tick()
            if each is not None:
                each()

    def vehicle_yaw(self):
        """The status's yaw from the nose (the quaternion's 3-2-1 yaw, as the readers take
        it), None before a postback."""
        s = self.status
        if s is None or math.isnan(s.q[0]):
            return None
        return euler_yaw(s.q)

    def heading_reading(self):
        """The earth yaw as QGroundControl (GimbalController.cc) and ArduPilot (AP_Mount)
        read the status: its vehicle-frame yaw plus the vehicle's heading now (here this
        script's own), delta_yaw ignored."""
        y = self.vehicle_yaw()
        if y is None or not self.status.flags & mav.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME:
            return None
        return angle_diff(y + self.yaw, 0)

    def earth_yaw(self):
        """The earth yaw as common.xml relates the status's frames: in the vehicle frame
        when YAW_IN_VEHICLE_FRAME is set, then plus delta_yaw."""
        s = self.status
        if s is None or math.isnan(s.q[0]) or math.isnan(s.delta_yaw):
            return None
        if not s.flags & mav.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME:
            return None
        return angle_diff(euler_yaw(s.q) + math.degrees(s.delta_yaw), 0)

    def pitch(self):
        s = self.status
        return None if s is None or math.isnan(s.q[0]) else pitch_past_vertical(s.q)

    def yaw_lock(self):
        return self.status is not None and bool(self.status.flags & mav.GIMBAL_DEVICE_FLAGS_YAW_LOCK)


def off(a, b):
    return math.inf if a is None else abs(angle_diff(a, b))


def start(gimbalctl, holds):
    proc = subprocess.Popen(
        [gimbalctl, "mavlink", "--sim", "--listen", "127.0.0.1:0", "--sim-lock-holds", holds,
         "--exit-after-ms", "120000"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=sys.stderr, text=True)
    line = proc.stdout.readline()
    port = int(line.split("listening on ")[1].split(",")[0].rsplit(":", 1)[1])
    return proc, port


def session(gimbalctl, holds, r):
    tag = f"[lock holds {holds}]"
    proc, port = start(gimbalctl, holds)
    try:
        print(f"mavlink_aiming: {tag} against gimbalctl mavlink on UDP {port}", flush=True)
        # 3. Both streams in one datagram, to a bridge that has seen neither.
        ap = Autopilot(port)
        ap.setpoint = (0, 40.0, 0.0)
        ap.m.write(ap.m.mav.heartbeat_encode(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_PX4, 0, 0,
                                             mav.MAV_STATE_ACTIVE).pack(ap.m.mav)
                   + ap.state_msg().pack(ap.m.mav) + ap.set_msg().pack(ap.m.mav))
        ap.next_hb = ap.now() + 1.0
        ap.run(SETTLE_S)
        r.check(off(ap.vehicle_yaw(), 40.0) < SETTLED and off(ap.earth_yaw(), 70.0) < SETTLED,
                f"{tag} both streams in one datagram: 40 from the nose, 70 from north "
                f"(status {ap.vehicle_yaw()}, earth {ap.earth_yaw()})")

        # 5. A followed yaw is no lock.
        r.check(not ap.yaw_lock(), f"{tag} flags 0 (followed): no YAW_LOCK "
                f"(flags 0x{ap.status.flags if ap.status else 0:x})")

        # 2. The vehicle-frame yaw through a turn 30 -> 120.
        worst = [0.0]
        locks = [False]

        def follow():
            earth = ap.yaw + 40.0
            worst[0] = max(worst[0], off(ap.vehicle_yaw(), 40.0), off(ap.earth_yaw(), earth),
                           off(ap.heading_reading(), earth))
            locks[0] = locks[0] or ap.yaw_lock()
        ap.turn(120.0, follow)
        ap.run(SETTLE_S / 2)
        r.check(worst[0] < during_turn(ap.stall) and off(ap.vehicle_yaw(), 40.0) < SETTLED
                and off(ap.earth_yaw(), 160.0) < SETTLED,
                f"{tag} vehicle frame through a turn to 120: 40 from the nose and the heading + 40 throughout "
                f"(worst {worst[0]:.1f} of {during_turn(ap.stall):.1f}, then {ap.vehicle_yaw()}, earth {ap.earth_yaw()})")
        r.check(not locks[0], f"{tag} no YAW_LOCK while the yaw follows the vehicle")

        # 1. The earth-frame yaw (a yaw lock through a turn): vehicle at 30, earth 100, turn to 120.
        ap.turn(30.0)
        ap.setpoint = (EARTH, 100.0, -20.0)
        ap.run(SETTLE_S)
        r.check(off(ap.earth_yaw(), 100.0) < SETTLED and off(ap.vehicle_yaw(), 70.0) < SETTLED,
                f"{tag} earth 100 with the vehicle at 30: 70 from the nose "
                f"(earth {ap.earth_yaw()}, status {ap.vehicle_yaw()})")
        r.check(ap.yaw_lock(), f"{tag} YAW_LOCK while the earth yaw is held")
        worst = [0.0]
        ap.turn(120.0, lambda: worst.__setitem__(
            0, max(worst[0], off(ap.earth_yaw(), 100.0), off(ap.heading_reading(), 100.0))))
        ap.run(SETTLE_S / 2)
        r.check(worst[0] < during_turn(ap.stall) and off(ap.earth_yaw(), 100.0) < SETTLED
                and off(ap.vehicle_yaw(), -20.0) < SETTLED,
                f"{tag} earth 100 through a turn to 120: -20 from the nose "
                f"(worst {worst[0]:.1f} of {during_turn(ap.stall):.1f} during, then earth {ap.earth_yaw()}, status {ap.vehicle_yaw()})")
        r.check(off(ap.pitch(), -20.0) < SETTLED, f"{tag} pitch -20 ({ap.pitch()})")

        # 6. The image attitude: the camera looks at 100 from north, 20 down.
        since = len(ap.images)
        ap.m.mav.command_long_send(AP_SYSTEM, CAMERA, mav.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 0, 1, 1, 0, 0, 0)
        ap.run(1.0)
        image = ap.images[since] if len(ap.images) > since else None
        q = list(image.q) if image else [math.nan] * 4
        yaw = None if math.isnan(q[0]) else euler_yaw(q)
        pitch = None if math.isnan(q[0]) else pitch_past_vertical(q)
        r.check(off(yaw, 100.0) < SETTLED and off(pitch, -20.0) < SETTLED,
                f"{tag} CAMERA_IMAGE_CAPTURED.q: the camera in the earth frame (yaw {yaw}, pitch {pitch})")

        # 4. A reboot mid-hold: back to the setpoint once the gimbal is up again.
        # At rest after the restart the camera looks along the nose (120): the first
        # postback says so, then the loop sends the setpoint again.
        proc.stdin.write("reboot\n")
        proc.stdin.flush()
        away = [0.0]
        ap.run(3.0 + SETTLE_S, lambda: away.__setitem__(0, max(away[0], off(ap.earth_yaw(), 100.0))))
        r.check(away[0] > 10 and off(ap.earth_yaw(), 100.0) < SETTLED,
                f"{tag} a reboot mid-hold: back to earth 100 "
                f"(at most {away[0]:.1f} off, then {ap.earth_yaw()})")
    except Exception as e:  # a crash is a failure with its reason, not a traceback only
        r.check(False, f"{tag} crashed: {e!r}")
    finally:
        proc.kill()
        proc.wait()


def main():
    gimbalctl = sys.argv[1]
    behaviours = sys.argv[2:] or ["north", "motor"]
    r = Checks()
    for holds in behaviours:
        session(gimbalctl, holds, r)
    return r.summary("mavlink_aiming")


if __name__ == "__main__":
    sys.exit(main())
