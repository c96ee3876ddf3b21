//! The bridge holding what it was told, with the simulated gimbal in the loop (the core's
//! CAN link between them) and the autopilot streaming its state and setpoints as PX4 and
//! ArduPilot do: every case against both behaviours the document leaves open, the gimbal
//! in lock holding its north heading or its motor angle.
//!
//! What is checked is what the autopilot and the ground station read: the status's
//! vehicle-frame yaw, and the earth yaw QGroundControl makes of it (yaw + `delta_yaw`),
//! against the setpoint itself.

mod common;
use common::*;

use idu_gimbal::link::{Config, Link};
use idu_gimbal::sim::{LockHolds, SimConfig, Simulator};
use idu_gimbal::Instant;
use idu_gimbal_mavlink::attitude::YawPitch;
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::BridgeConfig;
use mavio::dialects::common::enums::{GimbalDeviceErrorFlags, MavSeverity};
use mavio::dialects::common::enums::{GimbalDeviceFlags, MavCmd};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CameraImageCaptured, GimbalDeviceAttitudeStatus,
    GlobalPositionInt, Statustext,
};

const BOTH: [LockHolds; 2] = [LockHolds::North, LockHolds::Motor];
/// PX4's yaw lock and ROI (`output_mavlink.cpp`).
const PX4_EARTH: GimbalDeviceFlags =
    GimbalDeviceFlags::YAW_LOCK.union(GimbalDeviceFlags::YAW_IN_EARTH_FRAME);

struct Rig {
    bridge: Firmware,
    sim: Simulator,
    now: u32,
    vehicle_deg: f32,
    seq: u8,
    setpoint: Option<(GimbalDeviceFlags, f32, f32)>,
    /// Sent every 200 ms (the 5 Hz the bridge asks for).
    position: Option<GlobalPositionInt>,
    status: Option<GimbalDeviceAttitudeStatus>,
    images: Vec<CameraImageCaptured>,
    texts: Vec<String>,
}

fn state(yaw_deg: f32) -> AutopilotStateForGimbalDevice {
    AutopilotStateForGimbalDevice {
        target_system: AP.0,
        target_component: 0,
        q: YawPitch {
            yaw_rad: yaw_deg.to_radians(),
            pitch_rad: 0.0,
        }
        .to_quaternion(),
        angular_velocity_z: 0.0,
        ..Default::default()
    }
}

fn wrap(deg: f32) -> f32 {
    (deg + 180.0).rem_euclid(360.0) - 180.0
}

fn off(a: f32, b: f32) -> f32 {
    wrap(a - b).abs()
}

impl Rig {
    fn new(holds: LockHolds) -> Self {
        Self::with(SimConfig {
            lock_holds: holds,
            ..SimConfig::default()
        })
    }

    /// A gimbal that takes commands and does not move.
    fn stuck() -> Self {
        Self::with(SimConfig {
            slew_dps: 0.0,
            ..SimConfig::default()
        })
    }

    fn with(sim: SimConfig) -> Self {
        let bridge = Firmware::new(
            Link::new(Config::default()),
            BridgeConfig {
                camera: Some(CameraConfig::new("rtsp://192.168.42.108:554/stream=0").unwrap()),
                ..BridgeConfig::default()
            },
        );
        let sim = Simulator::new(sim, Instant::from_millis(0));
        Rig {
            bridge,
            sim,
            now: 0,
            vehicle_deg: 0.0,
            seq: 0,
            setpoint: None,
            position: None,
            status: None,
            images: Vec::new(),
            texts: Vec::new(),
        }
    }

    fn send(&mut self, message: &dyn mavio::Message) {
        self.seq = self.seq.wrapping_add(1);
        let bytes = frame(AP, self.seq, message);
        self.bridge.receive_all(&bytes, t(self.now));
    }

    /// One millisecond: the autopilot's heartbeat (1 Hz), state and setpoint (50 Hz, as
    /// ArduPilot; PX4 asked for 20 Hz sends no faster), the bridge, the link, the gimbal.
    fn tick(&mut self) {
        let now = t(self.now);
        if self.now.is_multiple_of(1000) {
            self.send(&heartbeat());
        }
        if self.now.is_multiple_of(20) {
            self.send(&state(self.vehicle_deg));
            if let Some((flags, yaw, pitch)) = self.setpoint {
                self.send(&set_attitude(flags, yaw, pitch));
            }
        }
        if let (Some(p), true) = (self.position.clone(), self.now.is_multiple_of(200)) {
            self.send(&p);
        }
        let link = &mut self.bridge.link;
        link.poll(now);
        while let Some(f) = link.next_transmit() {
            link.transmit_done(None);
            let _ = self.sim.receive(f.id, &f.data, now);
        }
        let _ = self.sim.poll(now);
        while let Some(f) = self.sim.pop_frame() {
            self.bridge.link.receive(f.id, &f.data, now);
        }
        self.bridge.poll(now);
        let frames = sent(&mut self.bridge);
        if let Some(s) = of::<GimbalDeviceAttitudeStatus>(&frames).pop() {
            self.status = Some(s);
        }
        self.images.extend(of::<CameraImageCaptured>(&frames));
        for t in of::<Statustext>(&frames) {
            assert_eq!(t.severity, MavSeverity::Warning);
            let end = t.text.iter().position(|&b| b == 0).unwrap_or(50);
            self.texts
                .push(String::from_utf8(t.text[..end].to_vec()).unwrap());
        }
        self.now += 1;
    }

    fn run(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick();
        }
    }

    fn turn(&mut self, to: f32, dps: f32, mut each: impl FnMut(&Rig)) {
        let step = dps / 1000.0;
        while self.vehicle_deg != to {
            let d = to - self.vehicle_deg;
            self.vehicle_deg = if d.abs() <= step {
                to
            } else {
                self.vehicle_deg + step * d.signum()
            };
            self.tick();
            each(self);
        }
    }

    /// The status's yaw from the nose and pitch, degrees.
    fn status_angles(&self) -> (f32, f32) {
        let s = self.status.as_ref().expect("a status");
        let a = YawPitch::from_quaternion(s.q).expect("a postback in the status");
        (a.yaw_rad.to_degrees(), a.pitch_rad.to_degrees())
    }

    /// The earth yaw as QGroundControl and ArduPilot read the status: its vehicle-frame yaw
    /// plus the vehicle's heading now (both ignore `delta_yaw`).
    fn heading_reading(&self) -> f32 {
        let s = self.status.as_ref().expect("a status");
        assert!(s.flags.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME));
        wrap(self.status_angles().0 + self.vehicle_deg)
    }

    /// The earth yaw as common.xml relates the status's frames: vehicle-frame yaw +
    /// delta_yaw.
    fn status_earth_yaw(&self) -> f32 {
        let s = self.status.as_ref().expect("a status");
        assert!(s.flags.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME));
        assert!(!s.delta_yaw.is_nan(), "delta_yaw known");
        wrap(self.status_angles().0 + s.delta_yaw.to_degrees())
    }

    fn yaw_lock(&self) -> bool {
        self.status
            .as_ref()
            .is_some_and(|s| s.flags.contains(GimbalDeviceFlags::YAW_LOCK))
    }
}

/// How far a settled yaw may be off, degrees: the gimbal's angle commands are in tenths of a
/// degree (the aim sent rounds by up to 0.05°), its postbacks in hundredths (0.01°). The
/// simulator lands on the command exactly.
const SETTLED_YAW: f32 = 0.06;

/// How far a settled pitch may be off, degrees: the same two (a region of interest's pitch,
/// computed in `f32`, lands within 0.003° more of the exact `f64` look angle: 0.052 seen).
const SETTLED_PITCH: f32 = 0.06;

/// How far either reading of the status's earth yaw may be off while the vehicle turns at
/// `dps`: the gimbal's 255 ms of lag, and the status read up to 100 ms after it was sent
/// (its period) against the heading then. The postback's age is not in it: the status says
/// the motor angle now, from the postback and what the vehicle has turned since.
fn reading_lag(dps: f32) -> f32 {
    dps * (0.255 + 0.1) + 0.1
}

#[test]
fn an_earth_yaw_is_held_while_the_vehicle_turns() {
    for holds in BOTH {
        // A yaw lock through a turn: vehicle at 30, earth 100, the vehicle turns to 120.
        let mut rig = Rig::new(holds);
        rig.vehicle_deg = 30.0;
        rig.run(1000);
        rig.setpoint = Some((PX4_EARTH, 100.0, -20.0));
        rig.run(3000);
        assert!(
            off(rig.status_earth_yaw(), 100.0) < SETTLED_YAW,
            "{holds:?}"
        );
        assert!(off(rig.status_angles().0, 70.0) < SETTLED_YAW, "{holds:?}");
        let (mut worst, mut worst_heading) = (0.0f32, 0.0f32);
        rig.turn(120.0, 30.0, |r| {
            worst = worst.max(off(r.status_earth_yaw(), 100.0));
            worst_heading = worst_heading.max(off(r.heading_reading(), 100.0));
        });
        assert!(worst < reading_lag(30.0), "{holds:?}: {worst}");
        assert!(
            worst_heading < reading_lag(30.0),
            "{holds:?}: {worst_heading}"
        );
        rig.run(1500);
        assert!(
            off(rig.status_earth_yaw(), 100.0) < SETTLED_YAW,
            "{holds:?}"
        );
        // -20 from the nose.
        assert!(
            off(rig.status_angles().0, -20.0) < SETTLED_YAW,
            "{holds:?}: {:?}",
            rig.status_angles()
        );
        assert!(
            (rig.status_angles().1 + 20.0).abs() < SETTLED_PITCH,
            "{holds:?}"
        );
        assert!(
            rig.yaw_lock(),
            "{holds:?}: YAW_LOCK while held in the earth frame"
        );
    }
}

#[test]
fn a_vehicle_yaw_keeps_its_angle_from_the_nose_while_the_vehicle_turns() {
    for holds in BOTH {
        for flags in [
            GimbalDeviceFlags::empty(),
            GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME,
        ] {
            let mut rig = Rig::new(holds);
            rig.vehicle_deg = 30.0;
            rig.run(1000);
            rig.setpoint = Some((flags, 40.0, -10.0));
            rig.run(3000);
            let (mut worst, mut worst_earth) = (0.0f32, 0.0f32);
            rig.turn(-60.0, 30.0, |r| {
                worst = worst.max(off(r.status_angles().0, 40.0));
                let earth = wrap(r.vehicle_deg + 40.0);
                worst_earth = worst_earth
                    .max(off(r.status_earth_yaw(), earth))
                    .max(off(r.heading_reading(), earth));
            });
            // The angle from the nose, read against the heading it is held from: the same
            // lag as the earth yaw's (`heading_reading` is the vehicle-frame yaw plus the
            // heading now).
            assert!(worst < reading_lag(30.0), "{holds:?} {flags:?}: {worst}");
            assert!(
                worst_earth < reading_lag(30.0),
                "{holds:?} {flags:?}: {worst_earth}"
            );
            rig.run(1500);
            assert!(
                off(rig.status_angles().0, 40.0) < SETTLED_YAW,
                "{holds:?} {flags:?}"
            );
            assert!(
                off(rig.status_earth_yaw(), -20.0) < SETTLED_YAW,
                "{holds:?} {flags:?}"
            );
            assert!(
                !rig.yaw_lock(),
                "{holds:?} {flags:?}: a followed yaw is no lock"
            );
        }
    }
}

#[test]
fn both_streams_starting_in_one_datagram_leave_the_camera_where_the_setpoint_says() {
    for holds in BOTH {
        let mut rig = Rig::new(holds);
        rig.vehicle_deg = 30.0;
        // The autopilot's first heartbeat, state and setpoint in one UDP read.
        let mut datagram = frame(AP, 0, &heartbeat());
        datagram.extend(frame(AP, 1, &state(30.0)));
        datagram.extend(frame(
            AP,
            2,
            &set_attitude(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 40.0, 0.0),
        ));
        let taken = rig.bridge.receive_datagram(&datagram, t(0));
        assert_eq!(taken.bytes, datagram.len());
        rig.setpoint = Some((GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 40.0, 0.0));
        rig.run(3000);
        // 40 from the nose, not 70 (40 taken north-referenced with the vehicle at 30).
        assert!(
            off(rig.status_angles().0, 40.0) < SETTLED_YAW,
            "{holds:?}: {:?}",
            rig.status_angles()
        );
        assert!(off(rig.status_earth_yaw(), 70.0) < SETTLED_YAW, "{holds:?}");
    }
}

#[test]
fn a_gimbal_that_reboots_mid_hold_comes_back_to_the_setpoint() {
    for holds in BOTH {
        let mut rig = Rig::new(holds);
        rig.vehicle_deg = 10.0;
        rig.run(1000);
        rig.setpoint = Some((PX4_EARTH, 100.0, -30.0));
        rig.run(3000);
        assert!(
            off(rig.status_earth_yaw(), 100.0) < SETTLED_YAW,
            "{holds:?}"
        );
        rig.sim.reboot(t(rig.now));
        // 3 s of start-up, a postback, the loop's look, the slew of 90° at 60°/s.
        rig.run(3000 + 500 + 50 + 1500 + 500);
        assert!(
            off(rig.status_earth_yaw(), 100.0) < SETTLED_YAW,
            "{holds:?}: {}",
            rig.status_earth_yaw()
        );
        assert!(
            (rig.status_angles().1 + 30.0).abs() < SETTLED_PITCH,
            "{holds:?}"
        );
    }
}

#[test]
fn an_image_carries_the_cameras_attitude_in_the_earth_frame() {
    for holds in BOTH {
        let mut rig = Rig::new(holds);
        rig.vehicle_deg = 60.0;
        rig.run(1000);
        rig.setpoint = Some((PX4_EARTH, 20.0, -45.0));
        rig.run(3000);
        rig.send(&command7(
            (AP.0, 100),
            MavCmd::ImageStartCapture,
            [0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0],
        ));
        rig.run(10);
        let image = rig.images.last().expect("an image");
        let a = YawPitch::from_quaternion(image.q).expect("a known attitude");
        // The camera looks at 20° from north, 45° down: the quaternion's own reading, to
        // the postback's 0.01° and f32 trigonometry.
        assert!(off(a.yaw_rad.to_degrees(), 20.0) < 0.02, "{holds:?}: {a:?}");
        assert!(
            (a.pitch_rad.to_degrees() + 45.0).abs() < 0.02,
            "{holds:?}: {a:?}"
        );
    }
    // Images taken while the vehicle turns (at 30°/s from 30° to 129°, an image at every
    // 11°: 367 ms apart, so that they fall at every age of the 2 Hz postback), an earth yaw
    // held or a yaw that follows the vehicle (40° from the nose): each image's yaw is the
    // camera's now within the gimbal's lag, whatever the postback's age.
    for holds in BOTH {
        for (flags, yaw) in [(PX4_EARTH, 100.0), (GimbalDeviceFlags::empty(), 40.0)] {
            let mut rig = Rig::new(holds);
            rig.vehicle_deg = 30.0;
            rig.run(1000);
            rig.setpoint = Some((flags, yaw, -20.0));
            rig.run(3000);
            let mut worst = 0.0f32;
            for i in 1..=9u8 {
                rig.turn(30.0 + 11.0 * f32::from(i), 30.0, |_| {});
                let taken = rig.images.len();
                // Each capture its own sequence number, or it is a retransmission.
                rig.send(&command7(
                    (AP.0, 100),
                    MavCmd::ImageStartCapture,
                    [0.0, 0.0, 1.0, f32::from(i), 0.0, 0.0, 0.0],
                ));
                rig.tick();
                assert_eq!(rig.images.len(), taken + 1, "{holds:?} {flags:?}");
                let image = rig.images.last().expect("an image");
                let a = YawPitch::from_quaternion(image.q).expect("a known attitude");
                let expected = if flags == PX4_EARTH {
                    yaw
                } else {
                    wrap(rig.vehicle_deg + yaw)
                };
                worst = worst.max(off(a.yaw_rad.to_degrees(), expected));
            }
            assert!(worst < reading_lag(30.0), "{holds:?} {flags:?}: {worst}");
        }
    }
    // Unknown without a vehicle heading: NaN.
    let mut b = camera_bridge(CameraConfig::new("rtsp://192.168.42.108:554/stream=0").unwrap());
    for d in idu_gimbal::wire::postback::Postback::default().to_can_frames() {
        b.link.receive(idu_gimbal::wire::ids::POSTBACK, &d, t(10));
    }
    b.receive_all(
        &frame(
            AP,
            1,
            &command7(
                (AP.0, 100),
                MavCmd::ImageStartCapture,
                [0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0],
            ),
        ),
        t(10),
    );
    let image = &of::<CameraImageCaptured>(&sent(&mut b))[0];
    assert!(image.q.iter().all(|v| v.is_nan()), "{:?}", image.q);
}

#[test]
fn a_setpoint_beyond_the_yaw_travel_or_not_reached_is_reported_once() {
    let mut rig = Rig::new(LockHolds::North);
    rig.vehicle_deg = 0.0;
    rig.run(1000);
    // North 175 with the vehicle at 0: the motor stops at 170.
    rig.setpoint = Some((PX4_EARTH, 175.0, 0.0));
    rig.run(5000);
    let s = rig.status.clone().unwrap();
    assert!(s
        .failure_flags
        .contains(GimbalDeviceErrorFlags::AT_YAW_LIMIT));
    assert_eq!(
        rig.texts,
        ["Gimbal: setpoint beyond yaw travel, held at limit"]
    );
    // Back in reach: the flag clears.
    rig.setpoint = Some((PX4_EARTH, 90.0, 0.0));
    rig.run(3000);
    let s = rig.status.clone().unwrap();
    assert!(!s
        .failure_flags
        .contains(GimbalDeviceErrorFlags::AT_YAW_LIMIT));
    // A gimbal that takes commands and does not move: not reached, said once.
    let mut rig = Rig::stuck();
    rig.run(1000);
    rig.setpoint = Some((GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 90.0, 0.0));
    rig.run(20_000);
    assert_eq!(rig.texts, ["Gimbal: setpoint not reached, re-sent 3 times"]);
    assert_eq!(rig.bridge.link.stats().aim_not_reached, 1);
}

/// The aim's troubles are told whatever the status's interval: with the status stopped
/// (`SET_MESSAGE_INTERVAL` −1), the text still comes, within the heartbeat's second.
#[test]
fn an_aim_not_reached_is_told_with_the_status_stopped() {
    let mut rig = Rig::stuck();
    rig.run(1000);
    rig.send(&command7(
        (AP.0, 154),
        MavCmd::SetMessageInterval,
        [285.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    ));
    rig.run(1000);
    rig.status = None;
    rig.setpoint = Some((GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 90.0, 0.0));
    rig.run(20_000);
    assert!(rig.status.is_none(), "the status stopped");
    assert_eq!(rig.texts, ["Gimbal: setpoint not reached, re-sent 3 times"]);
}

#[cfg(feature = "roi")]
#[test]
fn a_region_of_interest_is_held_while_the_vehicle_turns() {
    use idu_gimbal::geo::{look_at, Position};
    let truth = look_at(
        &Position::new(47.0, 8.0, 500.0).unwrap(),
        &Position::new(47.0018, 8.0, 400.0).unwrap(),
    )
    .unwrap();
    let bearing = truth.bearing_deg as f32;
    for holds in BOTH {
        let mut rig = Rig::new(holds);
        rig.vehicle_deg = -90.0;
        rig.position = Some(GlobalPositionInt {
            lat: 470_000_000,
            lon: 80_000_000,
            alt: 500_000,
            relative_alt: 100_000,
            ..Default::default()
        });
        rig.run(1000);
        // 200 m north of the vehicle, 100 m below it: at home's height (COMMAND_LONG's
        // altitude is relative to home, 400 m here).
        rig.send(&command7(
            (AP.0, 154),
            MavCmd::DoSetRoiLocation,
            [0.0, 0.0, 0.0, 0.0, 47.0018, 8.0, 0.0],
        ));
        rig.run(3000);
        assert!(
            off(rig.status_earth_yaw(), bearing) < SETTLED_YAW,
            "{holds:?}"
        );
        assert!(
            rig.yaw_lock(),
            "{holds:?}: a region of interest is held in the earth frame"
        );
        let mut worst = 0.0f32;
        rig.turn(60.0, 30.0, |r| {
            worst = worst
                .max(off(r.status_earth_yaw(), bearing))
                .max(off(r.heading_reading(), bearing))
        });
        assert!(worst < reading_lag(30.0), "{holds:?}: {worst}");
        rig.run(1500);
        assert!(
            off(rig.status_earth_yaw(), bearing) < SETTLED_YAW,
            "{holds:?}"
        );
        let pitch = rig.status_angles().1;
        assert!(
            (pitch - truth.elevation_deg as f32).abs() < SETTLED_PITCH,
            "{pitch} {truth:?}"
        );
    }
}
