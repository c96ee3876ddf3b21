//! Every stream of the family, the definition's settings over the extended parameter
//! protocol (as QGroundControl lists them and MAVSDK reads them one by one), and the
//! definition file over MAVLink FTP as each client asks for it.

mod common;
use common::*;

use idu_gimbal::video::{Camera as VideoCamera, Family, Stream};
use idu_gimbal::wire::control::{
    Command, DualLightCommand, ElectronicZoom, Focus, GimbalCommand, Palette,
};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::{GimbalType, Postback};
use idu_gimbal_mavlink::camera::{definition, CameraConfig};
use mavio::dialects::common::enums::{
    CameraMode, MavCmd, MavParamExtType, MavResult, ParamAck, VideoStreamStatusFlags,
};
use mavio::dialects::common::messages::{
    CameraInformation, CameraSettings, CommandAck, FileTransferProtocol, ParamExtAck,
    ParamExtRequestList, ParamExtRequestRead, ParamExtSet, ParamExtValue, VideoStreamInformation,
    VideoStreamStatus,
};
use mavio::protocol::{Frame, V2};

const CAMERA: u8 = 100;

fn bridge(family: Family) -> Firmware {
    camera_bridge(CameraConfig::with_streams_of(&VideoCamera::new(family)).unwrap())
}

fn ask(b: &mut Firmware, cmd: MavCmd, p1: f32, p2: f32) -> (MavResult, Vec<Frame<V2>>) {
    b.receive_all(&frame(GCS, 0, &command((AP.0, CAMERA), cmd, p1, p2)), t(10));
    let mut frames = sent(b);
    // What did not fit the outbox at once follows at the next polls.
    for ms in 11..20 {
        b.poll(t(ms));
        frames.extend(sent(b));
    }
    let acks: Vec<CommandAck> = of(&frames);
    assert_eq!(acks.len(), 1);
    (acks[0].result, frames)
}

fn text(field: &[u8]) -> &str {
    let end = field.iter().position(|&c| c == 0).unwrap_or(field.len());
    std::str::from_utf8(&field[..end]).unwrap()
}

#[test]
fn every_stream_of_the_dual_light_with_the_infrared_one_thermal() {
    let mut b = bridge(Family::DualLight);
    let cam = VideoCamera::new(Family::DualLight);
    let expected = [
        (1, "main", cam.url(Stream::Main).unwrap(), false),
        (2, "aux1", cam.url(Stream::Aux1).unwrap(), false),
        (3, "infrared", cam.url(Stream::Infrared).unwrap(), true),
    ];
    // QGroundControl: REQUEST_MESSAGE(269, param2 0 = all).
    let (r, frames) = ask(&mut b, MavCmd::RequestMessage, 269.0, 0.0);
    assert_eq!(r, MavResult::Accepted);
    let infos: Vec<VideoStreamInformation> = of(&frames);
    assert_eq!(infos.len(), 3);
    for (s, (id, name, uri, thermal)) in infos.iter().zip(&expected) {
        assert_eq!((s.stream_id, s.count), (*id, 3));
        assert_eq!(text(&s.name), *name);
        assert_eq!(text(&s.uri), uri.as_str());
        assert!(s.flags.contains(VideoStreamStatusFlags::RUNNING));
        assert_eq!(s.flags.contains(VideoStreamStatusFlags::THERMAL), *thermal);
    }
    // One stream by id, by either request; its status keeps the thermal flag (QGC's
    // VIDEO_STREAM_STATUS handling overwrites the flags).
    let (_, frames) = ask(&mut b, MavCmd::RequestMessage, 269.0, 3.0);
    let infos: Vec<VideoStreamInformation> = of(&frames);
    assert_eq!(infos.iter().map(|s| s.stream_id).collect::<Vec<_>>(), [3]);
    let (_, frames) = ask(&mut b, MavCmd::RequestVideoStreamInformation, 2.0, 0.0);
    let infos: Vec<VideoStreamInformation> = of(&frames);
    assert_eq!(infos.iter().map(|s| s.stream_id).collect::<Vec<_>>(), [2]);
    let (_, frames) = ask(&mut b, MavCmd::RequestMessage, 270.0, 0.0);
    let status: Vec<VideoStreamStatus> = of(&frames);
    let thermal: Vec<(u8, bool)> = status
        .iter()
        .map(|s| {
            (
                s.stream_id,
                s.flags.contains(VideoStreamStatusFlags::THERMAL),
            )
        })
        .collect();
    assert_eq!(thermal, [(1, false), (2, false), (3, true)]);
    // An id the camera does not have: denied, nothing sent.
    for id in [4.0, -1.0, 1.5, f32::NAN] {
        let (r, frames) = ask(&mut b, MavCmd::RequestMessage, 269.0, id);
        assert_eq!(r, MavResult::Denied, "{id}");
        assert!(of::<VideoStreamInformation>(&frames).is_empty());
    }
}

#[test]
fn a_single_stream_family_has_one_stream_and_no_thermal() {
    let mut b = bridge(Family::F10);
    let (_, frames) = ask(&mut b, MavCmd::RequestMessage, 269.0, 0.0);
    let infos: Vec<VideoStreamInformation> = of(&frames);
    assert_eq!(infos.len(), 1);
    assert_eq!((infos[0].stream_id, infos[0].count), (1, 1));
    assert!(!infos[0].flags.contains(VideoStreamStatusFlags::THERMAL));
}

fn param_id(name: &str) -> [u8; 16] {
    let mut id = [0u8; 16];
    id[..name.len()].copy_from_slice(name.as_bytes());
    id
}

fn value_of(v: u8) -> [u8; 128] {
    let mut f = [0u8; 128];
    f[0] = v;
    f
}

/// A ground station's `PARAM_EXT_REQUEST_READ` of the camera's setting at `index`, or named
/// `id` when `index` is −1.
fn read(b: &mut Firmware, id: [u8; 16], index: i16) {
    let m = ParamExtRequestRead {
        target_system: AP.0,
        target_component: CAMERA,
        param_id: id,
        param_index: index,
    };
    b.receive_all(&frame(GCS, 0, &m), t(20));
}

/// The PARAM_EXT_VALUEs the camera sent, as (name, value, index, count).
fn values(frames: &[Frame<V2>]) -> Vec<(String, u8, u16, u16)> {
    of::<ParamExtValue>(frames)
        .iter()
        .map(|v| {
            assert_eq!(v.param_type, MavParamExtType::Uint8);
            assert!(v.param_value[1..].iter().all(|&b| b == 0));
            (
                text(&v.param_id).to_string(),
                v.param_value[0],
                v.param_index,
                v.param_count,
            )
        })
        .collect()
}

fn list(b: &mut Firmware) -> Vec<(String, u8, u16, u16)> {
    let m = ParamExtRequestList {
        target_system: AP.0,
        target_component: CAMERA,
    };
    b.receive_all(&frame(GCS, 0, &m), t(10));
    let mut frames = sent(b);
    b.poll(t(11));
    frames.extend(sent(b));
    values(&frames)
}

fn set(b: &mut Firmware, name: &str, value: [u8; 128], ty: MavParamExtType) -> ParamExtAck {
    let m = ParamExtSet {
        target_system: AP.0,
        target_component: CAMERA,
        param_id: param_id(name),
        param_value: value,
        param_type: ty,
    };
    b.receive_all(&frame(GCS, 0, &m), t(10));
    let acks: Vec<ParamExtAck> = of(&sent(b));
    assert_eq!(acks.len(), 1);
    acks[0].clone()
}

#[test]
fn the_settings_are_listed_with_the_definitions_defaults() {
    let mut b = bridge(Family::DualLight);
    let all = list(&mut b);
    let expected: Vec<(String, u8, u16, u16)> =
        [("CAM_FOCUS", 0), ("IR_PALETTE", 0), ("IR_EZOOM", 0)]
            .iter()
            .enumerate()
            .map(|(i, (n, v))| (n.to_string(), *v, i as u16, 3))
            .collect();
    assert_eq!(all, expected);
    // A zoom camera has focus only.
    let mut z = bridge(Family::X3);
    assert_eq!(list(&mut z), vec![("CAM_FOCUS".to_string(), 0, 0, 1)]);
}

#[test]
fn setting_the_palette_sends_the_gimbal_its_command_and_acks_the_value() {
    let mut b = bridge(Family::DualLight);
    let ack = set(&mut b, "IR_PALETTE", value_of(10), MavParamExtType::Uint8);
    assert_eq!(ack.param_result, ParamAck::Accepted);
    assert_eq!(
        (ack.param_value, ack.param_type),
        (value_of(10), MavParamExtType::Uint8)
    );
    assert_eq!(
        queued_all(&mut b.link),
        vec![Command::DualLight(DualLightCommand::Palette(
            Palette::IceBlue
        ))]
    );
    // The value read back, by name (MAVSDK: index −1) and by index.
    for (id, index) in [(param_id("IR_PALETTE"), -1), ([0; 16], 1)] {
        read(&mut b, id, index);
        assert_eq!(
            values(&sent(&mut b)),
            vec![("IR_PALETTE".to_string(), 10, 1, 3)]
        );
    }
    // Electronic zoom and focus, each its command.
    for (name, v, c) in [
        (
            "IR_EZOOM",
            1,
            DualLightCommand::ElectronicZoom(ElectronicZoom::In).into(),
        ),
        (
            "IR_EZOOM",
            2,
            DualLightCommand::ElectronicZoom(ElectronicZoom::Out).into(),
        ),
        (
            "IR_EZOOM",
            0,
            DualLightCommand::ElectronicZoom(ElectronicZoom::Stop).into(),
        ),
        ("CAM_FOCUS", 1, GimbalCommand::Focus(Focus::Plus).into()),
        ("CAM_FOCUS", 2, GimbalCommand::Focus(Focus::Minus).into()),
        ("CAM_FOCUS", 3, GimbalCommand::Focus(Focus::Auto).into()),
        ("CAM_FOCUS", 0, GimbalCommand::Focus(Focus::Stop).into()),
    ] {
        let ack = set(&mut b, name, value_of(v), MavParamExtType::Uint8);
        assert_eq!(
            (ack.param_result, ack.param_value[0]),
            (ParamAck::Accepted, v)
        );
        let queued: Vec<Command> = queued_all(&mut b.link);
        assert_eq!(queued, vec![c], "{name} = {v}");
    }
}

#[test]
fn a_value_outside_the_options_is_refused_with_the_value_kept() {
    let mut b = bridge(Family::DualLight);
    assert_eq!(
        set(&mut b, "IR_PALETTE", value_of(3), MavParamExtType::Uint8).param_result,
        ParamAck::Accepted
    );
    let _ = queued_all(&mut b.link);
    for (value, ty) in [
        (value_of(15), MavParamExtType::Uint8),
        (value_of(255), MavParamExtType::Uint8),
        (value_of(3), MavParamExtType::Uint16),
        (value_of(3), MavParamExtType::Real32),
    ] {
        let ack = set(&mut b, "IR_PALETTE", value, ty);
        // QGroundControl shows the ACK's value: the one kept, with its type.
        assert_eq!(
            ack.param_result,
            ParamAck::ValueUnsupported,
            "{:?} {ty:?}",
            &value[..2]
        );
        assert_eq!(
            (ack.param_value, ack.param_type),
            (value_of(3), MavParamExtType::Uint8)
        );
        assert!(queued_all(&mut b.link).is_empty());
    }
    // An unknown name, and a thermal setting on a camera without a thermal sensor.
    let ack = set(&mut b, "CAM_ISO", value_of(1), MavParamExtType::Uint8);
    assert_eq!(ack.param_result, ParamAck::ValueUnsupported);
    let mut z = bridge(Family::X3);
    let ack = set(&mut z, "IR_PALETTE", value_of(1), MavParamExtType::Uint8);
    assert_eq!(ack.param_result, ParamAck::ValueUnsupported);
    assert!(queued_all(&mut z.link).is_empty());
}

#[test]
fn a_value_is_read_by_its_types_width_whatever_follows_it() {
    // QGroundControl 5.0 leaves its stack buffer's bytes after the value
    // (QGCCameraIO.cc _sendParameter): a uint8 is its first byte.
    let mut b = bridge(Family::DualLight);
    let mut garbage = [0xA5u8; 128];
    garbage[0] = 7;
    let ack = set(&mut b, "IR_PALETTE", garbage, MavParamExtType::Uint8);
    assert_eq!(ack.param_result, ParamAck::Accepted);
    assert_eq!(ack.param_value, value_of(7));
    assert_eq!(
        queued_all(&mut b.link),
        [Command::from(DualLightCommand::Palette(
            Palette::from_code(7).unwrap()
        ))]
    );
}

#[test]
fn reset_camera_settings_puts_every_setting_back_to_its_default() {
    let mut b = bridge(Family::DualLight);
    for (name, v) in [("IR_PALETTE", 9), ("CAM_FOCUS", 3), ("IR_EZOOM", 1)] {
        let ack = set(&mut b, name, value_of(v), MavParamExtType::Uint8);
        assert_eq!(ack.param_result, ParamAck::Accepted, "{name}");
    }
    let _ = queued_all(&mut b.link);
    // QGroundControl sends param1 1 and, until ACCEPTED, TEMPORARILY_REJECTED or FAILED,
    // blocks its photo, video and mode buttons (VehicleCameraControl.cc _mavCommandResult).
    let (result, frames) = ask(&mut b, MavCmd::ResetCameraSettings, 1.0, 0.0);
    assert_eq!(result, MavResult::Accepted);
    assert_eq!(of::<CameraSettings>(&frames).len(), 1);
    assert_eq!(
        queued_all(&mut b.link),
        [
            Command::from(GimbalCommand::Focus(Focus::Stop)),
            Command::from(DualLightCommand::Palette(Palette::from_code(0).unwrap())),
            Command::from(DualLightCommand::ElectronicZoom(ElectronicZoom::Stop)),
        ]
    );
    let listed = list(&mut b);
    assert!(listed.iter().all(|(_, v, _, _)| *v == 0), "{listed:?}");
    // A queue with room for two of the three settings: TEMPORARILY_REJECTED, which
    // QGroundControl also lets go of, and nothing sent or changed (all or none).
    let ack = set(&mut b, "IR_PALETTE", value_of(9), MavParamExtType::Uint8);
    assert_eq!(ack.param_result, ParamAck::Accepted);
    let (result, _) = ask(&mut b, MavCmd::SetCameraMode, 0.0, 1.0);
    assert_eq!(result, MavResult::Accepted);
    let _ = queued_all(&mut b.link);
    while b.link.command_room() > 2 {
        b.link.send(GimbalCommand::Recenter).unwrap();
    }
    let (result, _) = ask(&mut b, MavCmd::ResetCameraSettings, 1.0, 0.0);
    assert_eq!(result, MavResult::TemporarilyRejected);
    // The mode too stays (a reset would put the image mode back).
    let (_, frames) = ask(&mut b, MavCmd::RequestMessage, 260.0, 0.0);
    assert_eq!(of::<CameraSettings>(&frames)[0].mode_id, CameraMode::Video);
    assert_eq!(
        queued_all(&mut b.link),
        [Command::from(GimbalCommand::Recenter); 6]
    );
    let listed = list(&mut b);
    assert!(
        listed.iter().any(|(_, v, _, _)| *v == 9),
        "the palette kept: {listed:?}"
    );
    // Room for exactly the three: reset.
    let _ = queued_all(&mut b.link);
    while b.link.command_room() > 3 {
        b.link.send(GimbalCommand::Recenter).unwrap();
    }
    let (result, _) = ask(&mut b, MavCmd::ResetCameraSettings, 1.0, 0.0);
    assert_eq!(result, MavResult::Accepted);
    assert_eq!(queued_all(&mut b.link).len(), 5 + 3);
}

#[test]
fn a_setting_the_gimbals_queue_cannot_take_fails_and_keeps_the_value() {
    let mut b = bridge(Family::DualLight);
    // Fill the link's command queue.
    while b.link.send(GimbalCommand::Recenter).is_ok() {}
    let ack = set(&mut b, "IR_PALETTE", value_of(5), MavParamExtType::Uint8);
    assert_eq!(ack.param_result, ParamAck::Failed);
    assert_eq!(ack.param_value, value_of(0));
}

#[test]
fn reads_of_unknown_names_or_indexes_are_not_answered() {
    let mut b = bridge(Family::X3);
    for (id, index) in [
        (param_id("IR_PALETTE"), -1),
        (param_id("NOPE"), -1),
        ([0; 16], 1),
        ([0; 16], 300),
    ] {
        read(&mut b, id, index);
        assert!(values(&sent(&mut b)).is_empty());
    }
    // A list for another component is not ours.
    let m = ParamExtRequestList {
        target_system: AP.0,
        target_component: 1,
    };
    b.receive_all(&frame(GCS, 0, &m), t(30));
    assert!(values(&sent(&mut b)).is_empty());
    // Nor one to every component of another system; one to every system is.
    for (system, answered) in [(42, false), (0, true)] {
        let m = ParamExtRequestList {
            target_system: system,
            target_component: 0,
        };
        b.receive_all(&frame(GCS, 0, &m), t(40));
        let mut frames = sent(&mut b);
        b.poll(t(41));
        frames.extend(sent(&mut b));
        assert_eq!(!values(&frames).is_empty(), answered, "system {system}");
    }
}

/// An FTP request payload, written out by hand: seq, session, opcode, size, offset, data.
fn ftp(seq: u16, session: u8, opcode: u8, offset: u32, data: &[u8]) -> FileTransferProtocol {
    let mut p = [0u8; 251];
    p[0..2].copy_from_slice(&seq.to_le_bytes());
    p[2] = session;
    p[3] = opcode;
    p[4] = data.len() as u8;
    p[8..12].copy_from_slice(&offset.to_le_bytes());
    p[12..12 + data.len()].copy_from_slice(data);
    FileTransferProtocol {
        target_network: 0,
        target_system: AP.0,
        target_component: CAMERA,
        payload: p,
    }
}

/// The FTP replies to `m`, with the polls that follow a burst.
fn ftp_ask(b: &mut Firmware, m: &FileTransferProtocol) -> Vec<FileTransferProtocol> {
    b.receive_all(&frame(GCS, 0, m), t(10));
    let mut frames = sent(b);
    for ms in 11..40 {
        b.poll(t(ms));
        frames.extend(sent(b));
    }
    let replies: Vec<FileTransferProtocol> = of(&frames);
    for r in &replies {
        // To the client that asked, never broadcast (pymavlink requires it).
        assert_eq!((r.target_system, r.target_component), GCS);
    }
    replies
}

const OPEN: u8 = 4;
const READ: u8 = 5;
const BURST: u8 = 15;
const ACK: u8 = 128;

/// A definition file as the bridge serves it: its empty `<model>` filled with `model`.
fn served(template: &[u8], model: &str) -> Vec<u8> {
    let text = std::str::from_utf8(template).unwrap();
    assert_eq!(text.matches("<model></model>").count(), 1);
    text.replace("<model></model>", &format!("<model>{model}</model>"))
        .into_bytes()
}

#[test]
fn the_definition_is_read_as_mavsdk_reads_it_and_as_pymavlink_bursts_it() {
    for (family, template) in [
        (Family::DualLight, definition::DUAL_LIGHT),
        (Family::X3, definition::ZOOM),
    ] {
        // Served with the model filled in: no postback yet, so the unknown type's.
        let file = served(template, "IDU camera");
        let file = file.as_slice();
        let mut b = bridge(family);
        // MAVSDK: the path without a leading '/' and with its NUL.
        let r = ftp_ask(&mut b, &ftp(1, 0, OPEN, 0, b"camera.xml\0"));
        assert_eq!(r.len(), 1);
        let p = &r[0].payload;
        assert_eq!((p[3], p[4], p[5]), (ACK, 4, OPEN));
        assert_eq!(
            u32::from_le_bytes(p[12..16].try_into().unwrap()) as usize,
            file.len()
        );
        let session = p[2];
        let mut got = Vec::new();
        let mut seq = 2;
        while got.len() < file.len() {
            // MAVSDK asks for min(239, what is left).
            let mut m = ftp(seq, session, READ, got.len() as u32, &[]);
            m.payload[4] = (file.len() - got.len()).min(239) as u8;
            let r = ftp_ask(&mut b, &m);
            let p = &r[0].payload;
            assert_eq!((p[3], p[5]), (ACK, READ));
            got.extend_from_slice(&p[12..12 + p[4] as usize]);
            seq += 1;
        }
        assert_eq!(got, file);
        // QGroundControl's path, with its '/': a burst from offset 0 brings the whole file.
        let r = ftp_ask(&mut b, &ftp(100, 0, OPEN, 0, b"/camera.xml"));
        let session = r[0].payload[2];
        // pymavlink's burst: 80 bytes a packet (its default burst_read_size).
        let mut m = ftp(101, session, BURST, 0, &[]);
        m.payload[4] = 80;
        let r = ftp_ask(&mut b, &m);
        let mut got = Vec::new();
        for (i, m) in r.iter().enumerate() {
            let p = &m.payload;
            assert_eq!((p[3], p[5]), (ACK, BURST));
            assert_eq!(u16::from_le_bytes([p[0], p[1]]), 102 + i as u16);
            assert_eq!(
                u32::from_le_bytes(p[8..12].try_into().unwrap()) as usize,
                got.len()
            );
            got.extend_from_slice(&p[12..12 + p[4] as usize]);
            assert_eq!(
                p[6] == 1,
                i + 1 == r.len(),
                "burst_complete on the last only"
            );
        }
        assert_eq!(got, file);
    }
}

#[test]
fn the_definitions_model_is_the_camera_informations() {
    // QGroundControl renames the camera to the definition's <model> and lists it under
    // CAMERA_INFORMATION's: they must be one name (camera::definition).
    for (gimbal_type, model) in [
        (GimbalType::X30, "X30-X30GT"),
        (GimbalType::DualLight30x, "30x dual light"),
    ] {
        let mut b = bridge(Family::DualLight);
        let p = Postback {
            gimbal_type,
            ..Postback::default()
        };
        for data in p.to_can_frames() {
            b.link.receive(ids::POSTBACK, &data, t(5));
        }
        let r = ftp_ask(&mut b, &ftp(1, 0, OPEN, 0, b"/camera.xml"));
        let size = u32::from_le_bytes(r[0].payload[12..16].try_into().unwrap()) as usize;
        let want = served(definition::DUAL_LIGHT, model);
        assert_eq!(size, want.len());
        let mut got = Vec::new();
        while got.len() < size {
            let mut m = ftp(
                2 + got.len() as u16,
                r[0].payload[2],
                READ,
                got.len() as u32,
                &[],
            );
            m.payload[4] = 239;
            let p = &ftp_ask(&mut b, &m)[0].payload;
            got.extend_from_slice(&p[12..12 + p[4] as usize]);
        }
        assert_eq!(got, want);
        let xml = String::from_utf8(got).unwrap();
        assert!(xml.contains(&format!("<model>{model}</model>")), "{model}");
        // And CAMERA_INFORMATION (REQUEST_MESSAGE 259, as QGroundControl asks) names the same.
        let (r, frames) = ask(&mut b, MavCmd::RequestMessage, 259.0, 0.0);
        assert_eq!(r, MavResult::Accepted);
        let info: Vec<CameraInformation> = of(&frames);
        assert_eq!(info.len(), 1);
        assert_eq!(text(&info[0].model_name), model);
    }
}

#[test]
fn a_burst_goes_on_to_its_client_while_another_is_answered() {
    let mut b = bridge(Family::DualLight);
    let other: (u8, u8) = (GCS.0, GCS.1 + 1);
    b.receive_all(&frame(GCS, 0, &ftp(1, 0, OPEN, 0, b"/camera.xml")), t(10));
    let _ = sent(&mut b);
    // The burst starts (its first packet answers the request)...
    let mut m = ftp(2, 0, BURST, 0, &[]);
    m.payload[4] = 80;
    b.receive_all(&frame(GCS, 1, &m), t(10));
    // ... and another client asks something before the rest is sent, then asks for a
    // burst of its own that is refused (a size past 239): GCS's burst goes on, to GCS.
    b.receive_all(&frame(other, 0, &ftp(7, 0, 0, 0, &[])), t(10));
    let mut refused = ftp(8, 0, BURST, 0, &[]);
    refused.payload[4] = 240;
    b.receive_all(&frame(other, 1, &refused), t(10));
    let mut frames = sent(&mut b);
    for ms in 11..40 {
        b.poll(t(ms));
        frames.extend(sent(&mut b));
    }
    let replies: Vec<FileTransferProtocol> = of(&frames);
    let to_other: Vec<_> = replies
        .iter()
        .filter(|r| (r.target_system, r.target_component) == other)
        .collect();
    assert_eq!(to_other.len(), 2);
    assert_eq!(to_other[0].payload[5], 0, "the None request's ACK");
    // NAK (129) of the burst request, InvalidDataSize (3).
    assert_eq!(
        (
            to_other[1].payload[3],
            to_other[1].payload[5],
            to_other[1].payload[12]
        ),
        (129, BURST, 3)
    );
    let burst: Vec<_> = replies
        .iter()
        .filter(|r| r.payload[5] == BURST && r.payload[3] == 128)
        .collect();
    let file = served(definition::DUAL_LIGHT, "IDU camera");
    assert_eq!(burst.len(), file.len().div_ceil(80));
    assert!(burst
        .iter()
        .all(|r| (r.target_system, r.target_component) == GCS));
    // The FTP server's counters, through the bridge: four requests, the refused one among
    // them, and every packet of the burst.
    let stats = b.ftp_stats().unwrap();
    assert_eq!(
        (stats.requests, stats.bad_requests, stats.bursts),
        (4, 1, 1)
    );
    assert_eq!(stats.burst_packets as usize, burst.len() - 1);
    // A bridge with no camera has no FTP server.
    let none = idu_gimbal_mavlink::Bridge::new(
        idu_gimbal_mavlink::BridgeConfig::default().check().unwrap(),
    );
    assert!(none.ftp_stats().is_none());
}

#[test]
fn a_set_of_a_type_the_dialect_does_not_know_is_answered() {
    // PARAM_EXT_SET: target 0 and 1, param_id 2..18, param_value 18..146, param_type 146.
    let raw_set = |name: &str, value: u8, ty: u8| {
        let mut p = vec![0u8; 147];
        (p[0], p[1]) = (AP.0, CAMERA);
        p[2..18].copy_from_slice(&param_id(name));
        p[18] = value;
        p[146] = ty;
        raw_frame(GCS, 323, ParamExtSet::crc_extra(), &p)
    };
    // PARAM_EXT_ACK: param_id 0..16, param_value 16..144, param_type 144, result 145.
    let raw_acks = |b: &mut Firmware| -> Vec<Vec<u8>> {
        sent(b)
            .iter()
            .filter(|f| f.message_id() == 324)
            .map(|f| {
                let mut p = f.payload().bytes().to_vec();
                p.resize(146, 0);
                p
            })
            .collect()
    };
    let mut b = bridge(Family::DualLight);
    let unsupported = ParamAck::ValueUnsupported as u8;
    // A type past MAV_PARAM_EXT_TYPE's (11 is its last): answered, once, VALUE_UNSUPPORTED,
    // with the value in effect and its type for a parameter there is.
    for ty in [0u8, 12, 200, 255] {
        b.receive_all(&raw_set("IR_PALETTE", 3, ty), t(10));
        let acks = raw_acks(&mut b);
        assert_eq!(acks.len(), 1, "type {ty}");
        let a = &acks[0];
        assert_eq!(&a[..16], &param_id("IR_PALETTE"));
        assert_eq!(
            (a[16], a[144], a[145]),
            (0, MavParamExtType::Uint8 as u8, unsupported)
        );
        // And an unknown name: echoed, its type as sent.
        b.receive_all(&raw_set("NO_SUCH", 3, ty), t(10));
        let acks = raw_acks(&mut b);
        assert_eq!(acks.len(), 1, "type {ty}");
        assert_eq!(
            (acks[0][16], acks[0][144], acks[0][145]),
            (3, ty, unsupported)
        );
    }
    assert!(queued(&mut b.link).is_empty(), "nothing sent to the gimbal");
}
