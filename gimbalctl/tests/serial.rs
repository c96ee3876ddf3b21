//! The serial paths end to end on pseudo-terminals: `sim --pty` plays the gimbal's UART,
//! `send`, `monitor` and `mavlink` open its slave side with `--serial PATH`; a test-made pty
//! pair plays a pulled USB adapter, a line at the wrong baud rate, and (for
//! `mavlink --autopilot-serial`) the autopilot's TELEM port, speaking MAVLink built with
//! `mavio` (the bridge's re-export).
//!
//! Every wait is bounded; every child is killed when its test ends.

#![cfg(unix)]

mod common;

use common::mavlink::{frame, heartbeat, request_information, GIMBAL};
use common::*;
use std::net::UdpSocket;
use std::process::{Command, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use idu_gimbal_mavlink::attitude::YawPitch;
use idu_gimbal_mavlink::framing::{Check, FrameReader};
use idu_gimbal_mavlink::mavio;
use mavio::dialects::common::enums::{GimbalDeviceFlags, MavAutopilot, MavType};
use mavio::dialects::common::messages::{
    GimbalDeviceAttitudeStatus, GimbalDeviceInformation, GimbalDeviceSetAttitude, Heartbeat,
};
use mavio::mavspec::rust::spec::MessageSpecStatic;
use mavio::Message;

/// Waits until gimbalctl has opened the slave side of `pty`.
fn wait_open(pty: &mut TestPty) {
    let deadline = Instant::now() + Duration::from_secs(10);
    while !pty.is_open() {
        assert!(Instant::now() < deadline, "{} never opened", pty.path);
        thread::sleep(Duration::from_millis(10));
    }
}

/// Waits for `child`, whose port was just taken away, to end with exit 1 saying that it
/// went away; its stderr. All of it: the log is read to its end, since the child's last
/// lines may still be in the pipe when its exit is seen.
#[track_caller]
fn went_away(child: &mut Guard, stderr: Log) -> String {
    let code = wait_with_timeout(&mut child.0, TIMEOUT);
    let stderr = stderr.finish();
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("went away"), "{stderr}");
    stderr
}

#[test]
fn send_and_monitor_over_the_simulated_uart() {
    let (_sim, path, log) = start_pty_sim();
    let out = ok(&["monitor", "--serial", &path, "--count", "2"]);
    let lines = out.lines();
    assert_eq!(lines.len(), 2, "{}", out.stdout);
    assert!(lines[0].starts_with("pitch 0.00 deg"), "{}", out.stdout);
    // The baud rate is taken (a pty ignores it).
    ok(&[
        "send",
        "--serial",
        &format!("{path}:115200"),
        "pitch",
        "-30",
    ]);
    log.wait(&format!("{path}: pitch -30"), Duration::from_secs(5));
    // The gimbal slews at 60 deg/s: -30 within 1.5 s of postbacks.
    let out = ok(&["monitor", "--serial", &path, "--json", "--count", "4"]);
    let last = out.json().pop().unwrap();
    assert_eq!(last["pitch_deg"], -30, "{}", out.stdout);
    assert_eq!(last["id"], serde_json::Value::Null);
    // Vehicle frames are CAN only: a usage error, nothing opened.
    usage_error_naming(&["send", "--serial", &path, "gps", "47", "8"], &["--can"]);
}

#[test]
fn send_holds_a_rate_over_the_uart() {
    let (_sim, path, log) = start_pty_sim();
    ok(&[
        "send",
        "--serial",
        &path,
        "--repeat-ms",
        "50",
        "--for-ms",
        "300",
        "rate",
        "0",
        "10",
    ]);
    log.wait(&format!("{path}: rate 0 10"), Duration::from_secs(5));
    log.wait(&format!("{path}: rate 0 0"), Duration::from_secs(5));
    // The client gone, the sim says so (the master reads EIO with no client).
    log.wait(&format!("{path} closed"), Duration::from_secs(5));
    // Each command once, not each of its repeats; the one client's opening and closing
    // said once each.
    let text = log.text();
    for line in ["rate 0 10", "rate 0 0"] {
        let n = text.matches(&format!("{path}: {line}\n")).count();
        assert_eq!(n, 1, "{line}: {text}");
    }
    for line in ["opened", "closed"] {
        let n = text.matches(&format!("{path} {line}\n")).count();
        assert_eq!(n, 1, "{line}: {text}");
    }
}

/// The other end of the line closing mid-session (a USB adapter pulled): exit 1 at once,
/// saying so, after the postbacks that came.
#[test]
fn a_port_that_goes_away_is_exit_1() {
    let mut pty = TestPty::new();
    let path = pty.path.clone();
    let mut child = command(&["monitor", "--serial", &path])
        .spawn()
        .expect("spawn gimbalctl");
    let stdout = lines(child.stdout.take().expect("stdout"));
    let stderr = Log::collect(child.stderr.take().expect("stderr"));
    let mut monitor = Guard(child);
    // A postback every 100 ms once gimbalctl has the port open (the open drops what came
    // before it, however long it takes), until the monitor prints one; then the line goes
    // away. Gone only once one printed: a hang-up drops what the port has not read.
    wait_open(&mut pty);
    let deadline = Instant::now() + Duration::from_secs(10);
    let line = loop {
        assert!(pty.write(&postback(1, 0, 3, -1234, 9000, 0)));
        match stdout.recv_timeout(Duration::from_millis(100)) {
            Ok(line) => break line,
            Err(_) if Instant::now() < deadline => {}
            Err(e) => panic!("no postback printed ({e}): {}", stderr.text()),
        }
    };
    assert!(
        line.starts_with("pitch -12.34 deg  heading 90.00 deg"),
        "{line}"
    );
    drop(pty);
    let stderr = went_away(&mut monitor, stderr);
    assert!(stderr.contains(&path), "{stderr}");
    // One more may have been read before the hang-up: the count is of what printed.
    let printed = 1 + stdout.iter().count();
    assert!(
        stderr.contains(&format!("after {printed} postback")),
        "{printed} printed: {stderr}"
    );
}

/// The sim going away under `send --repeat-ms` and `mavlink` ends them too.
#[test]
fn the_sim_exiting_ends_a_session_with_exit_1() {
    // Each session, and what the sim logs once it is under way: the bridge once it has the
    // port (else it could not open it, a different error); a rate held for 20 s once its
    // first command came.
    type Session = (&'static [&'static str], fn(&str) -> String);
    let sessions: [Session; 2] = [
        (
            &[
                "mavlink",
                "--listen",
                "127.0.0.1:0",
                "--exit-after-ms",
                "20000",
            ],
            |path| format!("{path} opened"),
        ),
        (
            &[
                "send",
                "--repeat-ms",
                "50",
                "--for-ms",
                "20000",
                "rate",
                "0",
                "10",
            ],
            |path| format!("{path}: rate 0 10"),
        ),
    ];
    for (args, under_way) in sessions {
        let (sim, path, log) = start_pty_sim();
        let mut full = vec![args[0], "--serial", &path];
        full.extend_from_slice(&args[1..]);
        let (mut session, _out, stderr) = spawn(&full);
        log.wait(&under_way(&path), Duration::from_secs(10));
        drop(sim);
        went_away(&mut session, stderr);
    }
}

/// Bytes that hold no frame (what a wrong baud rate gives): counted and said on stderr
/// with the likely cause, while monitor goes on.
#[test]
fn garbage_on_the_line_is_counted_and_said() {
    let mut pty = TestPty::new();
    let path = pty.path.clone();
    let (_monitor, _stdout, stderr) = spawn(&["monitor", "--serial", &format!("{path}:9600")]);
    wait_open(&mut pty);
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        // 0x55 never starts a frame.
        pty.write(&[0x55; 64]);
        let err = stderr.text();
        if err.contains("held no valid frame") && err.contains("no postback") {
            assert!(err.contains("wrong baud rate"), "{err}");
            assert!(err.contains("9600") && err.contains("115200"), "{err}");
            break;
        }
        assert!(Instant::now() < deadline, "never said: {err}");
        thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn serial_usage_and_open_errors() {
    for (args, words) in [
        (
            &["monitor", "--serial", "/dev/ttyUSB0:0"][..],
            &["--serial", "[50, 4000000]"][..],
        ),
        (&["monitor", "--serial", "/dev/ttyUSB0:"], &["--serial"]),
        (
            &[
                "monitor",
                "--serial",
                "/dev/ttyS0",
                "--tcp",
                "127.0.0.1:2000",
            ],
            &["--serial", "--tcp"],
        ),
        (
            &["mavlink", "--sim", "--autopilot-serial", "/dev/x:7"],
            &["--autopilot-serial", "[50, 4000000]"],
        ),
        (
            &[
                "mavlink",
                "--sim",
                "--autopilot-serial",
                "/dev/x",
                "--listen",
                "127.0.0.1:0",
            ],
            &["--autopilot-serial", "--listen"],
        ),
        (
            &["sim", "--pty", "--listen", "127.0.0.1:0"],
            &["--pty", "--listen"],
        ),
    ] {
        usage_error_naming(args, words);
    }
    for (args, words) in [
        (
            &["monitor", "--serial", "/dev/gimbalctl-no-such-tty"][..],
            &["no such device", "plugged in"][..],
        ),
        (
            &["send", "--serial", "/dev/null", "center"],
            &["not a serial port"],
        ),
        (
            &[
                "mavlink",
                "--sim",
                "--autopilot-serial",
                "/dev/gimbalctl-no-such-tty",
            ],
            &["--autopilot-serial", "no such device"],
        ),
    ] {
        failure_naming(args, words);
    }
}

/// A tty the user may not open: exit 1 naming the group to join. Root may open any tty, so
/// as root the binary, copied where every user may run it, is run as `nobody` through
/// `runuser`; as anyone else the tty is made unreadable to its owner and the binary run
/// directly. Either way the open fails with "permission denied".
#[test]
fn permission_denied_names_the_group() {
    use std::os::unix::fs::PermissionsExt;

    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    let pty = TestPty::new();
    let path = pty.path.clone();
    let out = if root {
        // A checkout may sit under a directory only root may enter.
        let dir = std::env::temp_dir().join(format!("gimbalctl-nobody-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
        let bin = dir.join("gimbalctl");
        std::fs::copy(BIN, &bin).unwrap();
        let out = Command::new("runuser")
            .args(["-u", "nobody", "--"])
            .arg(&bin)
            .args(["monitor", "--serial", &path])
            .stdin(Stdio::null())
            .output()
            .expect("runuser (util-linux), to open the tty as nobody");
        std::fs::remove_dir_all(&dir).unwrap();
        out
    } else {
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o000)).unwrap();
        Command::new(BIN)
            .args(["monitor", "--serial", &path])
            .stdin(Stdio::null())
            .output()
            .unwrap()
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(out.stdout.is_empty());
    assert!(stderr.contains("permission denied"), "{stderr}");
    assert!(stderr.contains("add yourself to it"), "{stderr}");
}

// ---------------------------------------------------------------------------------------
// MAVLink over the serial paths

/// The autopilot: system 1, component 1.
const AP: (u8, u8) = (1, 1);

fn autopilot_heartbeat() -> Heartbeat {
    heartbeat(MavType::Quadrotor, MavAutopilot::Px4)
}

fn pitch_setpoint(deg: f32) -> GimbalDeviceSetAttitude {
    GimbalDeviceSetAttitude {
        target_system: AP.0,
        target_component: GIMBAL,
        // The yaw in the vehicle frame: the serial link is nose-referenced.
        flags: GimbalDeviceFlags::empty(),
        q: YawPitch {
            yaw_rad: 0.0,
            pitch_rad: deg.to_radians(),
        }
        .to_quaternion(),
        angular_velocity_x: f32::NAN,
        angular_velocity_y: f32::NAN,
        angular_velocity_z: f32::NAN,
    }
}

/// What the autopilot has heard from the gimbal component: message ids.
#[derive(Default)]
struct Heard {
    reader: FrameReader,
    ids: Vec<u32>,
}

impl Heard {
    fn feed(&mut self, bytes: &[u8]) {
        let ids = &mut self.ids;
        self.reader.feed(bytes, |f| {
            if let Some(frame) = f.to_frame() {
                if frame.component_id() == GIMBAL {
                    ids.push(frame.message_id());
                }
            }
            Check::Unhandled
        });
    }

    fn has<M: MessageSpecStatic>(&self) -> bool {
        self.ids.contains(&M::spec().id())
    }

    /// Panics once `deadline` has passed, saying what was heard and what the sim and the
    /// bridge logged.
    #[track_caller]
    fn assert_before(&self, deadline: Instant, sim: &Log, bridge: &Log) {
        assert!(
            Instant::now() < deadline,
            "heard {:?}; sim {}; bridge {}",
            self.ids,
            sim.text(),
            bridge.text()
        );
    }
}

/// `mavlink --serial` (the gimbal on the simulated UART) with the autopilot on UDP.
#[test]
fn mavlink_bridges_udp_to_the_uart_gimbal() {
    let (_sim, path, log) = start_pty_sim();
    // A port the bridge binds itself, said on its first stdout line (one taken here and
    // freed could be taken by another in between).
    let (_bridge, line, stderr) = start(
        &[
            "mavlink",
            "--serial",
            &path,
            "--listen",
            "127.0.0.1:0",
            "--exit-after-ms",
            "30000",
        ],
        "gimbalctl mavlink: listening on ",
        Duration::from_secs(10),
    );
    let listen: std::net::SocketAddr = line
        .split("listening on ")
        .nth(1)
        .and_then(|rest| rest.split(',').next())
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("no address in {line:?}"));
    let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    sock.set_read_timeout(Some(Duration::from_millis(50)))
        .unwrap();
    let mut heard = Heard::default();
    let deadline = Instant::now() + Duration::from_secs(15);
    let mut seq = 0u8;
    let mut buf = [0u8; 2048];
    loop {
        for m in [
            &autopilot_heartbeat() as &dyn Message,
            &request_information(AP.0),
            &pitch_setpoint(-30.0),
        ] {
            let _ = sock.send_to(&frame(AP, seq, m), listen);
            seq = seq.wrapping_add(1);
        }
        while let Ok(n) = sock.recv(&mut buf) {
            heard.feed(&buf[..n]);
        }
        let logged = log.has(&format!("{path}: pitch -30"));
        if logged
            && heard.has::<Heartbeat>()
            && heard.has::<GimbalDeviceInformation>()
            && heard.has::<GimbalDeviceAttitudeStatus>()
        {
            break;
        }
        heard.assert_before(deadline, &log, &stderr);
        thread::sleep(Duration::from_millis(100));
    }
    // Said at the first postback, which may come after the answers (every 500 ms).
    stderr.wait("gimbal link up", Duration::from_secs(5));
}

/// `mavlink --serial --autopilot-serial`: the gimbal on the simulated UART, the autopilot on
/// a second pty (the test, at the default 921600 baud), MAVLink as a byte stream both ways;
/// then the autopilot's port closing ends the bridge with exit 1.
#[test]
fn mavlink_bridges_an_autopilot_on_a_serial_port() {
    let (_sim, path, log) = start_pty_sim();
    let mut ap = TestPty::new();
    let ap_path = ap.path.clone();
    let (mut bridge, out, stderr) = spawn(&[
        "mavlink",
        "--serial",
        &path,
        "--autopilot-serial",
        &ap_path,
        "--exit-after-ms",
        "30000",
    ]);
    let mut heard = Heard::default();
    let deadline = Instant::now() + Duration::from_secs(15);
    let mut seq = 0u8;
    wait_open(&mut ap);
    loop {
        let mut bytes = Vec::new();
        for m in [
            &autopilot_heartbeat() as &dyn Message,
            &request_information(AP.0),
            &pitch_setpoint(-45.0),
        ] {
            bytes.extend(frame(AP, seq, m));
            seq = seq.wrapping_add(1);
        }
        // A byte stream: in uneven pieces.
        for piece in bytes.chunks(7) {
            ap.write(piece);
        }
        heard.feed(&ap.read_for(Duration::from_millis(100)));
        let logged = log.has(&format!("{path}: pitch -45"));
        if logged && heard.has::<Heartbeat>() && heard.has::<GimbalDeviceInformation>() {
            break;
        }
        heard.assert_before(deadline, &log, &stderr);
    }
    // The autopilot's port goes away: exit 1, saying which.
    drop(ap);
    let err = went_away(&mut bridge, stderr);
    assert!(err.contains(&ap_path), "{err}");
    let first = out.join().unwrap();
    assert!(
        first.starts_with(&format!(
            "gimbalctl mavlink: autopilot on {ap_path} at 921600 baud, gimbal: the UART on {path}"
        )),
        "{first}"
    );
}

/// `mavlink --sim --autopilot-serial`: twenty requests in one write, more than the bridge's
/// outbox holds answers for: every one ACCEPTED with its message, exactly once. The bridge
/// takes the stream up to a frame that waits for room and holds the rest until it has sent.
/// (Once three were ACCEPTED, the rest TEMPORARILY_REJECTED, and refusals that did not fit
/// the outbox lost.)
#[test]
fn a_burst_of_requests_on_the_autopilot_serial_port_is_answered_in_full() {
    use mavio::dialects::common::enums::MavResult;
    use mavio::dialects::common::messages::CommandAck;
    let mut ap = TestPty::new();
    let ap_path = ap.path.clone();
    let (_bridge, _out, stderr) = spawn(&[
        "mavlink",
        "--sim",
        "--autopilot-serial",
        &ap_path,
        "--exit-after-ms",
        "30000",
    ]);
    wait_open(&mut ap);
    // Heartbeats until the bridge is heard: it has the port open and configured (bytes
    // written before then may be flushed).
    let mut heard = Heard::default();
    let deadline = Instant::now() + Duration::from_secs(10);
    while !heard.has::<Heartbeat>() {
        ap.write(&frame(AP, 0, &autopilot_heartbeat()));
        heard.feed(&ap.read_for(Duration::from_millis(100)));
        heard.assert_before(deadline, &stderr, &stderr);
    }
    let mut bytes = Vec::new();
    for seq in 1..=20 {
        bytes.extend(frame(AP, seq, &request_information(AP.0)));
    }
    ap.write(&bytes);
    let (mut acks, mut information) = (Vec::new(), 0);
    let mut reader = FrameReader::new();
    let deadline = Instant::now() + Duration::from_secs(10);
    while information < 20 && Instant::now() < deadline {
        reader.feed(&ap.read_for(Duration::from_millis(100)), |f| {
            match f.to_frame() {
                Some(m) if m.component_id() == GIMBAL => {
                    if let Ok(ack) = m.decode_message::<CommandAck>() {
                        acks.push(ack.result);
                    } else if m.message_id() == GimbalDeviceInformation::spec().id() {
                        information += 1;
                    }
                }
                _ => {}
            }
            Check::Unhandled
        });
    }
    // Anything more would come within the next moments.
    reader.feed(&ap.read_for(Duration::from_millis(300)), |f| {
        if let Some(m) = f.to_frame() {
            if m.component_id() == GIMBAL {
                if let Ok(ack) = m.decode_message::<CommandAck>() {
                    acks.push(ack.result);
                } else if m.message_id() == GimbalDeviceInformation::spec().id() {
                    information += 1;
                }
            }
        }
        Check::Unhandled
    });
    assert_eq!(acks, vec![MavResult::Accepted; 20], "{}", stderr.text());
    assert_eq!(information, 20, "{}", stderr.text());
}
