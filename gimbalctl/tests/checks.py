"""What the end-to-end clients share (mavlink_e2e.py, mavlink_camera.py, mavsdk_camera.py,
mavlink_aiming.py, qgc_camera.py): the tally they keep (each check printed as it is made, "ok" or "FAIL",
then a last line "NAME: N passed, M failed"), and the simulated gimbal's behaviour they run
`gimbalctl mavlink --sim` with. Imported from the clients' own directory, which Python puts
first on the path when it runs one of them."""

import os
import time

DEFINITIONS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                           "idu-gimbal-mavlink", "camera-definitions")


def served_definition(name, model):
    """A camera definition as the bridge serves it: the file `name` of
    idu-gimbal-mavlink/camera-definitions/ with its empty `<model>` filled with `model`
    (CAMERA_INFORMATION's model_name), which QGroundControl renames the camera to."""
    with open(os.path.join(DEFINITIONS, name), "rb") as f:
        template = f.read()
    assert template.count(b"<model></model>") == 1, f"{name}: one empty <model>"
    return template.replace(b"<model></model>", b"<model>" + model.encode() + b"</model>")


def sim_options():
    """`--sim-lock-holds WHAT` from the environment's GIMBALCTL_SIM_LOCK_HOLDS (`north` or
    `motor`: what the simulated gimbal holds in lock while the vehicle turns), so that the
    suite runs each client against both; none (gimbalctl's default) when unset."""
    what = os.environ.get("GIMBALCTL_SIM_LOCK_HOLDS")
    return ["--sim-lock-holds", what] if what else []


def raw_fields(msg):
    """A message's fields as bytes on the wire (pymavlink decodes char arrays to str, cut at
    the first NUL: a PARAM_EXT value byte 0 decodes as ""). MAVLink 2 drops the payload's
    trailing zeros: pad them back."""
    buf = bytes(msg.get_msgbuf())
    payload = buf[10:10 + buf[1]]  # the v2 header is 10 bytes; byte 1 is the payload length
    u = msg.unpacker
    values = u.unpack(payload.ljust(u.size, b"\0")[:u.size])
    return dict(zip(msg.ordered_fieldnames, values))


class Inbox:
    """What a pymavlink connection (`self.m`) has received, each message with the monotonic
    time it was read; `bad` holds what did not parse. Subclasses may send on each pump
    (`on_pump`), as a ground station's heartbeat."""

    def __init__(self, m):
        self.m = m
        self.messages = []  # (monotonic time, message)
        self.bad = []

    def on_pump(self):
        pass

    def pump(self):
        self.on_pump()
        while True:
            msg = self.m.recv_match(blocking=False)
            if msg is None:
                return
            if msg.get_type() == "BAD_DATA":
                self.bad.append(msg)
                continue
            self.messages.append((time.monotonic(), msg))

    def mark(self):
        """The index to look from for what arrives next."""
        self.pump()
        return len(self.messages)

    def after(self, msg, otherwise):
        """The mark just past `msg`, a message received here: what its sender sent after
        it (one socket keeps the order). `otherwise` when `msg` is None."""
        for i, (_, m) in enumerate(self.messages):
            if m is msg:
                return i + 1
        return otherwise

    def wait(self, pred, timeout, since):
        """The first message since the mark `since` for which `pred` holds, waiting up to
        `timeout` seconds; None after that."""
        end = time.monotonic() + timeout
        while True:
            self.pump()
            for _, msg in self.messages[since:]:
                if pred(msg):
                    return msg
            if time.monotonic() >= end:
                return None
            time.sleep(0.001)

    def idle(self, seconds):
        """Keeps receiving for `seconds`."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.pump()
            time.sleep(0.002)


class Checks:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, ok, what):
        """Counts and prints one check; returns `ok`, so that a caller can stop after a
        failure."""
        print(("  ok   " if ok else "  FAIL ") + what, flush=True)
        if ok:
            self.passed += 1
        else:
            self.failed += 1
        return ok

    def summary(self, name):
        """Prints the last line; returns the exit status: 0 only when checks ran and none
        failed."""
        print(f"{name}: {self.passed} passed, {self.failed} failed", flush=True)
        return 0 if self.failed == 0 and self.passed > 0 else 1
