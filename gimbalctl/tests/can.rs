//! `--can IFACE` through the binary: the errors a user meets opening an interface (run on
//! any Linux machine), and `send` and `monitor` on a real SocketCAN interface, `vcan0`
//! (ignored unless asked for: a kernel without the vcan module, as in some containers and
//! CI's, has none; `cargo test -p gimbalctl --test can -- --ignored` where it is up). The CAN transport itself (the library's `CanPort<C>` under `send`,
//! `monitor` and `mavlink`) is tested on the core's mock bus by the unit tests
//! (`send_monitor::tests`, `mavlink::tests`); only the socket's opening is SocketCAN's.

#![cfg(target_os = "linux")]

mod common;

use common::*;
use std::time::{Duration, Instant};

use embedded_can::Id;
use socketcan::{CanFrame, CanSocket, EmbeddedFrame, ExtendedId, Socket};

#[test]
fn can_usage_and_open_errors() {
    for (args, words) in [
        (
            &["monitor", "--can", "a-name-far-too-long"][..],
            &["--can", "1 to 15"][..],
        ),
        (&["monitor", "--can", "can0/x"], &["--can"]),
        (
            &["send", "--can", "can0", "--serial", "/dev/ttyS0", "center"],
            &["--can", "--serial"],
        ),
        (&["control", "--can", ""], &["--can"]),
    ] {
        usage_error_naming(args, words);
    }
    for (args, words) in [
        (
            &["monitor", "--can", "gimbalctl0"][..],
            &["--can gimbalctl0", "no such network interface", "vcan"][..],
        ),
        (&["send", "--can", "lo", "center"], &["not a CAN interface"]),
        (
            &["mavlink", "--can", "gimbalctl0", "--listen", "127.0.0.1:0"],
            &["no such network interface"],
        ),
    ] {
        failure_naming(args, words);
    }
}

/// `vcan0`, up, or why not.
fn vcan0() -> Option<CanSocket> {
    let flags = std::fs::read_to_string("/sys/class/net/vcan0/flags").ok()?;
    let up = u32::from_str_radix(flags.trim().trim_start_matches("0x"), 16).ok()? & 1 == 1;
    if !up {
        return None;
    }
    let socket = CanSocket::open("vcan0").ok()?;
    socket.set_read_timeout(Duration::from_millis(100)).ok()?;
    Some(socket)
}

fn ext(id: u32, data: &[u8]) -> CanFrame {
    CanFrame::new(ExtendedId::new(id).unwrap(), data).unwrap()
}

#[test]
#[ignore = "needs vcan0 up: sudo modprobe vcan && sudo ip link add dev vcan0 type vcan && sudo ip link set up vcan0"]
fn send_and_monitor_on_vcan0() {
    let bus = vcan0().expect(
        "no vcan0 interface up here (sudo modprobe vcan && sudo ip link add dev vcan0 type \
         vcan && sudo ip link set up vcan0)",
    );
    // send: the frame `encode` prints, on the bus.
    ok(&["send", "--can", "vcan0", "pitch", "-45"]);
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        assert!(Instant::now() < deadline, "no control frame on vcan0");
        let Ok(f) = bus.read_frame() else { continue };
        if f.id() == Id::Extended(ExtendedId::new(0x0F01).unwrap()) {
            assert_eq!(f.data(), [0x0F, 0x08, 0x02, 0x3E, 0xFE, 0, 0, 0]);
            break;
        }
    }
    // monitor: another controller's command, then a postback, from the test's socket.
    let (mut monitor, stdout, _stderr) = spawn(&["monitor", "--can", "vcan0", "--count", "1"]);
    std::thread::sleep(Duration::from_millis(500));
    bus.write_frame(&ext(0x0F01, &[0x0F, 0x07, 0, 0, 0, 0, 0, 0]))
        .unwrap();
    for data in postback_frames(&postback(1, 0, 3, -3000, 18000, -150)) {
        bus.write_frame(&ext(0x030F_0001, &data)).unwrap();
    }
    assert_eq!(wait_with_timeout(&mut monitor.0, TIMEOUT), Some(0));
    let out = stdout.join().unwrap();
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(
        lines,
        [
            "control  00000F01  look-down",
            "pitch -30.00 deg  heading 180.00 deg  motor -1.50 deg  mode lock  tracking no  gimbal 1 (X30/X30GT)"
        ]
    );
}
