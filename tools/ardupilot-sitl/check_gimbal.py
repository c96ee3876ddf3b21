#!/usr/bin/env python3
"""GCS-side helper for run_check.sh: drives ArduCopter SITL (TCP serial0) as a GCS and
reports what ArduPilot says about a MAVLink gimbal (the bridge under test, on SERIAL2).

Also listens to the bridge directly as a passive UDP peer (it answers every peer it hears
from), so the simulated gimbal's own GIMBAL_DEVICE_ATTITUDE_STATUS can be compared with
ArduPilot's re-published one.

Everything is bounded: --deadline seconds overall (default 150).
"""
import argparse
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
DEADLINE = 150.0


def log(*a):
    print("[%6.1fs] " % (time.monotonic() - T0) + " ".join(str(x) for x in a), flush=True)


def check_deadline():
    if time.monotonic() - T0 > DEADLINE:
        log("FAIL: overall deadline of %.0fs reached" % DEADLINE)
        sys.exit(3)


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

    def bridge_stderr_new(self):
        if not self.bridge_err or not os.path.exists(self.bridge_err):
            return []
        with open(self.bridge_err, "r", errors="replace") as f:
            f.seek(self.bridge_err_pos)
            data = f.read()
            self.bridge_err_pos = f.tell()
        return [ln for ln in data.splitlines() if ln.strip()]


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


def report(p, title, expect, want=None):
    """want: ("body"|"earth", yaw_deg, pitch_deg) commanded target, for the summary table."""
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
    lines = p.bridge_stderr_new()
    print("  bridge stderr since last step: %s" % ("(nothing)" if not lines else ""))
    for ln in lines[-15:]:
        print("    | " + ln)


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
    ap_.add_argument("--deadline", type=float, default=150.0)
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
    report(p, "idle after discovery (no command yet)", "vehicle yaw ~%g" % hdg)

    P = -30.0
    Y = 20.0
    steps = [
        ("DO_GIMBAL_MANAGER_PITCHYAW pitch %g yaw %g flags 0 (yaw body frame / follow)" % (P, Y),
         lambda: command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [P, Y, float("nan"), float("nan"), 0, 0, 0]),
         "body yaw %g -> earth yaw %g, pitch %g" % (Y, wrap180(Y + hdg), P), ("body", Y, P)),
        ("DO_GIMBAL_MANAGER_PITCHYAW pitch %g yaw %g flags YAW_LOCK|YAW_IN_EARTH_FRAME (80)" % (P, Y),
         lambda: command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [P, Y, float("nan"), float("nan"), 16 | 64, 0, 0]),
         "earth yaw %g -> body yaw %g, pitch %g" % (Y, wrap180(Y - hdg), P), ("earth", Y, P)),
        ("DO_GIMBAL_MANAGER_PITCHYAW pitch %g yaw %g flags YAW_IN_EARTH_FRAME only (64)" % (P, Y),
         lambda: command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [P, Y, float("nan"), float("nan"), 64, 0, 0]),
         "per spec earth yaw %g (body %g); ArduPilot only looks at YAW_LOCK so likely body %g" % (Y, wrap180(Y - hdg), Y),
         ("earth", Y, P)),
        ("DO_MOUNT_CONTROL pitch %g roll 0 yaw %g mode MAVLINK_TARGETING" % (P, Y),
         lambda: command_long(p, mavlink.MAV_CMD_DO_MOUNT_CONTROL, [P, 0, Y, 0, 0, 0, mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING]),
         "body yaw %g (DO_MOUNT_CONTROL yaw is body frame) -> earth %g, pitch %g" % (Y, wrap180(Y + hdg), P),
         ("body", Y, P)),
    ]
    # ROI: 100 m north of home, 57.7 m below home -> bearing 0 (north), pitch ~ -30
    roi_lat = lat + math.degrees(100.0 / 6378137.0)
    steps.append((
        "DO_SET_ROI_LOCATION 100 m north of home, 57.7 m below (COMMAND_INT, GLOBAL_RELATIVE_ALT)",
        lambda: command_int(p, mavlink.MAV_CMD_DO_SET_ROI_LOCATION, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                            [0], int(round(roi_lat * 1e7)), int(round(lon * 1e7)), -57.7),
        "earth yaw 0 (north) -> body yaw %g, pitch ~-30" % wrap180(0 - hdg), ("earth", 0.0, -30.0)))
    steps.append((
        "DO_GIMBAL_MANAGER_PITCHYAW flags NEUTRAL (2)",
        lambda: command_long(p, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, [float("nan")] * 4 + [2, 0, 0]),
        "neutral (MNT1_NEUTRAL_x), flags NEUTRAL", ("body", 0.0, 0.0)))

    for title, fn, expect, want in steps:
        r = fn()
        log("sent %s -> %s" % (title, res_name(r)))
        p.spin(a.settle)
        report(p, title, expect, want)

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
    print("-" * 100)
    log("done; sources seen: %s" % sorted(p.seen_sources))
    return 0 if found else 2


if __name__ == "__main__":
    sys.exit(main())
