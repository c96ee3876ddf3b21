//! The MAVLink bridge on an emulated STM32F405 (QEMU `netduinoplus2`): a scripted autopilot
//! inside the firmware drives the bridge, which drives the simulated gimbal.
//!
//! - The autopilot and the bridge talk MAVLink 2 over the crate's in-memory serial line
//!   (`mock::serial::Pipe`), as they would over a UART.
//! - The bridge drives the firmware's link, whose CAN port (`CanPort` over the in-memory CAN
//!   bus, `mock::Bus`) reaches the simulated gimbal (`sim::Simulator`) on the other end.
//! - The autopilot behaves as ArduPilot does: heartbeats at 1 Hz, its state at 50 Hz, the
//!   gimbal's information asked for every second until it comes, setpoints at 20 Hz.
//!
//! Steps: information; an earth-frame setpoint; a setpoint with flags 0 pitching to −100°;
//! a rate held then dropped (the core's dead-man stops the gimbal); a photo; tracking a
//! rectangle (the gimbal turns toward it, `CAMERA_TRACKING_IMAGE_STATUS` says it tracks)
//! and stopping it; the thermal palette set through the extended parameters of the dual
//! light's camera definition; and, all along, an attitude status never more than a second
//! old. Time is simulated, 1 ms a loop, so the
//! run is the same on every machine. Exit status (semihosting): 0 only if every step's
//! effect was seen.
//!
//! ```sh
//! cargo run --release --bin qemu_mavlink   # in boards/stm32f405_qemu
//! ```
#![no_std]
#![no_main]

// The STM32F405's interrupt vector table (cortex-m-rt's `device` feature requires one).
use stm32f4xx_hal as _;

mod fw {
    use embedded_io::{Read, Write};
    use idu_gimbal::mock::serial::{Pipe, Rx, Tx};
    use idu_gimbal::mock::Bus;
    use idu_gimbal::sim::SimConfig;
    use idu_gimbal::video::{Camera, Family};
    use idu_gimbal::wire::control::Palette;
    use idu_gimbal::wire::postback::GimbalType;
    use idu_gimbal::{Config, Instant, Link, Port};
    use idu_gimbal_mavlink::attitude::YawPitch;
    use idu_gimbal_mavlink::camera::CameraConfig;
    use idu_gimbal_mavlink::framing::{Check, FrameReader, MAX_FRAME_LEN};
    use idu_gimbal_mavlink::{Bridge, BridgeConfig, SerialInput};
    use mavio::dialects::common::enums::{
        CameraTrackingStatusFlags, EstimatorStatusFlags, GimbalDeviceFlags, MavAutopilot, MavCmd,
        MavLandedState, MavModeFlag, MavParamExtType, MavResult, MavState, MavType, ParamAck,
    };
    use mavio::dialects::common::messages::{
        AutopilotStateForGimbalDevice, CameraTrackingImageStatus, CommandAck, CommandLong,
        GimbalDeviceAttitudeStatus, GimbalDeviceInformation, GimbalDeviceSetAttitude, Heartbeat,
        ParamExtAck, ParamExtSet,
    };
    use mavio::protocol::{Frame, V2};
    use mavio::Message;

    // Semihosting output and exit (its panic and HardFault handlers exit with status 1).
    use idu_firmware_support::session::{CanRig, DemoBus, Rig};
    use idu_firmware_support::{println, qemu};

    type Line<'a> = (Rx<'a, 512>, Tx<'a, 512>);

    /// What the autopilot has seen from the bridge.
    #[derive(Default)]
    struct Seen {
        acks: [Option<MavResult>; 8],
        info: bool,
        /// The earth-frame yaw (the status's yaw plus delta_yaw) and pitch of the latest
        /// status, degrees, and whether it was in the vehicle frame.
        status: Option<(f32, f32, bool)>,
        last_status: Option<u32>,
        worst_gap: u32,
        /// The latest CAMERA_TRACKING_IMAGE_STATUS said the camera tracks.
        tracking: Option<bool>,
        /// The latest PARAM_EXT_ACK: its result and value.
        param_ack: Option<(ParamAck, u8)>,
    }

    struct Autopilot<'a> {
        line: Line<'a>,
        reader: FrameReader,
        seq: u8,
        seen: Seen,
    }

    const AP: (u8, u8) = (1, 1);

    impl Autopilot<'_> {
        fn send(&mut self, m: &dyn Message) {
            let Ok(b) = Frame::builder()
                .version(V2)
                .sequence(self.seq)
                .system_id(AP.0)
                .component_id(AP.1)
                .message(m)
            else {
                return;
            };
            self.seq = self.seq.wrapping_add(1);
            let mut buf = [0u8; MAX_FRAME_LEN];
            if let Ok(n) = b.build().serialize(&mut buf) {
                let _ = self.line.1.write(&buf[..n]);
            }
        }

        fn command(&mut self, target: u8, command: MavCmd, p: [f32; 3]) {
            self.command4(target, command, [p[0], p[1], p[2], 0.0]);
        }

        fn command4(&mut self, target: u8, command: MavCmd, p: [f32; 4]) {
            self.send(&CommandLong {
                target_system: AP.0,
                target_component: target,
                command,
                confirmation: 0,
                param1: p[0],
                param2: p[1],
                param3: p[2],
                param4: p[3],
                param5: 0.0,
                param6: 0.0,
                param7: 0.0,
            });
        }

        fn setpoint(&mut self, flags: GimbalDeviceFlags, yaw: f32, pitch: f32, yaw_rate: f32) {
            let q = if yaw_rate == 0.0 {
                YawPitch {
                    yaw_rad: yaw.to_radians(),
                    pitch_rad: pitch.to_radians(),
                }
                .to_quaternion()
            } else {
                [f32::NAN; 4]
            };
            self.send(&GimbalDeviceSetAttitude {
                target_system: AP.0,
                target_component: 154,
                flags,
                q,
                angular_velocity_x: f32::NAN,
                angular_velocity_y: if yaw_rate == 0.0 { f32::NAN } else { 0.0 },
                angular_velocity_z: if yaw_rate == 0.0 {
                    f32::NAN
                } else {
                    yaw_rate.to_radians()
                },
            });
        }

        /// Heartbeat at 1 Hz and the vehicle state (level, heading 30°) at 50 Hz.
        fn periodic(&mut self, ms: u32) {
            if ms.is_multiple_of(1000) {
                self.send(&Heartbeat {
                    type_: MavType::Quadrotor,
                    autopilot: MavAutopilot::Ardupilotmega,
                    base_mode: MavModeFlag::empty(),
                    custom_mode: 0,
                    system_status: MavState::Active,
                    mavlink_version: 3,
                });
            }
            if ms.is_multiple_of(20) {
                self.send(&AutopilotStateForGimbalDevice {
                    target_system: AP.0,
                    target_component: 154,
                    time_boot_us: u64::from(ms) * 1000,
                    q: YawPitch {
                        yaw_rad: 30f32.to_radians(),
                        pitch_rad: 0.0,
                    }
                    .to_quaternion(),
                    q_estimated_delay_us: 0,
                    vx: 0.0,
                    vy: 0.0,
                    vz: 0.0,
                    v_estimated_delay_us: 0,
                    feed_forward_angular_velocity_z: 0.0,
                    estimator_status: EstimatorStatusFlags::empty(),
                    landed_state: MavLandedState::InAir,
                    angular_velocity_z: 0.0,
                });
            }
        }

        /// Reads what the bridge sent.
        fn read(&mut self, ms: u32) {
            let mut buf = [0u8; 256];
            let Autopilot {
                line, reader, seen, ..
            } = self;
            while let Ok(n) = line.0.read(&mut buf) {
                if n == 0 {
                    break;
                }
                reader.feed(&buf[..n], |f| {
                    if let Ok(ack) = f.decode::<CommandAck>() {
                        let slot = seen.acks.iter_mut().find(|a| a.is_none());
                        if let Some(slot) = slot {
                            *slot = Some(ack.result);
                        }
                    } else if let Ok(t) = f.decode::<CameraTrackingImageStatus>() {
                        seen.tracking =
                            Some(t.tracking_status == CameraTrackingStatusFlags::Active);
                    } else if let Ok(a) = f.decode::<ParamExtAck>() {
                        seen.param_ack = Some((a.param_result, a.param_value[0]));
                    } else if f.decode::<GimbalDeviceInformation>().is_ok() {
                        seen.info = true;
                    } else if let Ok(s) = f.decode::<GimbalDeviceAttitudeStatus>() {
                        if let Some(last) = seen.last_status {
                            seen.worst_gap = seen.worst_gap.max(ms - last);
                        }
                        seen.last_status = Some(ms);
                        // As a ground station reads it: the vehicle-frame yaw plus
                        // delta_yaw, the vehicle's heading (common.xml: q_earth =
                        // q_delta_yaw * q_vehicle).
                        seen.status = YawPitch::from_quaternion(s.q).map(|a| {
                            (
                                (a.yaw_rad + s.delta_yaw).to_degrees(),
                                a.pitch_rad.to_degrees(),
                                s.flags.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME),
                            )
                        });
                    }
                    Check::Unhandled
                });
            }
        }
    }

    struct World<'a> {
        ap: Autopilot<'a>,
        bridge: Bridge,
        link: Link,
        /// The firmware's CAN port and the simulated gimbal on the other end of the bus.
        rig: CanRig<'a>,
        bridge_line: Line<'a>,
        /// Bytes read from the autopilot's line that the bridge has not taken yet.
        input: SerialInput<256>,
        ms: u32,
        failures: u32,
    }

    impl World<'_> {
        /// One millisecond of everyone.
        fn tick(&mut self) {
            let now = Instant::from_millis(self.ms);
            self.ap.periodic(self.ms);
            let line = &mut self.bridge_line.0;
            // The in-memory line has no errors to report.
            let _ = self
                .input
                .receive(&mut self.bridge, &mut self.link, now, |buf| line.read(buf));
            let _ = self.rig.port().poll(&mut self.link, now);
            self.bridge.poll(&mut self.link, now);
            loop {
                let bytes = self.bridge.transmit_bytes();
                if bytes.is_empty() {
                    break;
                }
                // What the pipe took (a fault-free one takes all); the rest at the next
                // millisecond.
                match self.bridge_line.1.write(bytes) {
                    Ok(n) if n > 0 => self.bridge.transmit_written(n),
                    _ => break,
                }
            }
            self.rig.run_gimbal(now);
            self.ap.read(self.ms);
            self.ms += 1;
        }

        /// Runs `each` every millisecond until `done`, at most `timeout_ms`.
        fn until(
            &mut self,
            what: &str,
            timeout_ms: u32,
            mut each: impl FnMut(&mut Self),
            done: impl Fn(&Self) -> bool,
        ) {
            for _ in 0..timeout_ms {
                each(self);
                self.tick();
                if done(self) {
                    println!("  ok   {} (t={} ms)", what, self.ms);
                    return;
                }
            }
            self.failures += 1;
            println!("  FAIL {}: not seen within {} ms", what, timeout_ms);
        }

        fn status_near(&self, yaw: f32, pitch: f32) -> bool {
            self.ap.seen.status.is_some_and(|(y, p, vehicle_frame)| {
                let dy = (y - yaw + 540.0) % 360.0 - 180.0;
                vehicle_frame && dy.abs() < 0.5 && (p - pitch).abs() < 0.5
            })
        }
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        println!("qemu_mavlink: scripted autopilot -> MAVLink bridge -> CAN -> simulated gimbal");
        let bus: DemoBus = Bus::new(7);
        let pipe: Pipe<512> = Pipe::new(7);
        // The dual light: its three streams, the thermal settings of its definition, on
        // both sides.
        let sim_config = SimConfig {
            gimbal_type: GimbalType::DualLight30x,
            ..SimConfig::default()
        };
        let (Some(ap_line), Some(bridge_line), Some(rig)) = (
            pipe.port(0),
            pipe.port(1),
            CanRig::with_gimbal(&bus, sim_config, Instant::from_millis(0)),
        ) else {
            qemu::exit(false)
        };
        let camera = CameraConfig::with_streams_of(&Camera::new(Family::DualLight)).ok();
        let Ok(config) = (BridgeConfig {
            camera,
            ..BridgeConfig::default()
        })
        .check() else {
            qemu::exit(false)
        };
        let bridge = Bridge::new(config);
        let mut w = World {
            ap: Autopilot {
                line: ap_line,
                reader: FrameReader::new(),
                seq: 0,
                seen: Seen::default(),
            },
            bridge,
            link: Link::new(Config::default()),
            rig,
            bridge_line,
            input: SerialInput::new(),
            ms: 0,
            failures: 0,
        };

        w.until(
            "GIMBAL_DEVICE_INFORMATION on request (broadcast, every second until answered)",
            5_000,
            |w| {
                if w.ms % 1000 == 10 {
                    w.ap.command(0, MavCmd::RequestMessage, [283.0, 0.0, 0.0]);
                }
            },
            |w| w.ap.seen.info && w.ap.seen.acks[0] == Some(MavResult::Accepted),
        );
        w.until(
            "setpoint yaw 90 (earth frame) pitch -30 reached, status in the vehicle frame + delta_yaw",
            6_000,
            |w| {
                if w.ms.is_multiple_of(50) {
                    w.ap.setpoint(GimbalDeviceFlags::YAW_IN_EARTH_FRAME, 90.0, -30.0, 0.0);
                }
            },
            |w| w.status_near(90.0, -30.0) && w.rig.sim_state().motor_yaw_deg == 60.0,
        );
        w.until(
            "setpoint flags 0 (vehicle frame) yaw 0 pitch -100 reached",
            6_000,
            |w| {
                if w.ms.is_multiple_of(50) {
                    w.ap.setpoint(GimbalDeviceFlags::empty(), 0.0, -100.0, 0.0);
                }
            },
            |w| w.status_near(30.0, -100.0),
        );
        // A rate for 1 s, then nothing: the gimbal turns, then the dead-man stops it.
        let before = w.rig.sim_state().motor_yaw_deg;
        for _ in 0..1_000 {
            if w.ms.is_multiple_of(50) {
                w.ap.setpoint(GimbalDeviceFlags::empty(), 0.0, 0.0, 20.0);
            }
            w.tick();
        }
        for _ in 0..600 {
            w.tick();
        }
        let stopped = w.rig.sim_state().motor_yaw_deg;
        for _ in 0..500 {
            w.tick();
        }
        let still = w.rig.sim_state().motor_yaw_deg;
        if stopped - before > 10.0 && still == stopped && w.rig.sim_state().rate == (0.0, 0.0) {
            println!(
                "  ok   rate setpoints turned the gimbal {:.1} deg, the dead-man stopped it",
                stopped - before
            );
        } else {
            w.failures += 1;
            println!(
                "  FAIL rate: turned {:.1} deg, then {:.1}",
                stopped - before,
                still - stopped
            );
        }
        w.until(
            "IMAGE_START_CAPTURE (single) accepted, the gimbal took a photo",
            2_000,
            |w| {
                if w.ms.is_multiple_of(1000) {
                    w.ap.command(100, MavCmd::ImageStartCapture, [0.0, 0.0, 1.0]);
                }
            },
            |w| w.rig.sim_state().photos == 1,
        );
        // Tracking as QGroundControl asks for it: the status every 500 ms, then a rectangle
        // right of the centre, (0.6, 0.45)-(0.7, 0.55): the simulated gimbal turns toward
        // it (its heading grows), and the status says it tracks.
        w.ap.command(100, MavCmd::SetMessageInterval, [275.0, 500_000.0, 0.0]);
        let heading = w.rig.sim_state().motor_yaw_deg;
        w.until(
            "TRACK_RECTANGLE: the gimbal tracks, turns toward the box, the status says ACTIVE",
            3_000,
            |w| {
                if w.ms.is_multiple_of(1000) {
                    w.ap.command4(100, MavCmd::CameraTrackRectangle, [0.6, 0.45, 0.7, 0.55]);
                }
            },
            |w| {
                let s = w.rig.sim_state();
                s.tracking && s.motor_yaw_deg > heading + 1.0 && w.ap.seen.tracking == Some(true)
            },
        );
        w.until(
            "STOP_TRACKING: the gimbal stops, the status says IDLE",
            3_000,
            |w| {
                if w.ms.is_multiple_of(1000) {
                    w.ap.command(100, MavCmd::CameraStopTracking, [0.0; 3]);
                }
            },
            |w| !w.rig.sim_state().tracking && w.ap.seen.tracking == Some(false),
        );
        // The palette, a setting of the dual light's camera definition (PARAM_EXT_SET).
        w.until(
            "PARAM_EXT_SET IR_PALETTE 2: ACCEPTED, the gimbal's palette is iron red",
            2_000,
            |w| {
                if w.ms.is_multiple_of(1000) {
                    let mut param_id = [0u8; 16];
                    param_id[..10].copy_from_slice(b"IR_PALETTE");
                    let mut param_value = [0u8; 128];
                    param_value[0] = 2;
                    w.ap.send(&ParamExtSet {
                        target_system: AP.0,
                        target_component: 100,
                        param_id,
                        param_value,
                        param_type: MavParamExtType::Uint8,
                    });
                }
            },
            |w| {
                w.ap.seen.param_ack == Some((ParamAck::Accepted, 2))
                    && w.rig.sim_state().palette == Some(Palette::IronRed)
            },
        );
        let gap = w.ap.seen.worst_gap;
        if gap < 1_000 && w.ap.seen.last_status.is_some() {
            println!("  ok   attitude status never older than {} ms", gap);
        } else {
            w.failures += 1;
            println!("  FAIL attitude status gap {} ms", gap);
        }
        let s = w.bridge.stats();
        println!(
            "bridge: {} frames in, {} bad, {} ACKs, {} angle setpoints, {} rate setpoints, {} refused",
            s.reader.frames, s.reader.bad_frames, s.acks, s.angle_setpoints, s.rate_setpoints, s.refused_setpoints
        );
        println!(
            "{}",
            if w.failures == 0 {
                "qemu_mavlink: passed"
            } else {
                "qemu_mavlink: FAILED"
            }
        );
        qemu::exit(w.failures == 0)
    }
}
