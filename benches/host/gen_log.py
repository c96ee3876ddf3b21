#!/usr/bin/env python3
"""Deterministic `candump -L` log of IDU gimbal vehicle and control frames, for the host
decode benchmark (`benches/host/compare.sh`).

    python3 benches/host/gen_log.py N [--seed S] > log
    python3 benches/host/gen_log.py --verify target/release/gimbalctl [--verify-count K]

Each line is `(SECONDS.MICROS) can0 IIIIIIII#DDDDDDDDDDDDDDDD`, timestamps increasing by
100..2000 us. The mix (by line): attitude 0000FF13 35 %, GPS 0000FF15 20 %, altitude
0000FF16 15 %, control 00000F01 30 %.

Every frame is valid per the protocol, so every line decodes to one JSON message:
- vehicle frames: little-endian wire units inside the library's ranges (attitude pitch
  +-9000, roll +-18000, heading -18000..17999 centidegrees, zero padding; GPS lat/lon
  +-9e8 / +-1.8e9 in 1e-7 degree; altitude any int32 cm, zero padding);
- control frames: each is built from a `gimbalctl encode COMMAND ARGS` command line with
  varied values (exact decimals of wire units, so the tool's rounding is the identity) and
  laid out as the library encodes it. `--verify GIMBALCTL` checks that claim: it runs
  `gimbalctl encode` on a sample of the generated command lines and compares bytes, then
  runs `gimbalctl decode --stats` on a generated log and checks every line became a
  message with no malformed line.

The same N and seed give the same bytes on any Python 3 (random.Random is seeded and only
its integer methods are used).
"""

import argparse
import json
import random
import subprocess
import sys

CONTROL_ID = 0x00000F01
ATTITUDE_ID = 0x0000FF13
GPS_ID = 0x0000FF15
ALTITUDE_ID = 0x0000FF16

GIMBAL = 0x0F
DUAL_LIGHT = 0x1F


def le16(v):
    """Two's-complement little-endian 16-bit value."""
    v &= 0xFFFF
    return [v & 0xFF, v >> 8]


def le32(v):
    v &= 0xFFFFFFFF
    return [v & 0xFF, (v >> 8) & 0xFF, (v >> 16) & 0xFF, v >> 24]


def dec(value, decimals):
    """The exact decimal text of value / 10^decimals (as a command-line argument)."""
    if decimals == 0:
        return str(value)
    sign = "-" if value < 0 else ""
    a = abs(value)
    scale = 10 ** decimals
    return f"{sign}{a // scale}.{a % scale:0{decimals}d}"


def frame(peripheral, cmd, data=()):
    """A control frame: peripheral, command code, DATA1..DATA6 (zero padded)."""
    b = [peripheral, cmd] + list(data)
    return b + [0] * (8 - len(b))


# Control commands: each returns (encode argv, 8 data bytes), field layout as in
# src/wire/control.rs (X = DATA1-2, Y = DATA3-4, box W/H = DATA5/DATA6, sub-code = DATA1,
# photo parameter = DATA2, angle = DATA2-3).

def c_point_zoom(r, per=GIMBAL, name="point-zoom"):
    x, y = r.randint(-10000, 10000), r.randint(-10000, 10000)
    return [name, str(x), str(y)], frame(per, 0x01, le16(x) + le16(y))


def c_rate(r, per=GIMBAL, name="rate"):
    yaw, pitch = r.randint(-10000, 10000), r.randint(-10000, 10000)  # centi deg/s
    return [name, dec(yaw, 2), dec(pitch, 2)], frame(per, 0x04, le16(yaw) + le16(pitch))


def c_track(r, per=GIMBAL, name="track"):
    x, y = r.randint(0, 8191), r.randint(0, 8191)
    w16, h16 = r.randint(0, 255), r.randint(0, 255)  # box sent as /16
    argv = [name, str(x), str(y), str(w16 * 16), str(h16 * 16)]
    return argv, frame(per, 0x05, le16(x) + le16(y) + [w16, h16])


def c_heading(r):
    deci = r.randint(0, 3600)
    return ["heading", dec(deci, 1)], frame(GIMBAL, 0x08, [1] + le16(deci))


def c_pitch(r):
    deci = r.randint(-1000, 600)
    return ["pitch", dec(deci, 1)], frame(GIMBAL, 0x08, [2] + le16(deci))


def c_zoom_to(r):
    centi = r.randint(100, 3500)
    return ["zoom-to", dec(centi, 2)], frame(GIMBAL, 0x08, [3] + le16(centi))


def c_photo(r):
    mode = r.randint(1, 5)
    if mode in (1, 5):
        argv, param = ["photo", "single" if mode == 1 else "stop"], 0
    else:
        param = r.randint(1, 255)
        argv = ["photo", {2: "burst", 3: "timelapse", 4: "timer"}[mode], str(param)]
    return argv, frame(GIMBAL, 0x10, [mode, param])


def c_sub(name, cmd, words, per=GIMBAL):
    def make(r):
        i = r.randrange(len(words))
        return [name, words[i]], frame(per, cmd, [i + 1])

    return make


def c_focus_at(r):
    x, y = r.randint(0, 8191), r.randint(0, 8191)
    return ["focus-at", str(x), str(y)], frame(GIMBAL, 0x14, le16(x) + le16(y) + [25, 25])


def c_fixed(name, per, cmd):
    return lambda r: ([name], frame(per, cmd))


def c_palette(r):
    p = r.randint(0, 14)
    return ["palette", str(p)], frame(DUAL_LIGHT, 0x02, [p])


CONTROL = [
    c_point_zoom,
    c_fixed("follow", GIMBAL, 0x02),
    c_fixed("center", GIMBAL, 0x03),
    c_rate,
    c_rate,  # rate commands are the most frequent on a real bus (sent every ~50 ms)
    c_rate,
    c_track,
    c_fixed("track-stop", GIMBAL, 0x06),
    c_fixed("look-down", GIMBAL, 0x07),
    c_heading,
    c_pitch,
    c_pitch,
    c_zoom_to,
    c_photo,
    c_sub("record", 0x11, ["start", "stop"]),
    c_sub("zoom", 0x12, ["in", "out", "stop", "reset", "double", "half"]),
    c_sub("focus", 0x13, ["plus", "minus", "stop", "auto"]),
    c_focus_at,
    c_fixed("calibrate", GIMBAL, 0xF0),
    lambda r: c_point_zoom(r, DUAL_LIGHT, "ir-point-zoom"),
    lambda r: c_rate(r, DUAL_LIGHT, "ir-rate"),
    lambda r: c_track(r, DUAL_LIGHT, "ir-track"),
    c_fixed("ir-track-stop", DUAL_LIGHT, 0x07),
    c_sub("ir-zoom", 0x12, ["in", "out", "stop"], DUAL_LIGHT),
    c_palette,
]


def attitude(r):
    p, ro, h = r.randint(-9000, 9000), r.randint(-18000, 18000), r.randint(-18000, 17999)
    return ATTITUDE_ID, le16(p) + le16(ro) + le16(h) + [0, 0]


def gps(r):
    lat, lon = r.randint(-900_000_000, 900_000_000), r.randint(-1_800_000_000, 1_800_000_000)
    return GPS_ID, le32(lat) + le32(lon)


def altitude(r):
    # Mostly plausible flight altitudes, now and then anything an int32 holds.
    cm = r.randint(-50_000, 1_000_000) if r.randrange(16) else r.randint(-(2**31), 2**31 - 1)
    return ALTITUDE_ID, le32(cm) + [0, 0, 0, 0]


def control(r):
    return CONTROL_ID, CONTROL[r.randrange(len(CONTROL))](r)[1]


# Cumulative percentages: attitude 35, GPS 20, altitude 15, control 30.
MIX = [(35, attitude), (55, gps), (70, altitude), (100, control)]


def lines(n, seed):
    r = random.Random(seed)
    us = 1_700_000_000 * 1_000_000
    for _ in range(n):
        us += r.randint(100, 2000)
        k = r.randrange(100)
        for limit, make in MIX:
            if k < limit:
                break
        can_id, data = make(r)
        yield f"({us // 1_000_000}.{us % 1_000_000:06d}) can0 {can_id:08X}#{bytes(data).hex().upper()}\n"


def write(n, seed, out):
    buf = []
    for line in lines(n, seed):
        buf.append(line)
        if len(buf) >= 65536:
            out.write("".join(buf))
            buf.clear()
    out.write("".join(buf))


def verify(gimbalctl, count, seed):
    """Checks the control encodings against `gimbalctl encode`, and a generated log against
    `gimbalctl decode --stats`."""
    r = random.Random(seed)
    checked = 0
    kinds = set()
    # Every command kind at least once, then random ones.
    makers = list(CONTROL) + [CONTROL[r.randrange(len(CONTROL))] for _ in range(count)]
    for make in makers:
        argv, data = make(r)
        kinds.add(argv[0])
        want = f"{CONTROL_ID:08X}#{bytes(data).hex().upper()}"
        got = subprocess.run(
            [gimbalctl, "encode", *argv], capture_output=True, text=True, check=False
        )
        if got.returncode != 0 or got.stdout.strip() != want:
            sys.exit(f"gen_log: encode {' '.join(argv)}: tool gave {got.stdout.strip()!r} "
                     f"(exit {got.returncode}, {got.stderr.strip()!r}), generator {want!r}")
        checked += 1
    n = 20_000
    text = "".join(lines(n, seed)).encode()
    got = subprocess.run([gimbalctl, "decode", "--stats"], input=text, capture_output=True,
                         check=True)
    out = got.stdout.decode().splitlines()
    stats = json.loads(out[-1])
    want = {"type": "stats", "lines": n, "frames": n, "messages": n, "crc_errors": 0,
            "incomplete": 0, "malformed_lines": 0, "foreign_frames": 0}
    if stats != want or len(out) != n + 1:
        sys.exit(f"gen_log: decode of {n} generated lines: {stats}")
    print(f"gen_log: {checked} control frames ({len(kinds)} commands) match `gimbalctl encode`; "
          f"{n} generated lines decode to {n} messages, none malformed", file=sys.stderr)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("lines", type=int, nargs="?", default=1_000_000)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--verify", metavar="GIMBALCTL")
    ap.add_argument("--verify-count", type=int, default=200)
    a = ap.parse_args()
    if a.verify:
        verify(a.verify, a.verify_count, a.seed)
    else:
        write(a.lines, a.seed, sys.stdout)


if __name__ == "__main__":
    main()
