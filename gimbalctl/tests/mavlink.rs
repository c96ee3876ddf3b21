//! `gimbalctl mavlink`: usage errors (exit 2, stderr naming the argument, stdout empty), a
//! runtime failure (exit 1), and a clean run. The protocol itself is tested end to end by
//! `tests/mavlink_e2e.py` with pymavlink (run by `scripts/test.sh`).

mod common;

use common::*;
use std::net::{TcpListener, UdpSocket};

#[test]
fn usage_errors_name_the_argument() {
    for (args, words) in [
        (&["mavlink"][..], &["--sim", "--tcp"][..]),
        (
            &["mavlink", "--sim", "--tcp", "127.0.0.1:2000"],
            &["--sim", "--tcp"],
        ),
        (
            &["mavlink", "--sim", "--system-id", "0"],
            &["--system-id", "1..=255"],
        ),
        (
            &["mavlink", "--sim", "--system-id", "256"],
            &["--system-id"],
        ),
        (
            &["mavlink", "--sim", "--camera", "x9"],
            &["--camera", "a2000", "f10"],
        ),
        (&["mavlink", "--sim", "--listen", "nowhere"], &["--listen"]),
        (&["mavlink", "--sim", "--to", "nowhere"], &["--to"]),
    ] {
        let out = usage_error(args);
        for w in words {
            assert!(
                out.stderr.contains(w),
                "{args:?}: {w:?} not in {}",
                out.stderr
            );
        }
    }
}

#[test]
fn runtime_failures_exit_1() {
    // A UDP port already taken.
    let taken = UdpSocket::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let out = run(&["mavlink", "--sim", "--listen", &addr]);
    assert_eq!(out.code, 1, "{}", out.stderr);
    assert!(out.stdout.is_empty());
    assert!(out.stderr.contains("cannot listen on"));
    // No serial server there.
    let closed = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = closed.local_addr().unwrap().to_string();
    drop(closed);
    let out = run(&["mavlink", "--tcp", &addr, "--listen", "127.0.0.1:0"]);
    assert_eq!(out.code, 1, "{}", out.stderr);
    assert!(out.stdout.is_empty());
}

#[test]
fn a_timed_run_says_where_it_listens_and_exits_0() {
    let out = run(&[
        "mavlink",
        "--sim",
        "--listen",
        "127.0.0.1:0",
        "--exit-after-ms",
        "300",
    ]);
    assert_eq!(out.code, 0, "{out:?}");
    // Progress goes to stderr: the link coming up, the timed exit.
    assert!(
        out.stderr.contains("exiting after 300 ms"),
        "{}",
        out.stderr
    );
    let line = out.lines()[0].to_string();
    assert!(
        line.starts_with("gimbalctl mavlink: listening on 127.0.0.1:"),
        "{line}"
    );
}

/// More UDP peers than the bridge remembers (8): the ninth is ignored, said once on
/// stderr, while the first eight keep receiving.
#[test]
fn peers_beyond_the_bound_are_ignored_and_said_so() {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};

    let mut child = Command::new(env!("CARGO_BIN_EXE_gimbalctl"))
        .args([
            "mavlink",
            "--sim",
            "--listen",
            "127.0.0.1:0",
            "--exit-after-ms",
            "6000",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let addr = line
        .split("listening on ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .unwrap()
        .to_string();
    // A MAVLink 2 heartbeat from an autopilot (system 1, component 1), sequence 0.
    let heartbeat: [u8; 21] = [
        0xFD, 9, 0, 0, 0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 2, 3, 0x51, 4, 3, 0, 0,
    ];
    let peers: Vec<UdpSocket> = (0..9)
        .map(|_| UdpSocket::bind("127.0.0.1:0").unwrap())
        .collect();
    for p in &peers {
        p.set_read_timeout(Some(Duration::from_millis(200)))
            .unwrap();
        // The CRC does not matter: any datagram makes its sender a peer.
        p.send_to(&heartbeat, &addr).unwrap();
        std::thread::sleep(Duration::from_millis(20));
    }
    // Heartbeats go out at 1 Hz: within 3 s each of the first eight hears one.
    let deadline = Instant::now() + Duration::from_secs(3);
    let mut heard = [false; 9];
    while Instant::now() < deadline && !heard[..8].iter().all(|&h| h) {
        for (i, p) in peers.iter().enumerate() {
            let mut buf = [0u8; 512];
            if p.recv(&mut buf).is_ok() {
                heard[i] = true;
            }
        }
    }
    assert!(heard[..8].iter().all(|&h| h), "{heard:?}");
    assert!(!heard[8], "the ninth peer was answered");
    child.kill().unwrap();
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.matches("ignoring").count(), 1, "{stderr}");
}
