#!/usr/bin/env python3
"""MAVSDK's Camera plugin (the `mavsdk` Python package, 4.x, its native library inside the
wheel) as a ground station against `gimbalctl mavlink --sim`, on UDP loopback.

    python3 gimbalctl/tests/mavsdk_camera.py target/debug/gimbalctl

MAVSDK finds the camera component by its heartbeat and CAMERA_INFORMATION, then drives it
with its own commands: a photo, video start and stop, zoom by range; and it reads the
video stream's URI, which it asks for on its own (VIDEO_STREAM_INFORMATION every 20 s,
VIDEO_STREAM_STATUS every 5 s).

Ends with a line "N passed, M failed"; exit status 0 only if nothing failed.
"""
import asyncio
import os
import subprocess
import sys
import time

from mavsdk.asyncio import ComponentType, Configuration, Mavsdk
from mavsdk.asyncio.plugins.camera.camera import CameraAsync
from mavsdk.plugins.camera.camera import CameraError

CAMERA = 100
# `--camera x3` (the default): the vendor document's RTSP form with its default address and
# credentials (idu_gimbal::video).
URI = "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0"
# MAVSDK asks for VIDEO_STREAM_INFORMATION every 20 s; allow one period and a margin.
STREAM_TIMEOUT_S = 30.0

passed = 0
failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
        print(f"  ok   {what}", flush=True)
    else:
        failed += 1
        print(f"  FAIL {what}", flush=True)


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


async def run(gimbalctl):
    # gimbalctl sends to every peer it has heard from; MAVSDK listens on a port of its own,
    # given to gimbalctl with --to, and answers from it.
    sink = socket_port()
    proc = subprocess.Popen(
        [gimbalctl, "mavlink", "--sim", "--listen", "127.0.0.1:0", "--to",
         f"127.0.0.1:{sink}", "--exit-after-ms", "90000"],
        stdout=subprocess.PIPE, stderr=sys.stderr, text=True,
    )
    try:
        line = proc.stdout.readline()
        port = int(line.split("listening on ")[1].split(",")[0].rsplit(":", 1)[1])
        print(f"mavsdk_camera: gimbalctl mavlink on UDP {port}, MAVSDK on {sink}", flush=True)
        mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
        await mavsdk.add_any_connection(f"udpin://127.0.0.1:{sink}")

        async def a_system():
            systems = await mavsdk.get_systems()
            return systems[0] if systems else None

        system = await wait_for("a system", a_system, 10.0)
        check(system is not None, "MAVSDK sees the bridge's system")
        if system is None:
            return
        camera = CameraAsync(system)

        async def listed():
            cameras = (await camera.camera_list()).cameras
            return [c for c in cameras if c.component_id == CAMERA]

        found = await wait_for("the camera", listed, 10.0)
        check(bool(found), "the camera (component 100) is listed")
        if not found:
            return
        info = found[0]
        check(info.vendor_name == "IDU", f"vendor name {info.vendor_name!r}")

        async def succeeds(what, call):
            try:
                await call
                check(True, what)
            except CameraError as e:
                check(False, f"{what}: {e}")

        await succeeds("take_photo", camera.take_photo(CAMERA))
        await succeeds("zoom_range 50 %", camera.zoom_range(CAMERA, 50.0))
        await succeeds("start_video", camera.start_video(CAMERA))
        await succeeds("stop_video", camera.stop_video(CAMERA))

        async def stream():
            s = await camera.get_video_stream_info(CAMERA)
            return s if s.settings.uri else None

        s = await wait_for("the video stream", stream, STREAM_TIMEOUT_S)
        check(s is not None and s.settings.uri == URI,
              f"video stream URI {s.settings.uri if s else None!r}")
        check(s is not None and s.status == s.VideoStreamStatus.IN_PROGRESS,
              "the stream is running")
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
    print(f"mavsdk_camera: {passed} passed, {failed} failed", flush=True)
    # Leave without running MAVSDK's destructors from the garbage collector at exit.
    os._exit(0 if failed == 0 and passed > 0 else 1)


if __name__ == "__main__":
    main()
