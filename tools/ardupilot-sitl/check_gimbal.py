#!/usr/bin/env python3
"""GCS-side helper for run_check.sh: drives ArduCopter SITL (TCP serial0) as a GCS and
reports what ArduPilot says about a MAVLink gimbal (the bridge under test, on SERIAL2).

Also listens to the bridge directly as a passive UDP peer (it answers every peer it hears
from), so the simulated gimbal's own GIMBAL_DEVICE_ATTITUDE_STATUS can be compared with
ArduPilot's re-published one.

The steps on the ground print what they see against what is expected (the yaw and pitch, and
the bridge's own YAW_LOCK/NEUTRAL flags). The last step flies (unless --no-flight): GUIDED, arm,
take off, a region of interest, then a turn on the spot; it passes or fails on the earth yaw's
error against the true bearing to the ROI (see turning_roi). Exit code: 0, 2 when ArduPilot did
not find the gimbal, 4 when the turning ROI failed, 3 on the overall deadline.

Everything is bounded: --deadline seconds overall (default 280).
"""
import argparse
import collections
import hashlib
import math
import os
import sys
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402

mavlink = mavutil.mavlink

GDF = [(1, "RETRACT"), (2, "NEUTRAL"), (4, "ROLL_LOCK"), (8, "PITCH_LOCK"), (16, "YAW_LOCK"),
       (32, "YAW_IN_VEHICLE_FRAME"), (64, "YAW_IN_EARTH_FRAME"), (128, "ACCEPTS_YAW_IN_EARTH_FRAME"),
       (256, "RC_EXCLUSIVE"), (512, "RC_MIXED")]

T0 = time.monotonic()
DEADLINE = 280.0


def log(*a):
    print("[%6.1fs] " % (time.monotonic() - T0) + " ".join(str(x) for x in a), flush=True)


def check_deadline():
    if time.monotonic() - T0 > DEADLINE:
        log("FAIL: overall deadline of %.0fs reached" % DEADLINE)
        sys.exit(1)


def flag_names(v):
    n = [name for bit, name in GDF if v & bit]
    return "%d(%s)" % (v, "|".join(n) if n else "-")


def q_to_euler_deg(q):
    w, x, y, z = q
    if any(isinstance(c, float) and math.isnan(c) for c in q):
        return (float("nan"),) * 3
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    s = max(-1.0, min(1.0, 2 * (w * y - z * x)))
    pitch = math.asin(s)
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return tuple(math.degrees(v) for v in (roll, pitch, yaw))


def wrap180(d):
    if math.isnan(d):
        return d
    return (d + 180.0) % 360.0 - 180.0


def fmt(v, nd=1):
    return "nan" if v is None or (isinstance(v, float) and math.isnan(v)) else ("%.*f" % (nd, v))


class Pump:
    """Reads both links, keeps the latest of each message per source."""

    def __init__(self, ap, obs, bridge_err):
        self.ap = ap
        self.obs = obs
        self.latest = {}  # (link, type, sys, comp) -> (time, msg)
        self.acks = []
        self.params = {}
        self.last_hb = 0.0
        self.bridge_err = bridge_err
        self.bridge_err_pos = 0
        self.seen_sources = set()
        self.mount_text_at = None  # when ArduPilot announced "Mount: <vendor> <model>"
        # ArduPilot's ATTITUDE as (its time_boot_ms, yaw deg, yawspeed deg/s), to pair its
        # re-published GIMBAL_DEVICE_ATTITUDE_STATUS (stamped with the same clock) with the
        # vehicle yaw of that moment while the vehicle turns
        self.att_hist = collections.deque(maxlen=600)

    def send_heartbeats(self):
        now = time.monotonic()
        if now - self.last_hb < 1.0:
            return
        self.last_hb = now
        for c in (self.ap, self.obs):
            if c is None:
                continue
            try:
                c.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            except Exception:
                pass

    def _recv(self, link, conn):
        n = 0
        while True:
            try:
                m = conn.recv_match(blocking=False)
            except Exception:
                return n
            if m is None:
                return n
            n += 1
            t = m.get_type()
            if t == "BAD_DATA":
                continue
            key = (link, t, m.get_srcSystem(), m.get_srcComponent())
            if (link, m.get_srcSystem(), m.get_srcComponent()) not in self.seen_sources:
                self.seen_sources.add((link, m.get_srcSystem(), m.get_srcComponent()))
                log("new source on %s link: sys %d comp %d (%s)" % (link, m.get_srcSystem(), m.get_srcComponent(), t))
            self.latest[key] = (time.monotonic(), m)
            if link == "ap":
                if t == "STATUSTEXT":
                    log("AP STATUSTEXT (%d/%d): %s" % (m.get_srcSystem(), m.get_srcComponent(), m.text))
                    if m.text.startswith("Mount:"):
                        self.mount_text_at = time.monotonic()
                elif t == "COMMAND_ACK":
                    self.acks.append(m)
                elif t == "PARAM_VALUE":
                    self.params[m.param_id] = m.param_value
                elif t == "ATTITUDE" and m.get_srcSystem() == 1 and m.get_srcComponent() == 1:
                    if self.att_hist and m.time_boot_ms < self.att_hist[-1][0]:
                        self.att_hist.clear()  # rebooted
                    self.att_hist.append((m.time_boot_ms, math.degrees(m.yaw), math.degrees(m.yawspeed)))

    def spin(self, seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            check_deadline()
            self.send_heartbeats()
            n = self._recv("ap", self.ap)
            if self.obs is not None:
                n += self._recv("bridge", self.obs)
            if n == 0:
                time.sleep(0.005)

    def get(self, link, t, sysid=None, comp=None, max_age=None):
        best = None
        for (l, tt, s, c), (ts, m) in self.latest.items():
            if l != link or tt != t:
                continue
            if sysid is not None and s != sysid:
                continue
            if comp is not None and c != comp:
                continue
            if max_age is not None and time.monotonic() - ts > max_age:
                continue
            if best is None or ts > best[0]:
                best = (ts, m)
        return None if best is None else best[1]

    def vehicle_yaw_at(self, boot_ms):
        """ArduPilot's vehicle yaw (deg) at its time boot_ms, interpolated between ATTITUDE
        samples; None if there is no sample within 0.3 s of it."""
        h = self.att_hist
        if not h:
            return None
        if boot_ms <= h[0][0]:
            return h[0][1] if h[0][0] - boot_ms <= 300 else None
        if boot_ms >= h[-1][0]:
            return h[-1][1] if boot_ms - h[-1][0] <= 300 else None
        for (t0, y0, _), (t1, y1, _) in zip(reversed(list(h)[:-1]), reversed(list(h)[1:])):
            if t0 <= boot_ms <= t1:
                f = 0.0 if t1 == t0 else (boot_ms - t0) / float(t1 - t0)
                return wrap180(y0 + f * wrap180(y1 - y0))
        return None

    def bridge_stderr_new(self):
        if not self.bridge_err or not os.path.exists(self.bridge_err):
            return []
        with open(self.bridge_err, "r", errors="replace") as f:
            f.seek(self.bridge_err_pos)
            data = f.read()
            self.bridge_err_pos = f.tell()
        return [ln for ln in data.splitlines() if ln.strip()]


def signing_now():
    """Now in MAVLink 2 signing's units: 10 us since 2015-01-01 00:00 GMT."""
    return int((time.time() - 1420070400) * 100000)


def setup_signing(p, obs, passphrase):
    """SETUP_SIGNING to ArduPilot with the passphrase's SHA-256 (MAVProxy's 'signing setup'):
    it stores the key and, from then on and after the reboot, signs on every link but the
    first (SERIAL0, this GCS link, which it trusts unsigned) and accepts only frames signed
    with the key on them, the gimbal's SERIAL2 among them. The observer signs too, so that the
    bridge takes it as a peer."""
    key = hashlib.sha256(passphrase.encode()).digest()
    p.ap.mav.setup_signing_send(p.ap.target_system, p.ap.target_component, key, signing_now())
    if obs is not None:
        obs.setup_signing(key, sign_outgoing=True, initial_timestamp=signing_now())
    log("SETUP_SIGNING sent to ArduPilot (key = SHA-256 of the passphrase); the observer signs")
    p.spin(1.0)


def connect_ap(url, timeout):
    end = time.monotonic() + timeout
    last_err = None
    while time.monotonic() < end:
        check_deadline()
        try:
            c = mavutil.mavlink_connection(url, source_system=255, source_component=190, retries=1)
            hb = c.wait_heartbeat(timeout=5)
            if hb is not None and c.target_system != 0:
                return c
            c.close()
        except Exception as e:  # SITL not listening yet, or closed during reboot
            last_err = e
        time.sleep(0.5)
    raise SystemExit("FAIL: no heartbeat from SITL at %s within %ss (%s)" % (url, timeout, last_err))


def command_long(p, cmd, params, wait=3.0):
    p.acks.clear()
    prm = list(params) + [0] * (7 - len(params))
    p.ap.mav.command_long_send(1, 1, cmd, 0, *prm)
    return wait_ack(p, cmd, wait)


def command_int(p, cmd, frame, params4, x, y, z, wait=3.0):
    p.acks.clear()
    prm = list(params4) + [0] * (4 - len(params4))
    p.ap.mav.command_int_send(1, 1, frame, cmd, 0, 0, *prm, x, y, z)
    return wait_ack(p, cmd, wait)


def wait_ack(p, cmd, wait):
    end = time.monotonic() + wait
    while time.monotonic() < end:
        p.spin(0.05)
        for a in p.acks:
            if a.command == cmd:
                return a.result
    return None


def res_name(r):
    if r is None:
        return "no ACK"
    e = mavlink.enums["MAV_RESULT"].get(r)
    return e.name if e else str(r)


def set_param(p, name, value, tries=3):
    for _ in range(tries):
        p.params.pop(name, None)
        p.ap.mav.param_set_send(1, 1, name.encode(), float(value), mavlink.MAV_PARAM_TYPE_INT8)
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            p.spin(0.05)
            if name in p.params:
                ok = abs(p.params[name] - value) < 1e-3
                log("PARAM_SET %s=%s -> PARAM_VALUE %s %s" % (name, value, p.params[name], "ok" if ok else "MISMATCH"))
                return ok
    log("PARAM_SET %s=%s: no PARAM_VALUE" % (name, value))
    return False


def read_param(p, name):
    p.params.pop(name, None)
    p.ap.mav.param_request_read_send(1, 1, name.encode(), -1)
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        p.spin(0.05)
        if name in p.params:
            return p.params[name]
    return None


def request_streams(p):
    want = [
        (mavlink.MAVLINK_MSG_ID_ATTITUDE, 100000),
        (mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS, 200000),
        (mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS, 500000),
        (mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION, 2000000),
        (mavlink.MAVLINK_MSG_ID_MOUNT_STATUS, 500000),
        (mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 500000),
    ]
    for mid, us in want:
        r = command_long(p, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, [mid, us], wait=1.5)
        log("SET_MESSAGE_INTERVAL %s %d us -> %s" % (mavlink.mavlink_map[mid].msgname if mid in mavlink.mavlink_map else mid, us, res_name(r)))


def describe_gdas(m, vehicle_yaw):
    r, pt, y = q_to_euler_deg(list(m.q))
    dy = getattr(m, "delta_yaw", float("nan"))
    dy_deg = math.degrees(dy) if not math.isnan(dy) else float("nan")
    s = "flags=%s q->roll %s pitch %s yaw %s | delta_yaw %s" % (
        flag_names(m.flags), fmt(r), fmt(pt), fmt(y), fmt(dy_deg))
    if m.flags & 32 or not (m.flags & 64):
        # vehicle-frame yaw (explicit, or ArduPilot's/legacy reading): earth = yaw + heading
        s += " | earth yaw = q yaw + delta_yaw: %s, = q yaw + ATTITUDE yaw: %s" % (
            fmt(wrap180(y + dy_deg)), fmt(wrap180(y + vehicle_yaw)) if vehicle_yaw is not None else "nan")
    if m.flags & 64:
        s += " | (q yaw is earth frame) body yaw = q yaw - ATTITUDE yaw: %s" % (
            fmt(wrap180(y - vehicle_yaw)) if vehicle_yaw is not None else "nan")
    s += " | target %d/%d dev_id %d" % (m.target_system, m.target_component, getattr(m, "gimbal_device_id", 0))
    return s


SUMMARY = []
FLAG_CHECKS = []  # (step, bridge status flags, (YAW_LOCK, NEUTRAL) expected, as expected?)


def report(p, title, expect, want=None, want_flags=None):
    """want: ("body"|"earth", yaw_deg, pitch_deg) commanded target, for the summary table.
    want_flags: (YAW_LOCK expected?, NEUTRAL expected?) in the bridge's own status."""
    att = p.get("ap", "ATTITUDE", 1, 1, max_age=2)
    vyaw = math.degrees(att.yaw) if att else None
    print("-" * 100)
    log("STEP: %s" % title)
    print("  expected: %s" % expect)
    print("  vehicle ATTITUDE yaw: %s deg (roll %s pitch %s)" % (
        fmt(vyaw), fmt(math.degrees(att.roll)) if att else "nan", fmt(math.degrees(att.pitch)) if att else "nan"))
    m = p.get("ap", "GIMBAL_DEVICE_ATTITUDE_STATUS", 1, 1, max_age=2)
    print("  ArduPilot (1/1) GIMBAL_DEVICE_ATTITUDE_STATUS: %s" % (describe_gdas(m, vyaw) if m else "none"))
    m = p.get("ap", "GIMBAL_MANAGER_STATUS", 1, 1, max_age=3)
    if m:
        print("  ArduPilot (1/1) GIMBAL_MANAGER_STATUS: flags=%s dev_id %d primary %d/%d" % (
            flag_names(m.flags), m.gimbal_device_id, m.primary_control_sysid, m.primary_control_compid))
    else:
        print("  ArduPilot (1/1) GIMBAL_MANAGER_STATUS: none")
    m = p.get("ap", "MOUNT_STATUS", max_age=3)
    if m:
        print("  MOUNT_STATUS: %s" % m)
    m = p.get("ap", "GIMBAL_DEVICE_ATTITUDE_STATUS", comp=154, max_age=2)
    print("  device (x/154) GIMBAL_DEVICE_ATTITUDE_STATUS routed by ArduPilot to the GCS: %s" % (
        describe_gdas(m, vyaw) if m else "none"))
    m = p.get("bridge", "GIMBAL_DEVICE_ATTITUDE_STATUS", comp=154, max_age=2)
    print("  device (x/154) GIMBAL_DEVICE_ATTITUDE_STATUS seen directly from the bridge: %s" % (
        describe_gdas(m, vyaw) if m else "none"))
    if want is not None and att is not None:
        apm = p.get("ap", "GIMBAL_DEVICE_ATTITUDE_STATUS", 1, 1, max_age=2)
        dev = p.get("bridge", "GIMBAL_DEVICE_ATTITUDE_STATUS", comp=154, max_age=2) or \
            p.get("ap", "GIMBAL_DEVICE_ATTITUDE_STATUS", comp=154, max_age=2)
        frame, wy, wp = want
        exp_earth = wrap180(wy + vyaw) if frame == "body" else wrap180(wy)
        ap_e = dev_e = float("nan")
        ap_p = dev_p = float("nan")
        if apm:
            _, ap_p, y = q_to_euler_deg(list(apm.q))
            ap_e = wrap180(y + vyaw)  # ArduPilot labels it YAW_IN_VEHICLE_FRAME, delta_yaw NaN
        if dev:
            _, dev_p, y = q_to_euler_deg(list(dev.q))
            dev_e = wrap180(y + math.degrees(dev.delta_yaw)) if dev.flags & 32 else wrap180(y)
        SUMMARY.append((title.split(" (")[0][:58], frame, wy, wp, vyaw, exp_earth, ap_e, ap_p, dev_e, dev_p))
    if want_flags is not None:
        dev = p.get("bridge", "GIMBAL_DEVICE_ATTITUDE_STATUS", comp=154, max_age=2) or \
            p.get("ap", "GIMBAL_DEVICE_ATTITUDE_STATUS", comp=154, max_age=2)
        got = (bool(dev.flags & 16), bool(dev.flags & 2)) if dev else None
        ok = got == tuple(want_flags)
        print("  bridge's own flags: YAW_LOCK %s NEUTRAL %s, expected YAW_LOCK %s NEUTRAL %s: %s" % (
            ("yes" if got[0] else "no") if got else "?", ("yes" if got[1] else "no") if got else "?",
            "yes" if want_flags[0] else "no", "yes" if want_flags[1] else "no", "ok" if ok else "MISMATCH"))
        FLAG_CHECKS.append((title.split(" (")[0][:58], dev.flags if dev else -1, want_flags, ok))
    lines = p.bridge_stderr_new()
    print("  bridge stderr since last step: %s" % ("(nothing)" if not lines else ""))
    for ln in lines[-15:]:
        print("    | " + ln)


def bearing_deg(lat1, lon1, lat2, lon2):
    """Bearing (deg from north) from point 1 to point 2, flat earth, as ArduPilot's
    AP_Mount_Backend::get_angle_target_to_location computes it for a region of interest."""
    x = wrap180(lon2 - lon1) * math.cos(math.radians((lat1 + lat2) / 2.0))
    y = lat2 - lat1
    return math.degrees(math.atan2(x, y))


def distance_m(lat1, lon1, lat2, lon2):
    x = math.radians(wrap180(lon2 - lon1)) * math.cos(math.radians((lat1 + lat2) / 2.0)) * 6378137.0
    y = math.radians(lat2 - lat1) * 6378137.0
    return math.hypot(x, y)


# Bounds of the turning step (see turning_roi). The simulated gimbal reports its motor angle
# in a postback every 500 ms (idu_gimbal::sim::SimConfig::postback_period_ms); the bridge's
# status (every 100 ms) carries the motor angle and delta_yaw = the vehicle's heading as of
# the status (the postback's angle turned back by the vehicle's turn since, while the yaw is
# held in the earth frame). ArduPilot adds the vehicle's *current* yaw to that motor angle
# (AP_Mount reads the quaternion as body frame), so its reading should be as close as the
# bridge's own; its bound keeps a postback period of room until a run shows it.
POSTBACK_PERIOD_S = 0.5
# What the closed loop itself may lag by: the autopilot's attitude reaches the bridge every
# 20 ms (ArduPilot's AUTOPILOT_STATE_FOR_GIMBAL_DEVICE at 50 Hz), the link re-commands the
# gimbal at most every 50 ms (aim_period_ms) once the heading moved past its 0.2 deg dead-band,
# the simulated gimbal slews at 60 deg/s (well above the turn rate), the bridge's status comes
# every 100 ms; 0.25 s covers their sum with room to spare.
LOOP_LAG_S = 0.25
STEADY_TOL_DEG = 2.0


def turning_roi(p, a, lat, lon):
    """Arm, take off in GUIDED, set a region of interest, turn the vehicle on the spot with
    CONDITION_YAW and compare, every 0.5 s, the mount's earth yaw (as ArduPilot reports it, and
    as the bridge reports it) with the true bearing from the vehicle to the ROI.
    Returns (passed, summary lines)."""
    print("=" * 100)
    log("STEP: yaw-locked ROI while the vehicle turns (GUIDED, take off to %g m, DO_SET_ROI_LOCATION,"
        " CONDITION_YAW %g deg at %g deg/s)" % (a.takeoff_alt, a.turn_deg, a.turn_rate))
    print("  expected: ArduPilot (mount mode GPS_POINT) re-sends the earth bearing to the ROI at 50 Hz with"
          " flags ROLL|PITCH|YAW_LOCK (28); the camera keeps that bearing while the vehicle turns under it:")
    print("  within %.1f deg once the turn is over; during it within %.1f deg + w x %.2f s (the bridge's own"
          " status) and %.1f deg + w x %.2f s (ArduPilot's reading, which adds the current vehicle yaw to the"
          " status's motor angle), w = the vehicle's peak yaw rate" % (
              STEADY_TOL_DEG, STEADY_TOL_DEG, LOOP_LAG_S, STEADY_TOL_DEG, POSTBACK_PERIOD_S + LOOP_LAG_S))
    fail = []
    # faster streams for this step: the readings are paired by time while the vehicle turns
    for mid, us in ((mavlink.MAVLINK_MSG_ID_ATTITUDE, 50000),
                    (mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS, 100000),
                    (mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 100000)):
        r = command_long(p, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, [mid, us], wait=1.5)
        log("SET_MESSAGE_INTERVAL %s %d us -> %s" % (mavlink.mavlink_map[mid].msgname, us, res_name(r)))

    # --- GUIDED, arm (retried while the pre-arm checks are not yet met), take off
    r = command_long(p, mavlink.MAV_CMD_DO_SET_MODE, [mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4])
    log("DO_SET_MODE GUIDED -> %s" % res_name(r))
    armed = False
    end = time.monotonic() + a.arm_wait
    while time.monotonic() < end:
        r = command_long(p, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, [1], wait=3)
        log("COMPONENT_ARM_DISARM arm -> %s" % res_name(r))
        if r == mavlink.MAV_RESULT_ACCEPTED:
            armed = True
            break
        p.spin(3.0)
    if not armed:
        return False, ["turning ROI: FAIL: could not arm within %.0f s" % a.arm_wait]
    r = command_long(p, mavlink.MAV_CMD_NAV_TAKEOFF, [0, 0, 0, 0, 0, 0, a.takeoff_alt])
    log("NAV_TAKEOFF %g m -> %s" % (a.takeoff_alt, res_name(r)))
    end = time.monotonic() + 40
    gp = None
    while time.monotonic() < end:
        p.spin(0.5)
        gp = p.get("ap", "GLOBAL_POSITION_INT", 1, 1, max_age=1)
        if gp and gp.relative_alt >= (a.takeoff_alt - 0.5) * 1000 and abs(gp.vz) < 30:
            break
    else:
        return False, ["turning ROI: FAIL: did not reach %g m (relative alt %s m)" % (
            a.takeoff_alt, fmt(gp.relative_alt / 1000.0) if gp else "nan")]
    log("at %.1f m above home" % (gp.relative_alt / 1000.0))

    # --- the ROI: 100 m north of home, 57.7 m below it (as the ROI step on the ground)
    roi_lat = lat + math.degrees(100.0 / 6378137.0)
    roi_lon = lon
    roi_rel_alt = -57.7
    r = command_int(p, mavlink.MAV_CMD_DO_SET_ROI_LOCATION, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                    [0], int(round(roi_lat * 1e7)), int(round(roi_lon * 1e7)), roi_rel_alt)
    log("DO_SET_ROI_LOCATION 100 m north of home, %g m relative -> %s" % (roi_rel_alt, res_name(r)))
    p.spin(a.settle)
    p.bridge_stderr_new()

    att = p.get("ap", "ATTITUDE", 1, 1, max_age=1)
    gp = p.get("ap", "GLOBAL_POSITION_INT", 1, 1, max_age=1)
    if att is None or gp is None:
        return False, ["turning ROI: FAIL: no ATTITUDE or GLOBAL_POSITION_INT from ArduPilot"]
    h0 = math.degrees(att.yaw)
    body0 = wrap180(bearing_deg(gp.lat / 1e7, gp.lon / 1e7, roi_lat, roi_lon) - h0)
    # turn the way that brings the ROI toward the nose, so the gimbal's yaw stays within the
    # motor's travel (+-170 deg) throughout
    turn = math.copysign(a.turn_deg, body0 if body0 != 0 else 1.0)
    target_h = wrap180(h0 + turn)

    samples = []  # (t, phase, vyaw, vrate, brg, exp_pitch, ap_e, ap_err, ap_pitch, ap_flags, dev_e, dev_err, dev_pitch, dev_flags)

    def sample(t_rel, phase):
        att = p.get("ap", "ATTITUDE", 1, 1, max_age=1)
        gp = p.get("ap", "GLOBAL_POSITION_INT", 1, 1, max_age=1)
        vyaw = math.degrees(att.yaw) if att else float("nan")
        vrate = math.degrees(att.yawspeed) if att else float("nan")
        brg = exp_pitch = float("nan")
        if gp:
            vlat, vlon = gp.lat / 1e7, gp.lon / 1e7
            brg = bearing_deg(vlat, vlon, roi_lat, roi_lon)
            exp_pitch = math.degrees(math.atan2(roi_rel_alt - gp.relative_alt / 1000.0,
                                                distance_m(vlat, vlon, roi_lat, roi_lon)))
        ap_e = ap_pitch = float("nan")
        ap_flags = -1
        apm = p.get("ap", "GIMBAL_DEVICE_ATTITUDE_STATUS", 1, 1, max_age=1)
        if apm:
            _, ap_pitch, y = q_to_euler_deg(list(apm.q))
            # the vehicle yaw of the moment ArduPilot sent it (same clock), as AP_Mount pairs them
            vy = p.vehicle_yaw_at(apm.time_boot_ms)
            if vy is not None:
                ap_e = wrap180(y + vy)
            ap_flags = apm.flags
        dev_e = dev_pitch = float("nan")
        dev_flags = -1
        dev = p.get("bridge", "GIMBAL_DEVICE_ATTITUDE_STATUS", comp=154, max_age=1)
        if dev:
            _, dev_pitch, y = q_to_euler_deg(list(dev.q))
            dev_e = wrap180(y + math.degrees(dev.delta_yaw)) if dev.flags & 32 else wrap180(y)
            dev_flags = dev.flags
        samples.append((t_rel, phase, vyaw, vrate, brg, exp_pitch, ap_e, wrap180(ap_e - brg), ap_pitch, ap_flags,
                        dev_e, wrap180(dev_e - brg), dev_pitch, dev_flags))
        print("  %6.1f %-6s | %7s %6s | %7s %6s | %7s %6s %6s %4s | %7s %6s %6s %4s" % (
            t_rel, phase, fmt(vyaw), fmt(vrate), fmt(brg), fmt(exp_pitch), fmt(ap_e), fmt(wrap180(ap_e - brg)),
            fmt(ap_pitch), ap_flags, fmt(dev_e), fmt(wrap180(dev_e - brg)), fmt(dev_pitch), dev_flags))

    print("  vehicle yaw %s, ROI at body yaw %s: turning %+g deg (CONDITION_YAW relative, direction %+d) to %s" % (
        fmt(h0), fmt(body0), turn, 1 if turn > 0 else -1, fmt(target_h)))
    print("  every 0.5 s; earth yaws in deg; 'AP' = ArduPilot's re-published status: q yaw (read as body frame)"
          " + the vehicle's ATTITUDE yaw at that status's time_boot_ms;")
    print("  'dev' = the bridge's own status: q yaw + delta_yaw; err = earth yaw - true bearing from the vehicle"
          " to the ROI; flags = GIMBAL_DEVICE_FLAGS (28 ROLL|PITCH|YAW_LOCK, +32 YAW_IN_VEHICLE_FRAME, +2 NEUTRAL)")
    print("  %6s %-6s | %7s %6s | %7s %6s | %7s %6s %6s %4s | %7s %6s %6s %4s" % (
        "t", "phase", "vehYaw", "rate", "bearing", "expPit", "APearth", "APerr", "APpit", "APfl",
        "devEarth", "devErr", "devPit", "dvfl"))
    for i in range(2):
        sample(-1.0 + 0.5 * i, "before")
        p.spin(0.5)
    att = p.get("ap", "ATTITUDE", 1, 1)
    boot_ms_cmd = att.time_boot_ms if att else 0
    p.acks.clear()
    p.ap.mav.command_long_send(1, 1, mavlink.MAV_CMD_CONDITION_YAW, 0, abs(turn), a.turn_rate,
                               1 if turn > 0 else -1, 1, 0, 0, 0)
    t_cmd = time.monotonic()
    expected_dur = abs(turn) / a.turn_rate
    done_at = None
    boot_ms_done = None
    next_t = t_cmd
    while True:
        while time.monotonic() < next_t:
            p.spin(min(0.02, max(0.0, next_t - time.monotonic())))
        now = time.monotonic()
        t_rel = now - t_cmd
        att = p.get("ap", "ATTITUDE", 1, 1, max_age=1)
        if done_at is None and att is not None and abs(wrap180(math.degrees(att.yaw) - target_h)) < 1.0 \
                and abs(math.degrees(att.yawspeed)) < 1.0:
            done_at = now
            boot_ms_done = att.time_boot_ms
        if done_at is None:
            phase = "turn"
        elif now - done_at < a.after_settle:
            phase = "settle"
        else:
            phase = "after"
        sample(t_rel, phase)
        if done_at is not None and now - done_at >= a.after_settle + a.after_s - 1e-6:
            break
        if done_at is None and t_rel > expected_dur * 2 + 10:
            fail.append("the vehicle did not finish its turn within %.0f s" % t_rel)
            break
        next_t += 0.5
    for ack in p.acks:
        if ack.command == mavlink.MAV_CMD_CONDITION_YAW:
            log("(the CONDITION_YAW sent at t=0 had been answered %s)" % res_name(ack.result))
    # the vehicle's peak yaw rate through the turn, from every ATTITUDE (20 Hz), not only the samples
    rates = [abs(r) for (t, _, r) in p.att_hist if t >= boot_ms_cmd and (boot_ms_done is None or t <= boot_ms_done)]
    w = max(rates) if rates else a.turn_rate
    dev_bound = STEADY_TOL_DEG + w * LOOP_LAG_S
    ap_bound = STEADY_TOL_DEG + w * (POSTBACK_PERIOD_S + LOOP_LAG_S)

    def worst(phase_set, idx):
        v = [abs(s_[idx]) if not math.isnan(s_[idx]) else float("inf") for s_ in samples if s_[1] in phase_set]
        return max(v) if v else float("nan")

    during = ("turn", "settle")
    res = {
        "AP during": (worst(during, 7), ap_bound), "AP after": (worst(("after",), 7), STEADY_TOL_DEG),
        "dev during": (worst(during, 11), dev_bound), "dev after": (worst(("after",), 11), STEADY_TOL_DEG),
    }
    lines = ["turning ROI: turned %+g deg in %s s (peak yaw rate %.1f deg/s); |error| worst (bound):" % (
        turn, fmt(done_at - t_cmd) if done_at else "nan", w)]
    for k in ("AP during", "AP after", "dev during", "dev after"):
        e, b = res[k]
        ok = e <= b
        lines.append("  %-10s %6s (%.1f) %s" % (k, fmt(e), b, "ok" if ok else "FAIL"))
        if not ok:
            fail.append("%s |error| %s > %.1f deg" % (k, fmt(e), b))
    fl = sorted(set(s_[13] for s_ in samples if s_[1] != "before"))
    lines.append("  bridge status flags seen through the turn: %s" % ", ".join(flag_names(f) for f in fl if f >= 0))
    lines.append("turning ROI: %s" % ("PASS" if not fail else "FAIL: " + "; ".join(fail)))
    for ln in p.bridge_stderr_new()[-10:]:
        print("    | " + ln)
    return not fail, lines


def main():
    global DEADLINE
    ap_ = argparse.ArgumentParser()
    ap_.add_argument("--ap", default="tcp:127.0.0.1:5760")
    ap_.add_argument("--bridge", default="127.0.0.1:14560", help="observe the bridge directly ('' to skip)")
    ap_.add_argument("--bridge-stderr", default="")
    ap_.add_argument("--home", required=True, help="LAT,LON,ALT,HEADING as given to SITL")
    ap_.add_argument("--mnt-type", type=int, default=6)
    ap_.add_argument("--cam-type", type=int, default=6)
    ap_.add_argument("--settle", type=float, default=3.0)
    ap_.add_argument("--heading-wait", type=float, default=45.0, help="max s to wait for a steady heading")
    ap_.add_argument("--deadline", type=float, default=280.0)
    ap_.add_argument("--no-flight", action="store_true", help="skip the last step (arm, take off, ROI while turning)")
    ap_.add_argument("--takeoff-alt", type=float, default=10.0, help="m above home for the turning ROI step")
    ap_.add_argument("--turn-deg", type=float, default=90.0, help="how far the vehicle turns with the ROI set")
    ap_.add_argument("--turn-rate", type=float, default=10.0, help="deg/s of that turn (CONDITION_YAW param2)")
    ap_.add_argument("--after-settle", type=float, default=1.0,
                     help="s after the turn ends still judged by the turn's bound (a postback period and more)")
    ap_.add_argument("--after-s", type=float, default=3.0, help="s sampled after that, judged within 2 deg")
    ap_.add_argument("--arm-wait", type=float, default=60.0, help="max s to retry arming (pre-arm checks)")
    ap_.add_argument("--signing-passphrase", default="",
                     help="set up MAVLink 2 signing in ArduPilot (SETUP_SIGNING, key = SHA-256 of the "
                          "passphrase, as MAVProxy's 'signing setup') before the reboot; the observer "
                          "signs with it too. Give the bridge the same --signing-passphrase")
    a = ap_.parse_args()
    DEADLINE = a.deadline
    lat, lon, alt, hdg = [float(v) for v in a.home.split(",")]

    log("connecting to SITL at %s as GCS 255/190" % a.ap)
    apc = connect_ap(a.ap, 40)
    log("SITL heartbeat: sys %d" % apc.target_system)
    obs = None
    if a.bridge:
        obs = mavutil.mavlink_connection("udpout:" + a.bridge, source_system=254, source_component=190)
        log("observing the bridge directly at udp %s as 254/190 (heartbeats only)" % a.bridge)
    p = Pump(apc, obs, a.bridge_stderr)
    p.spin(1.0)

    # --- parameters, then reboot (the *_TYPE parameters need one)
    ok = True
    ok &= set_param(p, "SERIAL2_PROTOCOL", 2)
    ok &= set_param(p, "MNT1_TYPE", a.mnt_type)
    ok &= set_param(p, "CAM1_TYPE", a.cam_type)
    if not ok:
        log("WARN: a parameter did not read back as set")
    if a.signing_passphrase:
        setup_signing(p, obs, a.signing_passphrase)
    r = command_long(p, mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, [1, 0], wait=3)
    log("PREFLIGHT_REBOOT_SHUTDOWN -> %s" % res_name(r))
    try:
        apc.close()
    except Exception:
        pass
    time.sleep(2.0)
    apc = connect_ap(a.ap, 40)
    p.ap = apc
    p.last_hb = 0
    t_boot = time.monotonic()
    log("reconnected after reboot")
    p.spin(0.5)
    for n in ("SERIAL2_PROTOCOL", "MNT1_TYPE", "CAM1_TYPE", "MNT1_YAW_MIN", "MNT1_YAW_MAX", "MNT1_DEFLT_MODE"):
        log("param %s = %s" % (n, read_param(p, n)))
    request_streams(p)

    # --- wait for ArduPilot to find the gimbal (it starts looking 10 s after boot)
    log("waiting for ArduPilot to find the gimbal (Mount: STATUSTEXT, then attitude status)")
    found = False
    end = time.monotonic() + 45
    while time.monotonic() < end:
        p.spin(0.5)
        mount_txt = p.mount_text_at is not None and p.mount_text_at >= t_boot
        gdas = p.get("ap", "GIMBAL_DEVICE_ATTITUDE_STATUS", 1, 1, max_age=1)
        dev = p.get("ap", "GIMBAL_DEVICE_ATTITUDE_STATUS", comp=154, max_age=1)
        if mount_txt and gdas is not None and dev is not None:
            found = True
            break
    log("gimbal found by ArduPilot: %s (%.1fs after reconnect)" % (found, time.monotonic() - t_boot))
    p.spin(2.0)  # let AUTOPILOT_STATE_FOR_GIMBAL_DEVICE start flowing
    # the EKF heading creeps for a while after yaw alignment; wait (bounded) until it holds
    # within 0.3 deg over 4 s, so the per-step readings are not blurred by a moving heading
    end = time.monotonic() + a.heading_wait
    hist = []
    while time.monotonic() < end:
        p.spin(0.5)
        att = p.get("ap", "ATTITUDE", 1, 1, max_age=1)
        if att:
            hist.append((time.monotonic(), math.degrees(att.yaw)))
        recent = [y for t, y in hist if t > time.monotonic() - 4.0]
        if hist and hist[0][0] < time.monotonic() - 4.0 and recent and max(recent) - min(recent) < 0.3:
            break
    log("vehicle heading %s deg (settled: %s)" % (fmt(hist[-1][1]) if hist else "nan",
        bool(hist) and time.monotonic() < end))
    m = p.get("ap", "GIMBAL_MANAGER_INFORMATION", 1, 1)
    if m:
        log("ArduPilot GIMBAL_MANAGER_INFORMATION: cap_flags=0x%x dev_id %d pitch [%s,%s] yaw [%s,%s] deg" % (
            m.cap_flags, m.gimbal_device_id, fmt(math.degrees(m.pitch_min)), fmt(math.degrees(m.pitch_max)),
            fmt(math.degrees(m.yaw_min)), fmt(math.degrees(m.yaw_max))))
    for (l, t, s, c), (ts, mm) in sorted(p.latest.items(), key=lambda kv: kv[0]):
        if t == "HEARTBEAT" and c != 190:
            log("heartbeat seen on %s link from %d/%d: type %d autopilot %d" % (l, s, c, mm.type, mm.autopilot))
    # The bridge's own status flags (its GIMBAL_DEVICE_ATTITUDE_STATUS, not ArduPilot's re-published
    # one, whose flags ArduPilot computes from its own mount mode): YAW_LOCK is set only while the
    # bridge holds the yaw in the earth frame (an earth-frame setpoint, which is what ArduPilot
    # sends for YAW_LOCK and for a region of interest: GIMBAL_DEVICE_SET_ATTITUDE flags 28), not
    # while it follows the vehicle (flags 0 from ArduPilot, or nothing commanded yet). It used to
    # be set whenever the gimbal reported its lock mode, i.e. after any angle command, which said
    # nothing about the frame; the released bridge still does that and shows MISMATCH here.
    report(p, "idle after discovery (no command yet)",
           "vehicle yaw ~%g; the bridge's own flags: no YAW_LOCK (nothing held in the earth frame)" % hdg,
           want_flags=(False, False))

    P = -30.0
    Y = 20.0
    steps = [
        ("DO_GIMBAL_MANAGER_PITCHYAW pitch %g yaw %g flags 0 (yaw body frame / follow)" % (P, Y),
         lambda: command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [P, Y, float("nan"), float("nan"), 0, 0, 0]),
         "body yaw %g -> earth yaw %g, pitch %g; bridge flags without YAW_LOCK (follows the vehicle)" % (
             Y, wrap180(Y + hdg), P), ("body", Y, P), (False, False)),
        ("DO_GIMBAL_MANAGER_PITCHYAW pitch %g yaw %g flags YAW_LOCK|YAW_IN_EARTH_FRAME (80)" % (P, Y),
         lambda: command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [P, Y, float("nan"), float("nan"), 16 | 64, 0, 0]),
         "earth yaw %g -> body yaw %g, pitch %g; bridge flags with YAW_LOCK (earth-frame hold)" % (
             Y, wrap180(Y - hdg), P), ("earth", Y, P), (True, False)),
        ("DO_GIMBAL_MANAGER_PITCHYAW pitch %g yaw %g flags YAW_IN_EARTH_FRAME only (64)" % (P, Y),
         lambda: command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [P, Y, float("nan"), float("nan"), 64, 0, 0]),
         "per spec earth yaw %g (body %g); ArduPilot only looks at YAW_LOCK so likely body %g, sent with flags 0:"
         " bridge flags without YAW_LOCK" % (Y, wrap180(Y - hdg), Y),
         ("earth", Y, P), (False, False)),
        ("DO_MOUNT_CONTROL pitch %g roll 0 yaw %g mode MAVLINK_TARGETING" % (P, Y),
         lambda: command_long(p, mavlink.MAV_CMD_DO_MOUNT_CONTROL, [P, 0, Y, 0, 0, 0, mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING]),
         "body yaw %g (DO_MOUNT_CONTROL yaw is body frame) -> earth %g, pitch %g; bridge flags without YAW_LOCK" % (
             Y, wrap180(Y + hdg), P), ("body", Y, P), (False, False)),
    ]
    # ROI: 100 m north of home, 57.7 m below home -> bearing 0 (north), pitch ~ -30
    roi_lat = lat + math.degrees(100.0 / 6378137.0)
    steps.append((
        "DO_SET_ROI_LOCATION 100 m north of home, 57.7 m below (COMMAND_INT, GLOBAL_RELATIVE_ALT)",
        lambda: command_int(p, mavlink.MAV_CMD_DO_SET_ROI_LOCATION, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                            [0], int(round(roi_lat * 1e7)), int(round(lon * 1e7)), -57.7),
        "earth yaw 0 (north) -> body yaw %g, pitch ~-30; bridge flags with YAW_LOCK" % wrap180(0 - hdg),
        ("earth", 0.0, -30.0), (True, False)))
    # NEUTRAL: ArduPilot's MAVLink gimbal backend does not pass NEUTRAL on to the device; it sends
    # MNT1_NEUTRAL_x (default 0, 0, 0) as a vehicle-frame angle target (GIMBAL_DEVICE_SET_ATTITUDE
    # flags 0, yaw 0, pitch 0, as seen on the wire). The bridge holds that forward and level in the
    # vehicle frame: its own flags have neither YAW_LOCK nor NEUTRAL (it was sent angles, not the
    # NEUTRAL flag); ArduPilot's re-published status says NEUTRAL, from its own mount mode.
    steps.append((
        "DO_GIMBAL_MANAGER_PITCHYAW flags NEUTRAL (2)",
        lambda: command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [float("nan")] * 4 + [2, 0, 0]),
        "neutral: MNT1_NEUTRAL_x (0, 0, 0) sent as a vehicle-frame angle: forward and level, following the vehicle"
        " (earth yaw = heading); ArduPilot's flags NEUTRAL, the bridge's without YAW_LOCK or NEUTRAL",
        ("body", 0.0, 0.0), (False, False)))

    for title, fn, expect, want, want_flags in steps:
        r = fn()
        log("sent %s -> %s" % (title, res_name(r)))
        p.spin(a.settle)
        report(p, title, expect, want, want_flags)

    print("=" * 100)
    print("SUMMARY (earth-frame yaw in deg, wrapped to +-180; 'AP' = ArduPilot's re-published status read as")
    print("vehicle-frame q yaw + vehicle ATTITUDE yaw; 'dev' = the bridge's own status, q yaw + delta_yaw)")
    print("%-58s %-5s %6s %6s | %6s %7s | %7s %6s %6s | %7s %6s %6s" % (
        "step", "frame", "yaw", "pitch", "veh", "expEarth", "APearth", "APerr", "APpit", "devEarth", "devErr", "devPit"))
    for (t, fr, wy, wp, vy, ee, ae, ap_p, de, dp) in SUMMARY:
        print("%-58s %-5s %6s %6s | %6s %7s | %7s %6s %6s | %7s %6s %6s" % (
            t, fr, fmt(wy), fmt(wp), fmt(vy), fmt(ee), fmt(ae), fmt(wrap180(ae - ee)), fmt(ap_p),
            fmt(de), fmt(wrap180(de - ee)), fmt(dp)))
    print("(the YAW_IN_EARTH_FRAME-only row is expected to be off by the heading: ArduPilot reads only YAW_LOCK)")
    print("the bridge's own status flags (expected: YAW_LOCK only while the yaw is held in the earth frame):")
    for (t, fl, (wl, wn), ok) in FLAG_CHECKS:
        print("  %-58s %-44s expected YAW_LOCK %-3s NEUTRAL %-3s %s" % (
            t, flag_names(fl) if fl >= 0 else "none", "yes" if wl else "no", "yes" if wn else "no",
            "ok" if ok else "MISMATCH"))
    print("  %d of %d as expected" % (sum(1 for c in FLAG_CHECKS if c[3]), len(FLAG_CHECKS)))
    print("-" * 100)
    turn_ok, turn_lines = True, []
    if not a.no_flight:
        turn_ok, turn_lines = turning_roi(p, a, lat, lon)
        print("=" * 100)
        for ln in turn_lines:
            print(ln)
        print("-" * 100)
    log("done; sources seen: %s" % sorted(p.seen_sources))
    # Exit 1 on either failure (2 is bad usage, argparse's); the line says which.
    if not found:
        log("FAIL: ArduPilot did not find the gimbal")
        return 1
    if not turn_ok:
        log("FAIL: the region of interest through the turn")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
