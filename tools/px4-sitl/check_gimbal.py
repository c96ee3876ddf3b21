#!/usr/bin/env python3
"""GCS-side helper for run_check.sh: drives PX4 SITL (SIH quadrotor) as a ground station on
PX4's GCS UDP port and reports what PX4 says about a MAVLink gimbal (the bridge under test).

Two phases, as run_check.sh calls them:

  --phase setup   sets MNT_MODE_IN 4, MNT_MODE_OUT 2, MAV_1_MODE 0, MAV_1_FORWARD 1 (and a slow
                  autonomous yaw rate, MPC_YAWRAUTO_MAX, so that turns can be sampled), shows
                  that MAV_1_CONFIG does not exist in SITL, and shows that PX4 SITL refuses
                  MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN (run_check.sh then stops PX4 from its shell
                  and starts it again in the same working directory, where the parameters are).
  --phase check   relays PX4's link to the bridge through a UDP relay that decodes both
                  directions (what PX4 really sends to the gimbal device: flags, rates,
                  frames), takes gimbal control as QGroundControl does
                  (DO_GIMBAL_MANAGER_CONFIGURE), arms, takes off in SIH, and runs the cases:
                  yaw lock through a turn, ROI hovering and turning, follow through a turn,
                  DO_MOUNT_CONTROL, the camera through PX4's forwarding.

For each case it prints, sampled through the case: the vehicle heading, the earth yaw and pitch
of the gimbal as PX4 forwards its GIMBAL_DEVICE_ATTITUDE_STATUS (read as QGroundControl's
GimbalController reads it: a vehicle-frame yaw plus the vehicle's heading; also plus the
status's own delta_yaw), the expected ones, the error, and GIMBAL_MANAGER_STATUS.flags.

Everything is bounded: --deadline seconds overall.
"""
import argparse
import collections
import math
import os
import select
import socket
import struct
import sys
import threading
import time

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402

mavlink = mavutil.mavlink
NAN = float("nan")

GDF = [(1, "RETRACT"), (2, "NEUTRAL"), (4, "ROLL_LOCK"), (8, "PITCH_LOCK"), (16, "YAW_LOCK"),
       (32, "YAW_IN_VEHICLE_FRAME"), (64, "YAW_IN_EARTH_FRAME"), (128, "ACCEPTS_YAW_IN_EARTH_FRAME"),
       (256, "RC_EXCLUSIVE"), (512, "RC_MIXED")]
# What QGroundControl sends (src/Gimbal/GimbalController.cc): sendPitchBodyYaw and
# sendPitchAbsoluteYaw.
QGC_BODY = (mavlink.GIMBAL_MANAGER_FLAGS_ROLL_LOCK | mavlink.GIMBAL_MANAGER_FLAGS_PITCH_LOCK
            | mavlink.GIMBAL_MANAGER_FLAGS_YAW_IN_VEHICLE_FRAME)
QGC_EARTH = (mavlink.GIMBAL_MANAGER_FLAGS_ROLL_LOCK | mavlink.GIMBAL_MANAGER_FLAGS_PITCH_LOCK
             | mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK | mavlink.GIMBAL_MANAGER_FLAGS_YAW_IN_EARTH_FRAME)
INT_TYPES = (mavlink.MAV_PARAM_TYPE_UINT8, mavlink.MAV_PARAM_TYPE_INT8, mavlink.MAV_PARAM_TYPE_UINT16,
             mavlink.MAV_PARAM_TYPE_INT16, mavlink.MAV_PARAM_TYPE_UINT32, mavlink.MAV_PARAM_TYPE_INT32)

T0 = time.monotonic()
DEADLINE = 300.0
GCS_SYS, GCS_COMP = 255, 190  # QGroundControl's ids


def now():
    return time.monotonic() - T0


def log(*a):
    print("[%6.1fs] " % now() + " ".join(str(x) for x in a), flush=True)


def check_deadline():
    if now() > DEADLINE:
        log("FAIL: overall deadline of %.0fs reached" % DEADLINE)
        sys.exit(1)


def flag_names(v):
    n = [name for bit, name in GDF if v & bit]
    return "%d(%s)" % (v, "|".join(n) if n else "-")


def isnan(v):
    return isinstance(v, float) and math.isnan(v)


def q_to_euler_deg(q):
    w, x, y, z = q
    if any(isnan(c) for c in q):
        return (NAN,) * 3
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    s = max(-1.0, min(1.0, 2 * (w * y - z * x)))
    pitch = math.asin(s)
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return tuple(math.degrees(v) for v in (roll, pitch, yaw))


def wrap180(d):
    if d is None or isnan(d):
        return NAN
    return (d + 180.0) % 360.0 - 180.0


def wrap360(d):
    if d is None or isnan(d):
        return NAN
    return d % 360.0


def fmt(v, nd=1):
    return "nan" if v is None or isnan(v) else ("%.*f" % (nd, v))


def yaw_in_vehicle_frame(flags):
    """QGroundControl's GimbalController::_yawInVehicleFrame."""
    if flags & mavlink.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME:
        return True
    if flags & mavlink.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME:
        return False
    return not (flags & mavlink.GIMBAL_DEVICE_FLAGS_YAW_LOCK)


def bearing_deg(lat1, lon1, lat2, lon2):
    p1, p2 = math.radians(lat1), math.radians(lat2)
    dl = math.radians(lon2 - lon1)
    y = math.sin(dl) * math.cos(p2)
    x = math.cos(p1) * math.sin(p2) - math.sin(p1) * math.cos(p2) * math.cos(dl)
    return math.degrees(math.atan2(y, x))


def distance_m(lat1, lon1, lat2, lon2):
    r = 6371000.0
    p1, p2 = math.radians(lat1), math.radians(lat2)
    a = math.sin((p2 - p1) / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(math.radians(lon2 - lon1) / 2) ** 2
    return 2 * r * math.asin(math.sqrt(a))


def offset_ll(lat, lon, north_m, east_m):
    return (lat + math.degrees(north_m / 6378137.0),
            lon + math.degrees(east_m / (6378137.0 * math.cos(math.radians(lat)))))


# ------------------------------------------------------------------------------------------
# The relay between PX4's link and the bridge: forwards datagrams unchanged both ways and
# decodes a copy of each, so that the check sees what PX4 sends to the gimbal device.


class Relay(threading.Thread):
    def __init__(self, listen, bridge):
        super().__init__(daemon=True)
        self.bridge = bridge
        self.px4_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.px4_sock.bind(listen)
        self.br_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.br_sock.bind(("127.0.0.1", 0))
        self.px4_addr = None
        self.parsers = {d: mavlink.MAVLink(None) for d in ("px4>br", "br>px4")}
        for prs in self.parsers.values():
            prs.robust_parsing = True
        self.lock = threading.Lock()
        self.stop = False
        self.times = collections.defaultdict(collections.deque)  # (dir, type) -> times
        self.counts = collections.Counter()
        self.set_att = []  # (t, flags, roll, pitch, yaw, wx, wy, wz, target)
        self.cmds = []  # (t, dir, text)
        self.latest = {}  # (dir, type) -> (t, msg)
        self.flag_changes = []  # (t, flags)
        self.sources = set()

    def run(self):
        while not self.stop:
            try:
                r, _, _ = select.select([self.px4_sock, self.br_sock], [], [], 0.2)
            except (OSError, ValueError):
                return
            for s in r:
                try:
                    data, addr = s.recvfrom(65535)
                except OSError:
                    continue
                if s is self.px4_sock:
                    self.px4_addr = addr
                    self.br_sock.sendto(data, self.bridge)
                    self._parse("px4>br", data)
                elif self.px4_addr is not None:
                    self.px4_sock.sendto(data, self.px4_addr)
                    self._parse("br>px4", data)

    def _parse(self, d, data):
        try:
            msgs = self.parsers[d].parse_buffer(data) or []
        except Exception:
            return
        t = now()
        with self.lock:
            for m in msgs:
                ty = m.get_type()
                if ty == "BAD_DATA":
                    continue
                self.sources.add((d, m.get_srcSystem(), m.get_srcComponent()))
                self.counts[(d, ty)] += 1
                q = self.times[(d, ty)]
                q.append(t)
                while q and q[0] < t - 120:
                    q.popleft()
                self.latest[(d, ty)] = (t, m)
                if ty == "GIMBAL_DEVICE_SET_ATTITUDE":
                    r_, p_, y_ = q_to_euler_deg(list(m.q))
                    self.set_att.append((t, m.flags, r_, p_, y_, m.angular_velocity_x, m.angular_velocity_y,
                                         m.angular_velocity_z, (m.target_system, m.target_component)))
                    if not self.flag_changes or self.flag_changes[-1][1] != m.flags:
                        self.flag_changes.append((t, m.flags))
                elif ty in ("COMMAND_LONG", "COMMAND_INT"):
                    name = mavlink.enums["MAV_CMD"].get(m.command)
                    name = name.name if name else str(m.command)
                    self.cmds.append((t, d, "%s %d/%d -> %d/%d %s p1=%s p2=%s" % (
                        ty, m.get_srcSystem(), m.get_srcComponent(), m.target_system, m.target_component,
                        name, fmt(m.param1, 0), fmt(m.param2, 0))))
                elif ty == "COMMAND_ACK":
                    name = mavlink.enums["MAV_CMD"].get(m.command)
                    self.cmds.append((t, d, "COMMAND_ACK %d/%d: %s -> %s" % (
                        m.get_srcSystem(), m.get_srcComponent(), name.name if name else m.command, res_name(m.result))))

    def rate(self, d, ty, t0, t1):
        with self.lock:
            q = list(self.times.get((d, ty), ()))
        n = sum(1 for t in q if t0 <= t <= t1)
        return n / max(t1 - t0, 1e-3)

    def get(self, d, ty, max_age=None):
        with self.lock:
            v = self.latest.get((d, ty))
        if v is None or (max_age is not None and now() - v[0] > max_age):
            return None
        return v[1]

    def set_att_between(self, t0, t1):
        with self.lock:
            return [s for s in self.set_att if t0 <= s[0] <= t1]

    def cmds_between(self, t0, t1):
        with self.lock:
            return [c for c in self.cmds if t0 <= c[0] <= t1]

    def close(self):
        self.stop = True
        for s in (self.px4_sock, self.br_sock):
            try:
                s.close()
            except OSError:
                pass


# ------------------------------------------------------------------------------------------
# The ground station's side


class Pump:
    """Reads PX4's GCS link, keeps the latest of each message per source."""

    def __init__(self, conn, direct=None):
        self.c = conn
        self.direct = direct  # optional direct connection to the bridge
        self.latest = {}  # (link, type, sys, comp) -> (time, msg)
        self.acks = []
        self.params = {}
        self.last_hb = 0.0
        self.seen = set()
        self.texts = []
        self.captured = []

    def send_heartbeats(self):
        t = time.monotonic()
        if t - self.last_hb < 1.0:
            return
        self.last_hb = t
        for c in (self.c, self.direct):
            if c is not None:
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
            src = (link, m.get_srcSystem(), m.get_srcComponent())
            if src not in self.seen:
                self.seen.add(src)
                log("new source on the %s link: %d/%d (%s)" % (link, src[1], src[2], t))
            self.latest[(link, t, m.get_srcSystem(), m.get_srcComponent())] = (time.monotonic(), m)
            if t == "STATUSTEXT":
                log("%s STATUSTEXT %d/%d: %s" % (link, m.get_srcSystem(), m.get_srcComponent(), m.text))
                self.texts.append(m.text)
            elif t == "COMMAND_ACK":
                self.acks.append((link, m))
            elif t == "PARAM_VALUE" and link == "px4":
                self.params[m.param_id] = m
            elif t == "CAMERA_IMAGE_CAPTURED":
                self.captured.append((link, m))

    def spin(self, seconds):
        end = time.monotonic() + seconds
        while True:
            check_deadline()
            self.send_heartbeats()
            n = self._recv("px4", self.c)
            if self.direct is not None:
                n += self._recv("direct", self.direct)
            if time.monotonic() >= end:
                return
            if n == 0:
                time.sleep(0.005)

    def get(self, t, sysid=None, comp=None, max_age=None, link="px4"):
        best = None
        for (lk, tt, s, c), (ts, m) in self.latest.items():
            if lk != link or tt != t:
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


def res_name(r):
    if r is None:
        return "no ACK"
    e = mavlink.enums["MAV_RESULT"].get(r)
    return e.name if e else str(r)


def cmd_name(c):
    e = mavlink.enums["MAV_CMD"].get(c)
    return e.name if e else str(c)


def wait_ack(p, cmd, wait, comp=None, link="px4"):
    end = time.monotonic() + wait
    while time.monotonic() < end:
        p.spin(0.05)
        for lk, a in p.acks:
            if lk == link and a.command == cmd and (comp is None or a.get_srcComponent() == comp):
                return a.result
    return None


def command_long(p, cmd, params, comp=1, wait=3.0, conn=None, link="px4", sysid=1):
    p.acks.clear()
    prm = list(params) + [0] * (7 - len(params))
    (conn or p.c).mav.command_long_send(sysid, comp, cmd, 0, *prm)
    return wait_ack(p, cmd, wait, comp, link)


def command_int(p, cmd, frame, params4, x, y, z, comp=1, wait=3.0):
    p.acks.clear()
    prm = list(params4) + [0] * (4 - len(params4))
    p.c.mav.command_int_send(1, comp, frame, cmd, 0, 0, *prm, x, y, z)
    return wait_ack(p, cmd, wait, comp)


def param_decode(m):
    if m.param_type in INT_TYPES:  # PX4 encodes integers bytewise in the float
        return struct.unpack("<i", struct.pack("<f", m.param_value))[0]
    return m.param_value


def read_param(p, name, wait=2.0):
    p.params.pop(name, None)
    p.c.mav.param_request_read_send(1, 1, name.encode(), -1)
    end = time.monotonic() + wait
    while time.monotonic() < end:
        p.spin(0.05)
        if name in p.params:
            return p.params[name]
    return None


def set_param(p, name, value):
    cur = read_param(p, name)
    if cur is None:
        log("PARAM %s: no PARAM_VALUE (the parameter does not exist here)" % name)
        return False
    ty = cur.param_type
    enc = struct.unpack("<f", struct.pack("<i", int(value)))[0] if ty in INT_TYPES else float(value)
    for _ in range(3):
        p.params.pop(name, None)
        p.c.mav.param_set_send(1, 1, name.encode(), enc, ty)
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            p.spin(0.05)
            if name in p.params:
                v = param_decode(p.params[name])
                ok = abs(v - value) < 1e-3
                log("PARAM_SET %s = %s (was %s) -> PARAM_VALUE %s %s" % (
                    name, value, param_decode(cur), v, "ok" if ok else "MISMATCH"))
                return ok
    log("PARAM_SET %s = %s: no PARAM_VALUE" % (name, value))
    return False


def connect_px4(url, timeout):
    end = time.monotonic() + timeout
    last = None
    while time.monotonic() < end:
        check_deadline()
        try:
            c = mavutil.mavlink_connection(url, source_system=GCS_SYS, source_component=GCS_COMP)
            t_end = time.monotonic() + 5
            while time.monotonic() < t_end:
                c.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
                m = c.recv_match(type="HEARTBEAT", blocking=True, timeout=1)
                if m is not None and m.get_srcComponent() == 1 and m.autopilot == mavlink.MAV_AUTOPILOT_PX4:
                    return c
            c.close()
        except Exception as e:  # PX4 not up yet
            last = e
        time.sleep(0.5)
    raise SystemExit("FAIL: no PX4 heartbeat at %s within %ss (%s)" % (url, timeout, last))


# ------------------------------------------------------------------------------------------
# setup phase


def phase_setup(a):
    log("connecting to PX4 at %s as GCS %d/%d" % (a.px4, GCS_SYS, GCS_COMP))
    c = connect_px4(a.px4, 60)
    p = Pump(c)
    p.spin(1.0)
    log("PX4 heartbeat from sys %d" % c.target_system)
    m = read_param(p, "MAV_1_CONFIG")
    log("MAV_1_CONFIG: %s" % ("absent (no PARAM_VALUE): SITL has no serial ports, so no MAV_x_CONFIG"
                              if m is None else "present = %s" % param_decode(m)))
    ok = True
    for name, v in (("MNT_MODE_IN", 4), ("MNT_MODE_OUT", 2), ("MAV_1_MODE", 0), ("MAV_1_FORWARD", 1),
                    ("MPC_YAWRAUTO_MAX", a.yaw_rate)):
        ok &= set_param(p, name, v)
    for name in ("MAV_1_RATE", "MAV_HB_FORW_EN", "MAV_SYS_ID", "MNT_RANGE_YAW", "MNT_MAX_PITCH", "MNT_MIN_PITCH"):
        m = read_param(p, name)
        log("param %s = %s" % (name, param_decode(m) if m else "absent"))
    p.spin(1.0)  # PX4 saves parameters asynchronously
    r = command_long(p, mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, [1, 0], wait=3)
    log("PREFLIGHT_REBOOT_SHUTDOWN (reboot) -> %s (SITL is built without CONFIG_BOARDCTL_RESET: "
        "Commander refuses; run_check.sh restarts PX4 itself)" % res_name(r))
    if not ok:
        log("FAIL: the setup's parameters did not all take")
    return 0 if ok else 1


# ------------------------------------------------------------------------------------------
# check phase


class Case:
    def __init__(self, name):
        self.name = name
        self.rows = []  # (t, segment, heading, exp_yaw, yaw_qgc, yaw_dy, exp_pitch, pitch, mgr_flags, dev_flags)
        self.t0 = now()
        self.t1 = None


class Checker:
    def __init__(self, p, relay, a):
        self.p = p
        self.relay = relay
        self.a = a
        self.cases = []
        self.dev_comp = 154

    def heading(self):
        att = self.p.get("ATTITUDE", 1, 1, max_age=1)
        return None if att is None else wrap360(math.degrees(att.yaw))

    def position(self):
        return self.p.get("GLOBAL_POSITION_INT", 1, 1, max_age=2)

    def reading(self):
        """(heading, earth yaw as QGC reads it, earth yaw with delta_yaw, pitch, dev flags, mgr flags)."""
        hdg = self.heading()
        g = self.p.get("GIMBAL_DEVICE_ATTITUDE_STATUS", comp=self.dev_comp, max_age=1)
        mgr = self.p.get("GIMBAL_MANAGER_STATUS", 1, 1, max_age=3)
        yq = yd = pitch = NAN
        dflags = None
        if g is not None:
            _, pitch, y = q_to_euler_deg(list(g.q))
            dflags = g.flags
            if yaw_in_vehicle_frame(g.flags):
                yq = wrap180(y + hdg) if hdg is not None else NAN
                dy = g.delta_yaw
                yd = wrap180(y + math.degrees(dy)) if not isnan(dy) else NAN
            else:
                yq = yd = wrap180(y)
        return hdg, yq, yd, pitch, dflags, (mgr.flags if mgr else None)

    def sample(self, case, segment, expect):
        hdg, yq, yd, pitch, dflags, mflags = self.reading()
        ey, ep = expect(hdg) if hdg is not None else (NAN, NAN)
        case.rows.append((now(), segment, hdg, ey, yq, yd, ep, pitch, mflags, dflags))
        print("  %6.1fs %-6s hdg %6s | earth yaw exp %7s  QGC %7s err %6s  (delta_yaw %7s) | pitch exp %6s got %6s"
              " err %5s | mgr flags %s | dev flags %s" % (
                  now(), segment, fmt(hdg), fmt(wrap180(ey)), fmt(yq), fmt(wrap180(yq - ey)), fmt(yd),
                  fmt(ep), fmt(pitch), fmt(pitch - ep), flag_names(mflags) if mflags is not None else "none",
                  flag_names(dflags) if dflags is not None else "none"), flush=True)

    def hold(self, case, seconds, segment, expect, step=0.5):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.p.spin(step)
            self.sample(case, segment, expect)

    def turn(self, target, case=None, expect=None, timeout=25.0, step=0.5):
        """Turns the hovering vehicle to `target` degrees with DO_REPOSITION (param4: yaw)."""
        r = command_long(self.p, mavlink.MAV_CMD_DO_REPOSITION,
                         [-1, mavlink.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE, 0, math.radians(wrap180(target)),
                          NAN, NAN, NAN], wait=2)
        log("DO_REPOSITION yaw %g deg (param4 in radians, as PX4's navigator takes it) -> %s" % (target, res_name(r)))
        end = time.monotonic() + timeout
        steady = None
        while time.monotonic() < end:
            self.p.spin(step)
            if case is not None:
                self.sample(case, "turn", expect)
            h = self.heading()
            if h is not None and abs(wrap180(h - target)) < 1.5:
                if steady is None:
                    steady = time.monotonic()
                elif time.monotonic() - steady > 1.0:
                    return True
            else:
                steady = None
        log("WARN: heading %s did not reach %g within %gs" % (fmt(self.heading()), target, timeout))
        return False

    def begin(self, name):
        print("=" * 120)
        c = Case(name)
        self.cases.append(c)
        log("CASE: %s" % name)
        return c

    def end(self, c):
        c.t1 = now()
        self.capture_report(c.t0, c.t1)
        lines = self.bridge_stderr_new()
        print("  bridge stderr during the case: %s" % ("(nothing)" if not lines else ""))
        for ln in lines[-12:]:
            print("    | " + ln)

    def capture_report(self, t0, t1):
        if self.relay is None:
            return
        sa = self.relay.set_att_between(t0, t1)
        dur = max(t1 - t0, 1e-3)
        flags = collections.Counter(s[1] for s in sa)
        print("  PX4 -> bridge during the case (%.1fs): GIMBAL_DEVICE_SET_ATTITUDE %d (%.1f Hz), flags %s" % (
            dur, len(sa), len(sa) / dur, ", ".join("%s x%d" % (flag_names(f), n) for f, n in flags.items()) or "-"))
        if sa:
            for label, s in (("first", sa[0]), ("last", sa[-1])):
                print("    %s: q -> roll %s pitch %s yaw %s, angular velocity %s %s %s rad/s, target %d/%d" % (
                    label, fmt(s[2]), fmt(s[3]), fmt(s[4]), fmt(s[5], 3), fmt(s[6], 3), fmt(s[7], 3), s[8][0], s[8][1]))
        print("    AUTOPILOT_STATE_FOR_GIMBAL_DEVICE %.1f Hz, GLOBAL_POSITION_INT %.1f Hz to the bridge; "
              "GIMBAL_DEVICE_ATTITUDE_STATUS %.1f Hz from it" % (
                  self.relay.rate("px4>br", "AUTOPILOT_STATE_FOR_GIMBAL_DEVICE", t0, t1),
                  self.relay.rate("px4>br", "GLOBAL_POSITION_INT", t0, t1),
                  self.relay.rate("br>px4", "GIMBAL_DEVICE_ATTITUDE_STATUS", t0, t1)))
        for t, d, txt in self.relay.cmds_between(t0, t1)[:12]:
            print("    %6.1fs %s %s" % (t, d, txt))

    def bridge_stderr_new(self):
        path = self.a.bridge_stderr
        if not path or not os.path.exists(path):
            return []
        with open(path, "r", errors="replace") as f:
            f.seek(getattr(self, "_err_pos", 0))
            data = f.read()
            self._err_pos = f.tell()
        return [ln for ln in data.splitlines() if ln.strip()]


def verdict(case, seg, yaw_tol, pitch_tol):
    rows = [r for r in case.rows if r[1] == seg]
    if not rows:
        return None
    ey = [abs(wrap180(r[4] - r[3])) for r in rows if not isnan(r[4]) and not isnan(r[3])]
    ep = [abs(r[7] - r[6]) for r in rows if not isnan(r[7]) and not isnan(r[6])]
    if not ey:
        return ("no data", NAN, NAN, len(rows))
    my = max(ey)
    mp = max(ep) if ep else NAN
    ok = my <= yaw_tol and (isnan(mp) or mp <= pitch_tol)
    return ("PASS" if ok else "FAIL", my, mp, len(rows))


def phase_check(a):
    relay = None
    if a.relay:
        lp, bp = a.relay.split(":")
        relay = Relay(("127.0.0.1", int(lp)), ("127.0.0.1", int(bp)))
        relay.start()
        log("relay: PX4's link -> 127.0.0.1:%s -> bridge 127.0.0.1:%s (both directions decoded)" % (lp, bp))
    direct = None
    if a.direct_bridge:
        direct = mavutil.mavlink_connection("udpout:" + a.direct_bridge, source_system=GCS_SYS,
                                            source_component=GCS_COMP)
        log("also talking to the bridge directly at %s (for the camera, where PX4 does not forward)" % a.direct_bridge)
    log("connecting to PX4 at %s as GCS %d/%d" % (a.px4, GCS_SYS, GCS_COMP))
    c = connect_px4(a.px4, 60)
    p = Pump(c, direct)
    chk = Checker(p, relay, a)
    p.spin(1.0)
    for n in ("MNT_MODE_IN", "MNT_MODE_OUT", "MAV_1_MODE", "MAV_1_FORWARD", "MAV_1_CONFIG", "MPC_YAWRAUTO_MAX"):
        m = read_param(p, n)
        log("param %s = %s" % (n, param_decode(m) if m else "absent"))
    # What QGroundControl asks for; ATTITUDE and GLOBAL_POSITION_INT are streamed by SITL's rc.
    for mid, us in ((mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS, 200000),
                    (mavlink.MAVLINK_MSG_ID_VFR_HUD, 200000)):
        r = command_long(p, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, [mid, us], wait=1.5)
        log("SET_MESSAGE_INTERVAL %s %d us -> %s" % (mavlink.mavlink_map[mid].msgname, us, res_name(r)))

    # --- discovery: the gimbal device and camera as PX4 relays them
    log("waiting for the gimbal through PX4 (heartbeats 154/100, GIMBAL_MANAGER_INFORMATION, statuses)")
    found = False
    info = None
    end = time.monotonic() + 40
    last_req = 0
    while time.monotonic() < end:
        p.spin(0.25)
        if info is None and time.monotonic() - last_req > 1.0:
            last_req = time.monotonic()
            p.c.mav.command_long_send(1, 1, mavlink.MAV_CMD_REQUEST_MESSAGE, 0,
                                      mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION, 0, 0, 0, 0, 0, 0)
        info = p.get("GIMBAL_MANAGER_INFORMATION", 1, 1)
        if (info is not None and p.get("GIMBAL_DEVICE_ATTITUDE_STATUS", comp=154, max_age=1) is not None
                and p.get("GIMBAL_MANAGER_STATUS", 1, 1, max_age=2) is not None):
            found = True
            break
    log("gimbal found through PX4: %s" % found)
    if info is not None:
        log("GIMBAL_MANAGER_INFORMATION (1/1): cap_flags 0x%x device %d pitch [%s, %s] yaw [%s, %s] deg" % (
            info.cap_flags, info.gimbal_device_id, fmt(math.degrees(info.pitch_min)), fmt(math.degrees(info.pitch_max)),
            fmt(math.degrees(info.yaw_min)), fmt(math.degrees(info.yaw_max))))
    for (lk, t, s, cc), (ts, mm) in sorted(p.latest.items(), key=lambda kv: kv[0]):
        if t == "HEARTBEAT" and lk == "px4":
            log("heartbeat through PX4 from %d/%d: type %d autopilot %d" % (s, cc, mm.type, mm.autopilot))
    if relay is not None:
        t1 = now()
        log("link PX4 <-> bridge, last 5 s: " + ", ".join(
            "%s %s %.1f Hz" % (d, ty, relay.rate(d, ty, t1 - 5, t1))
            for (d, ty) in sorted(relay.times) if relay.rate(d, ty, t1 - 5, t1) > 0))
        for t, d, txt in relay.cmds[:16]:
            log("  link command %6.1fs %s %s" % (t, d, txt))
        log("before any gimbal command:")
        chk.capture_report(0, now())
    if not found:
        log("FAIL: PX4 does not relay the gimbal")

    # --- take gimbal control as QGroundControl does
    r = command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE, [GCS_SYS, GCS_COMP, -1, -1, NAN, NAN, 0])
    log("DO_GIMBAL_MANAGER_CONFIGURE primary %d/%d -> %s" % (GCS_SYS, GCS_COMP, res_name(r)))
    p.spin(1.0)
    m = p.get("GIMBAL_MANAGER_STATUS", 1, 1, max_age=3)
    if m:
        log("GIMBAL_MANAGER_STATUS: flags %s device %d primary %d/%d" % (
            flag_names(m.flags), m.gimbal_device_id, m.primary_control_sysid, m.primary_control_compid))

    # --- arm and take off
    pos = None
    end = time.monotonic() + 60
    armed = False
    while time.monotonic() < end and not armed:
        p.spin(1.0)
        pos = chk.position()
        if pos is None or pos.lat == 0:
            continue
        r = command_long(p, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, [1, 0], wait=2)
        log("arm -> %s" % res_name(r))
        armed = r == mavlink.MAV_RESULT_ACCEPTED
        if not armed:
            p.spin(2.0)
    if not armed:
        log("FAIL: could not arm")
        return 1
    home_amsl = pos.alt / 1000.0
    r = command_long(p, mavlink.MAV_CMD_NAV_TAKEOFF, [NAN, 0, 0, NAN, NAN, NAN, home_amsl + a.alt])
    log("NAV_TAKEOFF to %.1f m AMSL (%g m up) -> %s" % (home_amsl + a.alt, a.alt, res_name(r)))
    end = time.monotonic() + 40
    while time.monotonic() < end:
        p.spin(0.5)
        pos = chk.position()
        if pos is not None and pos.relative_alt / 1000.0 > a.alt - 0.7:
            break
    p.spin(3.0)
    pos = chk.position()
    log("hovering at %s m, heading %s" % (fmt(pos.relative_alt / 1000.0 if pos else NAN), fmt(chk.heading())))
    r = command_long(p, mavlink.MAV_CMD_CONDITION_YAW, [60, 20, 0, 0], wait=2)
    log("CONDITION_YAW 60 -> %s (PX4 takes it only as a mission item)" % res_name(r))
    chk.turn(60)

    Y_LOCK, P_LOCK = 20.0, -20.0
    # 1. yaw lock (earth frame) through a turn
    case = chk.begin("1. yaw lock: DO_GIMBAL_MANAGER_PITCHYAW pitch %g yaw %g flags %s (QGC's absolute yaw), "
                     "vehicle turns 60 -> 150" % (P_LOCK, Y_LOCK, QGC_EARTH))
    exp1 = lambda h: (Y_LOCK, P_LOCK)  # noqa: E731
    r = command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [P_LOCK, Y_LOCK, NAN, NAN, QGC_EARTH, 0, 0])
    log("PITCHYAW -> %s" % res_name(r))
    chk.hold(case, a.settle, "settle", exp1)
    chk.hold(case, 2.0, "hover", exp1)
    chk.turn(150, case, exp1)
    chk.hold(case, 3.0, "after", exp1)
    chk.end(case)

    # 2. ROI while hovering and while turning
    # 100 m away at 60 deg right of the nose (210 deg while the vehicle heads 150; 30 deg left of
    # the nose after the turn to 240), 57.7 m below: 30 deg down. Within the gimbal's yaw range
    # (+-170 deg from the nose, GIMBAL_MANAGER_INFORMATION) all along.
    pos = chk.position()
    b = math.radians(wrap360(chk.heading() + 60.0))
    roi_lat, roi_lon = offset_ll(pos.lat / 1e7, pos.lon / 1e7, 100.0 * math.cos(b), 100.0 * math.sin(b))
    roi_alt = pos.alt / 1000.0 - 57.7

    def exp2(h):
        q = chk.position()
        if q is None:
            return (NAN, NAN)
        la, lo = q.lat / 1e7, q.lon / 1e7
        d = distance_m(la, lo, roi_lat, roi_lon)
        return (bearing_deg(la, lo, roi_lat, roi_lon), math.degrees(math.atan2(roi_alt - q.alt / 1000.0, d)))

    case = chk.begin("2. ROI: DO_SET_ROI_LOCATION (COMMAND_INT, MAV_FRAME_GLOBAL) %.7f %.7f %.1f m AMSL, ~100 m "
                     "away, hovering, then the vehicle turns 150 -> 240" % (roi_lat, roi_lon, roi_alt))
    r = command_int(p, mavlink.MAV_CMD_DO_SET_ROI_LOCATION, mavlink.MAV_FRAME_GLOBAL, [0],
                    int(round(roi_lat * 1e7)), int(round(roi_lon * 1e7)), roi_alt)
    log("DO_SET_ROI_LOCATION -> %s; expected bearing %s pitch %s" % (res_name(r), *[fmt(v) for v in exp2(0)]))
    chk.hold(case, a.settle, "settle", exp2)
    chk.hold(case, 3.0, "hover", exp2)
    chk.turn(240, case, exp2)
    chk.hold(case, 3.0, "after", exp2)
    r = command_long(p, mavlink.MAV_CMD_DO_SET_ROI_NONE, [0])
    log("DO_SET_ROI_NONE -> %s" % res_name(r))
    chk.end(case)

    # 3. follow: vehicle-frame yaw, no lock
    Y_F, P_F = 30.0, -10.0
    case = chk.begin("3. follow: DO_GIMBAL_MANAGER_PITCHYAW pitch %g yaw %g flags %s (QGC's body yaw), "
                     "vehicle turns 240 -> 330" % (P_F, Y_F, QGC_BODY))
    exp3 = lambda h: (wrap180(h + Y_F), P_F)  # noqa: E731
    r = command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [P_F, Y_F, NAN, NAN, QGC_BODY, 0, 0])
    log("PITCHYAW -> %s" % res_name(r))
    chk.hold(case, a.settle, "settle", exp3)
    chk.hold(case, 2.0, "hover", exp3)
    chk.turn(330, case, exp3)
    chk.hold(case, 3.0, "after", exp3)
    chk.end(case)

    # 4. DO_MOUNT_CONTROL (PX4: pitch absolute, yaw body frame)
    Y_M, P_M = -45.0, -40.0
    case = chk.begin("4. DO_MOUNT_CONTROL pitch %g roll 0 yaw %g mode MAVLINK_TARGETING, hovering" % (P_M, Y_M))
    exp4 = lambda h: (wrap180(h + Y_M), P_M)  # noqa: E731
    r = command_long(p, mavlink.MAV_CMD_DO_MOUNT_CONTROL, [P_M, 0, Y_M, 0, 0, 0, mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING])
    log("DO_MOUNT_CONTROL -> %s" % res_name(r))
    chk.hold(case, a.settle, "settle", exp4)
    chk.hold(case, 3.0, "hover", exp4)
    chk.end(case)

    # 5. the camera through PX4's forwarding
    print("=" * 120)
    log("CASE: 5. camera (component 100) through PX4's forwarding")
    cam_ok = True
    t5 = now()
    p.captured.clear()
    r = command_long(p, mavlink.MAV_CMD_REQUEST_MESSAGE, [mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION], comp=100, wait=3)
    p.spin(1.0)
    ci = p.get("CAMERA_INFORMATION", comp=100)
    log("REQUEST_MESSAGE CAMERA_INFORMATION to 1/100 -> %s" % res_name(r))
    if ci is not None:
        log("  CAMERA_INFORMATION from %d/%d: vendor %r model %r firmware 0x%x flags 0x%x resolution %dx%d "
            "definition v%d %r" % (ci.get_srcSystem(), ci.get_srcComponent(), bytes(ci.vendor_name).rstrip(b"\0"),
                                   bytes(ci.model_name).rstrip(b"\0"), ci.firmware_version, ci.flags,
                                   ci.resolution_h, ci.resolution_v, ci.cam_definition_version, ci.cam_definition_uri))
    else:
        cam_ok = False
        log("  no CAMERA_INFORMATION through PX4")
    pos = chk.position()
    hdg = chk.heading()
    r = command_long(p, mavlink.MAV_CMD_IMAGE_START_CAPTURE, [0, 0, 1, 1], comp=100, wait=3)
    log("IMAGE_START_CAPTURE (1 image, sequence 1) to 1/100 -> %s" % res_name(r))
    end = time.monotonic() + 6
    while time.monotonic() < end and not p.captured:
        p.spin(0.2)
    if not p.captured and direct is not None:
        log("  nothing through PX4; asking the bridge directly")
        r = command_long(p, mavlink.MAV_CMD_IMAGE_START_CAPTURE, [0, 0, 1, 2], comp=100, wait=3, conn=direct,
                         link="direct", sysid=0)
        log("  IMAGE_START_CAPTURE directly -> %s" % res_name(r))
        end = time.monotonic() + 6
        while time.monotonic() < end and not p.captured:
            p.spin(0.2)
    if p.captured:
        lk, m = next((c for c in p.captured if c[0] == "px4"), p.captured[0])
        _, cp, cy = q_to_euler_deg(list(m.q))
        log("  CAMERA_IMAGE_CAPTURED (%s link) from %d/%d: index %d result %d lat %.7f lon %.7f alt %.2f m rel %.2f m "
            "q -> yaw %s pitch %s url %r" % (lk, m.get_srcSystem(), m.get_srcComponent(), m.image_index,
                                           m.capture_result, m.lat / 1e7, m.lon / 1e7, m.alt / 1000.0,
                                           m.relative_alt / 1000.0, fmt(cy), fmt(cp), m.file_url))
        carried = (pos is not None and m.lat != 0
                   and distance_m(m.lat / 1e7, m.lon / 1e7, pos.lat / 1e7, pos.lon / 1e7) < 20)
        if pos is not None:
            log("  vehicle at the time: lat %.7f lon %.7f alt %.2f m rel %.2f m heading %s; position %s" % (
                pos.lat / 1e7, pos.lon / 1e7, pos.alt / 1000.0, pos.relative_alt / 1000.0, fmt(hdg),
                "carried" if carried else "NOT carried (no GLOBAL_POSITION_INT reaches the bridge?)"))
        if lk != "px4" or not carried:
            cam_ok = False
    else:
        cam_ok = False
        log("  no CAMERA_IMAGE_CAPTURED")
    chk.capture_report(t5, now())

    # --- summary
    print("=" * 120)
    print("SUMMARY (earth yaw as QGroundControl reads PX4's forwarded GIMBAL_DEVICE_ATTITUDE_STATUS: a vehicle-frame")
    print("q yaw plus the vehicle's heading; errors are max |got - expected| over the segment, deg)")
    print("%-86s %-6s %5s %8s %8s %s" % ("case", "seg", "n", "yawErr", "pitchErr", "verdict"))
    overall = True
    tol = {"hover": (3.0, 3.0), "turn": (10.0, 5.0), "after": (3.0, 3.0)}
    for cs in chk.cases:
        for seg in ("hover", "turn", "after"):
            v = verdict(cs, seg, *tol[seg])
            if v is None:
                continue
            print("%-86s %-6s %5d %8s %8s %s" % (cs.name[:86], seg, v[3], fmt(v[1]), fmt(v[2]), v[0]))
            overall &= v[0] == "PASS"
        mf = collections.Counter(r[8] for r in cs.rows if r[1] != "settle")
        print("%-86s manager flags relayed: %s" % ("", ", ".join("%s x%d" % (flag_names(f) if f is not None else "none", n)
                                                                 for f, n in mf.items())))
    print("%-86s %-6s %5s %8s %8s %s" % ("5. camera through PX4 (CAMERA_INFORMATION, a capture with the position)", "", "",
                                          "", "", "PASS" if cam_ok else "FAIL"))
    overall &= cam_ok
    print("(tolerances: hover/after 3 deg; during the turn 10 deg yaw, 5 deg pitch)")
    if relay is not None:
        print("-" * 120)
        print("GIMBAL_DEVICE_SET_ATTITUDE flags PX4 sent, in order of change:")
        for t, f in relay.flag_changes:
            print("  %6.1fs %s" % (t, flag_names(f)))
        print("message counts on the PX4 <-> bridge link: " + ", ".join(
            "%s %s %d" % (d, ty, n) for (d, ty), n in sorted(relay.counts.items())))
        relay.close()
    log("done; overall %s" % ("PASS" if overall else "FAIL"))
    return 0 if overall else 1


def main():
    global DEADLINE
    ap = argparse.ArgumentParser()
    ap.add_argument("--phase", choices=("setup", "check"), required=True)
    ap.add_argument("--px4", default="udpout:127.0.0.1:18570", help="PX4's GCS link (mavlink -u port of instance 0)")
    ap.add_argument("--relay", default="14561:14560",
                    help="LISTEN:BRIDGE: relay PX4's link (its -o port) to the bridge's port ('' for none)")
    ap.add_argument("--direct-bridge", default="", help="HOST:PORT of the bridge, for the camera when PX4 does not forward")
    ap.add_argument("--bridge-stderr", default="")
    ap.add_argument("--alt", type=float, default=6.0, help="take-off height, m")
    ap.add_argument("--yaw-rate", type=float, default=15.0, help="MPC_YAWRAUTO_MAX, deg/s (default 60)")
    ap.add_argument("--settle", type=float, default=4.0)
    ap.add_argument("--deadline", type=float, default=300.0)
    a = ap.parse_args()
    DEADLINE = a.deadline
    return phase_setup(a) if a.phase == "setup" else phase_check(a)


if __name__ == "__main__":
    sys.exit(main())
