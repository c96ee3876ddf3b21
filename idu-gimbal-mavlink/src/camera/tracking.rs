//! Click-to-track: `MAV_CMD_CAMERA_TRACK_POINT`, `MAV_CMD_CAMERA_TRACK_RECTANGLE` and
//! `MAV_CMD_CAMERA_STOP_TRACKING` to the gimbal's start / stop tracking (0x0F 0x05 / 0x06,
//! or the dual light's 0x1F 0x05 / 0x07 while the infrared image is the source), and
//! `CAMERA_TRACKING_IMAGE_STATUS` from the postback's tracking flag.
//!
//! **Coordinates.** MAVLink gives the image normalized, 0..1 from the top-left corner; the
//! document's image is 0..8191 on both axes from the same corner. A box's centre is the
//! midpoint scaled by 8191 and rounded; its sides are scaled by 8192 (the image's width in
//! units) and sent divided by 16, rounded, so the largest side the byte carries is
//! 255 × 16 = 4080 units, 0.498 of the image. A larger box is refused (`DENIED`), never
//! shrunk: the gimbal would lock onto something smaller than what was drawn. A rectangle's
//! corners may come in either order. A point (radius r, "1 is full image width") becomes
//! the box of side 2r, and at least [`POINT_BOX_SIDE`]: the tracker needs an area to
//! follow, and "0 is one pixel" gives it none.
//!
//! **Status.** The postback says whether the gimbal tracks, not where the target is in the
//! image. The gimbal's tracker turns the gimbal to keep its target at the image's centre,
//! so while it tracks what the bridge started, the status gives the target there, with the
//! size it was given: a point at (0.5, 0.5) with the radius of the box sent (the
//! commanded one, or half [`POINT_BOX_SIDE`] when that is larger), or the commanded
//! rectangle centred on it (`target_data` `IN_STATUS`). Between the command and the
//! gimbal's turn the target is still off centre: the box says where it is being brought.
//! Tracking the bridge did not start (the gimbal's own controls) is `ACTIVE` with no mode
//! and no box, nothing invented. The status is sent when asked (`MAV_CMD_REQUEST_MESSAGE`),
//! at the interval set with `MAV_CMD_SET_MESSAGE_INTERVAL`, and, with no interval set, every
//! [`TRACKING_STATUS_MS`] while tracking the bridge started and once `IDLE` when it stops:
//! QGroundControl 5.0 never asks for it (`_requestTrackingStatus` has no caller) and draws
//! the box from it. An interval of −1 stops it altogether.
//!
//! What the clients send and read (QGroundControl at HTRamsey/qgroundcontrol c15cc32, which
//! tracks master; MAVSDK at mavlink/MAVSDK 158e339, the 4.1 wheel's source):
//! - QGroundControl shows its tracking button for either capability flag
//!   (`VehicleCameraControl.cc`:130-138); a click sends `TRACK_POINT` with a radius of 20
//!   pixels of the video's width, a drag `TRACK_RECTANGLE` with its corners sorted
//!   (`FlyViewVideo.qml`:101, 141-180), each followed by `SET_MESSAGE_INTERVAL` for this
//!   status at 500,000 µs, and stop by −1 (`VehicleCameraControl.cc`:2334-2408). It draws
//!   the box only while `tracking_status` is `ACTIVE` alone (`VehicleCameraControl.h`:133).
//! - MAVSDK's `track_point`, `track_rectangle` and `track_stop` send the same commands with
//!   their unset params NaN (`camera_impl.cpp`:224-262); it never asks for the status.
//! - ArduPilot's `AP_Camera_MAVLinkCamV2` forwards no tracking to a MAVLink camera (it has no
//!   `set_tracking`): the ground station addresses the camera, and ArduPilot routes it.

use idu_gimbal::wire::control::{
    Command as GimbalCmd, DualLightCommand, GimbalCommand, ImagePoint, TrackingBox,
};
use idu_gimbal::Instant;
use mavio::dialects::common::enums::{
    CameraTrackingMode, CameraTrackingStatusFlags, CameraTrackingTargetData, MavResult,
};
use mavio::dialects::common::messages::CameraTrackingImageStatus;

use crate::command::Interval;
use crate::tx::Tx;
use idu_gimbal::link::{Link, Medium};

/// The status's period while tracking when no interval was set, ms: QGroundControl's own
/// ask (500,000 µs).
pub const TRACKING_STATUS_MS: u32 = 500;

/// The smallest box a point is tracked with, image units (1/32 of the image).
pub const POINT_BOX_SIDE: f32 = 256.0;
/// Image units across the image (0..8191).
const IMAGE_UNITS: f32 = 8192.0;

/// Which image the tracker works on: the visible camera's (0x0F), or the dual light's
/// infrared (0x1F), selected with `MAV_CMD_SET_CAMERA_SOURCE`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub(crate) enum Source {
    #[default]
    Visible,
    Infrared,
}

/// A tracking the bridge started.
#[derive(Clone, Copy, Debug)]
struct Started {
    mode: CameraTrackingMode,
    source: Source,
    /// The box's sides, normalized (a point's: twice its radius).
    size: (f32, f32),
}

/// What was last commanded, and how often to report.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Tracking {
    /// The last start, while not stopped.
    started: Option<Started>,
    pub(crate) source: Source,
    /// The status interval set, ms: `None` the default (while tracking), `Some(0)` none.
    interval_ms: Option<u32>,
    next: Option<Instant>,
    /// An `IDLE` status is owed: tracking stopped, the default interval in force.
    idle_owed: bool,
}

/// A normalized coordinate in [0, 1], or `None`.
fn unit(v: f32) -> Option<f32> {
    (0.0..=1.0).contains(&v).then_some(v)
}

/// The box of centre (cx, cy) and sides (w, h), all normalized; `None` when out of range.
fn tracking_box(cx: f32, cy: f32, w: f32, h: f32) -> Option<TrackingBox> {
    // In [0, 8191] after the range checks above: the casts are exact after rounding.
    let centre = ImagePoint::new(
        libm::roundf(cx * 8191.0) as i32,
        libm::roundf(cy * 8191.0) as i32,
    )
    .ok()?;
    TrackingBox::new(centre, w * IMAGE_UNITS, h * IMAGE_UNITS).ok()
}

impl Tracking {
    /// `MAV_CMD_CAMERA_TRACK_POINT`: param1, param2 the point, param3 the radius.
    pub(crate) fn point<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        params: [f32; 4],
    ) -> MavResult {
        let [x, y, r, _] = params;
        let (Some(x), Some(y), Some(r)) = (unit(x), unit(y), unit(r)) else {
            return MavResult::Denied;
        };
        let side = (2.0 * r).max(POINT_BOX_SIDE / IMAGE_UNITS);
        let Some(b) = tracking_box(x, y, side, side) else {
            return MavResult::Denied;
        };
        self.start(gimbal, b, CameraTrackingMode::Point, (side, side))
    }

    /// `MAV_CMD_CAMERA_TRACK_RECTANGLE`: param1, param2 the top-left corner, param3, param4
    /// the bottom-right one.
    pub(crate) fn rectangle<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        params: [f32; 4],
    ) -> MavResult {
        let [x1, y1, x2, y2] = params;
        let (Some(x1), Some(y1), Some(x2), Some(y2)) = (unit(x1), unit(y1), unit(x2), unit(y2))
        else {
            return MavResult::Denied;
        };
        let size = (libm::fabsf(x2 - x1), libm::fabsf(y2 - y1));
        let Some(b) = tracking_box((x1 + x2) / 2.0, (y1 + y2) / 2.0, size.0, size.1) else {
            return MavResult::Denied;
        };
        self.start(gimbal, b, CameraTrackingMode::Rectangle, size)
    }

    fn start<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        b: TrackingBox,
        mode: CameraTrackingMode,
        size: (f32, f32),
    ) -> MavResult {
        let command = match self.source {
            Source::Visible => GimbalCmd::from(GimbalCommand::StartTracking(b)),
            Source::Infrared => GimbalCmd::from(DualLightCommand::StartTracking(b)),
        };
        if gimbal.send(command).is_err() {
            return MavResult::TemporarilyRejected;
        }
        self.started = Some(Started {
            mode,
            source: self.source,
            size,
        });
        // The status at the next poll.
        self.next = None;
        self.idle_owed = false;
        MavResult::Accepted
    }

    /// `MAV_CMD_CAMERA_STOP_TRACKING`, on the image the tracking was started on.
    pub(crate) fn stop<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
    ) -> MavResult {
        let source = self.started.map_or(self.source, |s| s.source);
        let command = match source {
            Source::Visible => GimbalCmd::from(GimbalCommand::StopTracking),
            Source::Infrared => GimbalCmd::from(DualLightCommand::StopTracking),
        };
        if gimbal.send(command).is_err() {
            return MavResult::TemporarilyRejected;
        }
        self.idle_owed = self.started.take().is_some();
        self.next = None;
        MavResult::Accepted
    }

    /// `MAV_CMD_SET_MESSAGE_INTERVAL` for the status: µs; −1 stops it, 0 is the default
    /// (every [`TRACKING_STATUS_MS`] while tracking what the bridge started, once `IDLE`
    /// when that stops). Below 1 ms or above a minute is out of range.
    pub(crate) fn set_interval(&mut self, interval_us: f32, now: Instant) -> MavResult {
        self.interval_ms = match Interval::from_us(interval_us) {
            Some(Interval::Stop) => Some(0),
            Some(Interval::Default) => None,
            Some(Interval::Every(ms)) => Some(ms),
            None => return MavResult::Denied,
        };
        self.next = Some(now);
        MavResult::Accepted
    }

    /// The status's period now, ms, if it is sent on one.
    fn period(&self) -> Option<u32> {
        match self.interval_ms {
            Some(0) => None,
            Some(ms) => Some(ms),
            None => (self.started.is_some() || self.idle_owed).then_some(TRACKING_STATUS_MS),
        }
    }

    /// Whether the status is due at `now`.
    pub(crate) fn due(&self, now: Instant) -> bool {
        self.period().is_some() && self.next.is_none_or(|t| now.is_at_or_after(t))
    }

    /// Sends the status, due or asked for.
    pub(crate) fn send_status<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &Link<Q, T, M>,
        component: u8,
        now: Instant,
        tx: &mut Tx<'_>,
    ) {
        if let Some(ms) = self.period() {
            self.next = Some(now.add_millis(ms));
        }
        let tracking = gimbal.latest_postback(now).is_some_and(|(p, _)| p.tracking);
        if !tracking && self.started.is_none() {
            self.idle_owed = false;
        }
        let nan = f32::NAN;
        let mut s = CameraTrackingImageStatus {
            tracking_status: CameraTrackingStatusFlags::Idle,
            tracking_mode: CameraTrackingMode::None,
            target_data: CameraTrackingTargetData::empty(),
            point_x: nan,
            point_y: nan,
            radius: nan,
            rec_top_x: nan,
            rec_top_y: nan,
            rec_bottom_x: nan,
            rec_bottom_y: nan,
            camera_device_id: 0,
        };
        if tracking {
            s.tracking_status = CameraTrackingStatusFlags::Active;
            // Tracking the bridge did not start (the gimbal's own controls): no mode, no box.
            if let Some(t) = self.started {
                let (w, h) = t.size;
                s.tracking_mode = t.mode;
                s.target_data = CameraTrackingTargetData::IN_STATUS;
                // The tracker keeps its target at the centre (module docs).
                if t.mode == CameraTrackingMode::Point {
                    (s.point_x, s.point_y, s.radius) = (0.5, 0.5, w / 2.0);
                } else {
                    (s.rec_top_x, s.rec_top_y) = (0.5 - w / 2.0, 0.5 - h / 2.0);
                    (s.rec_bottom_x, s.rec_bottom_y) = (0.5 + w / 2.0, 0.5 + h / 2.0);
                }
            }
        }
        tx.out.send_encoded::<CameraTrackingImageStatus>(
            component,
            crate::codec::tracking_image_status::LEN,
            |p| crate::codec::tracking_image_status::encode(&s, p),
        );
    }
}
