//! The camera (camera protocol v2): capture, zoom, and the RTSP stream, component 100.
//!
//! What the IDU camera offers through MAVLink's basic camera commands, each taken from
//! `COMMAND_LONG` or `COMMAND_INT` alike:
//!
//! - images: `MAV_CMD_IMAGE_START_CAPTURE` as common.xml defines it (param2 the interval,
//!   param3 the count, 0 until stopped, param4 the single capture's sequence number), run
//!   by the bridge with the gimbal's single shot and reported one `CAMERA_IMAGE_CAPTURED`
//!   per image when it is taken, with consecutive indexes; the latest are kept for
//!   re-requests (see [`crate::capture`]). `MAV_CMD_IMAGE_STOP_CAPTURE` stops it;
//! - video: `MAV_CMD_VIDEO_START_CAPTURE` / `STOP_CAPTURE`;
//! - zoom (`MAV_CMD_SET_CAMERA_ZOOM`): range (0 to 100 % of the zoom range) → zoom ratio;
//!   continuous → zoom in, out or stop by the value's sign (common.xml: "a rate ... the
//!   sign decides the direction"); step (±1 to ±5) → 2× in or out per step; focal length
//!   and field of view → `UNSUPPORTED`. The zoom range follows the gimbal type in the
//!   postback (30× on the X30, X30T and 30× dual light, 3.5× on the 3.5× models) unless
//!   configured; the level reported is the ratio last set, unknown (NaN) after a
//!   continuous zoom, which the gimbal does not report the end of;
//! - one video stream (id 1, RTSP, running) whose URI comes from the configuration (built
//!   with `idu_gimbal::video`): `VIDEO_STREAM_INFORMATION`, and `VIDEO_STREAM_STATUS` (which
//!   MAVSDK's camera plugin polls);
//! - `CAMERA_INFORMATION` (vendor and model from the postback's gimbal type, the gimbal
//!   device's component id as `gimbal_device_id`), `CAMERA_SETTINGS`,
//!   `CAMERA_CAPTURE_STATUS`, `STORAGE_INFORMATION` (one storage, status `NOT_SUPPORTED`:
//!   the gimbal does not say).
//!
//! The dual-light camera's thermal palettes have no basic MAVLink command and are left out
//! (no camera definition file is served): use the core's `DualLightCommand::Palette`.

use core::fmt;

use idu_gimbal::wire::control::{
    Command as GimbalCmd, GimbalCommand, Photo, Video, Zoom, ZoomRatio,
};
use idu_gimbal::wire::postback::GimbalType;
use idu_gimbal::Instant;
use mavio::dialects::common::enums::{
    CameraCapFlags, CameraMode, CameraZoomType, MavCmd, MavResult, StorageStatus, StorageType,
    StorageUsageFlag, VideoStreamEncoding, VideoStreamStatusFlags, VideoStreamType,
};
use mavio::dialects::common::messages::{
    CameraCaptureStatus, CameraImageCaptured, CameraInformation, CameraSettings,
    StorageInformation, VideoStreamInformation, VideoStreamStatus,
};

use crate::bridge::{id_of, name, Tx};
use crate::capture::{Capture, Image, Request};
use crate::command::Command;
use crate::framing::MAX_FRAME_LEN;
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
    /// The largest optical zoom ratio; `None` (the default): from the postback's gimbal
    /// type (see [`zoom_max_of`]).
    pub zoom_max: Option<f32>,
    /// The main stream's resolution (horizontal, vertical), when known: the vendor
    /// document gives none, so `None` by default (reported as 0, "unknown").
    pub resolution: Option<(u16, u16)>,
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
            zoom_max: None,
            resolution: None,
            uri: heapless::String::try_from(uri).map_err(|_| too_long)?,
        })
    }

    /// The stream URI.
    pub fn uri(&self) -> &str {
        &self.uri
    }
}

/// The optical zoom range of a gimbal type, as its name in the vendor document gives it:
/// 30× for the X30, X30T and 30× dual light, 3.5× for the 3.5× and 3.5× dual light;
/// `None` where the document does not say (laser ranging, A2000, unknown codes).
pub fn zoom_max_of(t: GimbalType) -> Option<f32> {
    match t {
        GimbalType::X30 | GimbalType::X30T | GimbalType::DualLight30x => Some(30.0),
        GimbalType::Zoom3_5x | GimbalType::DualLight3_5x => Some(3.5),
        GimbalType::LaserRanging | GimbalType::A2000 | GimbalType::Unknown(_) => None,
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
    /// This image was taken: its CAMERA_IMAGE_CAPTURED, then the status.
    Captured(Image),
    /// Kept images asked for again, indexes first..=last.
    Images(i32, i32),
}

/// The camera's state.
#[derive(Clone, Debug)]
pub(crate) struct Camera {
    pub(crate) config: CameraConfig,
    /// The gimbal device's component id, for `CAMERA_INFORMATION.gimbal_device_id`.
    gimbal_device_id: u8,
    /// The zoom ratio last set; NaN when unknown (after a continuous zoom).
    zoom: f32,
    capture: Capture,
    /// Kept images still to be sent again (first..=last), as the outbox makes room.
    resend: Option<(i32, i32)>,
    recording_since: Option<Instant>,
}

/// Whether a command is the camera's to answer.
pub(crate) fn owns(cmd: &Command) -> bool {
    match cmd.command {
        MavCmd::RequestMessage => [
            id_of::<CameraInformation>(),
            id_of::<CameraSettings>(),
            id_of::<StorageInformation>(),
            id_of::<CameraCaptureStatus>(),
            id_of::<CameraImageCaptured>(),
            id_of::<VideoStreamInformation>(),
            id_of::<VideoStreamStatus>(),
        ]
        .iter()
        .any(|&id| cmd.requests(id)),
        MavCmd::RequestCameraInformation
        | MavCmd::RequestCameraSettings
        | MavCmd::RequestStorageInformation
        | MavCmd::RequestCameraCaptureStatus
        | MavCmd::RequestVideoStreamInformation
        | MavCmd::RequestVideoStreamStatus
        | MavCmd::RequestCameraImageCapture
        | MavCmd::ImageStartCapture
        | MavCmd::ImageStopCapture
        | MavCmd::VideoStartCapture
        | MavCmd::VideoStopCapture
        | MavCmd::SetCameraZoom => true,
        _ => false,
    }
}

/// `param` as a whole number in `i32`, or `None`.
fn whole_i32(v: f32) -> Option<i32> {
    // |v| < 2^31 and whole: the cast is exact.
    (v.is_finite() && v == libm::truncf(v) && libm::fabsf(v) < 2_147_483_648.0).then_some(v as i32)
}

impl Camera {
    pub(crate) fn new(config: CameraConfig, gimbal_device_id: u8) -> Self {
        Camera {
            config,
            gimbal_device_id,
            zoom: 1.0,
            capture: Capture::new(),
            resend: None,
            recording_since: None,
        }
    }

    /// The zoom range now: configured, or from the gimbal type.
    fn zoom_max(&self, gimbal_type: Option<GimbalType>) -> Option<f32> {
        self.config.zoom_max.or(gimbal_type.and_then(zoom_max_of))
    }

    /// Acts on a command it owns: the ACK's result, and what to send after the ACK.
    pub(crate) fn command<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        cmd: &Command,
        now: Instant,
        position: Option<[i32; 4]>,
    ) -> (MavResult, Reply) {
        let reply = match cmd.command {
            MavCmd::RequestCameraInformation => Reply::Information,
            MavCmd::RequestCameraSettings => Reply::Settings,
            MavCmd::RequestStorageInformation => Reply::Storage,
            MavCmd::RequestCameraCaptureStatus => Reply::CaptureStatus,
            MavCmd::RequestVideoStreamInformation => Reply::Stream,
            MavCmd::RequestVideoStreamStatus => Reply::StreamStatus,
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraInformation>()) => {
                Reply::Information
            }
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraSettings>()) => Reply::Settings,
            MavCmd::RequestMessage if cmd.requests(id_of::<StorageInformation>()) => Reply::Storage,
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraCaptureStatus>()) => {
                Reply::CaptureStatus
            }
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraImageCaptured>()) => {
                return self.images_asked(cmd.params[1], cmd.params[2]);
            }
            // The superseded request (param1 the index), which MAVSDK falls back to.
            MavCmd::RequestCameraImageCapture => return self.images_asked(cmd.params[0], 0.0),
            MavCmd::RequestMessage if cmd.requests(id_of::<VideoStreamInformation>()) => {
                Reply::Stream
            }
            MavCmd::RequestMessage if cmd.requests(id_of::<VideoStreamStatus>()) => {
                Reply::StreamStatus
            }
            MavCmd::ImageStartCapture => return self.start_capture(gimbal, cmd, now, position),
            MavCmd::ImageStopCapture => {
                self.capture.stop();
                Reply::CaptureStatus
            }
            MavCmd::VideoStartCapture | MavCmd::VideoStopCapture => {
                let start = cmd.command == MavCmd::VideoStartCapture;
                let v = if start { Video::Start } else { Video::Stop };
                if gimbal
                    .send(GimbalCmd::from(GimbalCommand::Video(v)))
                    .is_err()
                {
                    return (MavResult::TemporarilyRejected, Reply::Nothing);
                }
                self.recording_since = start.then_some(now);
                Reply::CaptureStatus
            }
            MavCmd::SetCameraZoom => {
                let t = gimbal.gimbal_type();
                return (self.zoom(gimbal, cmd, t), Reply::Settings);
            }
            _ => return (MavResult::Unsupported, Reply::Nothing),
        };
        (MavResult::Accepted, reply)
    }

    /// `MAV_CMD_REQUEST_MESSAGE` for `CAMERA_IMAGE_CAPTURED`: param2 the first index (−1:
    /// all), param3 0 or NaN (that one), −1 (all from it) or the last index. `DENIED` for
    /// indexes not taken yet or not given (NaN), `FAILED` for ones no longer kept.
    fn images_asked(&mut self, first: f32, range: f32) -> (MavResult, Reply) {
        let denied = (MavResult::Denied, Reply::Nothing);
        let range = if range.is_nan() { 0.0 } else { range };
        let (Some(first), Some(range)) = (whole_i32(first), whole_i32(range)) else {
            return denied;
        };
        let (first, last) = match (first, range) {
            (-1, _) => (0, i32::MAX),
            (f, 0) if f >= 0 => (f, f),
            (f, -1) if f >= 0 => (f, i32::MAX),
            (f, l) if f >= 0 && l >= f => (f, l),
            _ => return denied,
        };
        if first >= self.capture.count() {
            return denied;
        }
        if self.capture.history(first, last).next().is_none() {
            return (MavResult::Failed, Reply::Nothing);
        }
        (MavResult::Accepted, Reply::Images(first, last))
    }

    fn start_capture<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        cmd: &Command,
        now: Instant,
        position: Option<[i32; 4]>,
    ) -> (MavResult, Reply) {
        let [_, interval, count, sequence] = cmd.params;
        let Ok(request) = Request::from_params(interval, count, sequence) else {
            return (MavResult::Denied, Reply::Nothing);
        };
        if self.capture.is_repeat(&request) {
            // The same capture again (its ACK was lost): acknowledge, take nothing.
            return (MavResult::Accepted, Reply::Nothing);
        }
        // The first image now, or the command is refused whole.
        if gimbal
            .send(GimbalCmd::from(GimbalCommand::Photo(Photo::Single)))
            .is_err()
        {
            return (MavResult::TemporarilyRejected, Reply::Nothing);
        }
        self.capture.start(request, now);
        let image = self.capture.taken(now, position);
        (MavResult::Accepted, Reply::Captured(image))
    }

    fn zoom<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        cmd: &Command,
        gimbal_type: Option<GimbalType>,
    ) -> MavResult {
        let [kind, v, _, _] = cmd.params;
        let (commands, ratio): ([Option<GimbalCommand>; 5], f32) =
            if kind == CameraZoomType::ZoomTypeRange as u8 as f32 {
                if !(0.0..=100.0).contains(&v) {
                    return MavResult::Denied;
                }
                let Some(max) = self.zoom_max(gimbal_type) else {
                    // The range is not known yet (no postback) or not at all (a model the
                    // document gives no zoom for, and none configured).
                    return if gimbal_type.is_none() {
                        MavResult::TemporarilyRejected
                    } else {
                        MavResult::Unsupported
                    };
                };
                let ratio = 1.0 + v / 100.0 * (max - 1.0);
                let Ok(r) = ZoomRatio::new(ratio) else {
                    return MavResult::Denied;
                };
                (
                    [Some(GimbalCommand::ZoomRatio(r)), None, None, None, None],
                    ratio,
                )
            } else if kind == CameraZoomType::ZoomTypeContinuous as u8 as f32 {
                // A rate: only its sign reaches the gimbal, which zooms at its own speed.
                let z = if v.is_nan() {
                    return MavResult::Denied;
                } else if v > 0.0 {
                    Zoom::In
                } else if v < 0.0 {
                    Zoom::Out
                } else {
                    Zoom::Stop
                };
                // Where a continuous zoom ends is not reported: the level is unknown.
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
                // The gimbal stops at its ends; an unknown level stays unknown (NaN through
                // the arithmetic: f32::max/min would turn it into a bound).
                let stepped = self.zoom * libm::powf(2.0, v);
                let ratio = match self.zoom_max(gimbal_type) {
                    _ if stepped.is_nan() => f32::NAN,
                    Some(max) => stepped.max(1.0).min(max),
                    None => stepped.max(1.0),
                };
                (c, ratio)
            } else {
                return MavResult::Unsupported;
            };
        for c in commands.into_iter().flatten() {
            if gimbal.send(GimbalCmd::from(c)).is_err() {
                return MavResult::TemporarilyRejected;
            }
        }
        self.zoom = ratio;
        MavResult::Accepted
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
            Reply::Captured(image) => {
                self.send_captured(&image, tx);
                self.send_capture_status(now, tx);
            }
            Reply::Images(first, last) => {
                self.resend = Some((first, last));
                self.resend_images(tx);
            }
        }
    }

    /// Kept images asked for again, as many as the outbox has room for; the rest at the
    /// next polls.
    fn resend_images(&mut self, tx: &mut Tx<'_>) {
        while let Some((first, last)) = self.resend {
            if tx.room() < MAX_FRAME_LEN {
                return;
            }
            let next = self.capture.history(first, last).next().copied();
            match next {
                Some(image) => {
                    self.send_captured(&image, tx);
                    self.resend = (image.index < last).then_some((image.index + 1, last));
                }
                None => self.resend = None,
            }
        }
    }

    /// Whether [`Camera::poll`] has anything to do at `now`: images due or asked for again.
    pub(crate) fn has_work(&self, now: Instant) -> bool {
        self.resend.is_some() || self.capture.due(now)
    }

    /// Images as they fall due, and images asked for again.
    pub(crate) fn poll<G: GimbalControl>(&mut self, gimbal: &mut G, now: Instant, tx: &mut Tx<'_>) {
        self.resend_images(tx);
        // An image whose command the gimbal's queue has no room for is tried at the next
        // poll: late, never lost.
        if self.capture.due(now)
            && tx.room() >= MAX_FRAME_LEN
            && gimbal
                .send(GimbalCmd::from(GimbalCommand::Photo(Photo::Single)))
                .is_ok()
        {
            let image = self.capture.taken(now, tx.position);
            self.send_captured(&image, tx);
        }
    }

    fn send_captured(&self, image: &Image, tx: &mut Tx<'_>) {
        let [lat, lon, alt, relative_alt] = image.position.unwrap_or([0; 4]);
        let msg = CameraImageCaptured {
            time_boot_ms: image.at.as_millis(),
            time_utc: 0,
            camera_id: 0,
            lat,
            lon,
            alt,
            relative_alt,
            q: [f32::NAN; 4],
            image_index: image.index,
            capture_result: 1,
            file_url: [0; 205],
        };
        tx.send(self.config.component, &msg);
    }

    fn send_information(&self, now: Instant, tx: &mut Tx<'_>) {
        let model = tx
            .gimbal_type
            .and_then(GimbalType::model_name)
            .unwrap_or("IDU gimbal camera");
        let (resolution_h, resolution_v) = self.config.resolution.unwrap_or((0, 0));
        let info = CameraInformation {
            time_boot_ms: now.as_millis(),
            vendor_name: name("IDU"),
            model_name: name(model),
            firmware_version: 0,
            focal_length: f32::NAN,
            sensor_size_h: f32::NAN,
            sensor_size_v: f32::NAN,
            resolution_h,
            resolution_v,
            lens_id: 0,
            flags: CameraCapFlags::CAPTURE_IMAGE
                | CameraCapFlags::CAPTURE_VIDEO
                | CameraCapFlags::CAN_CAPTURE_IMAGE_IN_VIDEO_MODE
                | CameraCapFlags::CAN_CAPTURE_VIDEO_IN_IMAGE_MODE
                | CameraCapFlags::HAS_BASIC_ZOOM
                | CameraCapFlags::HAS_VIDEO_STREAM,
            cam_definition_version: 0,
            cam_definition_uri: [0; 140],
            // The component id of the gimbal this camera is on (common.xml); ArduPilot's
            // AP_Camera_MAVLinkCamV2 reads it to pair the camera with its mount.
            gimbal_device_id: self.gimbal_device_id,
            camera_device_id: 0,
        };
        tx.send(self.config.component, &info);
    }

    /// The zoom level in % of the range; NaN when the level or the range is unknown.
    fn zoom_level(&self, gimbal_type: Option<GimbalType>) -> f32 {
        match self.zoom_max(gimbal_type) {
            Some(max) if max > 1.0 => (self.zoom - 1.0) / (max - 1.0) * 100.0,
            _ => f32::NAN,
        }
    }

    fn send_settings(&self, now: Instant, tx: &mut Tx<'_>) {
        let s = CameraSettings {
            time_boot_ms: now.as_millis(),
            mode_id: if self.recording_since.is_some() {
                CameraMode::Video
            } else {
                CameraMode::Image
            },
            zoom_level: self.zoom_level(tx.gimbal_type),
            focus_level: f32::NAN,
            camera_device_id: 0,
        };
        tx.send(self.config.component, &s);
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
        tx.send(self.config.component, &s);
    }

    fn send_capture_status(&self, now: Instant, tx: &mut Tx<'_>) {
        // common.xml: 0 idle, 3 "interval set and capture in progress".
        let (image_status, image_interval) = match self.capture.interval() {
            Some(ms) => (3, ms as f32 / 1000.0),
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
            image_count: self.capture.count(),
            camera_device_id: 0,
        };
        tx.send(self.config.component, &s);
    }

    fn send_stream(&self, tx: &mut Tx<'_>) {
        let uri = name::<URI_CAPACITY>(self.config.uri());
        let (resolution_h, resolution_v) = self.config.resolution.unwrap_or((0, 0));
        let s = VideoStreamInformation {
            stream_id: 1,
            count: 1,
            type_: VideoStreamType::Rtsp,
            flags: VideoStreamStatusFlags::RUNNING,
            framerate: 0.0,
            resolution_h,
            resolution_v,
            bitrate: 0,
            rotation: 0,
            hfov: 0,
            name: name("main"),
            uri,
            encoding: VideoStreamEncoding::Unknown,
            camera_device_id: 0,
        };
        tx.send(self.config.component, &s);
    }

    /// The stream's status (MAVSDK's camera plugin asks for it before it reports the
    /// stream): the same stream, running; what the gimbal does not report is 0 (unknown).
    fn send_stream_status(&self, tx: &mut Tx<'_>) {
        let (resolution_h, resolution_v) = self.config.resolution.unwrap_or((0, 0));
        let s = VideoStreamStatus {
            stream_id: 1,
            flags: VideoStreamStatusFlags::RUNNING,
            framerate: 0.0,
            resolution_h,
            resolution_v,
            bitrate: 0,
            rotation: 0,
            hfov: 0,
            camera_device_id: 0,
        };
        tx.send(self.config.component, &s);
    }
}
