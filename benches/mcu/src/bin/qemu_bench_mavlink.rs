//! Deterministic costs of the MAVLink bridge on an emulated STM32F405, counted in guest
//! instructions under QEMU `-icount shift=0` (the method of the core's
//! `qemu_bench`, whose meter this shares).
//!
//! - **Per received byte**: one second of what ArduPilot sends its MAVLink gimbal v2
//!   backend (`AP_Mount_Gremsy.cpp`): AUTOPILOT_STATE_FOR_GIMBAL_DEVICE at 50 Hz (the
//!   interval it asks of its own link, with its earth yaw rate in `angular_velocity_z`),
//!   a GIMBAL_DEVICE_SET_ATTITUDE at every 50 Hz update (earth frame: ROLL|PITCH|YAW_LOCK,
//!   NaN rates), aiming at a target that moves 2.5°/s in yaw (so about one setpoint in
//!   four moves past the 0.2° dead-band and re-commands the gimbal), GLOBAL_POSITION_INT at
//!   the 5 Hz the bridge asks for, and a HEARTBEAT; fed in one-second batches from 8-byte
//!   reads, divided by its bytes. The goal, <= 60, is enforced (exit 1 when over).
//! - **Latency**: the receive call that takes the last byte of a SET_ATTITUDE, which parses
//!   it and queues its heading and pitch commands in the CAN driver's queue; in
//!   instructions and in microseconds at 168 MHz (one instruction a cycle, a lower bound).
//! - An idle `Bridge::poll`, and one that sends the attitude status.
//!
//! Exit status 0 unless the run itself failed (the traffic not parsed as expected).
#![no_std]
#![no_main]

// The STM32F405's interrupt vector table (cortex-m-rt's `device` feature requires one).
use stm32f4xx_hal as _;

mod fw {
    use core::hint::black_box;

    use idu_gimbal::link::{Config, Link};
    use idu_gimbal::Instant;
    use idu_gimbal_mavlink::attitude::YawPitch;
    use idu_gimbal_mavlink::framing::{Check, MAX_FRAME_LEN};
    use idu_gimbal_mavlink::{Bridge, BridgeConfig};
    use mavio::dialects::common::enums::{
        EstimatorStatusFlags, GimbalDeviceFlags, MavAutopilot, MavLandedState, MavModeFlag,
        MavState, MavType,
    };
    use mavio::dialects::common::messages::{
        AutopilotStateForGimbalDevice, GimbalDeviceSetAttitude, GlobalPositionInt, Heartbeat,
    };
    use mavio::mavspec::rust::spec::MessageSpecStatic;
    use mavio::protocol::{Frame, V2};
    use mavio::Message;

    // Semihosting output and exit (its panic and HardFault handlers exit with status 1),
    // the instruction meter and the result table.
    use idu_firmware_support::meter::Meter;
    use idu_firmware_support::report::Table;
    use idu_firmware_support::{println, qemu};

    const GOAL_PER_BYTE: f32 = 60.0;

    /// One second of the autopilot's traffic.
    const SECOND: usize = 50 * 64 + 50 * 64 + 6 * 64;

    fn push(out: &mut heapless::Vec<u8, SECOND>, seq: &mut u8, m: &dyn Message) {
        let Ok(b) = Frame::builder()
            .version(V2)
            .sequence(*seq)
            .system_id(1)
            .component_id(1)
            .message(m)
        else {
            qemu::exit(false)
        };
        *seq = seq.wrapping_add(1);
        let mut buf = [0u8; MAX_FRAME_LEN];
        let Ok(n) = b.build().serialize(&mut buf) else {
            qemu::exit(false)
        };
        if out.extend_from_slice(&buf[..n]).is_err() {
            println!("traffic buffer too small");
            qemu::exit(false);
        }
    }

    /// ArduPilot's angle setpoint (earth frame) for yaw and pitch in degrees.
    fn set_attitude(yaw_deg: f32, pitch_deg: f32) -> GimbalDeviceSetAttitude {
        GimbalDeviceSetAttitude {
            target_system: 1,
            target_component: 154,
            // ArduPilot's earth frame (AP_Mount_Gremsy.cpp: all three locks).
            flags: GimbalDeviceFlags::ROLL_LOCK
                | GimbalDeviceFlags::PITCH_LOCK
                | GimbalDeviceFlags::YAW_LOCK,
            q: YawPitch {
                yaw_rad: yaw_deg.to_radians(),
                pitch_rad: pitch_deg.to_radians(),
            }
            .to_quaternion(),
            angular_velocity_x: f32::NAN,
            angular_velocity_y: f32::NAN,
            angular_velocity_z: f32::NAN,
        }
    }

    fn traffic() -> heapless::Vec<u8, SECOND> {
        let mut out = heapless::Vec::new();
        let mut seq = 0;
        push(
            &mut out,
            &mut seq,
            &Heartbeat {
                type_: MavType::Quadrotor,
                autopilot: MavAutopilot::Ardupilotmega,
                base_mode: MavModeFlag::empty(),
                custom_mode: 0,
                system_status: MavState::Active,
                mavlink_version: 3,
            },
        );
        for i in 0..50u32 {
            if i % 10 == 0 {
                push(
                    &mut out,
                    &mut seq,
                    &GlobalPositionInt {
                        time_boot_ms: i * 20,
                        lat: 473_977_420 + i as i32,
                        lon: 85_455_940,
                        alt: 488_000,
                        relative_alt: 38_000,
                        vx: 120,
                        vy: 0,
                        vz: 0,
                        hdg: 3000,
                    },
                );
            }
            push(
                &mut out,
                &mut seq,
                &AutopilotStateForGimbalDevice {
                    target_system: 1,
                    target_component: 154,
                    time_boot_us: u64::from(i) * 20_000,
                    q: YawPitch {
                        yaw_rad: 0.5,
                        pitch_rad: 0.02,
                    }
                    .to_quaternion(),
                    q_estimated_delay_us: 0,
                    vx: 1.0,
                    vy: 0.0,
                    vz: 0.0,
                    v_estimated_delay_us: 0,
                    feed_forward_angular_velocity_z: 0.0,
                    // ArduPilot's nav filter status, its low bits (attitude, velocity and
                    // position estimates good), and its earth yaw rate.
                    estimator_status: EstimatorStatusFlags::from_bits_truncate(0x037F),
                    landed_state: MavLandedState::Undefined,
                    angular_velocity_z: 0.0123,
                },
            );
            // A target moving 2.5°/s in yaw at 50 Hz: 0.05° a setpoint.
            push(
                &mut out,
                &mut seq,
                &set_attitude(20.0 + i as f32 * 0.05, -30.0),
            );
        }
        out
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let Some(core) = cortex_m::Peripherals::take() else {
            qemu::exit(false)
        };
        let mut m = Meter::new(core.SYST);
        let mut table = Table::new();
        println!(
            "qemu_bench_mavlink: {:.3} instructions per SysTick tick (calibrated), loop overhead {:.1} per iteration",
            m.instructions_per_tick(),
            m.loop_overhead()
        );
        let bytes = traffic();
        let mut bridge = Bridge::new(Link::new(Config::default()), BridgeConfig::default());
        let drain = |b: &mut Bridge<Link>| {
            let link = b.gimbal_mut();
            while link.next_transmit().is_some() {
                link.transmit_done(None);
            }
            let n = b.transmit_bytes().len();
            b.transmit_written(n);
        };
        // One second of traffic at a time, from 8-byte reads as a UART ring would give.
        let mut t = 0u32;
        let per_second = m.per_op(8, |_| {
            t = t.wrapping_add(1000);
            for chunk in bytes.chunks(8) {
                bridge.receive(black_box(chunk), Instant::from_millis(t));
            }
            drain(&mut bridge);
        });
        let s = bridge.stats();
        if s.reader.bad_frames != 0 || s.angle_commands == 0 {
            println!("bench: unexpected stats {:?}", s.reader);
            qemu::exit(false);
        }
        let per_byte = per_second / bytes.len() as f32;
        table.budget(
            "bridge: per received byte (an ArduPilot second: 50 Hz state and setpoints, 5 Hz position)",
            per_byte,
            "",
            GOAL_PER_BYTE,
        );
        table.add("bridge: bytes in that second", bytes.len() as f32, "B");
        // Where it goes: finding frames (each byte checksummed as it is copied in), then
        // also decoding the handled ones (CRC_EXTRA, mavio's payload decoding); and, for
        // comparison, mavio's own frame parse and checksum, the path the bridge took before
        // (see the `framing` module docs).
        let extra = <AutopilotStateForGimbalDevice as MessageSpecStatic>::crc_extra();
        let mut reader = idu_gimbal_mavlink::framing::FrameReader::new();
        let framing = m.per_op(8, |_| {
            for chunk in bytes.chunks(8) {
                reader.feed(black_box(chunk), |f| {
                    black_box(f.message_id());
                    Check::Unhandled
                });
            }
        });
        table.add(
            "  of which finding frames and checksumming them, per byte",
            framing / bytes.len() as f32,
            "",
        );
        let decoded = m.per_op(8, |_| {
            for chunk in bytes.chunks(8) {
                reader.feed(black_box(chunk), |f| {
                    match f.message_id() {
                        id if id == GimbalDeviceSetAttitude::message_id() => {
                            black_box(f.decode::<GimbalDeviceSetAttitude>().is_ok());
                        }
                        id if id == AutopilotStateForGimbalDevice::message_id() => {
                            black_box(f.decode::<AutopilotStateForGimbalDevice>().is_ok());
                        }
                        _ => {}
                    }
                    Check::Unhandled
                });
            }
        });
        table.add(
            "  of which decoding (CRC_EXTRA, mavio's payload decoding), per byte",
            (decoded - framing) / bytes.len() as f32,
            "",
        );
        let mavio = m.per_op(8, |_| {
            for chunk in bytes.chunks(8) {
                reader.feed(black_box(chunk), |f| {
                    if let Some(frame) = f.to_frame() {
                        black_box(frame.validate_checksum_with_crc_extra(extra).is_ok());
                    }
                    Check::Unhandled
                });
            }
        });
        table.add(
            "  (were frames parsed and checked by mavio: that much more per byte)",
            (mavio - framing) / bytes.len() as f32,
            "",
        );

        // Latency: the call that takes a SET_ATTITUDE's last byte.
        let mut frame = heapless::Vec::<u8, SECOND>::new();
        let mut seq = 0;
        let mut total = 0.0;
        const N: u32 = 64;
        for i in 0..N {
            frame.clear();
            // A new angle each time (1.5° and 0.5° apart): each re-commands the gimbal.
            let k = (100 + i) as f32;
            push(
                &mut frame,
                &mut seq,
                &set_attitude(k * 1.5, -k * 0.5 % 90.0),
            );
            let (head, last) = frame.split_at(frame.len() - 1);
            let now = Instant::from_millis(t + i);
            bridge.receive(head, now);
            total += m.once(|| bridge.receive(black_box(last), now));
            drain(&mut bridge);
        }
        let latency = total / N as f32;
        table.add(
            "bridge: SET_ATTITUDE's last byte -> heading and pitch queued for CAN",
            latency,
            "",
        );
        table.add("  the same at 168 MHz", latency / 168.0, "us");

        let now = Instant::from_millis(t + 10_000);
        bridge.poll(now);
        drain(&mut bridge);
        let idle = m.per_op(256, |_| bridge.poll(black_box(now)));
        table.add("bridge: idle poll (nothing due)", idle, "");
        let mut u = t + 20_000;
        let status = m.per_op(32, |_| {
            u = u.wrapping_add(100);
            bridge.poll(Instant::from_millis(u));
            drain(&mut bridge);
        });
        table.add(
            "bridge: poll sending the attitude status (10 Hz)",
            status,
            "",
        );
        table.add(
            "size_of Bridge<Link> with the default queues (RAM, bytes)",
            core::mem::size_of::<Bridge<Link>>() as f32,
            "B",
        );

        println!();
        let ok = table.print();
        println!();
        qemu::exit(ok)
    }
}
