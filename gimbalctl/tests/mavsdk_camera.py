#!/usr/bin/env python3
"""MAVSDK's Camera plugin (the `mavsdk` Python package, 4.x, its native library inside the
wheel) as a ground station against `gimbalctl mavlink --sim`, on UDP loopback.

    python3 gimbalctl/tests/mavsdk_camera.py target/debug/gimbalctl

MAVSDK finds the camera component by its heartbeat and CAMERA_INFORMATION, then drives it
with its own commands: photos (MAV_CMD_IMAGE_START_CAPTURE with count 1 and its capture
sequence number, 0 first, then 1: camera_impl.cpp make_command_take_photo), photos at an
interval (start_photo_interval: the interval and count 0, until stop_photo_interval), video
start and stop, zoom by range; every image must reach MAVSDK's capture_info once, with
consecutive indexes, the interval's at its pace. It reads the video stream's URI, which it
asks for on its own (VIDEO_STREAM_INFORMATION every 20 s, VIDEO_STREAM_STATUS every 5 s).

A second session, `--camera dual-light`, drives what MAVSDK 4.1's Python API offers beyond
that, and checks each effect on the simulated gimbal (which gimbalctl says on stderr):
focus (focus_out_start / focus_in_start / focus_stop / focus_auto: MAV_CMD_SET_CAMERA_FOCUS
continuous and auto; focus_range is refused, the gimbal has no focus position), tracking
(track_point, track_rectangle, track_stop), and the settings of the camera definition,
which MAVSDK downloads from the `mftp://` URI over MAVLink FTP and reads with
PARAM_EXT_REQUEST_READ: the palette set through set_setting reaches the gimbal.
MAVSDK 4.1 has no API for CAMERA_TRACKING_IMAGE_STATUS, the camera source or calibration;
mavlink_camera.py tests those with pymavlink.

Ends with a line "N passed, M failed"; exit status 0 only if nothing failed.
"""
import asyncio
import os
import subprocess
import sys
import tempfile
import threading
import time

# MAVSDK caches camera definitions by model and version in $HOME/.cache/mavsdk/camera
# (camera_impl.cpp): an empty home of its own, so that every run downloads the definition
# over MAVLink FTP.
os.environ["HOME"] = tempfile.mkdtemp(prefix="mavsdk-home-")

from mavsdk.asyncio import ComponentType, Configuration, Mavsdk
from mavsdk.asyncio.plugins.camera.camera import CameraAsync
from mavsdk.plugins.camera import Option, Setting
from mavsdk.plugins.camera.camera import CameraError

from checks import Checks, sim_options

CAMERA = 100
# `--camera x3` (the default): the vendor document's RTSP form with its default address and
# credentials (idu_gimbal::video).
def stream_uri(stream_id):
    return f"rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype={stream_id - 1}"
# MAVSDK asks for VIDEO_STREAM_INFORMATION every 20 s; allow one period and a margin.
STREAM_TIMEOUT_S = 30.0

CHECKS = Checks()
check = CHECKS.check


async def wait_for(what, poll, timeout):
    """Calls `poll` until it returns something truthy or `timeout` seconds pass."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = await poll()
        if value:
            return value
        await asyncio.sleep(0.2)
    print(f"  (timed out waiting for {what})", flush=True)
    return None


def start_bridge(gimbalctl, sink, *args):
    """`gimbalctl mavlink --sim ARGS`, sending to MAVSDK's port `sink` (gimbalctl sends to
    every peer it has heard from; MAVSDK listens on a port of its own, given with --to, and
    answers from it): the process, its UDP port (its first stdout line) and the lines of its
    stderr as they come (the simulated gimbal says there what its camera does)."""
    proc = subprocess.Popen(
        [gimbalctl, "mavlink", "--sim", *sim_options(), *args, "--listen", "127.0.0.1:0", "--to",
         f"127.0.0.1:{sink}", "--exit-after-ms", "90000"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    said = []

    def read_stderr():
        for line in proc.stderr:
            print(line, end="", file=sys.stderr, flush=True)
            said.append(line.strip())

    threading.Thread(target=read_stderr, daemon=True).start()
    line = proc.stdout.readline()
    port = int(line.split("listening on ")[1].split(",")[0].rsplit(":", 1)[1])
    return proc, port, said


async def find_camera(sink, who):
    """MAVSDK as a ground station on `sink`: the Mavsdk instance (kept alive by the caller),
    the camera plugin of the system it finds, and the camera component 100 as MAVSDK lists
    it; None where not found."""
    mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    await mavsdk.add_any_connection(f"udpin://127.0.0.1:{sink}")

    async def a_system():
        systems = await mavsdk.get_systems()
        return systems[0] if systems else None

    system = await wait_for("a system", a_system, 10.0)
    check(system is not None, f"MAVSDK sees {who}'s system")
    if system is None:
        return mavsdk, None, None
    camera = CameraAsync(system)

    async def listed():
        cameras = (await camera.camera_list()).cameras
        return [c for c in cameras if c.component_id == CAMERA]

    found = await wait_for("the camera", listed, 10.0)
    check(bool(found), f"{who}'s camera (component 100) is listed")
    return mavsdk, camera, found[0] if found else None


async def run(gimbalctl):
    sink = socket_port()
    proc, port, _ = start_bridge(gimbalctl, sink)
    try:
        print(f"mavsdk_camera: gimbalctl mavlink on UDP {port}, MAVSDK on {sink}", flush=True)
        _mavsdk, camera, info = await find_camera(sink, "the bridge")
        if info is None:
            return
        check(info.vendor_name == "IDU", f"vendor name {info.vendor_name!r}")

        async def succeeds(what, call):
            try:
                await call
                check(True, what)
            except CameraError as e:
                check(False, f"{what}: {e}")

        # Every image MAVSDK reports, with when it came.
        images = []

        async def collect():
            async for info in camera.subscribe_capture_info():
                images.append((time.monotonic(), info.index, info.is_success))

        collector = asyncio.ensure_future(collect())
        await asyncio.sleep(0.5)
        await succeeds("take_photo (sequence 0)", camera.take_photo(CAMERA))
        await succeeds("take_photo (sequence 1)", camera.take_photo(CAMERA))
        await wait_for("two images", lambda: asyncio.sleep(0, len(images) >= 2), 5.0)
        check([i for _, i, ok in images if ok] == [0, 1],
              f"one image for each take_photo, indexes {[i for _, i, _ in images]}")
        start = time.monotonic()
        await succeeds("start_photo_interval 0.5 s", camera.start_photo_interval(CAMERA, 0.5))
        await asyncio.sleep(2.2)
        await succeeds("stop_photo_interval", camera.stop_photo_interval(CAMERA))
        stopped = len(images)
        await asyncio.sleep(1.0)
        collector.cancel()
        timed = [(round(t - start, 2), i) for t, i, _ in images if t >= start]
        # Taken at 0, 0.5, 1.0, 1.5, 2.0 s on the bridge's grid, timed here as they reach
        # this script through mavsdk_server and its gRPC stream: a few ms late on an idle
        # machine, up to a few hundred on a loaded one, either report of a pair. Each gap
        # 0.2 to 0.8 s, and on average 0.45 to 0.6 (a late first report shortens it).
        spacing = [b[0] - a[0] for a, b in zip(timed, timed[1:])]
        check([i for _, i in timed] == list(range(2, 2 + len(timed))) and 4 <= len(timed) <= 6
              and all(0.2 < d < 0.8 for d in spacing) and 0.45 <= sum(spacing) / len(spacing) <= 0.6,
              f"images every 0.5 s with consecutive indexes: {timed}")
        check(len(images) == stopped, f"none after stop_photo_interval ({len(images) - stopped})")
        await succeeds("zoom_range 50 %", camera.zoom_range(CAMERA, 50.0))
        await succeeds("start_video", camera.start_video(CAMERA))
        await succeeds("stop_video", camera.stop_video(CAMERA))

        async def stream():
            s = await camera.get_video_stream_info(CAMERA)
            return s if s.settings.uri else None

        s = await wait_for("the video stream", stream, STREAM_TIMEOUT_S)
        # MAVSDK keeps the last stream it was told of; the X3 has three, ids 1 to 3, whose
        # addresses end in subtype=0, 1, 2.
        check(s is not None and s.settings.uri == stream_uri(s.stream_id),
              f"video stream {s.stream_id if s else None} at {s.settings.uri if s else None!r}")
        check(s is not None and s.status == s.VideoStreamStatus.IN_PROGRESS,
              "the stream is running")
    finally:
        proc.kill()
        proc.wait()


async def dual_light(gimbalctl):
    sink = socket_port()
    proc, port, said = start_bridge(gimbalctl, sink, "--camera", "dual-light")
    try:
        print(f"mavsdk_camera: dual light on UDP {port}, MAVSDK on {sink}", flush=True)
        _mavsdk, camera, info = await find_camera(sink, "the dual light")
        if info is None:
            return

        # Every stream, as MAVSDK reports them (it asks for them all at once, and every
        # 20 s): the third, the infrared stream, flagged thermal, which MAVSDK calls the
        # infrared spectrum.
        streams = {}

        async def collect_streams():
            async for update in camera.subscribe_video_stream_info():
                info = update.video_stream_info
                streams[info.stream_id] = (info.settings.uri, info.spectrum.name)

        collector = asyncio.ensure_future(collect_streams())

        async def effect(what, call, line):
            """`call` succeeds and the simulated gimbal then says `line`."""
            before = len(said)
            try:
                await call
            except CameraError as e:
                check(False, f"{what}: {e}")
                return

            async def heard():
                return line in said[before:]

            check(bool(await wait_for(line, heard, 3.0)), f"{what}: the gimbal says {line!r}")

        g = "gimbalctl mavlink: simulated gimbal: "
        await effect("focus_out_start", camera.focus_out_start(CAMERA), g + "focusing +")
        await effect("focus_stop", camera.focus_stop(CAMERA), g + "focus held")
        await effect("focus_in_start", camera.focus_in_start(CAMERA), g + "focusing -")
        await effect("focus_auto", camera.focus_auto(CAMERA), g + "auto-focus")
        try:
            await camera.focus_range(CAMERA, 50.0)
            check(False, "focus_range is refused")
        except CameraError as e:
            check(e.result.name == "DENIED", f"focus_range is refused: {e}")
        # QGroundControl's click: radius 20 px of 1280 = 0.015625, a 256-unit box (16 × 16).
        await effect("track_point", camera.track_point(CAMERA, 0.5, 0.5, 0.015625),
                     g + "tracking a 256x256 box at (4096, 4096)")
        await effect("track_stop", camera.track_stop(CAMERA), g + "tracking stopped")
        # (0.25, 0.25)-(0.5, 0.5): centre 0.375 × 8191 = 3071.6 → 3072, sides 2048.
        await effect("track_rectangle",
                     camera.track_rectangle(CAMERA, 0.25, 0.25, 0.5, 0.5),
                     g + "tracking a 2048x2048 box at (3072, 3072)")
        await effect("track_stop", camera.track_stop(CAMERA), g + "tracking stopped")

        # The settings, once MAVSDK has the definition (FTP) and every value (PARAM_EXT).
        async def options():
            try:
                return await camera.get_possible_setting_options(CAMERA)
            except CameraError:
                return None

        opts = await wait_for("the definition's settings", options, 20.0) or []
        ids = {o.setting_id: [x.option_id for x in o.options] for o in opts}
        check(sorted(ids) == ["CAM_FOCUS", "IR_EZOOM", "IR_PALETTE"], f"settings {sorted(ids)}")
        check(ids.get("IR_PALETTE") == [str(v) for v in range(15)],
              f"15 palettes: {ids.get('IR_PALETTE')}")
        palette = Setting(setting_id="IR_PALETTE", setting_description="",
                          option=Option(option_id="10", option_description=""), is_range=False)
        await effect("set_setting IR_PALETTE 10", camera.set_setting(CAMERA, palette),
                     g + "palette ice-blue")

        async def current():
            try:
                got = await camera.get_current_settings(CAMERA)
            except CameraError:
                return None
            return {s.setting_id: s.option.option_id for s in got}

        now = await wait_for("the current settings", current, 5.0) or {}
        check(now.get("IR_PALETTE") == "10", f"the current palette reads back: {now}")

        async def all_streams():
            return len(streams) == 3

        await wait_for("three streams", all_streams, STREAM_TIMEOUT_S)
        collector.cancel()
        check(streams == {
            1: (stream_uri(1), "VISIBLE_LIGHT"),
            2: (stream_uri(2), "VISIBLE_LIGHT"),
            3: (stream_uri(3), "INFRARED"),
        }, f"the dual light's streams: {streams}")
    finally:
        proc.kill()
        proc.wait()


def socket_port():
    import socket
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main():
    asyncio.run(run(sys.argv[1]))
    asyncio.run(dual_light(sys.argv[1]))
    status = CHECKS.summary("mavsdk_camera")
    # Leave without running MAVSDK's destructors from the garbage collector at exit.
    os._exit(status)


if __name__ == "__main__":
    main()
