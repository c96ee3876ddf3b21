//! The camera (camera protocol v2): capture, zoom, and the RTSP stream, component 100.
//!
//! What the IDU camera offers through MAVLink's basic camera commands:
//!
//! - images: `MAV_CMD_IMAGE_START_CAPTURE` with one image → single shot; N > 1 images →
//!   burst of N; unlimited images at an interval → time-lapse at that interval (whole
//!   seconds, 1 to 255); `MAV_CMD_IMAGE_STOP_CAPTURE` → stop. The gimbal reports no
//!   capture, so `CAMERA_IMAGE_CAPTURED` is sent for each image **commanded** (a burst's N at
//!   once, a time-lapse's at each interval), with `capture_result` 1;
//! - video: `MAV_CMD_VIDEO_START_CAPTURE` / `STOP_CAPTURE`;
//! - zoom (`MAV_CMD_SET_CAMERA_ZOOM`): range (0 to 100 % of the zoom range) → zoom ratio;
//!   continuous (−1, 0, +1) → zoom out, stop, in; step (±1 to ±5) → 2× out or in per step;
//!   focal length and field of view → `UNSUPPORTED`;
//! - one video stream (id 1, RTSP, running) whose URI comes from the configuration (built
//!   with `idu_gimbal::video`): `VIDEO_STREAM_INFORMATION`, and `VIDEO_STREAM_STATUS` (which
//!   MAVSDK's camera plugin polls);
//! - `CAMERA_SETTINGS` (mode, zoom level as the last commanded, in %), `CAMERA_CAPTURE_STATUS`,
//!   `STORAGE_INFORMATION` (one storage, status `NOT_SUPPORTED`: the gimbal does not say).
//!
//! The dual-light camera's thermal palettes have no basic MAVLink command and are left out
//! (no camera definition file is served): use the core's `DualLightCommand::Palette`.

use core::fmt;

use idu_gimbal::wire::control::{Command, GimbalCommand, Photo, Video, Zoom, ZoomRatio};
use idu_gimbal::Instant;
use mavio::dialects::common::enums::{
    CameraCapFlags, CameraMode, CameraZoomType, MavCmd, MavResult, StorageStatus, StorageType,
    StorageUsageFlag, VideoStreamEncoding, VideoStreamStatusFlags, VideoStreamType,
};
use mavio::dialects::common::messages::{
    CameraCaptureStatus, CameraImageCaptured, CameraInformation, CameraSettings, CommandLong,
    StorageInformation, VideoStreamInformation, VideoStreamStatus,
};
use mavio::mavspec::rust::spec::MessageSpecStatic;
use mavio::Message;

use crate::gimbal::GimbalControl;

/// `MAV_COMP_ID_CAMERA`.
pub const CAMERA_COMPONENT: u8 = 100;
/// The longest stream URI `VIDEO_STREAM_INFORMATION` holds.
pub const URI_CAPACITY: usize = 160;

/// A stream URI longer than `VIDEO_STREAM_INFORMATION`'s field: a configuration error,
/// never a truncation.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct UriTooLong {
    /// The URI's length, bytes.
    pub len: usize,
    /// The most the field holds.
    pub max: usize,
}

impl fmt::Display for UriTooLong {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "stream URI is {} bytes; VIDEO_STREAM_INFORMATION holds at most {}",
            self.len, self.max
        )
    }
}

/// The camera component's configuration.
#[derive(Clone, PartialEq, Debug)]
pub struct CameraConfig {
    /// Component id (default [`CAMERA_COMPONENT`], 100).
    pub component: u8,
    /// The largest optical zoom ratio (30 on the X30), for zoom in % and the zoom level.
    pub zoom_max: f32,
    uri: heapless::String<URI_CAPACITY>,
}

impl CameraConfig {
    /// A camera whose video stream is at `uri` (e.g. from `idu_gimbal::video::Camera::url`).
    pub fn new(uri: &str) -> Result<Self, UriTooLong> {
        let too_long = UriTooLong {
            len: uri.len(),
            max: URI_CAPACITY,
        };
        Ok(CameraConfig {
            component: CAMERA_COMPONENT,
            zoom_max: 30.0,
            uri: heapless::String::try_from(uri).map_err(|_| too_long)?,
        })
    }

    /// The stream URI.
    pub fn uri(&self) -> &str {
        &self.uri
    }
}

/// What to send after a command's ACK.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Reply {
    Nothing,
    Information,
    Settings,
    Storage,
    CaptureStatus,
    Stream,
    StreamStatus,
    /// This many images were commanded: one CAMERA_IMAGE_CAPTURED each, then the status.
    Captured(u8),
}

/// What the bridge gives the camera to send with.
pub(crate) struct Tx<'a> {
    pub(crate) send: &'a mut dyn FnMut(u8, &dyn Message),
    /// The vehicle position (lat, lon ×1e7, alt and relative alt in mm), for captures.
    pub(crate) position: Option<[i32; 4]>,
}

/// The camera's state.
#[derive(Clone, Debug)]
pub(crate) struct Camera {
    pub(crate) config: CameraConfig,
    /// The zoom ratio last commanded (the gimbal does not report it).
    zoom: f32,
    images: i32,
    time_lapse: Option<(u32, Instant)>,
    recording_since: Option<Instant>,
}

/// Whether a `COMMAND_LONG` is the camera's to answer.
pub(crate) fn owns(cmd: &CommandLong) -> bool {
    match cmd.command {
        MavCmd::RequestMessage => [
            <CameraInformation as MessageSpecStatic>::spec().id(),
            <CameraSettings as MessageSpecStatic>::spec().id(),
            <StorageInformation as MessageSpecStatic>::spec().id(),
            <CameraCaptureStatus as MessageSpecStatic>::spec().id(),
            <VideoStreamInformation as MessageSpecStatic>::spec().id(),
            <VideoStreamStatus as MessageSpecStatic>::spec().id(),
        ]
        .iter()
        .any(|&id| id as f32 == cmd.param1),
        MavCmd::RequestCameraInformation
        | MavCmd::RequestCameraSettings
        | MavCmd::RequestStorageInformation
        | MavCmd::RequestCameraCaptureStatus
        | MavCmd::RequestVideoStreamInformation
        | MavCmd::RequestVideoStreamStatus
        | MavCmd::ImageStartCapture
        | MavCmd::ImageStopCapture
        | MavCmd::VideoStartCapture
        | MavCmd::VideoStopCapture
        | MavCmd::SetCameraZoom => true,
        _ => false,
    }
}

fn name<const N: usize>(s: &str) -> [u8; N] {
    let mut out = [0u8; N];
    for (dst, src) in out.iter_mut().zip(s.bytes()) {
        *dst = src;
    }
    out
}

impl Camera {
    pub(crate) fn new(config: CameraConfig) -> Self {
        Camera {
            config,
            zoom: 1.0,
            images: 0,
            time_lapse: None,
            recording_since: None,
        }
    }

    /// Acts on a command it owns: the ACK's result, and what to send after the ACK.
    pub(crate) fn command<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        cmd: &CommandLong,
        now: Instant,
    ) -> (MavResult, Reply) {
        let id = if cmd.command == MavCmd::RequestMessage {
            Some(cmd.param1)
        } else {
            None
        };
        let is = |m: u32| id == Some(m as f32);
        let reply = match cmd.command {
            MavCmd::RequestCameraInformation => Reply::Information,
            MavCmd::RequestCameraSettings => Reply::Settings,
            MavCmd::RequestStorageInformation => Reply::Storage,
            MavCmd::RequestCameraCaptureStatus => Reply::CaptureStatus,
            MavCmd::RequestVideoStreamInformation => Reply::Stream,
            MavCmd::RequestVideoStreamStatus => Reply::StreamStatus,
            MavCmd::RequestMessage if is(<CameraInformation as MessageSpecStatic>::spec().id()) => {
                Reply::Information
            }
            MavCmd::RequestMessage if is(<CameraSettings as MessageSpecStatic>::spec().id()) => {
                Reply::Settings
            }
            MavCmd::RequestMessage if is(<StorageInformation as MessageSpecStatic>::spec().id()) => {
                Reply::Storage
            }
            MavCmd::RequestMessage
                if is(<CameraCaptureStatus as MessageSpecStatic>::spec().id()) =>
            {
                Reply::CaptureStatus
            }
            MavCmd::RequestMessage
                if is(<VideoStreamInformation as MessageSpecStatic>::spec().id()) =>
            {
                Reply::Stream
            }
            MavCmd::RequestMessage if is(<VideoStreamStatus as MessageSpecStatic>::spec().id()) => {
                Reply::StreamStatus
            }
            MavCmd::ImageStartCapture => return self.start_capture(gimbal, cmd, now),
            MavCmd::ImageStopCapture => {
                if !gimbal.send(Command::from(GimbalCommand::Photo(Photo::Stop))) {
                    return (MavResult::TemporarilyRejected, Reply::Nothing);
                }
                self.time_lapse = None;
                Reply::CaptureStatus
            }
            MavCmd::VideoStartCapture | MavCmd::VideoStopCapture => {
                let start = cmd.command == MavCmd::VideoStartCapture;
                let v = if start { Video::Start } else { Video::Stop };
                if !gimbal.send(Command::from(GimbalCommand::Video(v))) {
                    return (MavResult::TemporarilyRejected, Reply::Nothing);
                }
                self.recording_since = start.then_some(now);
                Reply::CaptureStatus
            }
            MavCmd::SetCameraZoom => return (self.zoom(gimbal, cmd), Reply::Settings),
            _ => return (MavResult::Unsupported, Reply::Nothing),
        };
        (MavResult::Accepted, reply)
    }

    /// Sends what a command produced (after its ACK).
    pub(crate) fn reply(&mut self, reply: Reply, now: Instant, tx: &mut Tx<'_>) {
        match reply {
            Reply::Nothing => {}
            Reply::Information => self.send_information(now, tx),
            Reply::Settings => self.send_settings(now, tx),
            Reply::Storage => self.send_storage(now, tx),
            Reply::CaptureStatus => self.send_capture_status(now, tx),
            Reply::Stream => self.send_stream(tx),
            Reply::StreamStatus => self.send_stream_status(tx),
            Reply::Captured(n) => {
                for _ in 0..n {
                    self.captured(now, tx);
                }
                self.send_capture_status(now, tx);
            }
        }
    }

    fn start_capture<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        cmd: &CommandLong,
        now: Instant,
    ) -> (MavResult, Reply) {
        let denied = (MavResult::Denied, Reply::Nothing);
        let (interval, total) = (cmd.param2, cmd.param3);
        let whole = |v: f32| v.is_finite() && (0.0..=255.0).contains(&v) && v == libm::truncf(v);
        if !whole(total) || !interval.is_finite() || interval < 0.0 {
            return denied;
        }
        // In range and whole: exact.
        let total = total as u32;
        let photo = match total {
            1 => Ok(Photo::Single),
            0 if interval >= 1.0 => Photo::time_lapse(libm::roundf(interval) as u32),
            0 => return denied,
            n => Photo::burst(n),
        };
        let Ok(photo) = photo else {
            return denied;
        };
        if !gimbal.send(Command::from(GimbalCommand::Photo(photo))) {
            return (MavResult::TemporarilyRejected, Reply::Nothing);
        }
        let reply = match photo {
            Photo::TimeLapse(s) => {
                let period = u32::from(s.get()) * 1000;
                self.time_lapse = Some((period, now.add_millis(period)));
                Reply::CaptureStatus
            }
            Photo::Burst(n) => Reply::Captured(n.get()),
            _ => Reply::Captured(1),
        };
        (MavResult::Accepted, reply)
    }

    fn zoom<G: GimbalControl>(&mut self, gimbal: &mut G, cmd: &CommandLong) -> MavResult {
        let v = cmd.param2;
        let kind = cmd.param1;
        let (commands, ratio): ([Option<GimbalCommand>; 5], f32) =
            if kind == CameraZoomType::ZoomTypeRange as u8 as f32 {
                if !(0.0..=100.0).contains(&v) {
                    return MavResult::Denied;
                }
                let ratio = 1.0 + v / 100.0 * (self.config.zoom_max - 1.0);
                let Ok(r) = ZoomRatio::new(ratio) else {
                    return MavResult::Denied;
                };
                (
                    [Some(GimbalCommand::ZoomRatio(r)), None, None, None, None],
                    ratio,
                )
            } else if kind == CameraZoomType::ZoomTypeContinuous as u8 as f32 {
                let z = if v == 0.0 {
                    Zoom::Stop
                } else if v == 1.0 {
                    Zoom::In
                } else if v == -1.0 {
                    Zoom::Out
                } else {
                    return MavResult::Denied;
                };
                // Continuous zoom leaves the ratio unknown: the level reads NaN until set.
                let ratio = if z == Zoom::Stop { self.zoom } else { f32::NAN };
                (
                    [Some(GimbalCommand::Zoom(z)), None, None, None, None],
                    ratio,
                )
            } else if kind == CameraZoomType::ZoomTypeStep as u8 as f32 {
                if !(v.is_finite() && v == libm::truncf(v) && v != 0.0 && libm::fabsf(v) <= 5.0) {
                    return MavResult::Denied;
                }
                let z = if v > 0.0 { Zoom::Double } else { Zoom::Half };
                // In range and whole: exact.
                let n = libm::fabsf(v) as usize;
                let mut c = [None; 5];
                for slot in c.iter_mut().take(n) {
                    *slot = Some(GimbalCommand::Zoom(z));
                }
                let factor = libm::powf(2.0, v);
                // max/min, not clamp: clamp panics on a NaN or inverted bound.
                (c, (self.zoom * factor).max(1.0).min(self.config.zoom_max))
            } else {
                return MavResult::Unsupported;
            };
        for c in commands.into_iter().flatten() {
            if !gimbal.send(Command::from(c)) {
                return MavResult::TemporarilyRejected;
            }
        }
        self.zoom = ratio;
        MavResult::Accepted
    }

    fn captured(&mut self, now: Instant, tx: &mut Tx<'_>) {
        let [lat, lon, alt, relative_alt] = tx.position.unwrap_or([0; 4]);
        let msg = CameraImageCaptured {
            time_boot_ms: now.as_millis(),
            time_utc: 0,
            camera_id: 0,
            lat,
            lon,
            alt,
            relative_alt,
            q: [f32::NAN; 4],
            image_index: self.images,
            capture_result: 1,
            file_url: [0; 205],
        };
        self.images = self.images.wrapping_add(1);
        (tx.send)(self.config.component, &msg);
    }

    /// Time-lapse images as they fall due.
    pub(crate) fn poll(&mut self, now: Instant, tx: &mut Tx<'_>) {
        if let Some((period, next)) = self.time_lapse {
            if now.is_at_or_after(next) {
                self.time_lapse = Some((period, now.add_millis(period)));
                self.captured(now, tx);
            }
        }
    }

    fn send_information(&self, now: Instant, tx: &mut Tx<'_>) {
        let info = CameraInformation {
            time_boot_ms: now.as_millis(),
            vendor_name: name("IDU"),
            model_name: name("IDU gimbal camera"),
            firmware_version: 0,
            focal_length: f32::NAN,
            sensor_size_h: f32::NAN,
            sensor_size_v: f32::NAN,
            resolution_h: 0,
            resolution_v: 0,
            lens_id: 0,
            flags: CameraCapFlags::CAPTURE_IMAGE
                | CameraCapFlags::CAPTURE_VIDEO
                | CameraCapFlags::CAN_CAPTURE_IMAGE_IN_VIDEO_MODE
                | CameraCapFlags::CAN_CAPTURE_VIDEO_IN_IMAGE_MODE
                | CameraCapFlags::HAS_BASIC_ZOOM
                | CameraCapFlags::HAS_VIDEO_STREAM,
            cam_definition_version: 0,
            cam_definition_uri: [0; 140],
            gimbal_device_id: crate::bridge::GIMBAL_COMPONENT,
            camera_device_id: 0,
        };
        (tx.send)(self.config.component, &info);
    }

    fn zoom_level(&self) -> f32 {
        (self.zoom - 1.0) / (self.config.zoom_max - 1.0) * 100.0
    }

    fn send_settings(&self, now: Instant, tx: &mut Tx<'_>) {
        let s = CameraSettings {
            time_boot_ms: now.as_millis(),
            mode_id: if self.recording_since.is_some() {
                CameraMode::Video
            } else {
                CameraMode::Image
            },
            zoom_level: self.zoom_level(),
            focus_level: f32::NAN,
            camera_device_id: 0,
        };
        (tx.send)(self.config.component, &s);
    }

    fn send_storage(&self, now: Instant, tx: &mut Tx<'_>) {
        let s = StorageInformation {
            time_boot_ms: now.as_millis(),
            storage_id: 1,
            storage_count: 1,
            status: StorageStatus::NotSupported,
            total_capacity: 0.0,
            used_capacity: 0.0,
            available_capacity: 0.0,
            read_speed: 0.0,
            write_speed: 0.0,
            type_: StorageType::Unknown,
            name: [0; 32],
            storage_usage: StorageUsageFlag::SET,
        };
        (tx.send)(self.config.component, &s);
    }

    fn send_capture_status(&self, now: Instant, tx: &mut Tx<'_>) {
        let (image_status, image_interval) = match self.time_lapse {
            Some((period, _)) => (2, period as f32 / 1000.0),
            None => (0, 0.0),
        };
        let s = CameraCaptureStatus {
            time_boot_ms: now.as_millis(),
            image_status,
            video_status: u8::from(self.recording_since.is_some()),
            image_interval,
            recording_time_ms: self
                .recording_since
                .map_or(0, |since| now.millis_since(since)),
            // Unknown: the gimbal does not report its storage.
            available_capacity: f32::NAN,
            image_count: self.images,
            camera_device_id: 0,
        };
        (tx.send)(self.config.component, &s);
    }

    fn send_stream(&self, tx: &mut Tx<'_>) {
        let mut uri = [0u8; URI_CAPACITY];
        for (dst, src) in uri.iter_mut().zip(self.config.uri.bytes()) {
            *dst = src;
        }
        let s = VideoStreamInformation {
            stream_id: 1,
            count: 1,
            type_: VideoStreamType::Rtsp,
            flags: VideoStreamStatusFlags::RUNNING,
            framerate: 0.0,
            resolution_h: 0,
            resolution_v: 0,
            bitrate: 0,
            rotation: 0,
            hfov: 0,
            name: name("main"),
            uri,
            encoding: VideoStreamEncoding::Unknown,
            camera_device_id: 0,
        };
        (tx.send)(self.config.component, &s);
    }

    /// The stream's status (MAVSDK's camera plugin asks for it before it reports the
    /// stream): the same stream, running; what the gimbal does not report is 0 (unknown).
    fn send_stream_status(&self, tx: &mut Tx<'_>) {
        let s = VideoStreamStatus {
            stream_id: 1,
            flags: VideoStreamStatusFlags::RUNNING,
            framerate: 0.0,
            resolution_h: 0,
            resolution_v: 0,
            bitrate: 0,
            rotation: 0,
            hfov: 0,
            camera_device_id: 0,
        };
        (tx.send)(self.config.component, &s);
    }
}
