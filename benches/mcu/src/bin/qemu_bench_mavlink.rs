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
//!   it and queues its heading and pitch commands in the CAN driver's queue (checked: every
//!   one of them queued, none refused); in instructions and in microseconds at 168 MHz (one
//!   instruction a cycle, a lower bound).
//! - An idle `Bridge::poll`, and one that sends the attitude status.
//! - **Beside the C MAVLink library** (built when `scripts/bench.sh` has generated it with
//!   pymavlink's `mavgen`; see `build.rs` and `c/mavlink_c.c`), in the same run on the same
//!   bytes: receiving (`mavlink_parse_char` and each message's `mavlink_msg_*_decode`, per
//!   byte of the second and per message of each kind, against the whole bridge: framing,
//!   checksum, decoding and acting) and sending (`mavlink_msg_*_pack` and
//!   `mavlink_msg_to_send_buffer` against the poll that sends the attitude status, and the
//!   bridge's send path for the heartbeat and the tracking status). Before any number is
//!   trusted, both sides are checked on the same bytes: the messages counted per id, no
//!   frame dropped, the last message of each kind decoded alike, and every frame the bridge
//!   sends parsed by the C library with its checksum good and, for the same fields and
//!   sequence number, byte for byte what the C library serializes. Goals, enforced: receive
//!   at most 0.55 of the C library's cost a byte, each send at most its cost.
//!
//! Exit status 0 unless the run failed (the traffic not parsed as expected, a check between
//! the two sides, or a goal).
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

    /// The frames in that second.
    const FRAMES_A_SECOND: u32 = 1 + 50 + 50 + 5;

    /// One second of the autopilot's traffic.
    const SECOND: usize = 50 * 64 + 50 * 64 + 6 * 64;

    /// Where the traffic comes from and goes: the autopilot (1) to the gimbal (154), or, for
    /// the receive path without acting, another component to another gimbal.
    #[derive(Clone, Copy)]
    struct Route {
        from: u8,
        to: u8,
    }

    const TO_THE_GIMBAL: Route = Route { from: 1, to: 154 };
    const ELSEWHERE: Route = Route { from: 2, to: 155 };

    fn push(out: &mut heapless::Vec<u8, SECOND>, seq: &mut u8, route: Route, m: &dyn Message) {
        let Ok(b) = Frame::builder()
            .version(V2)
            .sequence(*seq)
            .system_id(1)
            .component_id(route.from)
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
    fn set_attitude(to: u8, yaw_deg: f32, pitch_deg: f32) -> GimbalDeviceSetAttitude {
        GimbalDeviceSetAttitude {
            target_system: 1,
            target_component: to,
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

    fn traffic(route: Route) -> heapless::Vec<u8, SECOND> {
        let mut out = heapless::Vec::new();
        let mut seq = 0;
        push(
            &mut out,
            &mut seq,
            route,
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
                    route,
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
                route,
                &AutopilotStateForGimbalDevice {
                    target_system: 1,
                    target_component: route.to,
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
                route,
                &set_attitude(route.to, 20.0 + i as f32 * 0.05, -30.0),
            );
        }
        out
    }

    /// The C MAVLink library's side (`c/mavlink_c.h`), behind safe calls.
    #[cfg(mavlink_c)]
    mod c {
        /// `c_seen_t`.
        #[repr(C)]
        #[derive(Clone, Copy, Debug)]
        pub struct Seen {
            pub heartbeats: u32,
            pub setpoints: u32,
            pub states: u32,
            pub positions: u32,
            pub others: u32,
            pub dropped: u32,
            pub setpoint_q: [f32; 4],
            pub setpoint_flags: u16,
            pub setpoint_target_component: u8,
            pub state_q: [f32; 4],
            pub state_angular_velocity_z: f32,
            pub state_landed_state: u8,
            pub lat: i32,
            pub lon: i32,
            pub alt: i32,
        }

        /// `c_status_t`.
        #[repr(C)]
        pub struct Status {
            pub time_boot_ms: u32,
            pub q: [f32; 4],
            pub angular_velocity_x: f32,
            pub angular_velocity_y: f32,
            pub angular_velocity_z: f32,
            pub failure_flags: u32,
            pub delta_yaw: f32,
            pub delta_yaw_velocity: f32,
            pub flags: u16,
            pub target_system: u8,
            pub target_component: u8,
            pub gimbal_device_id: u8,
        }

        mod ffi {
            extern "C" {
                pub fn c_reset();
                pub fn c_receive(bytes: *const u8, len: u32);
                pub fn c_seen() -> *const super::Seen;
                pub fn c_send_status(
                    out: *mut u8,
                    seq: u8,
                    system: u8,
                    component: u8,
                    s: *const super::Status,
                ) -> u32;
                pub fn c_send_heartbeat(
                    out: *mut u8,
                    seq: u8,
                    system: u8,
                    component: u8,
                    type_: u8,
                ) -> u32;
                pub fn c_send_tracking_status(
                    out: *mut u8,
                    seq: u8,
                    system: u8,
                    component: u8,
                    tracking_status: u8,
                    tracking_mode: u8,
                ) -> u32;
            }
        }

        /// The longest frame the C library writes (MAVLINK_NUM_NON_PAYLOAD_BYTES + 255 +
        /// the signature).
        pub const FRAME: usize = 280;

        pub fn reset() {
            // SAFETY: no arguments; the library's state is its own statics.
            unsafe { ffi::c_reset() }
        }

        pub fn receive(bytes: &[u8]) {
            // SAFETY: the library reads `len` bytes from `bytes`, which holds them.
            unsafe { ffi::c_receive(bytes.as_ptr(), bytes.len() as u32) }
        }

        pub fn seen() -> Seen {
            // SAFETY: c_seen returns the address of its static, valid for the program.
            unsafe { *ffi::c_seen() }
        }

        pub fn send_status(out: &mut [u8; FRAME], seq: u8, s: &Status) -> usize {
            // SAFETY: `out` holds the longest frame the library writes; `s` is a live
            // c_status_t.
            unsafe { ffi::c_send_status(out.as_mut_ptr(), seq, 1, 154, s) as usize }
        }

        pub fn send_heartbeat(out: &mut [u8; FRAME], seq: u8, type_: u8) -> usize {
            // SAFETY: as send_status.
            unsafe { ffi::c_send_heartbeat(out.as_mut_ptr(), seq, 1, 154, type_) as usize }
        }

        pub fn send_tracking_status(out: &mut [u8; FRAME], seq: u8, status: u8, mode: u8) -> usize {
            // SAFETY: as send_status.
            unsafe {
                ffi::c_send_tracking_status(out.as_mut_ptr(), seq, 1, 100, status, mode) as usize
            }
        }
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut m = Meter::start("qemu_bench_mavlink");
        let mut table = Table::new();
        let bytes = traffic(TO_THE_GIMBAL);
        let elsewhere = traffic(ELSEWHERE);
        let mut bridge = Fw::new(BridgeConfig::default());
        let drain = |b: &mut Fw| {
            let link = &mut b.link;
            while link.next_transmit().is_some() {
                link.transmit_done(None);
            }
            let n = b.transmit_bytes().len();
            b.transmit_written(n);
        };
        // One second of traffic at a time, from 8-byte reads as a UART ring would give.
        let mut t = 0u32;
        // The bridge's receive path short of acting: the same second addressed to another
        // gimbal from another component, so that every frame is found, checksummed with its
        // message's CRC_EXTRA, dispatched and decoded, then left (counted as not for us; the
        // heartbeat, of a component that is no autopilot, ignored).
        // The same work as the C library's parse and decode.
        let before = bridge.stats();
        // Every byte is taken at once (the outbox never runs short here): summed, checked
        // after the timed runs.
        let mut taken = 0usize;
        let mut given = 0usize;
        let decoded = m.per_op(8, |_| {
            t = t.wrapping_add(1000);
            for chunk in elsewhere.chunks(8) {
                taken += bridge.receive(black_box(chunk), Instant::from_millis(t));
            }
            given += elsewhere.len();
            drain(&mut bridge);
        });
        let after = bridge.stats();
        let runs = (after.reader.frames - before.reader.frames) / FRAMES_A_SECOND;
        if after.reader.bad_frames != 0
            || runs == 0
            || after.reader.frames - before.reader.frames != runs * FRAMES_A_SECOND
            // The states and setpoints addressed elsewhere, and the positions (broadcast)
            // from a component that is not the autopilot's.
            || after.not_for_us - before.not_for_us != runs * (50 + 50 + 5)
            || after.angle_setpoints != before.angle_setpoints
            || after.vehicle_updates != before.vehicle_updates
        {
            println!("bench: the receive path without acting was not what it should be");
            qemu::exit(false);
        }
        let per_second = m.per_op(8, |_| {
            t = t.wrapping_add(1000);
            for chunk in bytes.chunks(8) {
                taken += bridge.receive(black_box(chunk), Instant::from_millis(t));
            }
            given += bytes.len();
            drain(&mut bridge);
        });
        if taken != given {
            println!("bench: a frame waited for room in the outbox");
            qemu::exit(false);
        }
        // Every timed second was read whole: its 106 frames each time (1 heartbeat, 50
        // states, 50 setpoints, 5 positions), none bad, the setpoints acted on.
        let s = bridge.stats();
        if s.reader.bad_frames != 0
            || s.reader.frames == 0
            || !s.reader.frames.is_multiple_of(FRAMES_A_SECOND)
            || s.angle_setpoints == 0
            || s.vehicle_updates == 0
        {
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
        let decoded_per_byte = decoded / elsewhere.len() as f32;
        table.add(
            "  of which dispatching and decoding (CRC_EXTRA, the codecs), per byte",
            decoded_per_byte - framing / bytes.len() as f32,
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

        // Latency: the call that takes a SET_ATTITUDE's last byte (the vehicle's state fresh
        // from the second just fed, so that the earth-frame setpoints convert).
        let before_latency = bridge.stats();
        let sent_before = bridge.link.stats().frames_sent;
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
                TO_THE_GIMBAL,
                &set_attitude(154, k * 1.5, -k * 0.5 % 90.0),
            );
            let (head, last) = frame.split_at(frame.len() - 1);
            let now = Instant::from_millis(t + i);
            let head_taken = bridge.receive(head, now);
            let mut last_taken = 0;
            total += m.once(|| last_taken = bridge.receive(black_box(last), now));
            if head_taken + last_taken != frame.len() {
                println!("bench: a setpoint waited for room in the outbox");
                qemu::exit(false);
            }
            drain(&mut bridge);
        }
        // Every setpoint was followed: taken as the aim, its heading and pitch commands
        // queued and sent, none refused.
        let after = bridge.stats();
        let sent = bridge.link.stats().frames_sent - sent_before;
        if after.refused_setpoints != before_latency.refused_setpoints
            || after.angle_setpoints - before_latency.angle_setpoints != N
            || sent < 2 * N
        {
            println!("bench: the latency's setpoints were not all followed");
            qemu::exit(false);
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
            "size_of Bridge (RAM, bytes)",
            core::mem::size_of::<Bridge>() as f32,
            "B",
        );

        println!();
        let mut ok = table.print();
        println!();
        #[cfg(mavlink_c)]
        {
            ok &= versus_c(
                &mut m,
                (&bytes, &elsewhere),
                &mut bridge,
                &drain,
                (decoded_per_byte, per_byte),
                status,
                u,
            );
        }
        #[cfg(not(mavlink_c))]
        {
            let _ = (decoded_per_byte, u);
            println!(
                "built without the C MAVLink library (IDU_MAVLINK_C_INCLUDE): run scripts/bench.sh for the comparison"
            );
            ok &= false;
        }
        println!();
        qemu::exit(ok)
    }

    /// Says `what` failed and returns false.
    #[cfg(mavlink_c)]
    fn failed(what: &str) -> bool {
        println!("  FAIL {}", what);
        false
    }

    /// The C MAVLink library beside the bridge on the same bytes (see the module docs):
    /// the checks, then the comparison table. Whether every check and goal held.
    #[cfg(mavlink_c)]
    fn versus_c(
        m: &mut Meter,
        (bytes, elsewhere): (&[u8], &[u8]),
        bridge: &mut Fw,
        drain: &dyn Fn(&mut Fw),
        (decoded_per_byte, bridge_per_byte): (f32, f32),
        bridge_status_poll: f32,
        mut ms: u32,
    ) -> bool {
        use idu_firmware_support::report::Comparison;
        use idu_gimbal_mavlink::codec;
        use idu_gimbal_mavlink::framing::{FrameReader, Outbox};
        use mavio::dialects::common::enums::{
            CameraTrackingMode, CameraTrackingStatusFlags, CameraTrackingTargetData,
            GimbalDeviceErrorFlags,
        };
        use mavio::dialects::common::messages::{
            CameraTrackingImageStatus, GimbalDeviceAttitudeStatus,
        };

        let mut ok = true;
        println!("Beside the C MAVLink library (pymavlink mavgen, C, MAVLink 2, common; arm-none-eabi-gcc -O2):");

        // The checks on the traffic: the C library's parse and decode against the bridge's
        // frame reader and codecs, message by message.
        c::reset();
        c::receive(bytes);
        let seen = c::seen();
        let ids = [
            Heartbeat::message_id(),
            GimbalDeviceSetAttitude::message_id(),
            AutopilotStateForGimbalDevice::message_id(),
            GlobalPositionInt::message_id(),
        ];
        let crcs = [
            Heartbeat::crc_extra(),
            GimbalDeviceSetAttitude::crc_extra(),
            AutopilotStateForGimbalDevice::crc_extra(),
            GlobalPositionInt::crc_extra(),
        ];
        let mut counts = [0u32; 4];
        let mut others = 0u32;
        let mut bad = 0u32;
        let mut kinds: [heapless::Vec<u8, SECOND>; 4] = Default::default();
        let mut last_set = None;
        let mut last_state = None;
        let mut last_position = None;
        let mut reader = FrameReader::new();
        reader.feed(bytes, |f| {
            let Some(k) = ids.iter().position(|&id| id == f.message_id()) else {
                others += 1;
                return Check::Unhandled;
            };
            if !f.checksum_holds(crcs[k]) {
                bad += 1;
                return Check::Bad;
            }
            counts[k] += 1;
            let _ = kinds[k].extend_from_slice(f.bytes());
            match k {
                1 => last_set = Some(codec::set_attitude::decode(f.payload())),
                2 => last_state = codec::autopilot_state::decode(f.payload()),
                3 => last_position = Some(codec::global_position::decode(f.payload())),
                _ => {}
            }
            Check::Handled
        });
        let c_counts = [seen.heartbeats, seen.setpoints, seen.states, seen.positions];
        if counts != c_counts || counts != [1, 50, 50, 5] || others != 0 || seen.others != 0 {
            ok = failed("messages per id differ (heartbeat, setpoint, state, position)");
            println!("       bridge {:?}, C library {:?}", counts, c_counts);
        }
        if bad != 0 || seen.dropped != 0 {
            ok = failed("a checksum failed");
        }
        let bits = |q: [f32; 4]| q.map(f32::to_bits);
        let same_set = last_set.is_some_and(|s| {
            bits(s.q) == bits(seen.setpoint_q)
                && s.flags.bits() == seen.setpoint_flags
                && s.target_component == seen.setpoint_target_component
        });
        let same_state = last_state.is_some_and(|s| {
            bits(s.q) == bits(seen.state_q)
                && s.angular_velocity_z.to_bits() == seen.state_angular_velocity_z.to_bits()
                && s.landed_state as u8 == seen.state_landed_state
        });
        let same_position =
            last_position.is_some_and(|p| (p.lat, p.lon, p.alt) == (seen.lat, seen.lon, seen.alt));
        if !(same_set && same_state && same_position) {
            ok = failed("the last message of a kind decoded differently");
        }

        let mut cmp = Comparison::new("C MAVLink library", "bridge");
        // Receiving: the second of traffic in 8-byte reads on both sides.
        c::reset();
        let c_second = m.per_op(8, |_| {
            for chunk in bytes.chunks(8) {
                c::receive(black_box(chunk));
            }
        });
        let after = c::seen();
        if after.dropped != 0
            || after.setpoints == 0
            || after.setpoints != after.states
            || after.setpoints != 50 * after.heartbeats
            || after.setpoints != 10 * after.positions
        {
            ok = failed("the C library's timed runs did not decode every message");
        }
        let c_per_byte = c_second / bytes.len() as f32;
        // The same second addressed elsewhere, the bytes the bridge's path short of acting
        // was measured on: the C library parses and decodes them alike.
        c::reset();
        let c_elsewhere = m.per_op(8, |_| {
            for chunk in elsewhere.chunks(8) {
                c::receive(black_box(chunk));
            }
        });
        let c_after = c::seen();
        if c_after.dropped != 0 || c_after.setpoints == 0 || c_after.setpoints != c_after.states {
            ok = failed("the C library's timed runs on the second addressed elsewhere");
        }
        cmp.row(
            "receive, per byte of the second: frames found, checksummed, dispatched, decoded",
            c_elsewhere / elsewhere.len() as f32,
            decoded_per_byte,
            // Half, until the bridge answered every request exactly once under any burst:
            // the room a frame's answer needs, looked at per frame, and the reader keeping a
            // frame back cost about 2 instructions a byte (BENCHMARKS.md).
            0.55,
        );
        cmp.row(
            "  the whole bridge, acting included (C: the same parse and decode)",
            c_per_byte,
            bridge_per_byte,
            1.0,
        );
        // Each kind alone: its frames of the second, per frame.
        let names = [
            "  per HEARTBEAT",
            "  per GIMBAL_DEVICE_SET_ATTITUDE",
            "  per AUTOPILOT_STATE_FOR_GIMBAL_DEVICE",
            "  per GLOBAL_POSITION_INT",
        ];
        for (k, kind) in kinds.iter().enumerate() {
            let n = counts[k].max(1) as f32;
            let c_cost = m.per_op(4, |_| c::receive(black_box(kind))) / n;
            let now = Instant::from_millis(ms);
            let mut short = false;
            let ours = m.per_op(4, |_| {
                short |= bridge.receive(black_box(kind), now) != kind.len();
                drain(bridge);
            }) / n;
            if short {
                println!("bench: a message waited for room in the outbox");
                qemu::exit(false);
            }
            cmp.info(names[k], c_cost, ours);
        }
        if c::seen().dropped != 0 || bridge.stats().reader.bad_frames != 0 {
            ok = failed("a frame was dropped while measuring each kind");
        }

        // Sending. The same status on both sides, sequence number 0: byte for byte alike.
        let status = GimbalDeviceAttitudeStatus {
            target_system: 0,
            target_component: 0,
            time_boot_ms: 123_456,
            flags: GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME | GimbalDeviceFlags::YAW_LOCK,
            q: YawPitch {
                yaw_rad: 0.3,
                pitch_rad: -0.5,
            }
            .to_quaternion(),
            angular_velocity_x: f32::NAN,
            angular_velocity_y: f32::NAN,
            angular_velocity_z: f32::NAN,
            failure_flags: GimbalDeviceErrorFlags::empty(),
            delta_yaw: 0.52,
            delta_yaw_velocity: 0.0123,
            gimbal_device_id: 0,
        };
        let c_status = c::Status {
            time_boot_ms: status.time_boot_ms,
            q: status.q,
            angular_velocity_x: status.angular_velocity_x,
            angular_velocity_y: status.angular_velocity_y,
            angular_velocity_z: status.angular_velocity_z,
            failure_flags: u32::from(status.failure_flags.bits()),
            delta_yaw: status.delta_yaw,
            delta_yaw_velocity: status.delta_yaw_velocity,
            flags: status.flags.bits(),
            target_system: status.target_system,
            target_component: status.target_component,
            gimbal_device_id: status.gimbal_device_id,
        };
        let mut c_frame = [0u8; c::FRAME];
        let mut out = Outbox::<512>::new();
        let same = |out: &Outbox<512>, c_frame: &[u8]| out.bytes() == c_frame;
        let n = c::send_status(&mut c_frame, 0, &c_status);
        let _ = out.push_with(
            1,
            154,
            GimbalDeviceAttitudeStatus::message_id(),
            GimbalDeviceAttitudeStatus::crc_extra(),
            codec::attitude_status::LEN,
            |p| codec::attitude_status::encode(&status, p),
        );
        if !same(&out, &c_frame[..n]) {
            ok = failed("GIMBAL_DEVICE_ATTITUDE_STATUS serialized differently");
        }
        let c_status_cost = m.per_op(32, |_| {
            black_box(c::send_status(&mut c_frame, 0, black_box(&c_status)));
        });
        // The bridge's own status frames, as it sent them in a poll, through the C parser.
        drain(bridge);
        ms = ms.wrapping_add(1_000);
        bridge.poll(Instant::from_millis(ms));
        c::reset();
        c::receive(bridge.transmit_bytes());
        let polled = c::seen();
        if polled.others == 0 || polled.dropped != 0 {
            ok = failed("the C library did not take the bridge's status poll");
        }
        drain(bridge);
        cmp.row(
            "send GIMBAL_DEVICE_ATTITUDE_STATUS (C: pack + to_send_buffer; bridge: the whole poll)",
            c_status_cost,
            bridge_status_poll,
            1.0,
        );

        // The gimbal device's, as the bridge builds it.
        let hb = codec::heartbeat::of_component(MavType::Gimbal);
        let hb_id = (Heartbeat::message_id(), Heartbeat::crc_extra());
        out.written(usize::MAX);
        let n = c::send_heartbeat(&mut c_frame, 0, MavType::Gimbal as u8);
        let mut out = Outbox::<512>::new();
        let _ = out.push_with(1, 154, hb_id.0, hb_id.1, codec::heartbeat::LEN, |p| {
            codec::heartbeat::encode(&hb, p)
        });
        if !same(&out, &c_frame[..n]) {
            ok = failed("HEARTBEAT serialized differently");
        }
        let c_hb = m.per_op(32, |_| {
            black_box(c::send_heartbeat(
                &mut c_frame,
                0,
                black_box(MavType::Gimbal as u8),
            ));
        });
        let ours_hb = m.per_op(32, |_| {
            let _ = out.push_with(1, 154, hb_id.0, hb_id.1, codec::heartbeat::LEN, |p| {
                codec::heartbeat::encode(black_box(&hb), p)
            });
            out.written(usize::MAX);
        });
        cmp.row(
            "send HEARTBEAT (C: pack + to_send_buffer; bridge: encode + queue)",
            c_hb,
            ours_hb,
            1.0,
        );

        let tracking = CameraTrackingImageStatus {
            tracking_status: CameraTrackingStatusFlags::Active,
            tracking_mode: CameraTrackingMode::Rectangle,
            target_data: CameraTrackingTargetData::empty(),
            point_x: f32::NAN,
            point_y: f32::NAN,
            radius: f32::NAN,
            rec_top_x: f32::NAN,
            rec_top_y: f32::NAN,
            rec_bottom_x: f32::NAN,
            rec_bottom_y: f32::NAN,
            camera_device_id: 0,
        };
        let tr_id = (
            CameraTrackingImageStatus::message_id(),
            CameraTrackingImageStatus::crc_extra(),
        );
        let len = codec::tracking_image_status::LEN;
        let mut out = Outbox::<512>::new();
        let n = c::send_tracking_status(&mut c_frame, 0, 1, 2);
        let _ = out.push_with(1, 100, tr_id.0, tr_id.1, len, |p| {
            codec::tracking_image_status::encode(&tracking, p)
        });
        if !same(&out, &c_frame[..n]) {
            ok = failed("CAMERA_TRACKING_IMAGE_STATUS serialized differently");
        }
        let c_tr = m.per_op(32, |_| {
            black_box(c::send_tracking_status(&mut c_frame, 0, black_box(1), 2));
        });
        let ours_tr = m.per_op(32, |_| {
            let _ = out.push_with(1, 100, tr_id.0, tr_id.1, len, |p| {
                codec::tracking_image_status::encode(black_box(&tracking), p)
            });
            out.written(usize::MAX);
        });
        cmp.row(
            "send CAMERA_TRACKING_IMAGE_STATUS (C: pack + to_send_buffer; bridge: encode + queue)",
            c_tr,
            ours_tr,
            1.0,
        );

        println!(
            "  checks: messages per id (1, 50, 50, 5) alike, no checksum failed, the last of each kind decoded alike, each frame sent byte for byte the C library's: {}",
            if ok { "ok" } else { "FAILED" }
        );
        println!();
        ok & cmp.print()
    }
}
