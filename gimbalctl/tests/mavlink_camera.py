#!/usr/bin/env python3
"""pymavlink against the camera component (100) of `gimbalctl mavlink --sim --camera
dual-light`, on UDP loopback: what MAVSDK's Camera plugin (mavsdk_camera.py) cannot reach.

    python3 gimbalctl/tests/mavlink_camera.py target/debug/gimbalctl

An autopilot (system 1, component 1, a quadrotor's HEARTBEAT every second, on the port given
to the bridge with --to) and a ground station (255/190, on a port of its own) talk to one
bridge. Every expectation below is computed here, from the specifications and the clients
named, not copied from the bridge:

1. MAVLink FTP (FILE_TRANSFER_PROTOCOL) on the camera, against its spec (mavlink.io
   services/ftp.md, with PX4's burst read, which the clients are written against):
   - pymavlink's own client, `pymavlink.mavftp.MAVFTP` (pymavlink 2.4.50 mavftp.py: the
     constructor's ResetSessions, `read` and `cmd_get` = OpenFileRO then BurstReadFile and
     gap repair with ReadFile, `cmd_list` = ListDirectory until NAK EOF), downloads the file
     CAMERA_INFORMATION points at (`mftp://camera.xml`, read as QGroundControl's
     FTPManager::_parseURI does: "/camera.xml") and lists "/";
   - hand-built packets (the "<HBBBBBBI" header of mavftp_op.py, padded to 251 bytes) for
     each rule of the server: open, read at the start, the middle, past the end, burst read,
     a session never opened, too many sessions, a path that does not exist, write
     operations, a bad size, an unknown opcode, a re-transmitted request (same sequence
     number: the same reply, no second session), CalcFileCRC32, an idle session reclaimed,
     the reply addressed to whoever asked.
2. The camera definition read by parsers that are not the bridge's: Python's xml.etree with
   the checks of QGroundControl's VehicleCameraControl::_loadCameraDefinitionFile,
   _loadConstants and _loadSettings (src/Camera/VehicleCameraControl.cc) and MAVSDK's
   CameraDefinition::parse_xml (camera_definition.cpp: the default is exactly one option),
   on both files in idu-gimbal-mavlink/camera-definitions/ and on the bytes downloaded; then
   the parameters against what PARAM_EXT_REQUEST_LIST returns, as QGroundControl asks for
   them (VehicleCameraControl::_requestAllParameters).
3. PARAM_EXT_SET of the thermal palette, every value and one too many, each reaching the
   simulated gimbal (which gimbalctl says on stderr).
4. CAMERA_TRACKING_IMAGE_STATUS at the intervals set with MAV_CMD_SET_MESSAGE_INTERVAL
   (500 ms is what QGroundControl's startTracking asks for, -1 what stopTracking sends),
   and its status while tracking.
5. MAV_CMD_CAMERA_TRACK_RECTANGLE / TRACK_POINT at every edge of the image and of the box
   size: the box the simulated gimbal is given, or DENIED and none.
6. MAV_CMD_SET_CAMERA_FOCUS (MAVSDK 4.1's focus_* parameters), 7. MAV_CMD_PREFLIGHT_
   CALIBRATION to the gimbal device (154), 8. MAV_CMD_SET_CAMERA_SOURCE, 9. every
   VIDEO_STREAM_INFORMATION at once (MAV_CMD_REQUEST_MESSAGE param2 0, as QGroundControl's
   _checkForVideoStreams asks).

Ends with a line "mavlink_camera: N passed, M failed"; exit status 0 only if nothing failed.
"""

import math
import os
import re
import struct
import subprocess
import sys
import tempfile
import threading
import time
import xml.etree.ElementTree as ET
import zlib

os.environ["MAVLINK20"] = "1"  # before pymavlink is imported: MAVLink 2 framing
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mav  # noqa: E402
from pymavlink.mavftp import MAVFTP, FtpError  # noqa: E402

from checks import Checks, Inbox, raw_fields, served_definition, sim_options  # noqa: E402

AP_SYSTEM, AP_COMPONENT = 1, 1
GCS_SYSTEM, GCS_COMPONENT = 255, 190
GIMBAL, CAMERA = 154, 100
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFINITIONS = os.path.join(REPO, "idu-gimbal-mavlink", "camera-definitions")
SAID = "gimbalctl mavlink: simulated gimbal: "

# QGroundControl's command ACK timeout is 3 s (Vehicle.cc:2540-2544); on loopback an ACK
# takes milliseconds, so 3 s only matters on a loaded machine.
ACK_TIMEOUT = 3.0
# QGroundControl's FTPManager waits 1 s for an FTP reply (FTPManager.h:257-258).
FTP_TIMEOUT = 1.0
# The simulated gimbal runs in the bridge's own 1 ms loop, and its changes are printed in the
# same tick: a line follows its command within milliseconds; 2 s covers a loaded machine.
EFFECT_TIMEOUT = 2.0
# After a refused command: no line for this long (hundreds of the bridge's ticks).
QUIET = 0.4
# The gimbal's postback (its tracking flag) comes every 500 ms: a change shows in the status
# within one postback and one status interval (100 ms here), 1.5 s with a margin.
POSTBACK_TIMEOUT = 1.5
# QGroundControl's per-parameter timer (QGCCameraIO.cc:377-384).
PARAM_TIMEOUT = 3.5

CHECKS = Checks()
check = CHECKS.check


def result_name(ack):
    return None if ack is None else mav.enums["MAV_RESULT"][ack.result].name


def f32(x):
    """x rounded to the nearest float32, as the bridge holds COMMAND_LONG params and computes.
    An f32 +, -, *, / of f32 operands is exactly the f64 result rounded once to f32 (f64
    has more than twice the bits), so f32(a op b) emulates the bridge's arithmetic."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


# --- the bridge and its stderr -----------------------------------------------------------


class Bridge:
    def __init__(self, gimbalctl, sink_port):
        self.proc = subprocess.Popen(
            [gimbalctl, "mavlink", "--sim", *sim_options(), "--camera", "dual-light", "--listen", "127.0.0.1:0",
             "--to", f"127.0.0.1:{sink_port}", "--exit-after-ms", "120000"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.said = []  # (monotonic time, line)
        self.lock = threading.Lock()
        threading.Thread(target=self._read_stderr, daemon=True).start()
        line = self.proc.stdout.readline()
        self.port = int(line.split("listening on ")[1].split(",")[0].rsplit(":", 1)[1])

    def _read_stderr(self):
        for line in self.proc.stderr:
            print(line, end="", file=sys.stderr, flush=True)
            with self.lock:
                self.said.append((time.monotonic(), line.strip()))

    def mark(self):
        with self.lock:
            return len(self.said)

    def lines(self, since):
        with self.lock:
            return list(self.said[since:])

    def wait_line(self, since, pred, timeout=EFFECT_TIMEOUT):
        """The first line after `since` for which pred holds: (time, line), or None."""
        end = time.monotonic() + timeout
        while True:
            for t, line in self.lines(since):
                if pred(line):
                    return t, line
            if time.monotonic() >= end:
                return None
            time.sleep(0.005)

    def stop(self):
        self.proc.kill()
        self.proc.wait()


# --- the autopilot (on --to) and the ground station ----------------------------------------


class Autopilot(threading.Thread):
    """The autopilot on the port the bridge is given with --to: it answers the bridge from
    there once it has heard it (udpin replies to whoever sent), with a HEARTBEAT every second,
    so the bridge takes system 1. It also sends the ground station's heartbeat every second,
    straight on the ground station's socket with an encoder of its own (so that the bridge,
    which drops a peer after 10 s of silence, keeps it through the longer waits), and drains
    its own socket, which gets everything the bridge sends."""

    def __init__(self):
        super().__init__(daemon=True)
        self.m = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=AP_SYSTEM,
                                            source_component=AP_COMPONENT, dialect="common")
        self.port = self.m.port.getsockname()[1]
        self.gcs_target = None  # (socket, address): set before start()
        self.first_camera_heartbeat = None  # the HEARTBEAT from 100 that reached --to first
        self.heartbeats_sent = 0
        self.stopping = threading.Event()

    def run(self):
        sock, addr = self.gcs_target

        class Out:
            def write(self, buf):
                try:
                    sock.sendto(buf, addr)
                except OSError:
                    pass
        gcs_mav = mav.MAVLink(Out(), srcSystem=GCS_SYSTEM, srcComponent=GCS_COMPONENT)
        next_hb = 0.0
        while not self.stopping.is_set():
            while True:
                msg = self.m.recv_match(blocking=False)
                if msg is None:
                    break
                if (self.first_camera_heartbeat is None and msg.get_type() == "HEARTBEAT"
                        and msg.get_srcComponent() == CAMERA):
                    self.first_camera_heartbeat = msg
            now = time.monotonic()
            # The autopilot speaks once the bridge has spoken to it (udpin learns its address).
            if self.first_camera_heartbeat is not None and now >= next_hb:
                next_hb = now + 1.0
                self.m.mav.heartbeat_send(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_PX4, 0, 0,
                                          mav.MAV_STATE_ACTIVE)
                gcs_mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0,
                                       mav.MAV_STATE_ACTIVE)
                self.heartbeats_sent += 1
            time.sleep(0.005)


class Gcs(Inbox):
    """The ground station: everything the script sends and reads, in this thread."""

    def __init__(self, bridge_port):
        super().__init__(mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{bridge_port}", source_system=GCS_SYSTEM,
            source_component=GCS_COMPONENT, dialect="common"))

    def since(self, since, kind, component=CAMERA):
        self.pump()
        return [(t, m) for t, m in self.messages[since:]
                if m.get_type() == kind and m.get_srcComponent() == component]

    def command(self, component, command, *params, timeout=ACK_TIMEOUT):
        """One COMMAND_LONG (no retry: a command has effects, and loopback loses nothing);
        returns its COMMAND_ACK from `component` or None, and the mark before sending."""
        params = list(params) + [0.0] * (7 - len(params))
        since = self.mark()
        self.m.mav.command_long_send(AP_SYSTEM, component, command, 0, *params)
        ack = self.wait(lambda m: m.get_type() == "COMMAND_ACK" and m.command == command
                        and m.get_srcComponent() == component, timeout, since)
        return ack, since

    def expect(self, component, command, params, result, what):
        ack, since = self.command(component, command, *params)
        check(ack is not None and ack.result == result, f"{what}: ACK {result_name(ack)}")
        return ack, since


# --- MAVLink FTP, by hand -------------------------------------------------------------------

ACK, NAK = 128, 129
OP_NONE, OP_TERMINATE, OP_RESET, OP_LIST, OP_OPEN, OP_READ = 0, 1, 2, 3, 4, 5
OP_CRC, OP_BURST = 14, 15
WRITE_OPS = {6: "CreateFile", 7: "WriteFile", 8: "RemoveFile", 9: "CreateDirectory",
             10: "RemoveDirectory", 11: "OpenFileWO", 12: "TruncateFile", 13: "Rename"}
E_INVALID_SIZE, E_INVALID_SESSION, E_NO_SESSIONS, E_EOF = 3, 4, 5, 6
E_UNKNOWN, E_PROTECTED, E_NOT_FOUND = 7, 9, 10


def ftp_packet(seq, session, opcode, offset=0, data=b"", size=None):
    size = len(data) if size is None else size
    head = struct.pack("<HBBBBBBI", seq, session, opcode, size, 0, 0, 0, offset)
    return (head + data).ljust(251, b"\0")


class FtpReply:
    def __init__(self, msg):
        p = bytes(msg.payload)
        (self.seq, self.session, self.opcode, self.size, self.req_opcode, self.burst_complete,
         _, self.offset) = struct.unpack_from("<HBBBBBBI", p)
        self.data = p[12:12 + self.size]
        self.raw = p
        self.target = (msg.target_system, msg.target_component)

    def __repr__(self):
        kind = {ACK: "ACK", NAK: "NAK"}.get(self.opcode, self.opcode)
        return (f"{kind} seq {self.seq} session {self.session} size {self.size} req {self.req_opcode}"
                f" off {self.offset} complete {self.burst_complete} data {self.data[:12]!r}")


class RawFtp:
    def __init__(self, gcs):
        self.gcs = gcs
        self.seq = 1000  # ours; MAVFTP's start at 0

    def next_seq(self):
        self.seq += 1
        return self.seq

    def send(self, packet, component=GCS_COMPONENT):
        m = self.gcs.m.mav
        m.srcComponent = component
        try:
            m.file_transfer_protocol_send(0, AP_SYSTEM, CAMERA, list(packet))
        finally:
            m.srcComponent = GCS_COMPONENT

    def replies(self, since, component=GCS_COMPONENT):
        return [FtpReply(m) for _, m in self.gcs.since(since, "FILE_TRANSFER_PROTOCOL")
                if m.target_component == component]

    def request(self, session, opcode, offset=0, data=b"", size=None, seq=None, component=GCS_COMPONENT):
        """Sends one request; returns (seq, its reply or None)."""
        seq = self.next_seq() if seq is None else seq
        since = self.gcs.mark()
        self.send(ftp_packet(seq, session, opcode, offset, data, size), component)
        end = time.monotonic() + FTP_TIMEOUT
        while time.monotonic() < end:
            got = self.replies(since, component)
            if got:
                return seq, got[0]
            time.sleep(0.001)
        return seq, None

    def is_reply(self, r, seq, opcode, component=GCS_COMPONENT):
        """The reply to request `seq` of `opcode`, addressed to its sender (the server's rules:
        seq + 1, req_opcode the request's, target the requester's system and component)."""
        return (r is not None and r.seq == (seq + 1) % 65536 and r.req_opcode == opcode
                and r.target == (GCS_SYSTEM, component))

    def expect_nak(self, session, opcode, code, what, **kw):
        seq, r = self.request(session, opcode, **kw)
        check(self.is_reply(r, seq, opcode) and r.opcode == NAK and r.size == 1 and r.data[0] == code,
              f"FTP {what}: NAK {code} (size 1), seq {seq}+1 to 255/190: {r}")
        return r

    def burst(self, session, offset, size):
        """A BurstReadFile: every packet until one says burst_complete (or 2 s: at the bridge's
        pace, a packet a tick, 2 KB takes a few tens of ms)."""
        seq = self.next_seq()
        since = self.gcs.mark()
        self.send(ftp_packet(seq, session, OP_BURST, offset, size=size))
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            got = self.replies(since)
            if got and (got[-1].burst_complete or got[-1].opcode == NAK):
                break
            time.sleep(0.002)
        return seq, self.replies(since)


def expected_crc(data):
    """MAVLink FTP's CalcFileCRC32: mavlink.io's "MAVLink CRC" (PX4's crc32part, which
    MavlinkFTP::_workCalcFileCRC32 starts at 0): the reflected CRC-32 (polynomial 0xEDB88320)
    with initial value 0 and no final XOR. Written out bit by bit here."""
    crc = 0
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ (0xEDB88320 if crc & 1 else 0)
    return crc


def ftp_raw_tests(gcs, xml):
    """Hand-built requests against each rule. Leaves two sessions open and idle, for the
    reclaim test later; returns (the session expected reclaimed, when they went idle)."""
    ftp = RawFtp(gcs)
    n = len(xml)
    u32 = lambda b: struct.unpack("<I", b)[0] if len(b) == 4 else None  # noqa: E731

    seq, r = ftp.request(0, OP_RESET)
    check(ftp.is_reply(r, seq, OP_RESET) and r.opcode == ACK and r.size == 0,
          f"FTP ResetSessions: ACK, seq {seq}+1, to 255/190: {r}")
    seq, r = ftp.request(0, OP_NONE)
    check(ftp.is_reply(r, seq, OP_NONE) and r.opcode == ACK, f"FTP None: ACK (\"always ACKed\"): {r}")
    # A request from another component of the ground station gets its reply addressed there.
    seq, r = ftp.request(0, OP_NONE, component=191)
    check(ftp.is_reply(r, seq, OP_NONE, component=191) and r.opcode == ACK,
          f"FTP reply addressed to the requester (255/191): {r and r.target}")

    # Open: the session (numbered from 0) and the file's length, u32, size 4.
    seq, r = ftp.request(0, OP_OPEN, data=b"/camera.xml")
    ok = check(ftp.is_reply(r, seq, OP_OPEN) and r.opcode == ACK and r.size == 4 and u32(r.data) == n
               and r.session == 0, f"FTP OpenFileRO /camera.xml: ACK, session 0, size 4, length {n}: {r}")
    s0 = r.session if ok else 0

    # Reads: at 0, in the middle, across the end (short), at the end and past it (EOF).
    for offset, size in ((0, 239), (n // 2, 100), (n - 10, 239)):
        seq, r = ftp.request(s0, OP_READ, offset=offset, size=size)
        want = xml[offset:offset + size]
        check(ftp.is_reply(r, seq, OP_READ) and r.opcode == ACK and r.offset == offset
              and r.size == len(want) and r.data == want,
              f"FTP ReadFile offset {offset} size {size}: the file's {len(want)} bytes there: {r}")
    ftp.expect_nak(s0, OP_READ, E_EOF, f"ReadFile at the end (offset {n})", offset=n, size=100)
    ftp.expect_nak(s0, OP_READ, E_EOF, f"ReadFile past the end (offset {n + 1000})", offset=n + 1000, size=100)
    ftp.expect_nak(1, OP_READ, E_INVALID_SESSION, "ReadFile in session 1, never opened", size=10)
    ftp.expect_nak(200, OP_READ, E_INVALID_SESSION, "ReadFile in session 200 (no such)", size=10)

    # Burst reads: consecutive seq from the request's + 1, offsets advancing by the size
    # asked (239 for 0), burst_complete on the packet reaching the end, and only there.
    # 239 is what QGroundControl asks for (FTPManager::_burstReadFileWorker: size =
    # sizeof(request.data)); pymavlink asks for 80, then 239.
    for size in (100, 239, 0):
        chunk = size or 239
        seq, packets = ftp.burst(s0, 0, size)
        want = [(o, xml[o:o + chunk]) for o in range(0, n, chunk)]
        ok = (len(packets) == len(want)
              and all(p.opcode == ACK and p.req_opcode == OP_BURST and p.target == (GCS_SYSTEM, GCS_COMPONENT)
                      and p.seq == (seq + 1 + i) % 65536 and p.offset == o and p.data == d
                      and p.burst_complete == (1 if i == len(want) - 1 else 0)
                      for i, (p, (o, d)) in enumerate(zip(packets, want))))
        check(ok and b"".join(p.data for p in packets) == xml,
              f"FTP BurstReadFile size {size}: {len(want)} packets of {chunk} bytes with the file's bytes, "
              f"seq {seq}+1.., only the last complete: got (offset, size, data bytes, complete) "
              f"{[(p.offset, p.size, len(p.data), p.burst_complete) for p in packets]}")
    seq, packets = ftp.burst(s0, n, 100)
    r = packets[0] if packets else None
    check(len(packets) == 1 and ftp.is_reply(r, seq, OP_BURST) and r.opcode == NAK and r.size == 1
          and r.data[0] == E_EOF, f"FTP BurstReadFile at the end: one NAK EOF: {packets}")

    # CalcFileCRC32: the value computed here, and which zlib form it is.
    seq, r = ftp.request(0, OP_CRC, data=b"/camera.xml")
    mine = expected_crc(xml)
    zlib_form = zlib.crc32(xml, 0xFFFFFFFF) ^ 0xFFFFFFFF  # zlib's, started at 0 and not inverted
    got = u32(r.data) if r is not None else None
    check(ftp.is_reply(r, seq, OP_CRC) and r.opcode == ACK and r.size == 4 and got == mine == zlib_form,
          f"FTP CalcFileCRC32: 0x{got or 0:08x}, expected 0x{mine:08x} (CRC-32 from 0, no final XOR "
          f"= zlib.crc32(data, 0xffffffff) ^ 0xffffffff; the ISO-HDLC zlib.crc32 is 0x{zlib.crc32(xml):08x})")
    ftp.expect_nak(0, OP_CRC, E_NOT_FOUND, "CalcFileCRC32 /nope.xml", data=b"/nope.xml")

    ftp.expect_nak(0, OP_OPEN, E_NOT_FOUND, "OpenFileRO /nope.xml (a session free)", data=b"/nope.xml")
    for op, name in WRITE_OPS.items():
        ftp.expect_nak(0, op, E_PROTECTED, f"{name} ({op}) /camera.xml", data=b"/camera.xml")
    ftp.expect_nak(s0, OP_READ, E_INVALID_SIZE, "ReadFile size 240", size=240)
    ftp.expect_nak(0, OP_OPEN, E_INVALID_SIZE, "OpenFileRO size 240", data=b"/camera.xml", size=240)
    ftp.expect_nak(0, 42, E_UNKNOWN, "opcode 42")

    # ListDirectory: one entry, "F<name>\t<size>" NUL-terminated, then EOF.
    seq, r = ftp.request(0, OP_LIST, data=b"/")
    entry = b"Fcamera.xml\t" + str(n).encode() + b"\0"
    check(ftp.is_reply(r, seq, OP_LIST) and r.opcode == ACK and r.data == entry,
          f"FTP ListDirectory /: {entry!r}: {r and r.data!r}")
    ftp.expect_nak(0, OP_LIST, E_EOF, "ListDirectory / from entry 1", data=b"/", offset=1)
    ftp.expect_nak(0, OP_LIST, E_NOT_FOUND, "ListDirectory /camera.xml (not a directory)", data=b"/camera.xml")

    # The path as each client sends it: with or without "/", with or without a NUL. A session
    # is the client's number, echoed (MAVProxy picks its own and routes replies by it,
    # mavproxy_ftp.py; ArduPilot's GCS_FTP.cpp does the same): the second session, then none
    # left for a third; TerminateSession frees it.
    seq, r = ftp.request(1, OP_OPEN, data=b"camera.xml")
    check(ftp.is_reply(r, seq, OP_OPEN) and r.opcode == ACK and u32(r.data) == n and r.session == 1,
          f"FTP OpenFileRO camera.xml in session 1: ACK in session 1, length {n}: {r}")
    s1 = 1
    ftp.expect_nak(2, OP_OPEN, E_NO_SESSIONS, "a third session (2) with two open", data=b"/camera.xml\0")
    for path in (b"/camera.xml\0", b"camera.xml\0"):
        seq, r = ftp.request(s1, OP_TERMINATE)
        check(ftp.is_reply(r, seq, OP_TERMINATE) and r.opcode == ACK and r.session == s1,
              f"FTP TerminateSession {s1}: ACK: {r}")
        seq, r = ftp.request(s1, OP_OPEN, data=path)
        check(ftp.is_reply(r, seq, OP_OPEN) and r.opcode == ACK and u32(r.data) == n and r.session == s1,
              f"FTP OpenFileRO {path!r} in the freed session {s1}: length {n}: {r}")
    seq, r = ftp.request(s1, OP_TERMINATE)
    check(ftp.is_reply(r, seq, OP_TERMINATE) and r.opcode == ACK, f"FTP TerminateSession {s1}: ACK: {r}")
    # A session not open: ACK as ArduPilot's server does (MAVProxy terminates on every exit).
    seq, r = ftp.request(s1, OP_TERMINATE)
    check(ftp.is_reply(r, seq, OP_TERMINATE) and r.opcode == ACK,
          f"FTP TerminateSession {s1} again (not open): ACK: {r}")

    # Re-transmission: the same seq and bytes get the same reply, and open no second session.
    ftp.request(0, OP_RESET)
    seq, first = ftp.request(0, OP_OPEN, data=b"/camera.xml")
    _, again = ftp.request(0, OP_OPEN, data=b"/camera.xml", seq=seq)
    check(first is not None and again is not None and first.raw == again.raw and first.opcode == ACK,
          f"FTP OpenFileRO re-sent with seq {seq}: the same reply ({first} / {again})")
    a = 0
    seq, first = ftp.request(a, OP_READ, offset=0, size=50)
    _, again = ftp.request(a, OP_READ, offset=0, size=50, seq=seq)
    check(first is not None and again is not None and first.raw == again.raw and first.data == xml[:50],
          f"FTP ReadFile re-sent with seq {seq}: the same bytes")
    # A retried open after another request (a new seq, the same session): the same session
    # re-opened, no second slot taken.
    seq, r = ftp.request(a, OP_OPEN, data=b"/camera.xml")
    check(ftp.is_reply(r, seq, OP_OPEN) and r.opcode == ACK and r.session == a,
          f"FTP OpenFileRO retried after another request: session {a} re-opened: {r}")
    b = 1
    seq, r = ftp.request(b, OP_OPEN, data=b"/camera.xml")
    check(ftp.is_reply(r, seq, OP_OPEN) and r.opcode == ACK and r.session == b,
          f"FTP the second session still free for another open: {r}")
    seq, first = ftp.request(b, OP_TERMINATE)
    _, again = ftp.request(b, OP_TERMINATE, seq=seq)
    check(first is not None and again is not None and first.opcode == ACK and first.raw == again.raw,
          f"FTP TerminateSession re-sent: ACK again ({again})")
    seq, r = ftp.request(b, OP_OPEN, data=b"/camera.xml")
    check(ftp.is_reply(r, seq, OP_OPEN) and r.opcode == ACK and r.session == b, f"FTP re-open session {b}: {r}")
    ftp.expect_nak(2, OP_OPEN, E_NO_SESSIONS, "OpenFileRO in a third session with both open (idle < 5 s)",
                   data=b"/camera.xml")
    # Session a was last used before b: it is the one idle longest.
    return ftp, a, time.monotonic()


def ftp_reclaim_test(ftp, oldest, idle_since):
    """Both sessions idle for more than 5 s: an OpenFileRO in a third session takes the slot of
    the one idle longest, which is then gone."""
    idle = time.monotonic() - idle_since
    seq, r = ftp.request(2, OP_OPEN, data=b"/camera.xml")
    check(idle > 5.0 and ftp.is_reply(r, seq, OP_OPEN) and r.opcode == ACK and r.session == 2,
          f"FTP OpenFileRO in session 2 after {idle:.1f} s idle: ACK: {r}")
    ftp.expect_nak(oldest, OP_READ, E_INVALID_SESSION, f"session {oldest} (idle longest) reclaimed", size=10)
    ftp.request(0, OP_RESET)


# --- the camera definition -----------------------------------------------------------------

# FactMetaData::stringToType (FactMetaData.h:397-429, .cc:837-850), case-insensitive.
INT_RANGES = {"uint8": (0, 2**8 - 1), "int8": (-2**7, 2**7 - 1), "uint16": (0, 2**16 - 1),
              "int16": (-2**15, 2**15 - 1), "uint32": (0, 2**32 - 1), "int32": (-2**31, 2**31 - 1),
              "uint64": (0, 2**64 - 1), "int64": (-2**63, 2**63 - 1)}
KNOWN_TYPES = set(INT_RANGES) | {"float", "double", "string", "bool", "elapsedseconds", "custom"}
EXT_TYPES = {"uint8": 1, "int8": 2, "uint16": 3, "int16": 4, "uint32": 5, "int32": 6,
             "uint64": 7, "int64": 8, "float": 9, "double": 10, "custom": 11}


def value_ok(kind, text):
    """A value of `kind`: decimal integers within the type's range (MAVSDK parses them with
    std::stoi: no hex, nothing else), numbers for float/double, 0/1 for bool."""
    if text is None:
        return False
    kind = kind.lower()
    if kind in INT_RANGES or kind == "bool":
        lo, hi = INT_RANGES.get(kind, (0, 1))
        return re.fullmatch(r"-?[0-9]+", text) is not None and lo <= int(text) <= hi
    if kind in ("float", "double"):
        try:
            return math.isfinite(float(text))
        except ValueError:
            return False
    return True  # string, custom, ElapsedSeconds: not numbers to MAVSDK (skipped there)


def number(text):
    return float(text) if re.fullmatch(r"-?[0-9]+", text or "") is None else int(text)


def validate_definition(data, label, want_version):
    """The checks QGroundControl applies before it uses a definition (qgc.md §1.2; any
    failure rejects the whole file, the camera then having no settings), with MAVSDK's where
    stricter. Returns the parameters [(name, type, default)] (None if it does not parse)."""
    # VCC:1109-1164, 840-844: the file must parse.
    try:
        root = ET.fromstring(data)
    except ET.ParseError as e:
        check(False, f"{label}: parses ({e})")
        return None
    check(True, f"{label}: parses (xml.etree)")
    # MAVSDK parse_xml requires the root <mavlinkcamera>; QGC finds <definition> anywhere.
    problems = [] if root.tag == "mavlinkcamera" else [f"root <{root.tag}>"]
    # VCC:874-887 _loadConstants: <definition version>, its <model> and <vendor> children
    # (MAVSDK needs their text non-empty: GetText() into a std::string).
    d = root.find(".//definition")
    if d is None:
        problems.append("no <definition>")
    else:
        v = d.get("version")
        if v is None or re.fullmatch(r"[0-9]+", v) is None:
            problems.append(f"version {v!r} not an integer")
        elif want_version is not None and int(v) != want_version:
            problems.append(f"version {v} != cam_definition_version {want_version}")
        for tag in ("model", "vendor"):
            e = d.find(tag)
            if e is None or not (e.text or "").strip():
                problems.append(f"<{tag}> missing or empty")
    check(not problems, f"{label}: <mavlinkcamera><definition version={want_version if want_version else 'N'}>"
          f" with <model> and <vendor> (QGC _loadConstants, VCC:874-887): {problems or 'ok'}")
    # VCC:852-855: <parameters> required; VCC:889-1107 _loadSettings over its <parameter>s.
    problems = []
    params = []
    ps = root.find(".//parameters")
    if ps is None:
        check(False, f"{label}: <parameters> present (VCC:852-855)")
        return None
    names = set()
    for p in ps.iter("parameter"):
        name, kind, default = p.get("name"), p.get("type"), p.get("default")
        if not name:  # VCC:897-907
            problems.append("a parameter without a name")
            continue
        if name in names:  # VCC:1012-1014 (QGC skips it with a warning; an error here)
            problems.append(f"{name}: duplicate")
        names.add(name)
        if kind is None or kind.lower() not in KNOWN_TYPES:  # VCC:914-918, 933-937
            problems.append(f"{name}: type {kind!r}")
            continue
        desc = p.find("description")  # VCC:944-947 (MAVSDK: text non-empty)
        if desc is None or not (desc.text or "").strip():
            problems.append(f"{name}: no <description>")
        if not value_ok(kind, default):  # VCC:999-1010 warns; MAVSDK drops it without a default
            problems.append(f"{name}: default {default!r} not a {kind}")
        options = p.findall("options/option")
        if options:
            values = []
            for o in options:  # VCC:2079-2088: name and value required
                if not o.get("name") or o.get("value") is None:
                    problems.append(f"{name}: option without name or value")
                elif not value_ok(kind, o.get("value")):  # VCC:2090-2095 warns
                    problems.append(f"{name}: option value {o.get('value')!r} not a {kind}")
                else:
                    values.append(number(o.get("value")))
            if len(set(values)) != len(values):
                problems.append(f"{name}: duplicate option values")
            # MAVSDK camera_definition.cpp: the default must equal exactly one option value.
            if value_ok(kind, default) and values.count(number(default)) != 1:
                problems.append(f"{name}: default {default} is not exactly one option's value")
        elif kind.lower() not in ("bool", "string", "custom") and (p.get("min") is None or p.get("max") is None):
            problems.append(f"{name}: neither options nor min/max (MAVSDK drops it)")
        params.append((name, kind.lower(), default))
    if not params:  # VCC:1099-1106
        problems.append("no parameter")
    check(not problems, f"{label}: {len(params)} parameters, each named, typed, described, its default "
          f"one of its options (QGC _loadSettings VCC:889-1107, MAVSDK parse_xml): {problems or 'ok'}")
    return params


# --- the sessions' parts --------------------------------------------------------------------


def camera_information(gcs):
    ack, since = gcs.expect(CAMERA, mav.MAV_CMD_REQUEST_MESSAGE, [mav.MAVLINK_MSG_ID_CAMERA_INFORMATION],
                            mav.MAV_RESULT_ACCEPTED, "REQUEST_MESSAGE CAMERA_INFORMATION")
    info = gcs.wait(lambda m: m.get_type() == "CAMERA_INFORMATION" and m.get_srcComponent() == CAMERA,
                    ACK_TIMEOUT, since)
    # The files' own version, which clients cache the definition under.
    with open(os.path.join(DEFINITIONS, "idu-dual-light.xml"), "rb") as f:
        version = int(re.search(rb'<definition version="(\d+)"', f.read()).group(1))
    check(info is not None and info.cam_definition_uri == "mftp://camera.xml"
          and info.cam_definition_version == version,
          f"CAMERA_INFORMATION: {info.cam_definition_uri if info else None!r} "
          f"version {info.cam_definition_version if info else None} (the files' {version})")
    return info


def parameters(gcs, xml_params, bridge):
    """PARAM_EXT_REQUEST_LIST as QGroundControl sends it, then the palette's every value."""
    since = gcs.mark()
    gcs.m.mav.param_ext_request_list_send(AP_SYSTEM, CAMERA)
    n = len(xml_params)
    gcs.wait(lambda m: len(gcs.since(since, "PARAM_EXT_VALUE")) >= n, PARAM_TIMEOUT, since)
    gcs.idle(0.5)  # and nothing more (one value a parameter)
    values = [raw_fields(m) for _, m in gcs.since(since, "PARAM_EXT_VALUE")]
    got = [(v["param_id"].rstrip(b"\0").decode(), v["param_type"], v["param_value"][0],
            v["param_value"][1:] == bytes(127), v["param_count"], v["param_index"]) for v in values]
    want = [(name, EXT_TYPES[kind], int(default), True, n, i) for i, (name, kind, default) in enumerate(xml_params)]
    check(got == want, "PARAM_EXT_REQUEST_LIST: one PARAM_EXT_VALUE a parameter, in the XML's order, "
          f"UINT8, value byte-wise = the default, count {n}, indexes 0..{n - 1}: {got}")

    palettes = ["black-hot", "white-hot", "iron-red", "rainbow", "lava", "rainbow-enhanced",
                "molten-metal", "bluish-red", "amber", "amber-inverted", "ice-blue", "high-contrast",
                "grayscale-inverted", "hot-red", "cold-blue"]
    # 0 last: the simulated gimbal says a palette when it changes, and 0 is the default.
    for code in list(range(1, 15)) + [0]:
        ack, line = set_palette(gcs, bridge, code)
        check(ack == (0, code) and line == SAID + "palette " + palettes[code],
              f"PARAM_EXT_SET IR_PALETTE {code}: ACK (result, value) {ack}, the gimbal says {line!r}")
    ack, line = set_palette(gcs, bridge, 15, wait=QUIET)
    check(ack == (mav.PARAM_ACK_VALUE_UNSUPPORTED, 0) and line is None,
          f"PARAM_EXT_SET IR_PALETTE 15: ACK VALUE_UNSUPPORTED with the value kept (0): {ack}, no palette said ({line!r})")
    since = gcs.mark()
    gcs.m.mav.param_ext_request_read_send(AP_SYSTEM, CAMERA, b"IR_PALETTE", -1)
    v = gcs.wait(lambda m: m.get_type() == "PARAM_EXT_VALUE" and m.get_srcComponent() == CAMERA, PARAM_TIMEOUT, since)
    f = raw_fields(v) if v else {}
    check(v is not None and f["param_id"].rstrip(b"\0") == b"IR_PALETTE" and f["param_value"] == bytes(128)
          and f["param_index"] == [p[0] for p in xml_params].index("IR_PALETTE"),
          f"PARAM_EXT_REQUEST_READ IR_PALETTE (by name): 0, index {f.get('param_index')}")


def set_palette(gcs, bridge, code, wait=EFFECT_TIMEOUT):
    """Returns ((param_result, value byte) of the PARAM_EXT_ACK, the palette line said).
    The value goes byte-wise at param_value[0] (parameter_ext.md), the rest zero; it is
    read back from the wire bytes, since pymavlink's str of "\\0..." is ""."""
    mark = bridge.mark()
    since = gcs.mark()
    gcs.m.mav.param_ext_set_send(AP_SYSTEM, CAMERA, b"IR_PALETTE", bytes([code]) + bytes(127),
                                 mav.MAV_PARAM_EXT_TYPE_UINT8)
    ack = gcs.wait(lambda m: m.get_type() == "PARAM_EXT_ACK" and m.get_srcComponent() == CAMERA, PARAM_TIMEOUT, since)
    said = bridge.wait_line(mark, lambda s: s.startswith(SAID + "palette"), wait)
    if ack is None:
        return None, said and said[1]
    f = raw_fields(ack)
    ok_rest = f["param_value"][1:] == bytes(127) and f["param_id"].rstrip(b"\0") == b"IR_PALETTE" \
        and f["param_type"] == mav.MAV_PARAM_EXT_TYPE_UINT8
    return (f["param_result"], f["param_value"][0] if ok_rest else ("bad", f)), said and said[1]


def tracking_status(gcs, bridge):
    """The status's rates, and what it says while tracking."""
    kind = "CAMERA_TRACKING_IMAGE_STATUS"

    def set_interval(us, result):
        return gcs.expect(CAMERA, mav.MAV_CMD_SET_MESSAGE_INTERVAL, [mav.MAVLINK_MSG_ID_CAMERA_TRACKING_IMAGE_STATUS, us],
                          result, f"SET_MESSAGE_INTERVAL {kind} {us} us")

    # The bridge sends when due in its 1 ms loop and then schedules the next one an interval
    # later: each period is the interval plus at most about a tick (+0.2 % at 500 ms, +1 %
    # at 100 ms). What is measured here is when this script read them: the first and last
    # receptions may each be late by a scheduling delay (tens of ms on a loaded machine, ~1 %
    # of 3 s). 10 % either way holds all of that with a margin and still tells 2 Hz from
    # 1.7 or 2.5 Hz.
    for us, hz in ((500000, 2.0), (100000, 10.0)):
        ack, since = set_interval(us, mav.MAV_RESULT_ACCEPTED)
        gcs.idle(3.0)
        times = [t for t, _ in gcs.since(since, kind)]
        rate = (len(times) - 1) / (times[-1] - times[0]) if len(times) > 2 else 0.0
        check(abs(rate - hz) <= 0.1 * hz, f"{kind} every {us} us: {rate:.2f} Hz ({len(times)} in 3 s), {hz} Hz +-10 %")
    # Now at 10 Hz: idle, then a rectangle, then stopped.
    latest = lambda since: ([m for _, m in gcs.since(since, kind)] or [None])[-1]  # noqa: E731
    s = latest(0)

    def nothing_known(s):
        return (s.target_data == 0 and all(math.isnan(getattr(s, f)) for f in (
            "point_x", "point_y", "radius", "rec_top_x", "rec_top_y", "rec_bottom_x", "rec_bottom_y")))
    check(s is not None and s.tracking_status == 0 and s.tracking_mode == 0 and nothing_known(s),
          f"{kind} before tracking: IDLE, mode NONE, target_data 0, coordinates NaN")
    # While tracking, the target at the image's centre (the gimbal's tracker turns it there)
    # with the box it was given: a 0.25 square, a point of radius 0.1 off centre.
    centred = {
        mav.CAMERA_TRACKING_MODE_RECTANGLE: lambda s: (
            (s.rec_top_x, s.rec_top_y, s.rec_bottom_x, s.rec_bottom_y) == (0.375, 0.375, 0.625, 0.625)
            and math.isnan(s.point_x)),
        mav.CAMERA_TRACKING_MODE_POINT: lambda s: (
            (s.point_x, s.point_y) == (0.5, 0.5) and abs(s.radius - 0.1) < 1e-6 and math.isnan(s.rec_top_x)),
    }
    for command, params, mode in ((mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.25, 0.25, 0.5, 0.5], mav.CAMERA_TRACKING_MODE_RECTANGLE),
                                  (mav.MAV_CMD_CAMERA_TRACK_POINT, [0.3, 0.7, 0.1], mav.CAMERA_TRACKING_MODE_POINT)):
        name = mav.enums["MAV_CMD"][command].name
        ack, since = gcs.expect(CAMERA, command, params, mav.MAV_RESULT_ACCEPTED, name)
        t0 = time.monotonic()
        s = gcs.wait(lambda m: m.get_type() == kind and m.tracking_status == 1, POSTBACK_TIMEOUT, since)
        check(s is not None and s.tracking_mode == mode
              and s.target_data == mav.CAMERA_TRACKING_TARGET_DATA_IN_STATUS and centred[mode](s),
              f"{kind} after {name}: ACTIVE in {time.monotonic() - t0:.2f} s, mode {mode}, "
              f"the target at the centre with the box given: {s}")
        ack, since = gcs.expect(CAMERA, mav.MAV_CMD_CAMERA_STOP_TRACKING, [], mav.MAV_RESULT_ACCEPTED, "CAMERA_STOP_TRACKING")
        t0 = time.monotonic()
        s = gcs.wait(lambda m: m.get_type() == kind and m.tracking_status == 0, POSTBACK_TIMEOUT, since)
        check(s is not None and s.tracking_mode == 0 and nothing_known(s),
              f"{kind} after CAMERA_STOP_TRACKING: IDLE in {time.monotonic() - t0:.2f} s, mode NONE")
    ack, since = set_interval(-1, mav.MAV_RESULT_ACCEPTED)
    after = gcs.mark()
    gcs.idle(1.5)
    check(not gcs.since(after, kind), f"{kind} interval -1: none for 1.5 s ({len(gcs.since(after, kind))})")
    set_interval(500, mav.MAV_RESULT_DENIED)
    after = gcs.mark()
    gcs.idle(0.3)
    check(not gcs.since(after, kind), f"{kind} after the refused 500 us: still none")


def half_away(x):
    """roundf: halves away from zero."""
    return math.floor(x + 0.5) if x >= 0 else -math.floor(-x + 0.5)


def unit(v):
    return v is not None and not math.isnan(v) and 0.0 <= v <= 1.0


def expect_box(cx, cy, w, h):
    """The line for a box of normalized centre and sides (float32 values), or None if the
    gimbal cannot be given it: centre × 8191 rounded; sides × 8192, at most 255 × 16 = 4080
    units, sent /16 rounded."""
    x, y = half_away(f32(cx * 8191.0)), half_away(f32(cy * 8191.0))
    sides = [f32(s * 8192.0) for s in (w, h)]
    if any(s > 4080.0 for s in sides):
        return None
    sw, sh = (half_away(f32(s / 16.0)) * 16 for s in sides)
    return f"{SAID}tracking a {sw}x{sh} box at ({x}, {y})"


def expect_rectangle(x1, y1, x2, y2):
    p = [f32(v) for v in (x1, y1, x2, y2)]  # COMMAND_LONG params are float32
    if not all(unit(v) for v in p):
        return None
    x1, y1, x2, y2 = p
    return expect_box(f32(f32(x1 + x2) / 2.0), f32(f32(y1 + y2) / 2.0), abs(f32(x2 - x1)), abs(f32(y2 - y1)))


def expect_point(x, y, r):
    x, y, r = (f32(v) for v in (x, y, r))
    if not all(unit(v) for v in (x, y, r)):
        return None
    side = max(f32(2.0 * r), f32(256.0 / 8192.0))  # the box: 2r, at least 1/32 of the image
    return expect_box(x, y, side, side)


def tracking_edges(gcs, bridge):
    nan = math.nan
    cases = [
        ("rectangle at the top-left corner, zero size", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0, 0, 0, 0]),
        ("rectangle at the bottom-right corner, zero size", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [1, 1, 1, 1]),
        ("rectangle (0.25, 0.25)-(0.5, 0.5)", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.25, 0.25, 0.5, 0.5]),
        ("the same, corners reversed", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.5, 0.5, 0.25, 0.25]),
        ("rectangle (0.1, 0.2)-(0.3, 0.6), not square", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.1, 0.2, 0.3, 0.6]),
        ("the same, x corners swapped", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.3, 0.2, 0.1, 0.6]),
        ("rectangle centred at 0.515625 (x 8191 = 4223.48 in f32)", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE,
         [0.5, 0.5, 0.53125, 0.53125]),
        ("the largest box, sides 0.498046875 (4080 units)", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE,
         [0.25, 0.25, 0.748046875, 0.748046875]),
        ("the largest box's width only", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.0, 0.4, 0.498046875, 0.6]),
        ("sides 0.4981, just above the largest", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.25, 0.25, 0.7481, 0.7481]),
        ("height 0.4981 only", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.4, 0.25, 0.6, 0.7481]),
        ("the whole image", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0, 0, 1, 1]),
        ("x -0.01", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [-0.01, 0.2, 0.3, 0.4]),
        ("bottom-right x 1.01", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.8, 0.2, 1.01, 0.4]),
        ("y NaN", mav.MAV_CMD_CAMERA_TRACK_RECTANGLE, [0.2, nan, 0.3, 0.4]),
        ("point at (0, 0), radius 0", mav.MAV_CMD_CAMERA_TRACK_POINT, [0, 0, 0]),
        ("point at (1, 0), radius 0", mav.MAV_CMD_CAMERA_TRACK_POINT, [1, 0, 0]),
        ("point at (0, 1), radius 0", mav.MAV_CMD_CAMERA_TRACK_POINT, [0, 1, 0]),
        ("point at (1, 1), radius 0", mav.MAV_CMD_CAMERA_TRACK_POINT, [1, 1, 0]),
        ("point at the centre, radius 0 (the 1/32 floor)", mav.MAV_CMD_CAMERA_TRACK_POINT, [0.5, 0.5, 0]),
        ("point, radius 0.1", mav.MAV_CMD_CAMERA_TRACK_POINT, [0.3, 0.7, 0.1]),
        ("point, radius 0.2490234375 (2r the largest side)", mav.MAV_CMD_CAMERA_TRACK_POINT, [0.5, 0.5, 0.2490234375]),
        ("point, radius 0.2491 (2r above it)", mav.MAV_CMD_CAMERA_TRACK_POINT, [0.5, 0.5, 0.2491]),
        ("point, radius 0.25", mav.MAV_CMD_CAMERA_TRACK_POINT, [0.5, 0.5, 0.25]),
        ("point, radius -0.1", mav.MAV_CMD_CAMERA_TRACK_POINT, [0.5, 0.5, -0.1]),
        ("point at x 1.5", mav.MAV_CMD_CAMERA_TRACK_POINT, [1.5, 0.5, 0]),
        ("point at x NaN", mav.MAV_CMD_CAMERA_TRACK_POINT, [nan, 0.5, 0]),
    ]
    for what, command, params in cases:
        track_case(gcs, bridge, what, command, params)


def track_case(gcs, bridge, what, command, params):
    rect = command == mav.MAV_CMD_CAMERA_TRACK_RECTANGLE
    want = expect_rectangle(*params) if rect else expect_point(*params)
    name = "TRACK_RECTANGLE" if rect else "TRACK_POINT"
    label = f"{name} {what} {params}"
    mark = bridge.mark()
    if want is None:
        gcs.expect(CAMERA, command, params, mav.MAV_RESULT_DENIED, label)
        gcs.idle(QUIET)
        said = [l for _, l in bridge.lines(mark) if l.startswith(SAID + "tracking")]
        check(not said, f"{label}: the gimbal tracks nothing ({said})")
        return
    ack, _ = gcs.expect(CAMERA, command, params, mav.MAV_RESULT_ACCEPTED, label)
    got = bridge.wait_line(mark, lambda l: l.startswith(SAID + "tracking") or l.startswith(SAID + "target lost"))
    check(got is not None and got[1] == want, f"{label}: {want[len(SAID):]!r}, said {got and got[1][len(SAID):]!r}")
    mark = bridge.mark()
    gcs.expect(CAMERA, mav.MAV_CMD_CAMERA_STOP_TRACKING, [], mav.MAV_RESULT_ACCEPTED, f"STOP_TRACKING after {what}")
    got = bridge.wait_line(mark, lambda l: l.startswith(SAID + "tracking stopped") or l.startswith(SAID + "target lost"))
    check(got is not None and got[1] == SAID + "tracking stopped", f"STOP_TRACKING after {what}: said {got and got[1]!r}")


def focus(gcs, bridge):
    # MAVSDK 4.1: focus_out_start (1, +1), focus_stop (1, 0), focus_in_start (1, -1),
    # focus_auto (4), focus_auto_single (5), focus_auto_continuous (6). The simulated gimbal
    # says a change only: "focus held" after auto-focus changes nothing, so a continuous
    # focus comes between autos.
    steps = [((1, 1), "focusing +"), ((1, 0), "focus held"), ((1, -1), "focusing -"), ((1, 0), "focus held"),
             ((4, 0), "auto-focus"), ((1, 1), "focusing +"), ((5, 0), "auto-focus"), ((1, -1), "focusing -"),
             ((6, 0), "auto-focus")]
    for (kind, value), line in steps:
        mark = bridge.mark()
        ack, since = gcs.expect(CAMERA, mav.MAV_CMD_SET_CAMERA_FOCUS, [kind, value], mav.MAV_RESULT_ACCEPTED,
                                f"SET_CAMERA_FOCUS type {kind} value {value}")
        got = bridge.wait_line(mark, lambda l: l.startswith(SAID + "focus") or l.startswith(SAID + "auto-focus"))
        settings = gcs.wait(lambda m: m.get_type() == "CAMERA_SETTINGS" and m.get_srcComponent() == CAMERA,
                            ACK_TIMEOUT, since)
        check(got is not None and got[1] == SAID + line and settings is not None,
              f"SET_CAMERA_FOCUS type {kind} value {value}: said {got and got[1][len(SAID):]!r}, "
              f"then CAMERA_SETTINGS {'received' if settings else 'missing'}")
    for kind, value in ((0, 1), (2, 50), (3, 10)):
        mark = bridge.mark()
        gcs.expect(CAMERA, mav.MAV_CMD_SET_CAMERA_FOCUS, [kind, value], mav.MAV_RESULT_DENIED,
                   f"SET_CAMERA_FOCUS type {kind} (step, range, meters: no focus position)")
        gcs.idle(QUIET)
        said = [l for _, l in bridge.lines(mark) if "focus" in l]
        check(not said, f"SET_CAMERA_FOCUS type {kind}: nothing said ({said})")


def calibration(gcs, bridge):
    mark = bridge.mark()
    gcs.expect(GIMBAL, mav.MAV_CMD_PREFLIGHT_CALIBRATION, [1, 0, 0, 0, 0, 0, 0], mav.MAV_RESULT_ACCEPTED,
               "PREFLIGHT_CALIBRATION gyro (p1 1) to the gimbal")
    start = bridge.wait_line(mark, lambda l: l == SAID + "calibrating")
    # The simulated gimbal's fast calibration lasts 2 s (sim.rs CALIBRATION_MS); the lines are
    # timed as this script's reader thread reads them, a few ms after they are written on an
    # idle machine, up to a few hundred on a loaded one (either line): 1.5 to 3 s.
    done = bridge.wait_line(mark, lambda l: l == SAID + "calibration done", timeout=4.0)
    took = done[0] - start[0] if start and done else None
    check(start is not None and took is not None and 1.5 <= took <= 3.0,
          f"calibrating, then calibration done {took if took is None else round(took, 2)} s later")
    mark = bridge.mark()
    gcs.expect(GIMBAL, mav.MAV_CMD_PREFLIGHT_CALIBRATION, [0, 0, 0, 0, 1, 0, 0], mav.MAV_RESULT_DENIED,
               "PREFLIGHT_CALIBRATION accelerometer (p5 1)")
    gcs.idle(QUIET)
    check(not [l for _, l in bridge.lines(mark) if "calibrat" in l], "accelerometer calibration: nothing said")


def source(gcs, bridge):
    gcs.expect(CAMERA, mav.MAV_CMD_SET_CAMERA_SOURCE, [0, mav.CAMERA_SOURCE_IR, 0], mav.MAV_RESULT_ACCEPTED,
               "SET_CAMERA_SOURCE IR (the dual light's thermal image)")
    # The tracker on the infrared image (the dual light's own start tracking).
    track_case(gcs, bridge, "on the infrared image", mav.MAV_CMD_CAMERA_TRACK_POINT, [0.5, 0.5, 0.015625])
    gcs.expect(CAMERA, mav.MAV_CMD_SET_CAMERA_SOURCE, [0, mav.CAMERA_SOURCE_RGB, mav.CAMERA_SOURCE_IR],
               mav.MAV_RESULT_DENIED, "SET_CAMERA_SOURCE with a secondary source")
    gcs.expect(CAMERA, mav.MAV_CMD_SET_CAMERA_SOURCE, [0, mav.CAMERA_SOURCE_RGB, 0], mav.MAV_RESULT_ACCEPTED,
               "SET_CAMERA_SOURCE RGB")


def streams(gcs):
    ack, since = gcs.expect(CAMERA, mav.MAV_CMD_REQUEST_MESSAGE, [mav.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, 0],
                            mav.MAV_RESULT_ACCEPTED, "REQUEST_MESSAGE VIDEO_STREAM_INFORMATION, all streams")
    gcs.wait(lambda m: len(gcs.since(since, "VIDEO_STREAM_INFORMATION")) >= 3, ACK_TIMEOUT, since)
    gcs.idle(0.3)
    got = [(m.stream_id, m.count, m.name, bool(m.flags & mav.VIDEO_STREAM_STATUS_FLAGS_THERMAL))
           for _, m in gcs.since(since, "VIDEO_STREAM_INFORMATION")]
    check(got == [(1, 3, "main", False), (2, 3, "aux1", False), (3, 3, "infrared", True)],
          f"VIDEO_STREAM_INFORMATION: 3 streams, ids 1..3, the third THERMAL: {got}")


def run(gimbalctl):
    # The files as they are served, before any bridge: their own version (no
    # CAMERA_INFORMATION yet), a model filled in.
    files = {}
    for name in ("idu-zoom.xml", "idu-dual-light.xml"):
        files[name] = validate_definition(served_definition(name, "X30-X30GT"), name, None)

    bridge = None
    ap = None
    try:
        # The autopilot's port first: it is the bridge's --to. It starts once the ground
        # station's socket exists (it sends the ground station's heartbeats on it).
        ap = Autopilot()
        bridge = Bridge(gimbalctl, ap.port)
        print(f"mavlink_camera: gimbalctl mavlink on UDP {bridge.port}, autopilot (--to) on {ap.port}", flush=True)
        gcs = Gcs(bridge.port)
        gcs.m.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, mav.MAV_STATE_ACTIVE)
        ap.gcs_target = (gcs.m.port, ("127.0.0.1", bridge.port))
        ap.start()
        # The bridge sends its heartbeats to --to from the start (1 Hz): 3 s.
        end = time.monotonic() + 3.0
        while ap.first_camera_heartbeat is None and time.monotonic() < end:
            time.sleep(0.01)
        check(ap.first_camera_heartbeat is not None, "the camera's HEARTBEAT reaches the --to address")
        # Wait for the autopilot's first heartbeat out, then the camera's next one.
        end = time.monotonic() + 3.0
        while ap.heartbeats_sent == 0 and time.monotonic() < end:
            time.sleep(0.01)
        since = gcs.mark()
        hb = gcs.wait(lambda m: m.get_type() == "HEARTBEAT" and m.get_srcComponent() == CAMERA, 3.0, since)
        check(hb is not None and hb.get_srcSystem() == AP_SYSTEM and hb.type == mav.MAV_TYPE_CAMERA,
              f"the camera: component 100, the autopilot's system 1, MAV_TYPE_CAMERA "
              f"({hb and (hb.get_srcSystem(), hb.type)})")

        info = camera_information(gcs)
        version = info.cam_definition_version if info else 1
        # Served with CAMERA_INFORMATION's model in its <model>, which QGroundControl renames
        # the camera to (VehicleCameraControl.cc _loadConstants).
        model = bytes(info.model_name).rstrip(b"\0").decode() if info else ""
        xml = served_definition("idu-dual-light.xml", model)
        ftp, oldest, idle_since = ftp_raw_tests(gcs, xml)

        params = files["idu-dual-light.xml"]
        if params:
            parameters(gcs, params, bridge)
        tracking_status(gcs, bridge)
        ftp_reclaim_test(ftp, oldest, idle_since)

        # pymavlink's own client: the path as QGroundControl reads "mftp://camera.xml".
        uri = info.cam_definition_uri if info else "mftp://camera.xml"
        path = "/" + uri[len("mftp://"):]
        client = MAVFTP(gcs.m, AP_SYSTEM, CAMERA)
        got = client.read(path, len(xml))
        check(got == xml, f"MAVFTP.read({path!r}, {len(xml)}): the file ({len(got) if got else got} bytes)")
        with tempfile.TemporaryDirectory() as tmp:
            local = os.path.join(tmp, "camera.xml")
            client.cmd_get([path, local])
            ret = client.process_ftp_reply("get", timeout=10)
            data = open(local, "rb").read() if os.path.exists(local) else None
        check(ret.error_code == FtpError.Success and data == xml,
              f"MAVFTP cmd_get {path}: {ret.error_code.name}, {len(data) if data else data} bytes equal the file's")
        ret = client.cmd_list(["/"])
        listing = [(e.name, e.is_dir, e.size_b) for e in (ret.directory_listing or [])]
        check(ret.error_code == FtpError.Success and listing == [("camera.xml", False, len(xml))],
              f"MAVFTP cmd_list /: {listing}")
        if data is not None:
            validate_definition(data, "the definition downloaded over FTP", version)
        validate_definition(xml, "idu-dual-light.xml against CAMERA_INFORMATION", version)

        tracking_edges(gcs, bridge)
        focus(gcs, bridge)
        calibration(gcs, bridge)
        source(gcs, bridge)
        streams(gcs)
        check(not gcs.bad, f"no malformed frame from the bridge ({len(gcs.bad)})")
    except Exception as e:  # a crash is a failure with its reason, not a traceback only
        import traceback
        traceback.print_exc()
        check(False, f"crashed: {e!r}")
    finally:
        if ap is not None:
            ap.stopping.set()
        if bridge is not None:
            bridge.stop()


def main():
    start = time.monotonic()
    run(sys.argv[1])
    print(f"mavlink_camera: ran {time.monotonic() - start:.1f} s", flush=True)
    return CHECKS.summary("mavlink_camera")


if __name__ == "__main__":
    sys.exit(main())
