#!/usr/bin/env python3
"""Writes the fuzz targets' seed corpora from the protocol's own vectors.

Each target's input layout is the one its property in `fuzz/properties.rs` (or
`fuzz/mavlink_properties.rs`) reads. The vectors: the protocol notes' control frames and its 24-byte
TCP look-down frame, a postback built field by field as the protocol notes lays it out (CRC-16/MODBUS
low byte first), and MAVLink 2 frames encoded by pymavlink (the autopilot's side).

    python3 fuzz/seeds.py            # writes fuzz/seeds/<target>/*, then run cargo fuzz cmin

The seeds are inputs to start from; `cargo fuzz cmin` then keeps the corpus minimal, and
the minimized corpus is what is checked in under fuzz/corpus/<target>/.
"""

import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def crc16_modbus(data):
    """CRC-16/MODBUS from its definition: reflected 0xA001, init 0xFFFF, no final xor."""
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


# the protocol notes, "Control frame": the document's own examples, and a few more commands.
CONTROL = {
    "left_5dps": "0F 04 0C FE 00 00 00 00",
    "up_5dps": "0F 04 00 00 F4 01 00 00",
    "heading_45": "0F 08 01 C2 01 00 00 00",
    "pitch_minus_45": "0F 08 02 3E FE 00 00 00",
    "zoom_10x": "0F 08 03 E8 03 00 00 00",
    "single_shot": "0F 10 01 00 00 00 00 00",
    "start_recording": "0F 11 01 00 00 00 00 00",
    "nose_following": "0F 02 00 00 00 00 00 00",
    "look_down": "0F 07 00 00 00 00 00 00",
    "thermal_palette_iron_red": "1F 02 02 00 00 00 00 00",
    "thermal_stop_tracking": "1F 07 00 00 00 00 00 00",
}
CONTROL = {k: bytes.fromhex(v) for k, v in CONTROL.items()}

# the protocol notes, "TCP / serial frame": look down 90 degrees.
TCP_LOOK_DOWN = bytes.fromhex("EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5E")


def control_frame(data):
    body = bytes([0xEB, 0x90, 0x0A]) + bytes(9) + bytes([0x40, 0x88]) + data
    return body + struct.pack("<H", crc16_modbus(body))


def postback(gimbal_type=1, tracking=0, mode=3, pitch=-4500, heading=27000, motor=4500):
    """The 27-byte postback of the protocol notes' table, CRC over bytes 0..=24, low byte first."""
    body = bytes([0xEB, 0x90, 0x0C]) + bytes(9) + bytes([0x21, 0xFE, 0x0F, 0x01])
    body += bytes([gimbal_type, tracking, mode]) + struct.pack("<hHh", pitch, heading, motor)
    return body + struct.pack("<H", crc16_modbus(body))


POSTBACKS = [postback(), postback(2, 1, 1, -11000, 0, -17000), postback(7, 0, 2, 6000, 35999, 17000)]
assert control_frame(CONTROL["look_down"]) == TCP_LOOK_DOWN


def can_frames(message27):
    padded = message27 + bytes(5)
    return [padded[i:i + 8] for i in range(0, 32, 8)]


def mavlink_frames():
    os.environ["MAVLINK20"] = "1"
    from pymavlink.dialects.v20 import common as mav

    class Sink:
        def write(self, b):
            pass

    m = mav.MAVLink(Sink(), srcSystem=1, srcComponent=1)
    m.robust_parsing = True
    out = {}
    out["heartbeat"] = m.heartbeat_encode(mav.MAV_TYPE_QUADROTOR, mav.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 4).pack(m)
    out["request_information"] = m.command_long_encode(
        1, 0, mav.MAV_CMD_REQUEST_MESSAGE, 0, mav.MAVLINK_MSG_ID_GIMBAL_DEVICE_INFORMATION, 0, 0, 0, 0, 0, 0
    ).pack(m)
    out["set_attitude"] = m.gimbal_device_set_attitude_encode(
        1, 154, mav.GIMBAL_DEVICE_FLAGS_YAW_LOCK, [0.96, -0.05, -0.26, 0.02], float("nan"), float("nan"), float("nan")
    ).pack(m)
    out["set_rate"] = m.gimbal_device_set_attitude_encode(
        1, 154, 0, [float("nan")] * 4, 0.0, 0.1, -0.2
    ).pack(m)
    out["autopilot_state"] = m.autopilot_state_for_gimbal_device_encode(
        1, 154, 0, [0.97, 0, 0, 0.26], 0, 0, 0, 0, 0, 0, 0, 4, 0
    ).pack(m)
    out["image_capture"] = m.command_long_encode(1, 100, mav.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 0, 1, 0, 0, 0, 0).pack(m)
    out["zoom"] = m.command_long_encode(1, 100, mav.MAV_CMD_SET_CAMERA_ZOOM, 0, 2, 50, 0, 0, 0, 0, 0).pack(m)
    return out


def main():
    root = os.path.join(HERE, "seeds")
    seeds = {t: {} for t in ("command_decode", "stream_parser", "assembler", "link", "serial_link", "mavlink_bridge",
                             "mavlink_messages")}
    for name, data in CONTROL.items():
        seeds["command_decode"][name] = data
    # stream_parser: first byte chooses the split point (mod length + 1).
    stream = TCP_LOOK_DOWN + POSTBACKS[0] + control_frame(CONTROL["zoom_10x"]) + POSTBACKS[1]
    seeds["stream_parser"]["look_down_tcp"] = bytes([5]) + TCP_LOOK_DOWN
    seeds["stream_parser"]["frames_and_postbacks"] = bytes([40]) + stream
    seeds["stream_parser"]["garbage_then_frame"] = bytes([3, 0xEB, 0x90, 0x0C, 0xEB]) + TCP_LOOK_DOWN
    # assembler: 11-byte records (selector, time step, 9 bytes); selector 16 = postback ID, 8 bytes.
    for i, pb in enumerate(POSTBACKS):
        seeds["assembler"][f"postback_{i}"] = b"".join(bytes([16, 10]) + f + b"\0" for f in can_frames(pb))
    # link: 12-byte records (op, time step, a, b, 8 bytes); op 0 with a 0, b 8 = postback frame.
    recv = b"".join(bytes([0, 10, 0, 8]) + f for f in can_frames(POSTBACKS[0]))
    send = bytes([4, 1, 0, 0]) + CONTROL["pitch_minus_45"] + bytes([10, 1, 0, 0]) + bytes(8)
    seeds["link"]["postback_then_command"] = recv + send
    # serial_link: 4-byte records (op, time step, a, b).
    seeds["serial_link"]["postback_split_command_write"] = bytes([1, 5, 200, 13, 2, 1, 0, 0, 3, 1, 0x3E, 0xFE, 5, 1, 10, 0, 6, 1, 30, 0])
    # mavlink_bridge: first byte chooses the split point.
    frames = mavlink_frames()
    for name, f in frames.items():
        seeds["mavlink_bridge"][name] = bytes([len(f) // 2]) + f
    seeds["mavlink_bridge"]["autopilot_session"] = bytes([77]) + b"".join(frames.values())
    # mavlink_messages: records [which, len, system, component, payload], `which` the index
    # in mavlink_properties.rs handled(); the checksum is the target's to compute.
    handled = [0, 33, 75, 76, 110, 284, 286, 320, 321, 323]

    def record(frame):
        msgid = int.from_bytes(frame[7:10], "little")
        n = frame[1]
        return bytes([handled.index(msgid), n, frame[5], frame[6]]) + frame[10:10 + n]

    kept = {k: f for k, f in frames.items() if int.from_bytes(f[7:10], "little") in handled}
    for name, f in kept.items():
        seeds["mavlink_messages"][name] = record(f)
    seeds["mavlink_messages"]["autopilot_session"] = b"".join(record(f) for f in kept.values())
    # A region of interest relative to home, home's altitudes at the ends of i32.
    from pymavlink.dialects.v20 import common as mav
    m = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    pos = m.global_position_int_encode(0, 473977420, 85455940, 2**31 - 1, -1, 0, 0, 0, 0).pack(m)
    roi = m.command_int_encode(1, 154, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, mav.MAV_CMD_DO_SET_ROI_LOCATION,
                               0, 0, 0, 0, 0, 0, 473987420, 85465940, 20.0).pack(m)
    seeds["mavlink_messages"]["roi_from_extreme_home"] = record(pos) + record(roi)
    for target, files in seeds.items():
        d = os.path.join(root, target)
        os.makedirs(d, exist_ok=True)
        for name, data in files.items():
            with open(os.path.join(d, name), "wb") as f:
                f.write(data)
    print(f"seeds written under {root}: " + ", ".join(f"{t} {len(f)}" for t, f in seeds.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
