//! The camera (camera protocol v2), component 100: capture, zoom, focus, click-to-track,
//! every video stream of the family, and the settings of its camera definition file.
//!
//! What the IDU camera offers through MAVLink, each command taken from `COMMAND_LONG` or
//! `COMMAND_INT` alike:
//!
//! - images: `MAV_CMD_IMAGE_START_CAPTURE` as common.xml defines it (param2 the interval,
//!   param3 the count, 0 until stopped, param4 the single capture's sequence number), run
//!   by the bridge with the gimbal's single shot and reported one `CAMERA_IMAGE_CAPTURED`
//!   per image when it is taken, with consecutive indexes; the latest are kept for
//!   re-requests (see [`crate::capture`]). `MAV_CMD_IMAGE_STOP_CAPTURE` stops it;
//! - video: `MAV_CMD_VIDEO_START_CAPTURE` / `STOP_CAPTURE`, with `CAMERA_CAPTURE_STATUS`
//!   while recording at the rate the start's param2 asks (Hz: 0 or NaN none, 0.001 to 1000);
//! - zoom and focus (`MAV_CMD_SET_CAMERA_ZOOM`, `MAV_CMD_SET_CAMERA_FOCUS`): see [`lens`].
//!   The zoom range follows the gimbal type in the postback (30× on the X30, X30T and 30×
//!   dual light, 3.5× on the 3.5× models) unless configured;
//! - tracking (`MAV_CMD_CAMERA_TRACK_POINT`, `TRACK_RECTANGLE`, `STOP_TRACKING`) and
//!   `CAMERA_TRACKING_IMAGE_STATUS`: see [`tracking`]. `MAV_CMD_SET_CAMERA_SOURCE` (param2
//!   `CAMERA_SOURCE_RGB` or `IR`) picks the image the dual light tracks on;
//! - every stream of the family (`VIDEO_STREAM_INFORMATION`, `VIDEO_STREAM_STATUS`): see
//!   [`stream`];
//! - on a camera with a thermal sensor, the camera definition file (served over MAVLink
//!   FTP, see [`definition`] and [`crate::ftp`]) and its settings (the extended parameter
//!   protocol, see [`settings`]);
//! - `MAV_CMD_RESET_CAMERA_SETTINGS`: the settings back to their defaults (see
//!   [`settings`]);
//! - `CAMERA_INFORMATION` (vendor and model from the postback's gimbal type, the gimbal
//!   device's component id as `gimbal_device_id`), `CAMERA_SETTINGS`,
//!   `CAMERA_CAPTURE_STATUS`, `STORAGE_INFORMATION` (one storage, status `NOT_SUPPORTED`:
//!   the gimbal does not say).
//!
//! Pointing zoom and pointing focus (0x0F 0x01, 0x14: a point of the image) have no
//! MAVLink command, and a ground station's click on the video means tracking, so they are
//! not offered.

mod config;
pub mod definition;
pub mod fov;
pub mod lens;
mod periodic;
pub mod settings;
pub mod stream;
pub mod tracking;

use idu_gimbal::wire::control::{Command as GimbalCmd, GimbalCommand, Photo, Video};
use idu_gimbal::wire::postback::GimbalType;
use idu_gimbal::Instant;
use mavio::dialects::common::enums::{
    CameraCapFlags, CameraMode, CameraSource, MavCmd, MavResult, StorageStatus, StorageType,
    StorageUsageFlag,
};
use mavio::dialects::common::messages::{
    CameraCaptureStatus, CameraFovStatus, CameraImageCaptured, CameraInformation, CameraSettings,
    CameraTrackingImageStatus, FileTransferProtocol, ParamExtRequestList, ParamExtRequestRead,
    ParamExtSet, StorageInformation, VideoStreamInformation, VideoStreamStatus,
};

use crate::capture::{Capture, Image, Request, Vantage};
use crate::command::Command;
use crate::framing::MAX_FRAME_LEN;
use crate::ftp::{FtpServer, PAYLOAD_LEN};
use crate::tx::{id_of, name, Tx};
use config::UNKNOWN_MODEL;
use idu_gimbal::link::{Link, Medium};
use periodic::Periodic;
use settings::Settings;
use tracking::{Source, Tracking};

pub use config::{
    camera_model, zoom_max_of, CameraConfig, StreamError, UriTooLong, CAMERA_COMPONENT,
    FTP_SESSIONS, URI_CAPACITY,
};

/// What to send after a command's ACK.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Reply {
    Nothing,
    Information,
    Settings,
    Storage,
    CaptureStatus,
    TrackingStatus,
    FovStatus,
    /// This image was taken: its CAMERA_IMAGE_CAPTURED, then the status.
    Captured(Image),
    /// Kept images asked for again, indexes first..=last.
    Images(i32, i32),
}

/// A message for the camera other than a command, decoded.
#[derive(Clone, Debug)]
pub(crate) enum Message {
    /// A `FILE_TRANSFER_PROTOCOL` request's payload.
    Ftp([u8; PAYLOAD_LEN]),
    ParamList,
    /// `PARAM_EXT_REQUEST_READ`: the name and the index.
    ParamRead([u8; 16], i16),
    ParamSet(crate::codec::param_ext::ParamSet),
}

/// The MAVLink camera component's state (the RTSP address builder is `video::Camera`).
#[derive(Clone, Debug)]
pub(crate) struct CameraComponent {
    /// The gimbal device's component id, for `CAMERA_INFORMATION.gimbal_device_id`.
    gimbal_device_id: u8,
    /// The zoom ratio last set; NaN when unknown (after a continuous zoom).
    zoom: f32,
    /// The mode last set (`MAV_CMD_SET_CAMERA_MODE`), image at start.
    mode: CameraMode,
    capture: Capture,
    /// Kept images still to be sent again (first..=last), as the outbox makes room.
    resend: Option<(i32, i32)>,
    recording_since: Option<Instant>,
    streams: stream::Pending,
    tracking: Tracking,
    fov_status: Periodic,
    /// `CAMERA_CAPTURE_STATUS` while recording, at the rate `VIDEO_START_CAPTURE` asked.
    recording_status: Periodic,
    settings: Settings,
    ftp: FtpServer<FTP_SESSIONS>,
}

/// A mask of the lowest `n` bits (of streams, of parameters); all eight for `n` >= 8.
pub(crate) fn low_bits(n: usize) -> u8 {
    // A shift by 8 (n = 0) is out of range: no bits.
    u8::MAX
        .checked_shr(8u32.saturating_sub(n as u32))
        .unwrap_or(0)
}

/// What the camera can do (`CAMERA_INFORMATION.flags`): photos and video in either mode, the
/// photo/video switch, zoom and focus, video streams, tracking a point or a rectangle.
const CAP_FLAGS: CameraCapFlags = CameraCapFlags::CAPTURE_IMAGE
    .union(CameraCapFlags::CAPTURE_VIDEO)
    .union(CameraCapFlags::HAS_MODES)
    .union(CameraCapFlags::CAN_CAPTURE_IMAGE_IN_VIDEO_MODE)
    .union(CameraCapFlags::CAN_CAPTURE_VIDEO_IN_IMAGE_MODE)
    .union(CameraCapFlags::HAS_BASIC_ZOOM)
    .union(CameraCapFlags::HAS_BASIC_FOCUS)
    .union(CameraCapFlags::HAS_VIDEO_STREAM)
    .union(CameraCapFlags::HAS_TRACKING_POINT)
    .union(CameraCapFlags::HAS_TRACKING_RECTANGLE);

/// Messages other than commands the camera answers.
pub(crate) fn handles(id: u32) -> bool {
    id == id_of::<FileTransferProtocol>()
        || id == id_of::<ParamExtSet>()
        || id == id_of::<ParamExtRequestRead>()
        || id == id_of::<ParamExtRequestList>()
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
            id_of::<CameraTrackingImageStatus>(),
            id_of::<CameraFovStatus>(),
        ]
        .iter()
        .any(|&id| cmd.requests(id)),
        MavCmd::SetMessageInterval => [
            id_of::<CameraTrackingImageStatus>(),
            id_of::<CameraFovStatus>(),
        ]
        .iter()
        .any(|&id| cmd.params[0] == id as f32),
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
        | MavCmd::SetCameraZoom
        | MavCmd::SetCameraFocus
        | MavCmd::CameraTrackPoint
        | MavCmd::CameraTrackRectangle
        | MavCmd::CameraStopTracking
        | MavCmd::SetCameraSource
        | MavCmd::ResetCameraSettings
        | MavCmd::SetCameraMode => true,
        _ => false,
    }
}

/// `param` as a whole number in `i32`, or `None`.
fn whole_i32(v: f32) -> Option<i32> {
    // |v| < 2^31 and whole: the cast is exact.
    (v.is_finite() && v == libm::truncf(v) && libm::fabsf(v) < 2_147_483_648.0).then_some(v as i32)
}

impl CameraComponent {
    pub(crate) fn new(config: &CameraConfig, gimbal_device_id: u8) -> Self {
        CameraComponent {
            gimbal_device_id,
            zoom: 1.0,
            mode: CameraMode::Image,
            capture: Capture::new(),
            resend: None,
            recording_since: None,
            streams: stream::Pending::default(),
            tracking: Tracking::default(),
            fov_status: Periodic::default(),
            recording_status: Periodic::default(),
            settings: Settings::new(config.has_thermal()),
            ftp: FtpServer::new(),
        }
    }

    /// The zoom range now: configured, or from the gimbal type.
    fn zoom_max(&self, config: &CameraConfig, gimbal_type: Option<GimbalType>) -> Option<f32> {
        config.zoom_max.or(gimbal_type.and_then(zoom_max_of))
    }

    /// Acts on a command it owns: the ACK's result, and what to send after the ACK.
    pub(crate) fn command<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        config: &CameraConfig,
        gimbal: &mut Link<Q, T, M>,
        cmd: &Command,
        from: (u8, u8),
        now: Instant,
        vantage: Vantage,
    ) -> (MavResult, Reply) {
        let streams = |id| stream::selection(config, id);
        let reply = match cmd.command {
            // No identity before the postback gives the gimbal type: ground stations keep
            // the first they read (see `camera_model`). The client asks again.
            MavCmd::RequestCameraInformation if gimbal.gimbal_type().is_none() => {
                return (MavResult::TemporarilyRejected, Reply::Nothing)
            }
            MavCmd::RequestMessage
                if cmd.requests(id_of::<CameraInformation>()) && gimbal.gimbal_type().is_none() =>
            {
                return (MavResult::TemporarilyRejected, Reply::Nothing)
            }
            MavCmd::RequestCameraInformation => Reply::Information,
            MavCmd::RequestCameraSettings => Reply::Settings,
            MavCmd::RequestStorageInformation => Reply::Storage,
            MavCmd::RequestCameraCaptureStatus => Reply::CaptureStatus,
            // The superseded requests: param1 the stream id, 0 for all.
            MavCmd::RequestVideoStreamInformation | MavCmd::RequestVideoStreamStatus => {
                let Some(s) = streams(cmd.params[0]) else {
                    return (MavResult::Denied, Reply::Nothing);
                };
                if cmd.command == MavCmd::RequestVideoStreamInformation {
                    self.streams.information(s);
                } else {
                    self.streams.status(s);
                }
                Reply::Nothing
            }
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraInformation>()) => {
                Reply::Information
            }
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraSettings>()) => Reply::Settings,
            MavCmd::RequestMessage if cmd.requests(id_of::<StorageInformation>()) => Reply::Storage,
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraCaptureStatus>()) => {
                Reply::CaptureStatus
            }
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraTrackingImageStatus>()) => {
                Reply::TrackingStatus
            }
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraFovStatus>()) => Reply::FovStatus,
            MavCmd::RequestMessage if cmd.requests(id_of::<CameraImageCaptured>()) => {
                return self.images_asked(cmd.params[1], cmd.params[2]);
            }
            // The superseded request (param1 the index), which MAVSDK falls back to.
            MavCmd::RequestCameraImageCapture => return self.images_asked(cmd.params[0], 0.0),
            // common.xml: param2 the stream id, 0 for all.
            MavCmd::RequestMessage => {
                let Some(s) = streams(cmd.params[1]) else {
                    return (MavResult::Denied, Reply::Nothing);
                };
                if cmd.requests(id_of::<VideoStreamInformation>()) {
                    self.streams.information(s);
                } else {
                    self.streams.status(s);
                }
                Reply::Nothing
            }
            MavCmd::SetMessageInterval => {
                let [message, interval, ..] = cmd.params;
                let result = if message == id_of::<CameraFovStatus>() as f32 {
                    fov::set_interval(&mut self.fov_status, interval, now)
                } else {
                    self.tracking.set_interval(interval, now)
                };
                return (result, Reply::Nothing);
            }
            MavCmd::ImageStartCapture => {
                return self.start_capture(gimbal, cmd, from, now, vantage)
            }
            MavCmd::ImageStopCapture => {
                self.capture.stop();
                Reply::CaptureStatus
            }
            MavCmd::VideoStartCapture | MavCmd::VideoStopCapture => {
                let start = cmd.command == MavCmd::VideoStartCapture;
                // param1: the stream recorded, 0 for all (NaN, left out, taken so); the
                // gimbal records its one video whichever, but an id it has not is refused.
                let stream = cmd.params[0];
                if !stream.is_nan() && streams(stream).is_none() {
                    return (MavResult::Denied, Reply::Nothing);
                }
                // common.xml: VIDEO_START_CAPTURE's param2 is how often (Hz) to send
                // CAMERA_CAPTURE_STATUS while recording, 0 for never (NaN taken so).
                let hz = cmd.params[1];
                // 1 ms to 1000 s: a longer period would pass the tick's half range.
                if !(hz.is_nan() || hz == 0.0 || (0.001..=1000.0).contains(&hz)) {
                    return (MavResult::Denied, Reply::Nothing);
                }
                // 0 and NaN: none (0 ms); else the period truncated.
                let period_ms = if start && hz > 0.0 {
                    (1000.0 / hz) as u32
                } else {
                    0
                };
                let v = if start { Video::Start } else { Video::Stop };
                if gimbal
                    .send(GimbalCmd::from(GimbalCommand::Video(v)))
                    .is_err()
                {
                    return (MavResult::TemporarilyRejected, Reply::Nothing);
                }
                self.recording_since = start.then_some(now);
                // The status the ACK is followed by is the first.
                self.recording_status
                    .set(period_ms, now.add_millis(period_ms));
                Reply::CaptureStatus
            }
            MavCmd::SetCameraZoom => {
                let t = gimbal.gimbal_type();
                return (self.zoom(gimbal, config, cmd.params, t), Reply::Settings);
            }
            // common.xml: "Camera must respond with a CAMERA_SETTINGS message (on success)".
            MavCmd::SetCameraFocus => {
                let result = lens::focus(gimbal, cmd.params);
                let reply = if result == MavResult::Accepted {
                    Reply::Settings
                } else {
                    Reply::Nothing
                };
                return (result, reply);
            }
            MavCmd::CameraTrackPoint => {
                return (self.tracking.point(gimbal, cmd.params), Reply::Nothing)
            }
            MavCmd::CameraTrackRectangle => {
                return (self.tracking.rectangle(gimbal, cmd.params), Reply::Nothing)
            }
            MavCmd::CameraStopTracking => return (self.tracking.stop(gimbal), Reply::Nothing),
            MavCmd::SetCameraSource => {
                return (self.set_source(config, cmd.params), Reply::Nothing)
            }
            // param2 the mode. Both capture in either (the CAN_CAPTURE_*_IN_*_MODE flags), so
            // the mode is the ground station's choice of shutter, told back in
            // CAMERA_SETTINGS: QGroundControl shows its photo/video switch only with
            // HAS_MODES and never reads the mode back itself (PhotoVideoControl.qml).
            MavCmd::SetCameraMode => {
                let [_, mode, _, _] = cmd.params;
                self.mode = if mode == CameraMode::Image as u8 as f32 {
                    CameraMode::Image
                } else if mode == CameraMode::Video as u8 as f32 {
                    CameraMode::Video
                } else {
                    // Survey (2) and anything else: no such mode here.
                    return (MavResult::Denied, Reply::Nothing);
                };
                Reply::Settings
            }
            // Answered ACCEPTED or TEMPORARILY_REJECTED, never DENIED or UNSUPPORTED: on those
            // QGroundControl stays "resetting" and ignores its photo, video and mode buttons
            // until it restarts (`VehicleCameraControl.cc` `_mavCommandResult`).
            MavCmd::ResetCameraSettings => {
                let result = self.settings.reset(gimbal);
                // A reset turned away changes nothing, the mode included.
                let reply = if result == MavResult::Accepted {
                    self.mode = CameraMode::Image;
                    Reply::Settings
                } else {
                    Reply::Nothing
                };
                return (result, reply);
            }
            _ => return (MavResult::Unsupported, Reply::Nothing),
        };
        (MavResult::Accepted, reply)
    }

    /// `MAV_CMD_SET_CAMERA_SOURCE`: param2 the primary source, the image tracking works
    /// on. Infrared only on a camera with a thermal sensor; a secondary source (param3,
    /// picture in picture) is not something the gimbal can be told.
    fn set_source(&mut self, config: &CameraConfig, params: [f32; 4]) -> MavResult {
        let [_, primary, secondary, _] = params;
        if secondary != 0.0 {
            return MavResult::Denied;
        }
        self.tracking.source = if primary == CameraSource::Default as u8 as f32
            || primary == CameraSource::Rgb as u8 as f32
        {
            Source::Visible
        } else if primary == CameraSource::Ir as u8 as f32 && config.has_thermal() {
            Source::Infrared
        } else {
            return MavResult::Denied;
        };
        MavResult::Accepted
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

    fn start_capture<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        cmd: &Command,
        from: (u8, u8),
        now: Instant,
        vantage: Vantage,
    ) -> (MavResult, Reply) {
        let [_, interval, count, sequence] = cmd.params;
        let Ok(request) = Request::from_params(interval, count, sequence) else {
            return (MavResult::Denied, Reply::Nothing);
        };
        if self.capture.is_repeat(&request, from, now) {
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
        self.capture.start(request, from, now);
        let image = self.capture.taken(now, vantage);
        (MavResult::Accepted, Reply::Captured(image))
    }

    /// Sends what a command produced (after its ACK).
    pub(crate) fn reply<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        config: &CameraConfig,
        gimbal: &Link<Q, T, M>,
        reply: Reply,
        now: Instant,
        tx: &mut Tx<'_>,
    ) {
        match reply {
            Reply::Nothing => {}
            Reply::Information => self.send_information(config, now, tx),
            Reply::Settings => self.send_settings(config, now, tx),
            Reply::Storage => self.send_storage(config, now, tx),
            Reply::CaptureStatus => self.send_capture_status(config, now, tx),
            Reply::TrackingStatus => self.tracking.send_status(gimbal, config.component, now, tx),
            Reply::FovStatus => fov::send_status(config, &mut self.fov_status, self.zoom, now, tx),
            Reply::Captured(image) => {
                self.send_captured(config, &image, tx);
                self.send_capture_status(config, now, tx);
            }
            Reply::Images(first, last) => {
                self.resend = Some((first, last));
                self.resend_images(config, tx);
            }
        }
        // What a request for streams left waiting, as far as there is room.
        self.streams.send(config, self.zoom, tx);
    }

    /// Kept images asked for again, as many as the outbox has room for; the rest at the
    /// next polls.
    fn resend_images(&mut self, config: &CameraConfig, tx: &mut Tx<'_>) {
        while let Some((first, last)) = self.resend {
            if tx.out.room() < MAX_FRAME_LEN {
                return;
            }
            let next = self.capture.history(first, last).next().copied();
            match next {
                Some(image) => {
                    self.send_captured(config, &image, tx);
                    self.resend = image
                        .index
                        .checked_add(1)
                        .filter(|&next| next <= last)
                        .map(|next| (next, last));
                }
                None => self.resend = None,
            }
        }
    }

    /// Whether [`CameraComponent::poll`] has anything to do at `now`: images due or asked for again,
    /// streams or parameters still to describe, a burst read, the tracking status.
    pub(crate) fn has_work(&self, now: Instant) -> bool {
        self.resend.is_some()
            || self.capture.due(now)
            || self.streams.any()
            || self.settings.pending()
            || self.ftp.burst_pending()
            || self.tracking.due(now)
            || self.fov_status.due(now)
            || self.recording_status.due(now)
    }

    /// Images as they fall due, what requests left waiting for room in the outbox, the
    /// burst read in progress and the tracking status.
    pub(crate) fn poll<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        config: &CameraConfig,
        gimbal: &mut Link<Q, T, M>,
        now: Instant,
        tx: &mut Tx<'_>,
    ) {
        self.resend_images(config, tx);
        self.streams.send(config, self.zoom, tx);
        self.settings.send_pending(config.component, tx);
        while self.ftp.burst_pending() && tx.out.room() >= MAX_FRAME_LEN {
            let mut payload = [0u8; PAYLOAD_LEN];
            let files = [self.definition(config, tx)];
            let Some(client) = self.ftp.burst_next(&files, now, &mut payload) else {
                break;
            };
            self.send_ftp(config, payload, client, tx);
        }
        if self.tracking.due(now) && tx.out.room() >= MAX_FRAME_LEN {
            self.tracking.send_status(gimbal, config.component, now, tx);
        }
        if self.recording_status.due(now) && tx.out.room() >= MAX_FRAME_LEN {
            self.recording_status.sent(now);
            self.send_capture_status(config, now, tx);
        }
        if self.fov_status.due(now) && tx.out.room() >= MAX_FRAME_LEN {
            fov::send_status(config, &mut self.fov_status, self.zoom, now, tx);
        }
        // An image whose command the gimbal's queue has no room for is tried at the next
        // poll: late, never lost.
        if self.capture.due(now)
            && tx.out.room() >= MAX_FRAME_LEN
            && gimbal
                .send(GimbalCmd::from(GimbalCommand::Photo(Photo::Single)))
                .is_ok()
        {
            let image = self.capture.taken(now, tx.vantage);
            self.send_captured(config, &image, tx);
        }
    }

    /// The FTP server's counters.
    pub(crate) fn ftp_stats(&self) -> crate::ftp::FtpStats {
        self.ftp.stats()
    }

    /// A message other than a command, addressed to the camera ([`handles`]): FTP and the
    /// extended parameters.
    pub(crate) fn message<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        config: &CameraConfig,
        gimbal: &mut Link<Q, T, M>,
        message: Message,
        from: (u8, u8),
        now: Instant,
        tx: &mut Tx<'_>,
    ) {
        match message {
            Message::Ftp(request) => {
                let mut reply = [0u8; PAYLOAD_LEN];
                let files = [self.definition(config, tx)];
                if self.ftp.request(&files, from, &request, now, &mut reply) {
                    self.send_ftp(config, reply, from, tx);
                }
            }
            Message::ParamList => self.settings.list(),
            Message::ParamRead(id, index) => self.settings.read(&id, index, config.component, tx),
            Message::ParamSet(set) => self.settings.set(gimbal, &set, config.component, tx),
        }
        self.settings.send_pending(config.component, tx);
    }

    /// The camera definition served: the family's, its model `CAMERA_INFORMATION`'s.
    fn definition(&self, config: &CameraConfig, tx: &Tx<'_>) -> crate::ftp::File<'static> {
        let model = tx.gimbal_type.map_or(UNKNOWN_MODEL, camera_model);
        definition::file(config.has_thermal(), model)
    }

    fn send_ftp(
        &self,
        config: &CameraConfig,
        payload: [u8; PAYLOAD_LEN],
        to: (u8, u8),
        tx: &mut Tx<'_>,
    ) {
        let m = FileTransferProtocol {
            target_network: 0,
            target_system: to.0,
            target_component: to.1,
            payload,
        };
        tx.out.send(config.component, &m);
    }

    fn send_captured(&self, config: &CameraConfig, image: &Image, tx: &mut Tx<'_>) {
        let [lat, lon, alt, relative_alt] = image.vantage.position.unwrap_or([0; 4]);
        let q = image.vantage.quaternion();
        let msg = CameraImageCaptured {
            time_boot_ms: image.at.as_millis(),
            time_utc: 0,
            camera_id: 0,
            lat,
            lon,
            alt,
            relative_alt,
            q,
            image_index: image.index,
            capture_result: 1,
            file_url: [0; 205],
        };
        tx.out.send(config.component, &msg);
    }

    fn send_information(&self, config: &CameraConfig, now: Instant, tx: &mut Tx<'_>) {
        let Some(model) = tx.gimbal_type.map(camera_model) else {
            return;
        };
        let (resolution_h, resolution_v) = config.resolution.unwrap_or((0, 0));
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
            flags: CAP_FLAGS,
            cam_definition_version: definition::VERSION,
            cam_definition_uri: name(definition::URI),
            // The component id of the gimbal this camera is on (common.xml); ArduPilot's
            // AP_Camera_MAVLinkCamV2 reads it to pair the camera with its mount.
            gimbal_device_id: self.gimbal_device_id,
            camera_device_id: 0,
        };
        tx.out.send(config.component, &info);
    }

    /// The zoom level in % of the range; NaN when the level or the range is unknown.
    fn zoom_level(&self, config: &CameraConfig, gimbal_type: Option<GimbalType>) -> f32 {
        match self.zoom_max(config, gimbal_type) {
            Some(max) if max > 1.0 => (self.zoom - 1.0) / (max - 1.0) * 100.0,
            _ => f32::NAN,
        }
    }

    fn send_settings(&self, config: &CameraConfig, now: Instant, tx: &mut Tx<'_>) {
        let s = CameraSettings {
            time_boot_ms: now.as_millis(),
            mode_id: self.mode,
            zoom_level: self.zoom_level(config, tx.gimbal_type),
            focus_level: f32::NAN,
            camera_device_id: 0,
        };
        tx.out.send(config.component, &s);
    }

    fn send_storage(&self, config: &CameraConfig, now: Instant, tx: &mut Tx<'_>) {
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
        tx.out.send(config.component, &s);
    }

    fn send_capture_status(&self, config: &CameraConfig, now: Instant, tx: &mut Tx<'_>) {
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
        tx.out.send(config.component, &s);
    }
}
