//! Helpers shared by the bridge's tests: frames built with `mavio`, the bridge's output
//! parsed back, the core link's queue read out.
#![allow(dead_code)] // each test file uses some

use idu_gimbal::link::{Can, Config, Link, Medium};
use idu_gimbal::wire::control::{Command, GimbalCommand};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::vehicle::VehicleFrame;
use idu_gimbal::Instant;
use idu_gimbal_mavlink::attitude::YawPitch;
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::framing::{Check, FrameReader};
use idu_gimbal_mavlink::{Bridge, BridgeConfig};
use mavio::dialects::common::enums::{
    GimbalDeviceFlags, MavAutopilot, MavCmd, MavModeFlag, MavState, MavType,
};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandLong, GimbalDeviceSetAttitude, GlobalPositionInt,
    Heartbeat,
};
use mavio::mavspec::rust::spec::MessageSpecStatic;
use mavio::protocol::{Frame, V2};
use mavio::Message;

/// A bridge and the link it drives, as a firmware holds them; the bridge's own methods
/// through `Deref`, those that take the link here.
pub struct Firmware<const Q: usize = 8, const T: usize = 8, M: Medium = Can> {
    pub bridge: Bridge,
    pub link: Link<Q, T, M>,
}

impl<const Q: usize, const T: usize, M: Medium> Firmware<Q, T, M> {
    pub fn new(link: Link<Q, T, M>, config: BridgeConfig) -> Self {
        Firmware {
            bridge: Bridge::new(config.check().unwrap()),
            link,
        }
    }

    pub fn receive(&mut self, bytes: &[u8], now: Instant) -> usize {
        self.bridge.receive(&mut self.link, bytes, now)
    }

    pub fn receive_datagram(
        &mut self,
        datagram: &[u8],
        now: Instant,
    ) -> idu_gimbal_mavlink::bridge::Taken {
        self.bridge.receive_datagram(&mut self.link, datagram, now)
    }

    pub fn poll(&mut self, now: Instant) {
        self.bridge.poll(&mut self.link, now)
    }
}

impl<const Q: usize, const T: usize, M: Medium> core::ops::Deref for Firmware<Q, T, M> {
    type Target = Bridge;
    fn deref(&self) -> &Bridge {
        &self.bridge
    }
}

impl<const Q: usize, const T: usize, M: Medium> core::ops::DerefMut for Firmware<Q, T, M> {
    fn deref_mut(&mut self) -> &mut Bridge {
        &mut self.bridge
    }
}

pub const AP: (u8, u8) = (7, 1);
pub const GCS: (u8, u8) = (255, 190);

pub fn t(ms: u32) -> Instant {
    Instant::from_millis(ms)
}

/// One MAVLink 2 frame from `(system, component)`.
pub fn frame(from: (u8, u8), seq: u8, message: &dyn Message) -> Vec<u8> {
    let f = Frame::builder()
        .version(V2)
        .sequence(seq)
        .system_id(from.0)
        .component_id(from.1)
        .message(message)
        .unwrap()
        .build();
    let mut buf = [0u8; 300];
    let n = f.serialize(&mut buf).unwrap();
    buf[..n].to_vec()
}

/// Every frame the bridge wrote since the last call, drained.
pub fn sent(bridge: &mut Bridge) -> Vec<Frame<V2>> {
    let bytes = bridge.transmit_bytes().to_vec();
    bridge.transmit_written(bytes.len());
    let mut more = bridge.transmit_bytes().to_vec();
    bridge.transmit_written(more.len());
    let mut all = bytes;
    all.append(&mut more);
    let mut frames = Vec::new();
    let mut reader = FrameReader::new();
    reader.feed(&all, |f| {
        frames.push(
            f.to_frame()
                .expect("mavio parses every frame the bridge sent"),
        );
        Check::Unhandled
    });
    assert_eq!(reader.pending(), 0);
    assert_eq!(reader.stats().skipped_bytes, 0);
    frames
}

pub fn of<M>(frames: &[Frame<V2>]) -> Vec<M>
where
    M: MessageSpecStatic
        + for<'a> TryFrom<&'a mavio::protocol::Payload, Error = mavio::error::SpecError>,
{
    frames
        .iter()
        .filter(|f| f.message_id() == M::spec().id())
        .map(|f| f.decode_message::<M>().unwrap())
        .collect()
}

pub fn heartbeat() -> Heartbeat {
    Heartbeat {
        type_: MavType::Quadrotor,
        autopilot: MavAutopilot::Ardupilotmega,
        base_mode: MavModeFlag::empty(),
        custom_mode: 0,
        system_status: MavState::Active,
        mavlink_version: 3,
    }
}

pub fn command(target: (u8, u8), command: MavCmd, p1: f32, p2: f32) -> CommandLong {
    command7(target, command, [p1, p2, 0.0, 0.0, 0.0, 0.0, 0.0])
}

/// `COMMAND_LONG` to `target` with params 1 to 7.
pub fn command7(target: (u8, u8), command: MavCmd, p: [f32; 7]) -> CommandLong {
    CommandLong {
        target_system: target.0,
        target_component: target.1,
        command,
        confirmation: 0,
        param1: p[0],
        param2: p[1],
        param3: p[2],
        param4: p[3],
        param5: p[4],
        param6: p[5],
        param7: p[6],
    }
}

/// Feeding a bridge whose outbox the test drains often enough for every frame to be taken
/// at once.
pub trait ReceiveAll {
    /// [`Bridge::receive`], every byte taken: the test fails if a frame had to wait for
    /// room in the outbox.
    fn receive_all(&mut self, bytes: &[u8], now: Instant);
}

impl<const Q: usize, const T: usize, M: Medium> ReceiveAll for Firmware<Q, T, M> {
    fn receive_all(&mut self, bytes: &[u8], now: Instant) {
        let taken = self.receive(bytes, now);
        assert_eq!(taken, bytes.len(), "a frame waits for room in the outbox");
    }
}

/// [`Bridge::receive`] of all of `bytes`, the outbox drained whenever a frame waits for room
/// in it, as a transport drains it; the frames sent meanwhile.
pub fn receive_draining<const Q: usize, const T: usize, M: Medium>(
    b: &mut Firmware<Q, T, M>,
    mut bytes: &[u8],
    now: Instant,
) -> Vec<Frame<V2>> {
    let mut out = Vec::new();
    loop {
        bytes = &bytes[b.receive(bytes, now)..];
        if bytes.is_empty() && !b.reader().is_waiting() {
            return out;
        }
        out.extend(sent(b));
    }
}

/// A bridge on the core's CAN link with `camera`, that has heard the autopilot's heartbeat
/// (so its system id is the autopilot's), its output so far drained.
pub fn camera_bridge(camera: CameraConfig) -> Firmware {
    let mut b = Firmware::new(
        Link::new(Config::default()),
        BridgeConfig {
            camera: Some(camera),
            ..BridgeConfig::default()
        },
    );
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    let _ = sent(&mut b);
    b
}

/// The commands the link queued, in order.
pub fn queued<const Q: usize, const T: usize>(link: &mut Link<Q, T>) -> Vec<GimbalCommand> {
    let mut out = Vec::new();
    while let Some(f) = link.next_transmit() {
        link.transmit_done(None);
        if f.id == ids::CONTROL {
            if let Ok(Command::Gimbal(c)) = Command::decode(&f.data) {
                out.push(c);
            }
        }
    }
    out
}

/// Every command the link queued, either peripheral, in order.
pub fn queued_all<const Q: usize, const T: usize>(link: &mut Link<Q, T>) -> Vec<Command> {
    let mut out = Vec::new();
    while let Some(f) = link.next_transmit() {
        link.transmit_done(None);
        if f.id == ids::CONTROL {
            out.push(Command::decode(&f.data).expect("the bridge queues valid commands"));
        }
    }
    out
}

/// Every vehicle frame the link queued (attitude, GPS, altitude), in order, each taken as
/// sent; a frame of any other kind fails the test.
pub fn queued_vehicle_frames<const Q: usize, const T: usize>(
    link: &mut Link<Q, T>,
) -> Vec<VehicleFrame> {
    let mut out = Vec::new();
    while let Some(f) = link.next_transmit() {
        link.transmit_done(None);
        out.push(VehicleFrame::decode(f.id, &f.data).expect("a vehicle frame"));
    }
    out
}

/// The autopilot's `GIMBAL_DEVICE_SET_ATTITUDE` to the gimbal device (component 154): yaw
/// and pitch in degrees, the rates unset (NaN).
pub fn set_attitude(
    flags: GimbalDeviceFlags,
    yaw_deg: f32,
    pitch_deg: f32,
) -> GimbalDeviceSetAttitude {
    GimbalDeviceSetAttitude {
        target_system: AP.0,
        target_component: 154,
        flags,
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

/// The autopilot's state for the gimbal device: the vehicle level, heading `yaw_deg`, not
/// turning, the rate sent as ArduPilot sends it (−0.0: MAVLink 2 keeps its sign bit on the
/// wire, where it drops +0.0, which reads as no rate sent, PX4's).
pub fn autopilot_state(yaw_deg: f32) -> AutopilotStateForGimbalDevice {
    AutopilotStateForGimbalDevice {
        target_system: AP.0,
        target_component: 154,
        time_boot_us: 0,
        q: YawPitch {
            yaw_rad: yaw_deg.to_radians(),
            pitch_rad: 0.0,
        }
        .to_quaternion(),
        q_estimated_delay_us: 0,
        vx: 0.0,
        vy: 0.0,
        vz: 0.0,
        v_estimated_delay_us: 0,
        feed_forward_angular_velocity_z: 0.0,
        estimator_status: Default::default(),
        landed_state: Default::default(),
        angular_velocity_z: -0.0,
    }
}

/// The autopilot's `GLOBAL_POSITION_INT`: 1e-7°, and altitudes in mm.
pub fn position(lat: i32, lon: i32, alt_mm: i32, relative_mm: i32) -> GlobalPositionInt {
    GlobalPositionInt {
        time_boot_ms: 0,
        lat,
        lon,
        alt: alt_mm,
        relative_alt: relative_mm,
        vx: 0,
        vy: 0,
        vz: 0,
        hdg: 0,
    }
}

/// MAVLink's checksum of `bytes` (a frame after its start byte, to the payload's end) and
/// `crc_extra`: CRC-16/MCRF4XX bit by bit, independent of the crate's table.
pub fn checksum(bytes: &[u8], crc_extra: u8) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for &b in bytes.iter().chain([crc_extra].iter()) {
        crc ^= u16::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0x8408
            } else {
                crc >> 1
            };
        }
    }
    crc
}

/// A MAVLink 2 frame of message `id` with `payload` as given, its checksum computed here
/// (CRC-16/MCRF4XX bit by bit, then `crc_extra`): what a sender whose dialect `mavio` does
/// not share puts on the wire.
pub fn raw_frame(from: (u8, u8), id: u32, crc_extra: u8, payload: &[u8]) -> Vec<u8> {
    let mut f = vec![0xFD, payload.len() as u8, 0, 0, 0, from.0, from.1];
    f.extend_from_slice(&id.to_le_bytes()[..3]);
    f.extend_from_slice(payload);
    let crc = checksum(&f[1..], crc_extra);
    f.extend_from_slice(&crc.to_le_bytes());
    f
}
