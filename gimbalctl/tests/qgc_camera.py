#!/usr/bin/env python3
"""QGroundControl's camera client, written from its C++ source, against the camera component
(100) of `gimbalctl mavlink --sim --camera FAMILY`, for every camera family, on UDP loopback:

    python3 gimbalctl/tests/qgc_camera.py target/debug/gimbalctl

QGroundControl cannot be built everywhere the suite runs, so this client sends what it sends,
in its order and with its timers, and checks the answers the way its code uses them. Sources:
QGroundControl Stable_V5.0 (a11717e, "5.0" below) and master (3a8c79b, "master"); each case
names the file and lines it rests on. A ground station 255/190 (QGroundControl's own ids) and
a stand-in autopilot (1/1, a heartbeat every second on the bridge's --to) talk to one bridge
per family:

1. Discovery (QGCCameraManager.cc): CAMERA_INFORMATION asked for once, at the camera's first
   heartbeat, with REQUEST_MESSAGE (Vehicle::requestMessage: the ACK, then the message
   within 1 s), falling back to MAV_CMD_REQUEST_CAMERA_INFORMATION; the identity QGC shows
   and the cache file name it builds from it.
2. The definition (VehicleCameraControl.cc, FTPManager.cc): FTPManager's download state
   machine (OpenFileRO in session 0, the server's session adopted, BurstReadFile with holes
   filled by ReadFile, ResetSessions), its sequence-number rules; the XML parsed as
   _loadCameraDefinitionFile parses it.
3. Start-up (_initWhenReady): PARAM_EXT_REQUEST_LIST, CAMERA_SETTINGS at 2000/3000 ms
   (500/1500 ms without settings), alternating REQUEST_MESSAGE and the legacy command, storage
   at 2500 ms, capture status at 2750 ms, every video stream (REQUEST_MESSAGE 269, param2 0).
4. Settings with QGCCameraParamIO's packing of PARAM_EXT_SET (uninitialised trailing bytes).
5. Modes, the shutter, the settings reset, pinch zoom, tracking (5.0 and master's drawing).
6. The field of view (master): CAMERA_FOV_STATUS after each CAMERA_SETTINGS, hfov used only
   when 0 < hfov < 180, and with --camera-fov/--camera-resolution its values at each zoom.

Ends with a line "qgc_camera: N passed, M failed"; exit status 0 only if nothing failed.
"""

import math
import os
import re
import struct
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET

os.environ["MAVLINK20"] = "1"  # before pymavlink is imported: MAVLink 2 framing
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mav  # noqa: E402

from checks import Checks, Inbox, raw_fields, served_definition, sim_options  # noqa: E402

FAMILIES = ["a2000", "x3", "argus", "dual-light", "f10"]
# QGroundControl's ids: MAVLinkProtocol's system 255 and MAV_COMP_ID_MISSIONPLANNER (190).
QGC_SYSTEM, QGC_COMPONENT = 255, 190
VEHICLE, CAMERA = 1, 100
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFINITIONS = os.path.join(REPO, "idu-gimbal-mavlink", "camera-definitions")

# Vehicle.h:1208-1210 (5.0): a command is ACKed within 3000 ms or sent again, 3 tries for
# the commands _sendMavCommandShouldRetry names (REQUEST_MESSAGE, Vehicle.cc:2587-2617), one
# for the others. Master: 1200 ms (MavCommandQueue.cc:197), 3 tries (MavCommandQueue.h:65).
ACK_TIMEOUT_5 = 3.0
ACK_TIMEOUT_MASTER = 1.2
MAX_TRIES = 3
# Vehicle.cc:2934 (5.0), RequestMessageCoordinator.cc:190-191 (master): the message asked
# for must come within 1000 ms of its ACK.
MESSAGE_WAIT = 1.0
# FTPManager.h:179-180 (5.0; master FTPManager.h:260-261): 1000 ms for each reply, 3 retries.
FTP_TIMEOUT = 1.0
FTP_MAX_RETRY = 3
# QGCCameraIO.cc:36-38 (5.0): 3000 ms for a PARAM_EXT_ACK, 3500 ms for a PARAM_EXT_VALUE.
PARAM_WRITE_TIMEOUT = 3.0
PARAM_REQUEST_TIMEOUT = 3.5
# The tracking status comes every 500 ms unasked while tracking (QGC 5.0 never asks), and the
# gimbal's postback, which says it tracks, every 500 ms: one of each, 1.5 s with a margin.
TRACK_STATUS_WAIT = 1.5
# The video's width QGroundControl divides a click's radius by (FlyViewVideo.qml:187, 5.0):
# a 1280-pixel-wide video, a radius of 20 pixels.
CLICK_RADIUS = 20 / 1280
# The lens given with --camera-fov and --camera-resolution in the field-of-view case: a
# 1920x1080 image, 60 degrees across at 1x, the vertical angle that aspect makes.
FOV_H = 60.0
FOV_RES = (1920, 1080)
FOV_V = math.degrees(2 * math.atan(math.tan(math.radians(FOV_H) / 2) * FOV_RES[1] / FOV_RES[0]))

CHECKS = Checks()


def check(ok, what):
    return CHECKS.check(ok, f"[{CURRENT[0]}] {what}")


CURRENT = ["-"]


def result_name(ack):
    return "no ACK" if ack is None else mav.enums["MAV_RESULT"][ack.result].name


def cstr(values):
    """A uint8[] field as QString(reinterpret_cast<const char*>(...)) reads it: up to the
    first NUL. Returns (text, whether a NUL was within the array)."""
    b = bytes(values)
    n = b.find(b"\0")
    return (b if n < 0 else b[:n]).decode("utf-8", "replace"), n >= 0


def js_round(x):
    """JavaScript's Math.round: halves round up (towards +infinity)."""
    return math.floor(x + 0.5)


# --- the bridge and the stand-in autopilot --------------------------------------------------


class Autopilot(threading.Thread):
    """The autopilot on the bridge's --to port: once the bridge has spoken to it (udpin
    learns its address), a quadrotor's HEARTBEAT every second, so that the bridge takes
    system 1 and QGroundControl has a vehicle; it drains what the bridge sends it."""

    def __init__(self):
        super().__init__(daemon=True)
        self.m = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=VEHICLE,
                                            source_component=1, dialect="common")
        self.port = self.m.port.getsockname()[1]
        self.stopping = threading.Event()

    def run(self):
        heard = False
        next_hb = 0.0
        while not self.stopping.is_set():
            while self.m.recv_match(blocking=False) is not None:
                heard = True
            now = time.monotonic()
            if heard and now >= next_hb:
                next_hb = now + 1.0
                self.m.mav.heartbeat_send(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_PX4, 0, 0,
                                          mav.MAV_STATE_ACTIVE)
            time.sleep(0.005)


def start_bridge(gimbalctl, family, to_port, extra=()):
    proc = subprocess.Popen(
        [gimbalctl, "mavlink", "--sim", *sim_options(), "--camera", family, *extra,
         "--listen", "127.0.0.1:0", "--to", f"127.0.0.1:{to_port}", "--exit-after-ms", "60000"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    line = proc.stdout.readline()
    if "listening on " not in line:
        proc.kill()
        proc.wait()
        return None, None
    port = int(line.split("listening on ")[1].split(",")[0].rsplit(":", 1)[1])
    return proc, port


# --- QGroundControl's Vehicle: its link, heartbeat, command queue and message requests -----


class Qgc(Inbox):
    def __init__(self, port, ack_timeout=ACK_TIMEOUT_5):
        super().__init__(mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{port}", source_system=QGC_SYSTEM,
            source_component=QGC_COMPONENT, dialect="common"))
        self.ack_timeout = ack_timeout
        self.next_hb = 0.0
        self.retried = []  # commands that needed more than one try

    def on_pump(self):
        now = time.monotonic()
        if now >= self.next_hb:  # QGroundControl's own heartbeat, every second
            self.next_hb = now + 1.0
            self.m.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, mav.MAV_STATE_ACTIVE)

    def camera(self, since, kind):
        """Messages of `kind` from the vehicle's camera (QGCCameraManager.cc:100-101: system
        the vehicle's, component 100 to 105), since a mark."""
        self.pump()
        return [m for _, m in self.messages[since:]
                if m.get_type() == kind and m.get_srcSystem() == VEHICLE and m.get_srcComponent() == CAMERA]

    def command(self, command, *params, retry=False):
        """Vehicle::_sendMavCommandWorker / _sendMavCommandFromList (Vehicle.cc:2634-2780,
        5.0): COMMAND_LONG with confirmation 0 (:2767), sent again after the ACK timeout up
        to maxTries (:2692) when the command is one that retries. Returns (ACK or None, the
        mark before the first send)."""
        params = [float(p) for p in params] + [0.0] * (7 - len(params))
        since = self.mark()
        for attempt in range(MAX_TRIES if retry else 1):
            sent = self.mark()
            self.m.mav.command_long_send(VEHICLE, CAMERA, command, 0, *params)
            ack = self.wait(lambda m: m.get_type() == "COMMAND_ACK" and m.command == command
                            and m.get_srcComponent() == CAMERA and m.get_srcSystem() == VEHICLE,
                            self.ack_timeout, sent)
            if ack is not None:
                if attempt:
                    self.retried.append((command, attempt + 1))
                return ack, since
        return None, since

    def request_message(self, msgid, *params):
        """Vehicle::requestMessage (Vehicle.cc:3006-3029, 5.0): REQUEST_MESSAGE msgid; the
        result ACCEPTED only when the ACK is ACCEPTED and the message comes, before the ACK
        or within 1000 ms after it (:2908-2945, :2952-2991). Returns (ACK, message)."""
        ack, since = self.command(mav.MAV_CMD_REQUEST_MESSAGE, msgid, *params, retry=True)
        if ack is None or ack.result != mav.MAV_RESULT_ACCEPTED:
            return ack, None
        name = mav.mavlink_map[msgid].msgname
        got = self.wait(lambda m: m.get_type() == name and m.get_srcComponent() == CAMERA,
                        MESSAGE_WAIT, since)
        return ack, got


# --- FTPManager (5.0) ------------------------------------------------------------------------

ACK, NAK = 128, 129
OP_RESET, OP_OPEN, OP_READ, OP_BURST = 2, 4, 5, 15
E_EOF = 6


class FtpManager:
    """FTPManager's download (FTPManager.cc, 5.0): the state machine of :43-49, the
    sequence numbers of :729-736 (outgoing one past the last incoming, expected incoming
    two further on) and the filters of :218-247 (FILE_TRANSFER_PROTOCOL from the camera,
    addressed to QGroundControl's system, not older than expected)."""

    def __init__(self, qgc):
        self.qgc = qgc
        self.expected = 0  # FTPManager.h:177
        self.since = qgc.mark()
        self.log = []

    def send(self, opcode, session=0, offset=0, size=0, data=b"", resend=False):
        if resend:  # "Must used same sequence number as previous request" (:364-368)
            self.expected = (self.expected - 2) & 0xFFFF
        seq = (self.expected + 1) & 0xFFFF
        self.expected = (self.expected + 2) & 0xFFFF
        head = struct.pack("<HBBBBBBI", seq, session, opcode, size, 0, 0, 0, offset)
        self.since = self.qgc.mark()
        self.qgc.m.mav.file_transfer_protocol_send(0, VEHICLE, CAMERA, list((head + data).ljust(251, b"\0")))

    def next_reply(self, timeout=FTP_TIMEOUT):
        """The next reply QGroundControl would hand to its state, or None after the timeout."""
        end = time.monotonic() + timeout
        while True:
            self.qgc.pump()
            while self.since < len(self.qgc.messages):
                _, m = self.qgc.messages[self.since]
                self.since += 1
                if (m.get_type() != "FILE_TRANSFER_PROTOCOL" or m.get_srcSystem() != VEHICLE
                        or m.get_srcComponent() != CAMERA or m.target_system != QGC_SYSTEM):
                    continue
                p = bytes(m.payload)
                seq, session, opcode, size, req, burst_complete, _, offset = struct.unpack_from("<HBBBBBBI", p)
                if ((self.expected - 1 - seq) & 0xFFFF) < 0xFFFF // 2:  # old packet (:241-247)
                    self.log.append(f"old seq {seq}")
                    continue
                return dict(seq=seq, session=session, opcode=opcode, size=size, req=req,
                            burst_complete=burst_complete, offset=offset, data=p[12:12 + size])
            if time.monotonic() >= end:
                return None
            time.sleep(0.001)

    def download(self, path):
        """Returns (bytes or None, what went wrong)."""
        # _openFileROBegin (:296-305): session 0, the path; a timeout fails (:307-311).
        self.send(OP_OPEN, 0, 0, len(path), path.encode())
        while True:
            r = self.next_reply()
            if r is None:
                return None, "OpenFileRO: no reply in 1 s"
            if r["req"] == OP_OPEN and r["seq"] == self.expected:  # :313-323
                break
        if r["opcode"] != ACK:
            return None, f"OpenFileRO NAK {r['data']!r}"
        if r["size"] != 4:  # :330-334
            return None, f"OpenFileRO ACK size {r['size']} (not 4)"
        session = r["session"]  # :336, the server's session adopted
        size = struct.unpack("<I", r["data"])[0]
        self.log.append(f"open: session {session}, {size} bytes")
        data = bytearray(size)
        have = 0
        missing = []
        offset = 0
        # _burstReadFileWorker (:353-371): size = sizeof(request.data) = 239.
        self.send(OP_BURST, session, offset, 239)
        retries = 0
        while True:
            r = self.next_reply()
            if r is None:  # _burstReadFileTimeout (:463-473)
                retries += 1
                if retries > FTP_MAX_RETRY:
                    return None, f"BurstReadFile: no reply, retries exceeded at {offset}"
                self.send(OP_BURST, session, offset, 239, resend=True)
                continue
            if r["req"] != OP_BURST or r["session"] != session:  # :382-389
                continue
            if r["opcode"] == ACK:
                if r["seq"] < self.expected:  # :394-397
                    continue
                if r["offset"] != offset:
                    if r["offset"] > offset:  # a hole (:401-408)
                        missing.append((offset, r["offset"] - offset))
                    else:
                        continue  # :409-414
                data[r["offset"]:r["offset"] + r["size"]] = r["data"]
                have += r["size"]
                offset = r["offset"] + r["size"]
                if r["burst_complete"]:  # :426-429: the next burst
                    self.expected = r["seq"]
                    retries = 0
                    self.send(OP_BURST, session, offset, 239)
                else:
                    self.expected = (r["seq"] + 1) & 0xFFFF  # :430-434
            elif r["opcode"] == NAK:
                if r["data"][:1] == bytes([E_EOF]):
                    if r["seq"] != self.expected:  # :441-452: data missing, from the last offset
                        self.expected = r["seq"]
                        retries = 0
                        self.send(OP_BURST, session, offset, 239)
                        continue
                    break  # :453-455
                return None, f"BurstReadFile NAK {r['data']!r}"  # :456-459
        self.log.append(f"burst: {have} bytes, holes {missing}")
        # _fillMissingBlocksWorker (:564-597): ReadFile for each hole.
        while missing:
            off, n = missing[0]
            want = min(239, n)
            self.send(OP_READ, session, off, want)
            r = self.next_reply()
            while r is not None and (r["req"] != OP_READ or r["seq"] != self.expected or r["session"] != session):
                r = self.next_reply()
            if r is None or r["opcode"] != ACK or r["offset"] != off:
                return None, f"ReadFile at {off}: {r}"
            data[off:off + r["size"]] = r["data"]
            have += r["size"]
            missing[0] = (off + r["size"], n - r["size"])
            if missing[0][1] <= 0:
                missing.pop(0)
        if have != size:  # :590-595 (download with checksize)
            return None, f"{have} bytes written of {size}"
        # _resetSessionsBegin (:677-683); a NAK or a timeout still completes (:698-707).
        self.send(OP_RESET)
        r = self.next_reply()
        while r is not None and (r["req"] != OP_RESET or r["seq"] != self.expected):
            r = self.next_reply()
        self.log.append(f"ResetSessions: {'ACK' if r and r['opcode'] == ACK else r}")
        self.reset_reply = r
        return bytes(data), ""


# --- the definition, as _loadCameraDefinitionFile reads it (5.0) -----------------------------

# FactMetaData::stringToType (FactMetaData.cc:799-812, 5.0): these, any case.
QGC_TYPES = {"uint8": (mav.MAV_PARAM_EXT_TYPE_UINT8, "<B"), "int8": (mav.MAV_PARAM_EXT_TYPE_INT8, "<b"),
             "uint16": (mav.MAV_PARAM_EXT_TYPE_UINT16, "<H"), "int16": (mav.MAV_PARAM_EXT_TYPE_INT16, "<h"),
             "uint32": (mav.MAV_PARAM_EXT_TYPE_UINT32, "<I"), "int32": (mav.MAV_PARAM_EXT_TYPE_INT32, "<i"),
             "uint64": (mav.MAV_PARAM_EXT_TYPE_UINT64, "<Q"), "int64": (mav.MAV_PARAM_EXT_TYPE_INT64, "<q"),
             "float": (mav.MAV_PARAM_EXT_TYPE_REAL32, "<f"), "double": (mav.MAV_PARAM_EXT_TYPE_REAL64, "<d"),
             "bool": (mav.MAV_PARAM_EXT_TYPE_UINT8, "<B"), "string": (mav.MAV_PARAM_EXT_TYPE_CUSTOM, None),
             "custom": (mav.MAV_PARAM_EXT_TYPE_CUSTOM, None), "elapsedseconds": (mav.MAV_PARAM_EXT_TYPE_INT32, "<i")}


def qt_number(kind, text):
    """FactMetaData::convertAndValidateRaw for the integer and float types: the value, or
    None when QString's toInt/toUInt/toDouble would fail."""
    fmt = QGC_TYPES[kind][1]
    if fmt is None or text is None:
        return None
    try:
        v = float(text) if fmt in ("<f", "<d") else int(text.strip(), 10)
        struct.pack(fmt, v)
        return v
    except (ValueError, struct.error):
        return None


def load_definition(data):
    """_loadCameraDefinitionFile (VehicleCameraControl.cc:789-831, 5.0). Returns (params or
    None, problems): params {name: dict(kind, default, options, control, updates, excl)} in
    the file's order."""
    try:
        root = ET.fromstring(data)  # QDomDocument::setContent (:797-803)
    except ET.ParseError as e:
        return None, [f"does not parse: {e}"]
    problems = []
    # _loadConstants (:835-848): the first <definition> anywhere, its version attribute,
    # its <model> and <vendor> children.
    defs = list(root.iter("definition"))
    if not defs or defs[0].get("version") is None or defs[0].find("model") is None \
            or defs[0].find("vendor") is None:
        return None, ["no <definition version> with <model> and <vendor> (:805-809, :835-848)"]
    # :811-815: <parameters> anywhere; _loadSettings over its <parameter> elements (:852-1068).
    plist = list(root.iter("parameters"))
    if not plist:
        return None, ["no <parameters> (:811-815)"]
    params = {}
    for p in plist[0].iter("parameter"):
        name, kind = p.get("name"), p.get("type")
        if name is None:  # :860-867
            return None, ["a parameter without a name (:866)"]
        if kind is None or kind.lower() not in QGC_TYPES:  # :875-879, :889-894
            return None, [f"{name}: type {kind!r} (:877, :892)"]
        kind = kind.lower()
        control = p.get("control", "1") != "0" and kind != "custom"  # read_attribute(bool): != "0"; :896-898
        if p.find("description") is None:  # :901-904 (read_value: a child <description>)
            return None, [f"{name}: no <description> (:903)"]
        updates = [u.text for u in p.iter("update") if u.text]  # _loadUpdates (:1917-1935): the text
        options = []
        excl = {}
        opts = list(p.iter("options"))
        for o in (opts[0].iter("option") if opts else []):
            if o.get("name") is None or o.get("value") is None:  # _loadNameValue (:2013-2031)
                return None, [f"{name}: an option without name or value (:2016, :2020)"]
            v = qt_number(kind, o.get("value"))
            if v is None and QGC_TYPES[kind][1] is not None:
                problems.append(f"{name}: option value {o.get('value')!r} not a {kind} (:2023-2029 warns)")
            options.append((o.get("name"), v))
            excl[v] = [e.text for e in o.iter("exclude") if e.text]  # _loadExclusions (:1895-1913): the text
        default = qt_number(kind, p.get("default"))
        if p.get("default") is not None and default is None and QGC_TYPES[kind][1] is not None:
            problems.append(f"{name}: default {p.get('default')!r} not a {kind} (:957-967 warns)")
        if name in params:  # :970-972: the second one dropped
            problems.append(f"{name}: duplicate (:971)")
            continue
        params[name] = dict(kind=kind, default=default, options=options, control=control,
                            updates=updates, excl=excl, write_only=p.get("writeonly", "0") != "0",
                            read_only=p.get("readonly", "0") != "0")
    if not params:  # :1061-1068
        return None, ["no parameter (:1068)"]
    # Every exclusion and update names a parameter QGroundControl knows (_updateActiveList,
    # _requestParamUpdates: _paramIO[name] of an unknown name would be a null pointer, :1423).
    for name, p in params.items():
        for other in p["updates"] + [e for es in p["excl"].values() for e in es]:
            if other not in params:
                problems.append(f"{name}: names {other!r}, not a parameter")
    return params, problems


def qgc_param_value(kind, value):
    """QGCCameraParamIO::_sendParameter's param_value (QGCCameraIO.cc:138-204, 5.0): the
    value's bytes in a param_ext_union_t that is never initialised, all 128 copied (:144, 191):
    the bytes after the value are whatever was on the stack; here a non-zero pattern."""
    garbage = bytes((0xA5 ^ (i * 37)) & 0xFF or 0x5A for i in range(128))
    raw = struct.pack(QGC_TYPES[kind][1], value)
    return raw + garbage[len(raw):]


def qgc_value_from_message(raw, param_type):
    """QGCCameraParamIO::_valueFromMessage (QGCCameraIO.cc:285-332, 5.0): by the message's
    param_type, from the front of param_value."""
    fmt = {mav.MAV_PARAM_EXT_TYPE_UINT8: "<B", mav.MAV_PARAM_EXT_TYPE_INT8: "<b",
           mav.MAV_PARAM_EXT_TYPE_UINT16: "<H", mav.MAV_PARAM_EXT_TYPE_INT16: "<h",
           mav.MAV_PARAM_EXT_TYPE_UINT32: "<I", mav.MAV_PARAM_EXT_TYPE_INT32: "<i",
           mav.MAV_PARAM_EXT_TYPE_UINT64: "<Q", mav.MAV_PARAM_EXT_TYPE_INT64: "<q",
           mav.MAV_PARAM_EXT_TYPE_REAL32: "<f"}.get(param_type)
    if fmt is None:
        return None  # CUSTOM as a string, anything else 0 with a qCritical (:314-329)
    return struct.unpack_from(fmt, raw)[0]


# --- the cases ------------------------------------------------------------------------------


def discovery(qgc):
    """Returns CAMERA_INFORMATION (or None)."""
    # QGCCameraManager.cc:141-152 (5.0): the first heartbeat of a camera component of the
    # vehicle (:100-101) starts _requestCameraInfo (:436-442); nothing asks again later.
    since = qgc.mark()
    hb = qgc.wait(lambda m: m.get_type() == "HEARTBEAT" and m.get_srcComponent() == CAMERA
                  and m.get_srcSystem() == VEHICLE, 5.0, since)
    if not check(hb is not None, "a camera HEARTBEAT from 1/100 within 5 s (QGCCameraManager.cc:100-111, 5.0)"):
        return None
    ack, info = qgc.request_message(mav.MAVLINK_MSG_ID_CAMERA_INFORMATION)
    fallback = None
    if info is None:
        # QGCCameraManager.cc:417-431 (5.0): once, MAV_CMD_REQUEST_CAMERA_INFORMATION.
        fallback, since = qgc.command(mav.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1)
        info = qgc.wait(lambda m: m.get_type() == "CAMERA_INFORMATION" and m.get_srcComponent() == CAMERA,
                        MESSAGE_WAIT, since)
    check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED and info is not None and fallback is None,
          f"REQUEST_MESSAGE CAMERA_INFORMATION at the first heartbeat: {result_name(ack)}, the message within "
          f"1 s of it, no fallback needed (QGCCameraManager.cc:436-442, Vehicle.cc:2908-2991, 5.0; asked once)")
    if info is None:
        return None
    vendor, v_nul = cstr(info.vendor_name)
    model, m_nul = cstr(info.model_name)
    # VehicleCameraControl.cc:131-132 (5.0): QString(char*) of each array, so each must hold
    # its NUL (a full array runs into the next field).
    check(v_nul and m_nul and vendor and model,
          f"vendor {vendor!r} and model {model!r}: non-empty, NUL-terminated within 32 bytes "
          "(VehicleCameraControl.cc:131-132, 5.0)")
    check(model != "IDU gimbal camera" and "IDU gimbal camera" not in vendor,
          f"no provisional identity: model {model!r} (QGCCameraManager.cc:141-163: read once)")
    # VehicleCameraControl.cc:134-138 (cache) and 2047-2051 (the FTP download's file name):
    # "<vendor>_<model>_%03d.xml" in QGroundControl's parameter directory: one file name.
    cache = "%s_%s_%03d.xml" % (vendor, model, info.cam_definition_version)
    bad = [c for c in cache if c in '/\\:*?"<>|' or ord(c) < 32]
    check(not bad and len(cache.encode()) <= 255,
          f"the cache file name QGC builds, {cache!r}, is one valid file name (VehicleCameraControl.cc:134-138, "
          f"2047-2051, 5.0; FTPManager.cc:340-346 opens it): {bad or 'ok'}")
    return info


def get_definition(qgc, info, family):
    """The definition, downloaded as QGroundControl downloads it. Returns its parameters."""
    uri = info.cam_definition_uri
    # VehicleCameraControl.cc:2040-2055 (5.0): an mftp:// URI goes to FTPManager::download;
    # _parseURI (FTPManager.cc:755-786) keeps the slash of "://": "mftp://camera.xml" ->
    # "/camera.xml", and "[;comp=N]" would name another component.
    if not check(uri.lower().startswith("mftp://") and "[;comp=" not in uri,
                 f"cam_definition_uri {uri!r}: mftp://, on the camera itself (VehicleCameraControl.cc:2040-2041)"):
        return None
    path = uri[len("mftp://") - 1:]
    ftp = FtpManager(qgc)
    data, why = ftp.download(path)
    check(data is not None, f"FTPManager download of {path!r}: {why or f'{len(data)} bytes'} ({'; '.join(ftp.log)}) "
          "(FTPManager.cc:34-83, 296-475, 564-707, 5.0)")
    if data is None:
        return None
    r = ftp.reset_reply
    check(r is not None and r["opcode"] == ACK, f"ResetSessions after the download: ACK (FTPManager.cc:677-707): {r}")
    name = "idu-dual-light.xml" if family == "dual-light" else "idu-zoom.xml"
    model, _ = cstr(info.model_name)
    check(data == served_definition(name, model),
          f"the bytes downloaded are {name}'s, its <model> CAMERA_INFORMATION's {model!r}")
    # _loadConstants renames the camera to the definition's <model> and <vendor>
    # (VehicleCameraControl.cc:835-848, 5.0); the camera list keeps the name it was added
    # under (QGCCameraManager.cc:217) and removes the camera by its name now when its
    # heartbeat stops (:274): the two must be the same, or a stale entry stays.
    d = ET.fromstring(data).find(".//definition")
    xml_ids = (d.findtext("vendor"), d.findtext("model")) if d is not None else None
    check(xml_ids == (cstr(info.vendor_name)[0], model),
          f"the definition's vendor and model {xml_ids} are CAMERA_INFORMATION's, under which QGC "
          "lists the camera (QGCCameraManager.cc:217, 274; VehicleCameraControl.cc:835-848, 5.0)")
    params, problems = load_definition(data)
    check(params is not None and not problems,
          f"_loadCameraDefinitionFile takes it: {len(params or {})} parameters {list(params or {})} "
          f"(VehicleCameraControl.cc:789-831, 835-1068, 5.0): {problems or 'ok'}")
    if params:
        for name, p in params.items():
            vals = [v for _, v in p["options"]]
            check(p["default"] is not None and (not vals or p["default"] in vals),
                  f"{name}: default {p['default']} is one of its options {vals} (:957-967, 928-956)")
    return params


def settings_request(qgc, n):
    """_requestCameraSettings (VehicleCameraControl.cc:1430-1453, 5.0): REQUEST_MESSAGE
    CAMERA_SETTINGS the first time and every other time, the legacy command between."""
    if n % 2 == 0:
        ack, since = qgc.command(mav.MAV_CMD_REQUEST_MESSAGE, mav.MAVLINK_MSG_ID_CAMERA_SETTINGS, retry=True)
        what = "REQUEST_MESSAGE CAMERA_SETTINGS"
    else:
        ack, since = qgc.command(mav.MAV_CMD_REQUEST_CAMERA_SETTINGS, 1)
        what = "MAV_CMD_REQUEST_CAMERA_SETTINGS (legacy)"
    got = None
    if ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED:
        got = qgc.wait(lambda m: m.get_type() == "CAMERA_SETTINGS" and m.get_srcComponent() == CAMERA,
                       MESSAGE_WAIT, since)
    return what, ack, got


def startup(qgc, info, params):
    """_initWhenReady (VehicleCameraControl.cc:173-200, 5.0) on its timers. Returns the
    parameter values read, the last CAMERA_SETTINGS, the streams."""
    basic = not params or not any(p["control"] for p in params.values())  # isBasic (.h:91)
    t0 = time.monotonic()
    values = {}
    if not basic:
        # _requestAllParameters (:1157-1180): PARAM_EXT_REQUEST_LIST; each parameter waits
        # 3500 ms for its value (QGCCameraIO.cc:38, 88-98), then asks by name (QGCCameraIO.cc:336-350, 354-387).
        since = qgc.mark()
        qgc.m.mav.param_ext_request_list_send(VEHICLE, CAMERA)
        readable = [n for n, p in params.items() if not p["write_only"]]
        qgc.wait(lambda m: {raw_fields(v)["param_id"].rstrip(b"\0").decode() for v in
                            qgc.camera(since, "PARAM_EXT_VALUE")} >= set(readable), PARAM_REQUEST_TIMEOUT, since)
        for m in qgc.camera(since, "PARAM_EXT_VALUE"):
            f = raw_fields(m)
            values[f["param_id"].rstrip(b"\0").decode()] = (f["param_type"], f["param_value"], f["param_count"])
        check(set(values) == set(readable),
              f"PARAM_EXT_REQUEST_LIST: a PARAM_EXT_VALUE for each parameter within 3.5 s "
              f"(VehicleCameraControl.cc:1157-1180, QGCCameraIO.cc:38): {sorted(values)}")
        for name in readable:
            if name not in values:
                continue
            ptype, raw, count = values[name]
            want_type = QGC_TYPES[params[name]["kind"]][0]
            v = qgc_value_from_message(raw, ptype)
            opts = [o for _, o in params[name]["options"]]
            check(ptype == want_type and count == len(params) and (not opts or v in opts) and v == params[name]["default"],
                  f"{name}: param_type {ptype} (QGC's for {params[name]['kind']}: {want_type}, QGCCameraIO.cc:50-89), "
                  f"count {count}, value {v} the default, one of its options (_valueFromMessage, QGCCameraIO.cc:285-332)")
    # The timers: settings at 500/1500 ms (basic) or 2000/3000 ms, streams at 250 ms (basic)
    # or when the parameters are done (_paramDone, :2191-2203), storage 2500, capture 2750.
    plan = ([(0.25, "streams"), (0.5, "settings"), (1.5, "settings")] if basic else
            [(0.0, "streams"), (2.0, "settings"), (3.0, "settings")]) + [(2.5, "storage"), (2.75, "capture")]
    plan.sort()
    n_settings = 0
    last_settings = None
    streams = []
    for at, what in plan:
        qgc.idle(max(0.0, t0 + at - time.monotonic()))
        if what == "settings":
            name, ack, got = settings_request(qgc, n_settings)
            n_settings += 1
            check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED and got is not None,
                  f"{name} at {at * 1000:.0f} ms: {result_name(ack)}, CAMERA_SETTINGS within 1 s "
                  f"(VehicleCameraControl.cc:{'179-181' if basic else '187-190'}, 1430-1453)")
            if got is not None:
                last_settings = got
                # handleSettings (:1482-1496): the mode; zoom and focus only when finite.
                ok_mode = got.mode_id in (mav.CAMERA_MODE_IMAGE, mav.CAMERA_MODE_VIDEO)
                check(ok_mode and (math.isfinite(got.zoomLevel) or not info.flags & mav.CAMERA_CAP_FLAGS_HAS_BASIC_ZOOM),
                      f"CAMERA_SETTINGS: mode {got.mode_id} (image or video), zoomLevel {got.zoomLevel} "
                      "(finite for a zoom camera: QGC ignores NaN, :1482-1496)")
        elif what == "storage":
            # _requestStorageInfo (:1456-1478): REQUEST_MESSAGE STORAGE_INFORMATION, storage 0.
            ack, since = qgc.command(mav.MAV_CMD_REQUEST_MESSAGE, mav.MAVLINK_MSG_ID_STORAGE_INFORMATION, 0, retry=True)
            got = None
            if ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED:
                got = qgc.wait(lambda m: m.get_type() == "STORAGE_INFORMATION", MESSAGE_WAIT, since)
            # _mavCommandResult (:708-741): FAILED or TEMPORARILY_REJECTED only retry the
            # legacy command; a camera without storage answers UNSUPPORTED, once.
            check(ack is not None and (got is not None if ack.result == mav.MAV_RESULT_ACCEPTED
                                       else ack.result in (mav.MAV_RESULT_UNSUPPORTED, mav.MAV_RESULT_DENIED)),
                  f"REQUEST_MESSAGE STORAGE_INFORMATION at 2500 ms: {result_name(ack)}"
                  f"{', the message' if got else ''} (VehicleCameraControl.cc:195, 1456-1478)")
        elif what == "capture":
            # _requestCaptureStatus (:638-655), at 2750 ms (:196).
            ack, got = qgc.request_message(mav.MAVLINK_MSG_ID_CAMERA_CAPTURE_STATUS)
            check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED and got is not None
                  and got.image_status <= 3 and got.video_status <= 1,
                  f"REQUEST_MESSAGE CAMERA_CAPTURE_STATUS at 2750 ms: {result_name(ack)}, "
                  f"image {got and got.image_status} video {got and got.video_status} (handleCaptureStatus :1541-1583)")
        elif what == "streams":
            streams = video_streams(qgc, info)
    check(not qgc.retried, f"every command answered at its first try (Vehicle.cc:2692, 2706-2720, 2785-2798): {qgc.retried}")
    return values, last_settings, streams


def video_streams(qgc, info):
    # _checkForVideoStreams (:2207-2218): with HAS_VIDEO_STREAM, _requestStreamInfo(0)
    # (:1774-1797): REQUEST_MESSAGE VIDEO_STREAM_INFORMATION, param2 0 = all streams.
    if not check(info.flags & mav.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM,
                 f"HAS_VIDEO_STREAM in flags {info.flags:#x} (:2209: else no video)"):
        return []
    ack, since = qgc.command(mav.MAV_CMD_REQUEST_MESSAGE, mav.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, 0, retry=True)
    first = qgc.wait(lambda m: m.get_type() == "VIDEO_STREAM_INFORMATION", MESSAGE_WAIT, since)
    count = first.count if first else 0
    qgc.wait(lambda m: len(qgc.camera(since, "VIDEO_STREAM_INFORMATION")) >= count, MESSAGE_WAIT, since)
    got = qgc.camera(since, "VIDEO_STREAM_INFORMATION")
    ids = [m.stream_id for m in got]
    # handleVideoInfo (:1587-1616): one QGCVideoStreamInfo per new stream_id, done when as
    # many as count; a THERMAL one is not listed (:1597-1604).
    visible = [m for m in got if not m.flags & mav.VIDEO_STREAM_STATUS_FLAGS_THERMAL]
    check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED and count > 0 and len(set(ids)) == count
          and all(m.count == count for m in got) and visible,
          f"REQUEST_MESSAGE VIDEO_STREAM_INFORMATION (all): {result_name(ack)}, {count} streams {ids}, "
          f"{len(visible)} listed (not THERMAL) (VehicleCameraControl.cc:1587-1616, 2207-2218, 5.0)")
    return got


def set_parameters(qgc, params):
    """QGCCameraParamIO::_sendParameter (QGCCameraIO.cc:138-204) with a value other than
    the default; PARAM_EXT_ACK ACCEPTED with the value (handleParamAck :223-235). Then the
    parameters it updates, asked for by name 500 ms later (_updateRanges :1405-1415,
    _requestParamUpdates :1420-1427). Returns the names changed."""
    changed = []
    for name, p in params.items():
        vals = [v for _, v in p["options"]]
        others = [v for v in vals if v != p["default"]]
        if not p["control"] or p["read_only"] or not others:
            continue
        value = others[-1]
        ptype = QGC_TYPES[p["kind"]][0]
        since = qgc.mark()
        qgc.m.mav.param_ext_set_send(VEHICLE, CAMERA, name.encode(), qgc_param_value(p["kind"], value), ptype)
        ack = qgc.wait(lambda m: m.get_type() == "PARAM_EXT_ACK" and m.get_srcComponent() == CAMERA,
                       PARAM_WRITE_TIMEOUT, since)
        f = raw_fields(ack) if ack else None
        got = qgc_value_from_message(f["param_value"], f["param_type"]) if f else None
        ok = check(f is not None and f["param_id"].rstrip(b"\0") == name.encode()
                   and f["param_result"] == mav.PARAM_ACK_ACCEPTED and got == value,
                   f"PARAM_EXT_SET {name} = {value} packed as QGC packs it (trailing bytes non-zero): "
                   f"PARAM_EXT_ACK {f and f['param_result']} value {got} (QGCCameraIO.cc:138-204, 223-258, 5.0)")
        if ok:
            changed.append(name)
        for other in p["updates"]:
            qgc.idle(0.5)
            since = qgc.mark()
            qgc.m.mav.param_ext_request_read_send(VEHICLE, CAMERA, other.encode(), -1)
            v = qgc.wait(lambda m: m.get_type() == "PARAM_EXT_VALUE", PARAM_REQUEST_TIMEOUT, since)
            check(v is not None, f"{name} updates {other}: PARAM_EXT_REQUEST_READ answered (:1420-1427, QGCCameraIO.cc:354-387)")
    return changed


def modes_and_shutter(qgc, info):
    """setCameraModeVideo/Photo (VehicleCameraControl.cc:441-495, 5.0) without a mode
    setting: MAV_CMD_SET_CAMERA_MODE, then the mode QGC shows comes back in CAMERA_SETTINGS;
    the shutter: takePhoto in photo mode (:340-373), startVideoRecording in video mode
    (:400-419)."""
    if not check(info.flags & mav.CAMERA_CAP_FLAGS_HAS_MODES,
                 f"HAS_MODES in flags {info.flags:#x} (hasModes, VehicleCameraControl.h:82: the photo/video switch)"):
        return
    for mode, name in ((mav.CAMERA_MODE_VIDEO, "video"), (mav.CAMERA_MODE_IMAGE, "photo")):
        ack, since = qgc.command(mav.MAV_CMD_SET_CAMERA_MODE, 0, mode)
        s = qgc.wait(lambda m: m.get_type() == "CAMERA_SETTINGS" and m.get_srcComponent() == CAMERA, MESSAGE_WAIT, since)
        check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED and s is not None and s.mode_id == mode,
              f"SET_CAMERA_MODE {name}: {result_name(ack)}, CAMERA_SETTINGS mode {s and s.mode_id} "
              f"(VehicleCameraControl.cc:{'441-466' if mode else '470-495'}, handleSettings :1482-1485)")
        if mode == mav.CAMERA_MODE_VIDEO and info.flags & mav.CAMERA_CAP_FLAGS_CAPTURE_VIDEO:
            # startVideoRecording (:400-419) then stopVideoRecording (:423-437).
            for cmd, state, label in ((mav.MAV_CMD_VIDEO_START_CAPTURE, 1, "start"), (mav.MAV_CMD_VIDEO_STOP_CAPTURE, 0, "stop")):
                ack, since = qgc.command(cmd, 0)
                qgc.idle(0.2)
                a2, st = qgc.request_message(mav.MAVLINK_MSG_ID_CAMERA_CAPTURE_STATUS)
                check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED and st is not None and st.video_status == state,
                      f"video mode, the shutter: VIDEO_{label.upper()}_CAPTURE {result_name(ack)}, capture status "
                      f"video {st and st.video_status} (VehicleCameraControl.cc:400-437, 689-696, handleCaptureStatus :1563-1567)")
        if mode == mav.CAMERA_MODE_IMAGE and info.flags & mav.CAMERA_CAP_FLAGS_CAPTURE_IMAGE:
            # takePhoto (:340-373): IMAGE_START_CAPTURE, interval 0, count 1, sequence 0.
            ack, since = qgc.command(mav.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, 0)
            cap = qgc.wait(lambda m: m.get_type() == "CAMERA_IMAGE_CAPTURED", 2.0, since)
            check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED and cap is not None,
                  f"photo mode, the shutter: IMAGE_START_CAPTURE {result_name(ack)}, CAMERA_IMAGE_CAPTURED within 2 s "
                  "(VehicleCameraControl.cc:340-373, 703-705)")


def reset(qgc, params, changed, basic):
    """resetSettings (VehicleCameraControl.cc:561-572, 5.0): RESET_CAMERA_SETTINGS 1; only
    ACCEPTED, TEMPORARILY_REJECTED or FAILED end the resetting state (:680-687, 708-718);
    anything else leaves _resetting set (:743-745) and the photo, video and mode buttons dead
    (:356, 402, 425, 443, 472). After ACCEPTED: parameters 500 ms later, settings 2500 ms later."""
    ack, since = qgc.command(mav.MAV_CMD_RESET_CAMERA_SETTINGS, 1)
    ok = check(ack is not None and ack.result in (mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_TEMPORARILY_REJECTED,
                                                  mav.MAV_RESULT_FAILED),
               f"RESET_CAMERA_SETTINGS: {result_name(ack)} (ACCEPTED, TEMPORARILY_REJECTED or FAILED end "
               "_resetting: VehicleCameraControl.cc:680-687, 708-718, 743-745)")
    if not ok or ack.result != mav.MAV_RESULT_ACCEPTED:
        return
    t0 = time.monotonic()
    if not basic:
        qgc.idle(0.5)
        since = qgc.mark()
        qgc.m.mav.param_ext_request_list_send(VEHICLE, CAMERA)
        qgc.wait(lambda m: len(qgc.camera(since, "PARAM_EXT_VALUE")) >= len(params), PARAM_REQUEST_TIMEOUT, since)
        got = {}
        for m in qgc.camera(since, "PARAM_EXT_VALUE"):
            f = raw_fields(m)
            got[f["param_id"].rstrip(b"\0").decode()] = qgc_value_from_message(f["param_value"], f["param_type"])
        want = {n: p["default"] for n, p in params.items() if not p["write_only"]}
        check(got == want and changed,
              f"after the reset, 500 ms on, PARAM_EXT_REQUEST_LIST: every parameter at its default {want} "
              f"(changed before: {changed}): {got} (VehicleCameraControl.cc:684-686)")
    qgc.idle(max(0.0, t0 + (0.0 if basic else 2.5) - time.monotonic()))
    what, ack, s = settings_request(qgc, 0)
    check(s is not None and s.mode_id == mav.CAMERA_MODE_IMAGE,
          f"after the reset, {what}: mode {s and s.mode_id}, image (VehicleCameraControl.cc:682-686)")


def pinch_zoom(qgc, info):
    """The pinch (FlightDisplayViewVideo.qml:219-232, 5.0): round(scale x -10) below 1, round
    (scale) above, each a stepZoom (VehicleCameraControl.cc:593-604: ZOOM_TYPE_STEP, the
    number as param2) whenever it is not 0. QGroundControl does not wait: a second
    SET_CAMERA_ZOOM while the first is unACKed fails as a duplicate (Vehicle.cc:2647-2660),
    so each must be ACKed before the next frame (here: before the next is sent)."""
    if not check(info.flags & mav.CAMERA_CAP_FLAGS_HAS_BASIC_ZOOM,
                 f"HAS_BASIC_ZOOM in flags {info.flags:#x} (hasZoom: the pinch and the zoom buttons)"):
        return None, None
    results = {}
    levels = {}
    for label, scales in (("out", [0.97 - 0.05 * i for i in range(19)]), ("in", [1.0 + 0.5 * i for i in range(19)])):
        sent = []
        for s in scales:
            z = js_round(s * -10) if s < 1 else js_round(s)
            if z == 0:
                continue
            ack, _ = qgc.command(mav.MAV_CMD_SET_CAMERA_ZOOM, mav.ZOOM_TYPE_STEP, z)
            sent.append(z)
            results[z] = result_name(ack)
        ok = all(results[z] == "MAV_RESULT_ACCEPTED" for z in sent)
        check(ok and sent, f"pinch {label}: ZOOM_TYPE_STEP {sorted(set(sent))} each ACCEPTED: "
              f"{ {z: results[z] for z in sorted(set(sent)) if results[z] != 'MAV_RESULT_ACCEPTED'} or 'all'}")
        qgc.idle(0.3)
        _, _, s = settings_request(qgc, 0)
        levels[label] = s.zoomLevel if s else None
    # CAMERA_SETTINGS.zoomLevel: "percentage of the full range (0.0 to 100.0)" (common.xml);
    # the pinch out and in each go beyond the range (at most 5 steps of 2x span it).
    check(levels["out"] == 0.0 and levels["in"] == 100.0,
          f"CAMERA_SETTINGS.zoomLevel after the pinch out {levels['out']}, after the pinch in {levels['in']} "
          "(0 and 100: common.xml's percentage of the range; QGC shows it, :1486-1491)")
    return levels, results


def tracking(qgc, info):
    """5.0: startTracking(rect) / (point, radius) (VehicleCameraControl.cc:2309-2350), the
    status drawn (handleTrackingImageStatus :1633-1668), stopTracking (:2354-2372). Master
    draws only finite coordinates: std::clamp passes NaN (VehicleCameraControl.cc:1746-1778)."""
    has_rect = info.flags & mav.CAMERA_CAP_FLAGS_HAS_TRACKING_RECTANGLE
    has_point = info.flags & mav.CAMERA_CAP_FLAGS_HAS_TRACKING_POINT
    if not check(has_rect or has_point, f"HAS_TRACKING_POINT or _RECTANGLE in flags {info.flags:#x} (:154-161)"):
        return
    fin = lambda *v: all(math.isfinite(x) and 0.0 <= x <= 1.0 for x in v)  # noqa: E731
    cases = []
    if has_rect:
        # A drag from (0.40, 0.30) to (0.55, 0.50) (FlyViewVideo.qml:178-190: x0, y0, x1, y1).
        cases.append(("rectangle", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, (0.40, 0.30, 0.55, 0.50), mav.CAMERA_TRACKING_MODE_RECTANGLE))
    if has_point:
        cases.append(("point", mav.MAV_CMD_CAMERA_TRACK_POINT, (0.60, 0.45, CLICK_RADIUS), mav.CAMERA_TRACKING_MODE_POINT))
    for label, cmd, params, mode in cases:
        ack, since = qgc.command(cmd, *params)
        # From the ACK on: a status of the case before may come between the command and it.
        st = qgc.wait(lambda m: m.get_type() == "CAMERA_TRACKING_IMAGE_STATUS" and m.get_srcComponent() == CAMERA
                      and m.tracking_status & mav.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE, TRACK_STATUS_WAIT,
                      qgc.after(ack, since))
        if st is not None and st.tracking_mode == mav.CAMERA_TRACKING_MODE_RECTANGLE:
            box = (st.rec_top_x, st.rec_top_y, st.rec_bottom_x, st.rec_bottom_y)
            drawn = fin(*box) and box[2] > box[0] and box[3] > box[1]
        elif st is not None:
            box = (st.point_x, st.point_y, st.radius)
            drawn = fin(st.point_x, st.point_y) and math.isfinite(st.radius) and st.radius > 0
        else:
            box, drawn = None, False
        check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED and st is not None and st.tracking_mode == mode and drawn,
              f"tracking a {label} {tuple(round(p, 4) for p in params)}: {result_name(ack)}, within 1.5 s a status ACTIVE, "
              f"mode {st and st.tracking_mode}, {box} finite in 0..1, a box to draw (5.0 :1633-1668, master :1746-1778)")
    a1, _ = qgc.command(mav.MAV_CMD_CAMERA_STOP_TRACKING)
    a2, since = qgc.command(mav.MAV_CMD_SET_MESSAGE_INTERVAL, mav.MAVLINK_MSG_ID_CAMERA_TRACKING_IMAGE_STATUS, -1)
    qgc.idle(1.0)  # two of the status's 500 ms intervals
    # After the ACK of −1: the status owed at the stop (ACTIVE, from the last postback while
    # tracking) goes before it, and may be read only after the command was sent.
    active = [m for m in qgc.camera(qgc.after(a2, since), "CAMERA_TRACKING_IMAGE_STATUS")
              if m.tracking_status & mav.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE]
    check(a1 is not None and a1.result == mav.MAV_RESULT_ACCEPTED and a2 is not None and a2.result == mav.MAV_RESULT_ACCEPTED
          and not active, f"stopTracking: STOP_TRACKING {result_name(a1)}, SET_MESSAGE_INTERVAL -1 {result_name(a2)}, "
          f"no ACTIVE status after ({len(active)}) (VehicleCameraControl.cc:2354-2372)")


def fov_status(qgc, info, expect):
    """Master: each CAMERA_SETTINGS makes QGCCameraManager ask for CAMERA_FOV_STATUS
    (QGCCameraManager.cc:425-441, 788-795); it uses hfov only when finite and 0 < hfov < 180,
    then vfov = 2 atan(tan(hfov / 2) x resolution_v / resolution_h of CAMERA_INFORMATION, or
    16/9) (:811-840, aspect :337-345). `expect`: the hfov and vfov the lens gives, or None
    (no lens: NaN, ignored)."""
    _, _, s = settings_request(qgc, 0)
    ack, fov = qgc.request_message(mav.MAVLINK_MSG_ID_CAMERA_FOV_STATUS)
    ok = check(ack is not None and ack.result == mav.MAV_RESULT_ACCEPTED and fov is not None,
               f"after CAMERA_SETTINGS (zoom {s and s.zoomLevel}), REQUEST_MESSAGE CAMERA_FOV_STATUS: {result_name(ack)}, "
               "the message within 1 s (QGCCameraManager.cc:441, 788-795, master 3a8c79b)")
    if not ok:
        return None
    if expect is None:
        check(math.isnan(fov.hfov) and math.isnan(fov.vfov),
              f"no lens configured: hfov {fov.hfov}, vfov {fov.vfov} NaN, which QGC ignores (QGCCameraManager.cc:816-818)")
        return fov
    used = math.isfinite(fov.hfov) and 0.0 < fov.hfov < 180.0
    aspect = info.resolution_v / info.resolution_h if info.resolution_h and info.resolution_v else 16 / 9
    vfov = math.degrees(2 * math.atan(math.tan(math.radians(fov.hfov) / 2) * aspect)) if used else None
    # f32 on the wire: 1e-3 degrees covers its rounding (about 4e-6 at 60 degrees).
    check(used and abs(fov.hfov - expect[0]) < 1e-3 and abs(fov.vfov - expect[1]) < 1e-3
          and vfov is not None and abs(vfov - fov.vfov) < 1e-3,
          f"CAMERA_FOV_STATUS hfov {fov.hfov:.4f} (lens: {expect[0]:.4f}), vfov {fov.vfov:.4f} ({expect[1]:.4f}); QGC uses "
          f"hfov (0 < hfov < 180, :816) and computes vfov {vfov and round(vfov, 4)} from the aspect "
          f"{info.resolution_h}x{info.resolution_v} (:820-840)")
    return fov


def with_bridge(gimbalctl, family, extra, session):
    """A stand-in autopilot and `gimbalctl mavlink --sim --camera FAMILY EXTRA...` for
    `session(port)`; a crash is a failure with its reason; both stopped after."""
    ap = Autopilot()
    ap.start()
    proc, port = start_bridge(gimbalctl, family, ap.port, extra)
    try:
        if check(proc is not None, f"gimbalctl mavlink --sim --camera {' '.join([family, *extra])} starts"):
            session(port)
    except Exception as e:  # a crash is a failure with its reason
        import traceback
        traceback.print_exc()
        check(False, f"crashed: {e!r}")
    finally:
        ap.stopping.set()
        if proc is not None:
            proc.kill()
            proc.wait()


def run_family(gimbalctl, family):
    def session(port):
        qgc = Qgc(port)
        info = discovery(qgc)
        if info is None:
            return
        params = get_definition(qgc, info, family) or {}
        basic = not any(p["control"] for p in params.values())
        values, settings, streams = startup(qgc, info, params)
        changed = set_parameters(qgc, params) if params else []
        modes_and_shutter(qgc, info)
        reset(qgc, params, changed, basic)
        pinch_zoom(qgc, info)
        tracking(qgc, info)
        fov_status(qgc, info, None)
        check(not qgc.bad, f"no malformed frame ({len(qgc.bad)})")

    with_bridge(gimbalctl, family, (), session)


def run_fov(gimbalctl, family):
    """The field of view with a lens configured: at 1x (the bridge starts at its widest), the
    lens's angles; after zooming in, hfov(z) = 2 atan(tan(HFOV / 2) / z) for the zoom ratio z
    the visible streams' VIDEO_STREAM_INFORMATION.hfov (whole degrees) agrees with."""
    extra = ["--camera-fov", f"{FOV_H},{FOV_V:.6f}", "--camera-resolution", f"{FOV_RES[0]}x{FOV_RES[1]}"]

    def session(port):
        qgc = Qgc(port, ACK_TIMEOUT_MASTER)
        since = qgc.mark()
        qgc.wait(lambda m: m.get_type() == "HEARTBEAT" and m.get_srcComponent() == CAMERA, 5.0, since)
        ack, info = qgc.request_message(mav.MAVLINK_MSG_ID_CAMERA_INFORMATION)
        if not check(info is not None and (info.resolution_h, info.resolution_v) == FOV_RES,
                     f"CAMERA_INFORMATION resolution {info and (info.resolution_h, info.resolution_v)}: "
                     f"{FOV_RES} as configured (QGC's aspect, QGCCameraManager.cc:337-345, master)"):
            return
        fov1 = fov_status(qgc, info, (FOV_H, FOV_V))
        streams = video_streams(qgc, info)
        visible = [m for m in streams if not m.flags & mav.VIDEO_STREAM_STATUS_FLAGS_THERMAL]
        thermal = [m for m in streams if m.flags & mav.VIDEO_STREAM_STATUS_FLAGS_THERMAL]
        check(visible and all(m.hfov == int(FOV_H) for m in visible) and all(m.hfov == 0 for m in thermal),
              f"VIDEO_STREAM_INFORMATION.hfov at 1x: visible {[m.hfov for m in visible]} = {int(FOV_H)}, "
              f"thermal {[m.hfov for m in thermal]} 0 (QGCVideoStreamInfo.cc: hfov shown)")
        # One step in: 2x (the bridge's step, docs/mavlink.md).
        ack, _ = qgc.command(mav.MAV_CMD_SET_CAMERA_ZOOM, mav.ZOOM_TYPE_STEP, 1)
        qgc.idle(0.3)
        z = 2.0
        h = math.degrees(2 * math.atan(math.tan(math.radians(FOV_H) / 2) / z))
        v = math.degrees(2 * math.atan(math.tan(math.radians(FOV_V) / 2) / z))
        fov2 = fov_status(qgc, info, (h, v))
        streams = video_streams(qgc, info)
        visible = [m for m in streams if not m.flags & mav.VIDEO_STREAM_STATUS_FLAGS_THERMAL]
        check(fov1 is not None and fov2 is not None and visible and all(m.hfov == int(h) for m in visible),
              f"at {z}x: VIDEO_STREAM_INFORMATION.hfov {[m.hfov for m in visible]} = {int(h)} whole degrees of {h:.3f}")

    with_bridge(gimbalctl, family, extra, session)


def main():
    start = time.monotonic()
    per = []
    for family in FAMILIES:
        CURRENT[0] = family
        before = CHECKS.passed + CHECKS.failed
        t = time.monotonic()
        run_family(sys.argv[1], family)
        run_fov(sys.argv[1], family)
        per.append(f"{family} {CHECKS.passed + CHECKS.failed - before} checks {time.monotonic() - t:.1f} s")
    print(f"qgc_camera: {'; '.join(per)}; ran {time.monotonic() - start:.1f} s", flush=True)
    return CHECKS.summary("qgc_camera")


if __name__ == "__main__":
    sys.exit(main())
