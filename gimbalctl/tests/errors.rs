//! Exit status of every error path: 2 for usage and out-of-range values (stderr names the
//! argument and its valid range, stdout empty), 1 for runtime failures; and `rtsp`.

mod common;

use common::*;
use std::net::TcpListener;

/// (arguments, words stderr must contain: the argument's name and its range).
const OUT_OF_RANGE: &[(&[&str], &[&str])] = &[
    (&["encode", "pitch", "60.1"], &["pitch", "-100", "60"]),
    (&["encode", "pitch", "-100.5"], &["pitch", "-100", "60"]),
    (&["encode", "pitch", "nan"], &["pitch", "-100", "60"]),
    (&["encode", "pitch", "1e300"], &["pitch", "-100", "60"]),
    (&["encode", "heading", "-1"], &["heading", "0", "360"]),
    (&["encode", "heading", "360.5"], &["heading", "0", "360"]),
    (&["encode", "zoom-to", "0.5"], &["zoom_ratio", "1", "35"]),
    (&["encode", "zoom-to", "36"], &["zoom_ratio", "1", "35"]),
    (&["encode", "rate", "101", "0"], &["yaw", "-100", "100"]),
    (&["encode", "rate", "0", "-101"], &["pitch", "-100", "100"]),
    (
        &["encode", "ir-rate", "0", "-100.01"],
        &["pitch", "-100", "100"],
    ),
    (
        &["encode", "point-zoom", "10001", "0"],
        &["x", "-10000", "10000"],
    ),
    (
        &["encode", "point-zoom", "0", "-10001"],
        &["y", "-10000", "10000"],
    ),
    (
        &["encode", "ir-point-zoom", "99999999999", "0"],
        &["x", "-10000", "10000"],
    ),
    (
        &["encode", "track", "8192", "0", "0", "0"],
        &["x", "0", "8191"],
    ),
    (
        &["encode", "track", "0", "-1", "0", "0"],
        &["y", "0", "8191"],
    ),
    (
        &["encode", "track", "0", "0", "4081", "0"],
        &["width", "0", "4080"],
    ),
    (
        &["encode", "ir-track", "0", "0", "0", "-1"],
        &["height", "0", "4080"],
    ),
    (&["encode", "focus-at", "8192", "0"], &["x", "0", "8191"]),
    (&["encode", "photo", "burst", "0"], &["count", "1", "255"]),
    (&["encode", "photo", "burst", "256"], &["count", "1", "255"]),
    (
        &["encode", "photo", "timelapse", "-1"],
        &["seconds", "1", "255"],
    ),
    (
        &["encode", "photo", "timer", "1000"],
        &["seconds", "1", "255"],
    ),
    (&["encode", "palette", "15"], &["palette", "0", "14"]),
    (&["encode", "palette", "-1"], &["palette", "0", "14"]),
    (
        &["encode", "palette", "purple"],
        &["palette", "0..=14", "ice-blue"],
    ),
    (&["encode", "gps", "90.1", "0"], &["latitude", "-90", "90"]),
    (
        &["encode", "gps", "0", "-181"],
        &["longitude", "-180", "180"],
    ),
    (&["encode", "altitude", "1e300"], &["altitude"]),
    (
        &["encode", "attitude", "91", "0", "0"],
        &["pitch", "-90", "90"],
    ),
    (
        &["encode", "attitude", "0", "181", "0"],
        &["roll", "-180", "180"],
    ),
    (&["encode", "attitude", "0", "0", "inf"], &["heading"]),
    (&["encode", "text", ""], &["text"]),
    (&["encode", "text", "caf\u{e9}"], &["text", "0x7F"]),
    // look-at: elevation outside [-100, 60], positions out of range, same position.
    (
        &["encode", "look-at", "0", "0", "0", "0", "0.0001", "1000"],
        &["elevation", "89.36", "-100", "60"],
    ),
    (
        &["encode", "look-at", "91", "0", "0", "0", "0", "0"],
        &["vehicle", "latitude", "-90", "90"],
    ),
    (
        &["encode", "look-at", "0", "0", "0", "0", "200", "0"],
        &["target", "longitude", "-180", "180"],
    ),
    (
        &["encode", "look-at", "1", "2", "3", "1", "2", "3"],
        &["target"],
    ),
    (
        &["send", "--tcp", "127.0.0.1:9", "pitch", "70"],
        &["pitch", "-100", "60"],
    ),
    // Every argument is checked before the server's name is looked up: `.invalid` has no
    // address (RFC 6761), and the out-of-range pitch is still what is said.
    (
        &["send", "--tcp", "nosuch.invalid", "pitch", "70"],
        &["pitch", "-100", "60"],
    ),
    // The simulator's address is its own option's, not `--tcp`'s.
    (
        &["sim", "--listen", "127.0.0.1:65536"],
        &["--listen", "127.0.0.1:65536", "[0, 65535]"],
    ),
    // A server that serves nobody is no server.
    (
        &["sim", "--max-clients", "0"],
        &["--max-clients", "1..=65535"],
    ),
];

#[test]
fn out_of_range_values_exit_2_naming_the_argument_and_range() {
    for (args, words) in OUT_OF_RANGE {
        usage_error_naming(args, words);
    }
}

/// Whole messages: the COMMAND first, then the argument, the value as typed (in exponent
/// form when very large, plain when 0) and the range the library's constructor checks.
#[test]
fn out_of_range_messages_say_the_value_as_typed() {
    for (args, message) in [
        (
            &["encode", "pitch", "1e300"][..],
            "pitch: pitch = 1e300 is out of range [-100, 60]",
        ),
        // Beyond f32: narrowed for the check, said as typed.
        (
            &["encode", "pitch", "1e39"],
            "pitch: pitch = 1e39 is out of range [-100, 60]",
        ),
        (
            &["encode", "pitch", "nan"],
            "pitch: pitch must be a finite number in [-100, 60], got NaN",
        ),
        (
            &["encode", "zoom-to", "0"],
            "zoom-to: zoom_ratio = 0 is out of range [1, 35]",
        ),
        // Beyond i32 and below u32: the same.
        (
            &["encode", "ir-point-zoom", "99999999999", "0"],
            "ir-point-zoom: x = 99999999999 is out of range [-10000, 10000]",
        ),
        (
            &["encode", "photo", "timelapse", "-1"],
            "photo: seconds = -1 is out of range [1, 255]",
        ),
        (
            &["encode", "altitude", "1e300"],
            "altitude: altitude = 1e300 is out of range [-21474836.48, 21474836.47]",
        ),
    ] {
        let out = usage_error(args);
        assert_eq!(
            out.stderr,
            format!("gimbalctl: error: {message}\n"),
            "gimbalctl {args:?}"
        );
    }
}

#[test]
fn bad_usage_exits_2() {
    for args in [
        &[][..],
        &["frobnicate"],
        &["encode"],
        &["encode", "frobnicate"],
        &["encode", "pitch"],
        &["encode", "pitch", "1", "2"],
        &["encode", "pitch", "abc"],
        &["encode", "rate", "1"],
        &["encode", "track", "1", "2", "3"],
        &["encode", "point-zoom", "1.5", "2"],
        &["encode", "look-down", "extra"],
        &["encode", "photo"],
        &["encode", "photo", "burst"],
        &["encode", "photo", "panorama"],
        &["encode", "record", "pause"],
        &["encode", "zoom", "sideways"],
        &["encode", "focus", "near"],
        &["encode", "ir-zoom", "reset"],
        &["encode", "look-at", "1", "2", "3", "4", "5"],
        &["encode", "--bogus", "look-down"],
        // Vehicle and text frames have no serial/TCP frame.
        &["encode", "--tcp", "gps", "1", "2"],
        &["encode", "--tcp", "altitude", "1"],
        &["encode", "--tcp", "attitude", "1", "2", "3"],
        &["encode", "--tcp", "text", "hi"],
        &["send", "--tcp", "127.0.0.1:9", "gps", "1", "2"],
        &["send", "--tcp", "127.0.0.1:9", "text", "hi"],
        &["send", "pitch", "-30"],
        &["send", "--tcp", "127.0.0.1:9"],
        &["send", "--tcp", "127.0.0.1:notaport", "look-down"],
        &[
            "send",
            "--tcp",
            "127.0.0.1:9",
            "--repeat-ms",
            "50",
            "rate",
            "1",
            "0",
        ],
        &[
            "send",
            "--tcp",
            "127.0.0.1:9",
            "--for-ms",
            "50",
            "rate",
            "1",
            "0",
        ],
        &[
            "send",
            "--tcp",
            "127.0.0.1:9",
            "--repeat-ms",
            "0",
            "--for-ms",
            "5",
            "rate",
            "1",
            "0",
        ],
        &["monitor"],
        &["monitor", "--tcp", "127.0.0.1:9", "--count", "-1"],
        &["sim", "--exit-after-ms", "soon"],
        &["decode", "--bogus"],
        &["decode", "a", "b"],
        &["rtsp", "x3"],
    ] {
        usage_error(args);
    }
    usage_error_naming(&["encode", "frobnicate"], &["frobnicate"]);
}

#[test]
fn help_and_version_exit_0() {
    for args in [
        &["--help"][..],
        &["--version"],
        &["encode", "--help"],
        &["encode", "pitch", "--help"],
        &["decode", "--help"],
        &["send", "--help"],
        &["monitor", "--help"],
        &["sim", "--help"],
        &["rtsp", "--help"],
    ] {
        let out = ok(args);
        assert!(!out.stdout.is_empty(), "{args:?}");
    }
    // The encode help lists every command.
    let help = ok(&["encode", "--help"]).stdout;
    for name in [
        "point-zoom",
        "ir-track-stop",
        "palette",
        "look-at",
        "text",
        "attitude",
    ] {
        assert!(help.contains(name), "{name} missing from {help}");
    }
}

#[test]
fn runtime_failures_exit_1() {
    let missing = "/nonexistent/gimbalctl.log";
    failure_naming(&["decode", missing], &[missing]);

    // A port with nobody listening.
    let closed = closed_port();
    let target = format!("127.0.0.1:{}", closed.port());
    for args in [
        vec!["send", "--tcp", &target, "pitch", "-30"],
        vec!["monitor", "--tcp", &target, "--count", "1"],
    ] {
        failure_naming(&args, &[target.as_str()]);
    }

    // A name with no address is a failure at run time, not a usage error.
    failure_naming(
        &["send", "--tcp", "nosuch.invalid", "pitch", "-30"],
        &["cannot resolve", "nosuch.invalid"],
    );

    // sim cannot listen on a port that is taken.
    let taken = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let out = run(&["sim", "--listen", &addr, "--exit-after-ms", "100"]);
    assert_eq!(out.code, 1, "{out:?}");
}

#[test]
fn rtsp_addresses() {
    let long = "u".repeat(33);
    let cases: &[(&[&str], &str)] = &[
        (&["rtsp", "a2000", "main"], "rtsp://192.168.42.108:554/live"),
        (
            &["rtsp", "x3", "main"],
            "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0",
        ),
        (
            &["rtsp", "x3", "aux1"],
            "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=1",
        ),
        (
            &["rtsp", "argus", "aux2"],
            "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=2",
        ),
        (
            &["rtsp", "dual-light", "main"],
            "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0",
        ),
        (
            &["rtsp", "dual-light", "infrared"],
            "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=2",
        ),
        (
            &["rtsp", "f10", "main"],
            "rtsp://192.168.42.108:554/ch1/sub/av_stream",
        ),
        (
            &[
                "rtsp",
                "x3",
                "main",
                "--ip",
                "10.0.0.7",
                "--user",
                "pilot",
                "--password",
                "p@ss:w",
            ],
            "rtsp://pilot:p%40ss%3Aw@10.0.0.7:554/cam/realmonitor?channel=1&subtype=0",
        ),
        (
            &["rtsp", "f10", "main", "--ip", "10.1.2.3"],
            "rtsp://10.1.2.3:554/ch1/sub/av_stream",
        ),
    ];
    for (args, url) in cases {
        assert_eq!(ok(args).stdout, format!("{url}\n"), "{args:?}");
    }
    for (args, words) in [
        (
            &["rtsp", "x5", "main"][..],
            &["x5", "a2000", "dual-light"][..],
        ),
        (&["rtsp", "x3", "side"], &["side", "main", "infrared"]),
        (&["rtsp", "a2000", "aux1"], &["a2000", "aux1", "main"]),
        (&["rtsp", "x3", "infrared"], &["x3", "infrared", "aux2"]),
        (&["rtsp", "dual-light", "aux2"], &["aux2", "infrared"]),
        (&["rtsp", "f10", "aux1"], &["f10", "aux1"]),
        (&["rtsp", "x3", "main", "--ip", "192.168.42"], &["--ip"]),
        (&["rtsp", "x3", "main", "--user", "u"], &["--password"]),
        (&["rtsp", "x3", "main", "--password", "p"], &["--user"]),
        (
            &["rtsp", "x3", "main", "--user", &long, "--password", "p"],
            &["32"],
        ),
    ] {
        usage_error_naming(args, words);
    }
}

/// A stderr nobody reads any more (a pipe whose reader exited) loses the lines, not the
/// run: `decode` reads its input to the end, then warns of a malformed line on stderr,
/// whose reader is gone by then; it exits 0 with its output, as with stderr open.
#[test]
fn a_closed_stderr_is_no_panic() {
    use std::io::{Read as _, Write as _};
    let mut child = command(&["decode"])
        .stdin(std::process::Stdio::piped())
        .spawn()
        .expect("spawn gimbalctl");
    drop(child.stderr.take());
    let mut stdin = child.stdin.take().expect("stdin");
    stdin
        .write_all(b"garbage\n00000F01#0F07000000000000\n")
        .expect("write stdin");
    drop(stdin);
    let mut stdout = String::new();
    child
        .stdout
        .take()
        .expect("stdout")
        .read_to_string(&mut stdout)
        .expect("read stdout");
    let status = child.wait().expect("wait");
    assert_eq!(status.code(), Some(0), "{stdout}");
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
}
