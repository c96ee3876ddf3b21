#!/usr/bin/env python3
"""MAVLink 2 signing against `gimbalctl mavlink --sim --signing-passphrase` (and
`--signing-key-file`), with pymavlink's own signing (`setup_signing`, the key the
passphrase's SHA-256 as MAVProxy's `signing setup` derives it):

1. a client signing with the key: its request is answered, the ACK and the message signed
   with the key (pymavlink checks each signature: good signatures counted, none bad);
2. an unsigned client and a client signing with another key: no answer;
3. a signed request sent again byte for byte (replayed): answered once;
4. the key from a file of 64 hex digits works alike; a file that is not one is a usage error
   (exit 2, stdout empty, stderr naming the argument).

Usage: mavlink_signing.py PATH/TO/gimbalctl
"""

import hashlib
import os
import re
import subprocess
import sys
import tempfile
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mav  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks, Inbox  # noqa: E402

PASSPHRASE = "idu-gimbal signing in CI"
KEY = hashlib.sha256(PASSPHRASE.encode()).digest()
GIMBAL = 154
GIMBAL_DEVICE_INFORMATION = 283
# Answers come within milliseconds on loopback; 2 s is the margin of a loaded CI machine.
ANSWER_S = 2.0

r = Checks()
check = r.check


def start(gimbalctl, *key_args):
    """The bridge, its port, and the file its stderr goes to."""
    err = tempfile.TemporaryFile(mode="w+")
    proc = subprocess.Popen(
        [gimbalctl, "mavlink", "--sim", "--listen", "127.0.0.1:0", "--exit-after-ms", "60000", *key_args],
        stdout=subprocess.PIPE, stderr=err, text=True)
    line = proc.stdout.readline()
    port = int(line.split("listening on ")[1].split(",")[0].rsplit(":", 1)[1])
    return proc, port, err


def signing_counts(err):
    """The counts of the bridge's latest signing line on stderr (said once a second as they
    grow): (accepted, unsigned, bad signature, replayed), or None."""
    err.seek(0)
    text = err.read()
    sys.stderr.write(text)
    found = re.findall(r"frames accepted: (\d+); turned away: (\d+) unsigned, "
                       r"(\d+) with a bad signature, (\d+) replayed", text)
    return tuple(int(v) for v in found[-1]) if found else None


class Client(Inbox):
    def __init__(self, port, key=None, system=255):
        super().__init__(mavutil.mavlink_connection(f"udpout:127.0.0.1:{port}", source_system=system,
                                                    source_component=190, dialect="common"))
        if key is not None:
            # pymavlink signs what it sends and, with no allow_unsigned_callback, drops what
            # is not signed with the key.
            self.m.setup_signing(key, sign_outgoing=True)

    def request(self, seq_bytes=None):
        """REQUEST_MESSAGE(GIMBAL_DEVICE_INFORMATION) to the gimbal (system 1 until the bridge
        hears an autopilot); the bytes sent."""
        msg = self.m.mav.command_long_encode(1, GIMBAL, mav.MAV_CMD_REQUEST_MESSAGE, 0,
                                             GIMBAL_DEVICE_INFORMATION, 0, 0, 0, 0, 0, 0)
        data = seq_bytes if seq_bytes is not None else msg.pack(self.m.mav)
        self.m.write(data)
        return data

    def answers(self, since):
        acks = [m for _, m in self.messages[since:] if m.get_type() == "COMMAND_ACK"
                and m.command == mav.MAV_CMD_REQUEST_MESSAGE]
        infos = [m for _, m in self.messages[since:] if m.get_type() == "GIMBAL_DEVICE_INFORMATION"]
        return acks, infos


def answered(client, what):
    since = client.mark()
    client.request()
    client.idle(ANSWER_S)
    acks, infos = client.answers(since)
    return acks, infos


def session(gimbalctl, label, *key_args):
    proc, port, err = start(gimbalctl, *key_args)
    try:
        good = Client(port, KEY)
        acks, infos = answered(good, "signed")
        signing = good.m.mav.signing
        check(len(acks) == 1 and acks[0].result == mav.MAV_RESULT_ACCEPTED and len(infos) == 1,
              f"{label}: a request signed with the key is answered: {len(acks)} ACK, {len(infos)} information")
        check(all(getattr(m, "_signed", False) for m in acks + infos) and signing.goodsig_count >= 2
              and signing.badsig_count == 0,
              f"{label}: the answers are signed with the key (pymavlink: {signing.goodsig_count} good, "
              f"{signing.badsig_count} bad signatures)")

        # Not acted on at all: no ACK to them, neither at their address (which never becomes
        # a peer) nor among what the signed client, a peer, receives.
        mark = good.mark()
        unsigned = Client(port, None, system=250)
        acks, infos = answered(unsigned, "unsigned")
        check(not acks and not infos, f"{label}: an unsigned request is not answered ({len(acks)} ACK)")

        wrong = Client(port, hashlib.sha256(b"another passphrase").digest(), system=251)
        acks, infos = answered(wrong, "wrong key")
        check(not acks and not infos, f"{label}: a request signed with another key is not answered ({len(acks)} ACK)")
        good.idle(0.5)
        to_them = [m for _, m in good.messages[mark:] if m.get_type() == "COMMAND_ACK"
                   and m.target_system in (250, 251)]
        check(not to_them, f"{label}: no ACK to either sent anywhere ({len(to_them)})")

        # The same signed bytes twice: the second is a replay.
        since = good.mark()
        data = good.request()
        good.idle(0.5)
        good.request(data)
        good.idle(ANSWER_S)
        acks, infos = good.answers(since)
        check(len(acks) == 1 and len(infos) == 1,
              f"{label}: a signed request sent twice byte for byte is answered once ({len(acks)} ACKs)")

        # The bridge says what it let through and turned away (once a second, as the counts
        # grow): the signed client's two requests (the replay is not one of them).
        good.idle(1.5)
        counts = signing_counts(err)
        check(counts is not None and counts[0] == 2 and counts[1] >= 1 and counts[2] >= 1
              and counts[3] == 1,
              f"{label}: stderr counts the accepted, unsigned, wrong-key and replayed frames: {counts}")
    except Exception as e:  # a crash is a failure with its reason
        check(False, f"{label}: crashed: {e!r}")
    finally:
        proc.kill()
        proc.wait()


def main():
    gimbalctl = sys.argv[1]
    session(gimbalctl, "--signing-passphrase", "--signing-passphrase", PASSPHRASE)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "key")
        with open(path, "w") as f:
            f.write(KEY.hex() + "\n")
        session(gimbalctl, "--signing-key-file", "--signing-key-file", path)
        with open(path, "w") as f:
            f.write("not a key\n")
        out = subprocess.run([gimbalctl, "mavlink", "--sim", "--signing-key-file", path,
                              "--exit-after-ms", "100"], capture_output=True, text=True, timeout=30)
        check(out.returncode == 2 and out.stdout == "" and "--signing-key-file" in out.stderr
              and "64 hex digits" in out.stderr,
              f"a key file that is not 64 hex digits: exit {out.returncode}, stderr {out.stderr.strip()!r}")
    return r.summary("mavlink_signing")


if __name__ == "__main__":
    sys.exit(main())
