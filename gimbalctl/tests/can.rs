//! `--can IFACE` through the binary: the errors a user meets opening an interface (run on
//! any Linux machine). `send` and `monitor` on a real SocketCAN interface need the vcan
//! module, which CI's kernel lacks: `tools/socketcan/run_check.sh` checks them by hand,
//! with can-utils at the other end. The CAN transport itself (the library's `CanPort<C>`
//! under `send`, `monitor` and `mavlink`) is tested on the core's mock bus by the unit
//! tests (`transport::can::tests`, `send_monitor::tests`, `mavlink::tests`); only the
//! socket's opening is SocketCAN's.

#![cfg(target_os = "linux")]

mod common;

use common::*;

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
