//! What MAVLink 2 signing costs per frame on an emulated STM32F405, in guest instructions
//! under QEMU `-icount shift=0` (the meter of `qemu_bench`). Built with the `signing`
//! feature (`scripts/bench.sh` builds it in a target directory of its own).
//!
//! Two bridges alike but for a key, the attitude status off, so that a poll at a whole
//! second sends one frame, the gimbal device's HEARTBEAT:
//!
//! - **Sending**: that poll (and the outbox drained) with the key, less the same without:
//!   what signing one frame costs (its SHA-256 over key, header, payload, checksum, link id
//!   and timestamp: 60 bytes, two SHA-256 blocks).
//! - **Receiving**: those heartbeats, fed to a third bridge with the same key, each taken
//!   whole, less the unsigned ones fed to a bridge without: what checking one signature
//!   costs (the same hash, the comparison, the stream's timestamp kept). Every signed frame
//!   is checked to have been accepted, none turned away.
//!
//! Budgets enforced (exit 1 when over); the figures go to BENCHMARKS.md.
#![no_std]
#![no_main]

// The STM32F405's interrupt vector table (cortex-m-rt's `device` feature requires one).
use stm32f4xx_hal as _;

// A module of each bench that measures the bridge, not a library: see its header.
#[path = "../firmware.rs"]
mod firmware;

mod fw {
    use crate::firmware::Fw;
    use core::hint::black_box;

    use idu_gimbal::Instant;
    use idu_gimbal_mavlink::signing::SigningConfig;
    use idu_gimbal_mavlink::BridgeConfig;

    use idu_firmware_support::meter::Meter;
    use idu_firmware_support::report::Table;
    use idu_firmware_support::{println, qemu};

    /// Budgets, guest instructions a frame: about a fifth above the figure measured.
    const SIGN_BUDGET: f32 = 11_500.0;
    const CHECK_BUDGET: f32 = 11_500.0;

    /// Heartbeats measured: `per_op` runs its body `N` and `2N` times.
    const N: u32 = 16;
    /// Bytes of a signed heartbeat: header 10, payload 9, checksum 2, signature 13.
    const SIGNED_LEN: usize = 34;

    fn bridge(signing: bool) -> Fw {
        Fw::new(BridgeConfig {
            attitude_status: None,
            signing: signing.then(|| SigningConfig::from_passphrase(b"bench", 0)),
            ..BridgeConfig::default()
        })
    }

    /// The bytes `b` has queued, written.
    fn drain(b: &mut Fw) {
        let n = b.transmit_bytes().len();
        b.transmit_written(n);
    }

    /// Instructions of a poll at the next whole second (one heartbeat sent), drained.
    fn send_cost(m: &mut Meter, b: &mut Fw) -> f32 {
        let mut t = 0u32;
        b.poll(Instant::from_millis(t));
        drain(b);
        m.per_op(N, |_| {
            t = t.wrapping_add(1_000);
            b.poll(black_box(Instant::from_millis(t)));
            drain(b);
        })
    }

    /// `3N` heartbeats from `b`, one a second, as they went out.
    fn heartbeats(b: &mut Fw, len: usize) -> heapless::Vec<u8, { 3 * 34 * 16 }> {
        let mut out = heapless::Vec::new();
        for s in 0..3 * N {
            b.poll(Instant::from_millis(100_000 + s * 1_000));
            let bytes = b.transmit_bytes();
            if bytes.len() != len || out.extend_from_slice(bytes).is_err() {
                println!(
                    "bench: a poll sent {} bytes, not one heartbeat",
                    bytes.len()
                );
                qemu::exit(false);
            }
            drain(b);
        }
        out
    }

    /// Instructions a heartbeat of `frames` (each `len` bytes) takes into `b`, drained.
    fn receive_cost(m: &mut Meter, b: &mut Fw, frames: &[u8], len: usize) -> f32 {
        let mut next = frames.chunks(len);
        m.per_op(N, |_| {
            let frame = next.next().unwrap_or(&[]);
            let taken = b.receive(black_box(frame), Instant::from_millis(200_000));
            if taken != frame.len() {
                qemu::exit(false);
            }
            drain(b);
        })
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut m = Meter::start("qemu_bench_signing");
        let mut table = Table::new();
        let mut signed = bridge(true);
        let mut plain = bridge(false);
        let sign = send_cost(&mut m, &mut signed) - send_cost(&mut m, &mut plain);

        let signed_frames = heartbeats(&mut signed, SIGNED_LEN);
        let plain_frames = heartbeats(&mut plain, SIGNED_LEN - 13);
        let mut checker = bridge(true);
        let mut unchecked = bridge(false);
        let check = receive_cost(&mut m, &mut checker, &signed_frames, SIGNED_LEN)
            - receive_cost(&mut m, &mut unchecked, &plain_frames, SIGNED_LEN - 13);
        let stats = checker.bridge.signing_stats().unwrap_or_default();
        if stats.accepted != 3 * N || stats.unsigned + stats.bad_signature + stats.replayed != 0 {
            println!(
                "bench: the signed heartbeats were not all accepted: {:?}",
                stats
            );
            qemu::exit(false);
        }
        table.budget(
            "signing: one frame sent (a heartbeat, 2 SHA-256 blocks), over unsigned",
            sign,
            "",
            SIGN_BUDGET,
        );
        table.budget(
            "signing: one frame's signature checked (the same), over unsigned",
            check,
            "",
            CHECK_BUDGET,
        );
        println!();
        let ok = table.print();
        println!();
        qemu::exit(ok)
    }
}
