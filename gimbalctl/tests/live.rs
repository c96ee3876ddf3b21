//! Live streams: `decode` and `monitor --json` hand over each result as soon as its input is
//! complete, without waiting for the input to end.
//!
//! Each test feeds a child process one line (or one frame) at a time over a pipe that stays
//! open, and waits for the decoded object before writing the next. The deadline per object
//! is 10 s: a live decoder answers in milliseconds, so only a decoder that holds its output
//! until the input ends (or a machine stalled for seconds) misses it, and such a decoder
//! never answers at all here because the pipe is not closed until the end.

mod common;

use common::*;
use std::io::Write;
use std::process::{ChildStdin, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::Duration;

/// How long each decoded object may take to appear (see the module docs).
const PER_OBJECT: Duration = Duration::from_secs(10);

/// Starts `gimbalctl ARGS` with piped stdin and stdout; stdout lines arrive on the channel.
fn spawn(args: &[&str]) -> (Guard, ChildStdin, Receiver<String>) {
    let mut child = command(args)
        .stdin(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn gimbalctl");
    let stdin = child.stdin.take().unwrap();
    let rx = lines(child.stdout.take().unwrap());
    (Guard(child), stdin, rx)
}

fn next_object(rx: &Receiver<String>, after: &str) -> serde_json::Value {
    let line = rx
        .recv_timeout(PER_OBJECT)
        .unwrap_or_else(|_| panic!("nothing decoded within {PER_OBJECT:?} of writing {after}"));
    serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"))
}

#[test]
fn decode_writes_each_object_before_the_next_line_comes() {
    let (mut child, mut stdin, rx) = spawn(&["decode"]);
    // Pitch -1..-5 deg: 0F 08 02 then the angle in 0.1 deg, little-endian (the protocol notes).
    for deg in 1..=5i16 {
        let [lo, hi] = (-deg * 10).to_le_bytes();
        let line = format!("00000F01#0F0802{lo:02X}{hi:02X}000000\n");
        stdin.write_all(line.as_bytes()).unwrap();
        stdin.flush().unwrap();
        let got = next_object(&rx, &line);
        assert_json_eq(
            &got,
            &serde_json::json!({"type": "command", "t": null, "id": 0xF01,
                "peripheral": "gimbal", "command": "pitch", "args": [-deg]}),
        );
    }
    // A postback in candump -L form: four frames; the object comes with the fourth.
    let msg = postback(1, 0, 2, -3000, 9000, -77);
    for (i, data) in postback_frames(&msg).iter().enumerate() {
        let line = format!("(1700000000.{:06}) can0 030F0001#{}\n", i * 1000, hex(data));
        stdin.write_all(line.as_bytes()).unwrap();
        stdin.flush().unwrap();
        if i < 3 {
            continue;
        }
        let got = next_object(&rx, &line);
        assert_eq!(got["type"], "postback", "{got}");
        assert_eq!(got["pitch_deg"], -30, "{got}");
        assert_eq!(got["heading_deg"], 90, "{got}");
        assert_eq!(got["t"], 1700000000.003, "{got}");
    }
    // And the end of input still ends the run with status 0.
    drop(stdin);
    assert_eq!(wait_with_timeout(&mut child.0, TIMEOUT), Some(0));
    // Nothing more was written: the stream ends (its reader finds the pipe closed) with no
    // line after the last one read.
    assert_eq!(
        rx.recv_timeout(TIMEOUT),
        Err(RecvTimeoutError::Disconnected),
        "nothing more was written"
    );
}

#[test]
fn decode_stream_writes_each_frame_before_the_next_comes() {
    let (mut child, mut stdin, rx) = spawn(&["decode", "--stream"]);
    for deg in [10i16, -20, 30] {
        let [lo, hi] = (deg * 10).to_le_bytes();
        let frame = tcp_frame(&[0x0F, 0x08, 0x02, lo, hi, 0, 0, 0]);
        stdin.write_all(&frame).unwrap();
        stdin.flush().unwrap();
        let got = next_object(&rx, &hex(&frame));
        assert_json_eq(
            &got,
            &serde_json::json!({"type": "command", "t": null, "id": null,
                "peripheral": "gimbal", "command": "pitch", "args": [deg]}),
        );
    }
    let pb = postback(1, 1, 0, 1234, 100, 0);
    stdin.write_all(&pb).unwrap();
    stdin.flush().unwrap();
    let got = next_object(&rx, "a postback");
    assert_eq!(got["pitch_deg"], 12.34, "{got}");
    assert_eq!(got["tracking"], true, "{got}");
    drop(stdin);
    assert_eq!(wait_with_timeout(&mut child.0, TIMEOUT), Some(0));
}

#[test]
fn monitor_json_writes_each_postback_as_it_arrives() {
    let (_sim, addr) = start_sim(&["--exit-after-ms", "20000"]);
    // No --count: monitor runs until killed, so its output is only seen if it is flushed
    // as it goes. The simulator sends a postback every 500 ms.
    let (_monitor, _stdin, rx) = spawn(&["monitor", "--tcp", &addr, "--json"]);
    for _ in 0..2 {
        let got = next_object(&rx, "nothing (waiting for the simulator's postbacks)");
        assert_eq!(got["type"], "postback", "{got}");
        assert_eq!(got["id"], serde_json::Value::Null, "{got}");
    }
}
