//! `gimbalctl mavlink`: usage errors (exit 2, stderr naming the argument, stdout empty), a
//! runtime failure (exit 1), and a clean run. The protocol itself is tested end to end by
//! `tests/mavlink_e2e.py` with pymavlink (run by `scripts/test.sh`).

mod common;

use common::*;
use std::net::UdpSocket;

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
        // A MAVLink address has no default port (the serial server's 2000 is not one): a
        // host alone is refused, not sent to port 2000. `--exit-after-ms` ends a run that
        // would take it.
        (
            &[
                "mavlink",
                "--sim",
                "--listen",
                "127.0.0.1:0",
                "--to",
                "127.0.0.1",
                "--exit-after-ms",
                "100",
            ],
            &["--to", "\"127.0.0.1\"", "HOST:PORT"],
        ),
        (
            &[
                "mavlink",
                "--sim",
                "--listen",
                "127.0.0.1",
                "--exit-after-ms",
                "100",
            ],
            &["--listen", "\"127.0.0.1\"", "HOST:PORT"],
        ),
        // The simulated gimbal's option, given for a real one: refused, not ignored.
        (
            &[
                "mavlink",
                "--tcp",
                "127.0.0.1:9",
                "--sim-lock-holds",
                "motor",
            ],
            &["--sim-lock-holds", "--sim"],
        ),
        (
            &["mavlink", "--sim", "--camera-fov", "60"],
            &["--camera-fov", "HFOV,VFOV", "less than 180"],
        ),
        (
            &["mavlink", "--sim", "--camera-fov", "60,180"],
            &[
                "--camera-fov",
                "vertical",
                "180°",
                "more than 0 and less than 180",
            ],
        ),
        (
            &["mavlink", "--sim", "--camera-resolution", "1920x0"],
            &["--camera-resolution", "WIDTHxHEIGHT", "1-65535"],
        ),
    ] {
        usage_error_naming(args, words);
    }
}

/// A signing key file holds 64 hex digits and nothing else: one of 64 characters that are
/// not all hex digits (a sign before each pair, a letter beyond `f`), or of 63 or 65
/// digits, is a usage error; 64 digits with spaces around them are a key.
#[test]
fn a_signing_key_file_holds_64_hex_digits() {
    let dir = std::env::temp_dir().join(format!("gimbalctl-key-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("key");
    let path_str = path.to_str().unwrap();
    for bad in [
        "+f".repeat(32),
        format!("{}g", "0".repeat(63)),
        "0".repeat(63),
        "0".repeat(65),
    ] {
        std::fs::write(&path, &bad).unwrap();
        usage_error_naming(
            &["mavlink", "--sim", "--signing-key-file", path_str],
            &["--signing-key-file", "64 hex digits"],
        );
    }
    std::fs::write(&path, format!("  {}\n", "a1".repeat(32))).unwrap();
    let out = run(&[
        "mavlink",
        "--sim",
        "--listen",
        "127.0.0.1:0",
        "--signing-key-file",
        path_str,
        "--exit-after-ms",
        "100",
    ]);
    assert_eq!(out.code, 0, "{out:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn runtime_failures_exit_1() {
    // A UDP port already taken.
    let taken = UdpSocket::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    failure_naming(
        &["mavlink", "--sim", "--listen", &addr],
        &["cannot listen on"],
    );
    // No serial server there.
    let closed = closed_port();
    let addr = format!("127.0.0.1:{}", closed.port());
    failure_naming(
        &["mavlink", "--tcp", &addr, "--listen", "127.0.0.1:0"],
        &["cannot connect to", &addr],
    );
    // A peer's name with no address (`.invalid`, RFC 6761): a failure at run time, not a
    // usage error.
    failure_naming(
        &[
            "mavlink",
            "--sim",
            "--listen",
            "127.0.0.1:0",
            "--to",
            "nosuch.invalid:14550",
        ],
        &["cannot resolve", "nosuch.invalid:14550"],
    );
}

#[test]
fn a_timed_run_says_where_it_listens_and_exits_0() {
    let out = run(&[
        "mavlink",
        "--sim",
        "--listen",
        "127.0.0.1:0",
        "--exit-after-ms",
        "1300",
    ]);
    assert_eq!(out.code, 0, "{out:?}");
    // Progress goes to stderr: the link coming up (said once), the timed exit; a run
    // past its first note (a second in) with nothing wrong warns of nothing.
    assert_eq!(
        out.stderr.lines().collect::<Vec<_>>(),
        [
            "gimbalctl mavlink: gimbal link up",
            "gimbalctl mavlink: exiting after 1300 ms"
        ],
        "{}",
        out.stderr
    );
    let line = out.lines()[0].to_string();
    assert!(
        line.starts_with("gimbalctl mavlink: listening on 127.0.0.1:"),
        "{line}"
    );
}
