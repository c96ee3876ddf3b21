//! The camera's field of view: its angles at the current zoom, and `CAMERA_FOV_STATUS`
//! (where the image centre meets the ground).
//!
//! **The lens is configuration.** The vendor document gives no focal length, sensor size or
//! field of view for any family, and no public source found states them for the IDU
//! cameras, so every family's default is unknown: [`CameraConfig::fov`] is `None` unless
//! the integrator sets it ([`FieldOfView::from_degrees`], the angles at 1×). With it:
//! - the visible streams' `VIDEO_STREAM_INFORMATION` and `VIDEO_STREAM_STATUS` carry the
//!   horizontal angle at the current zoom, in whole degrees (the field is an integer), which
//!   MAVProxy's camera module needs with the resolution to draw the footprint
//!   (`mavproxy_camera/__init__.py` `_show_camera_fov`: `0 < hfov < 180` and both
//!   resolutions above 0); the infrared stream has a lens of its own, not configured here,
//!   so its angle stays 0 (unknown);
//! - `CAMERA_FOV_STATUS` carries both angles at the current zoom, NaN when the lens or the
//!   zoom is unknown (after a continuous zoom).
//!
//! The zoom is optical: the angle at ratio `z` is `2 atan(tan(a / 2) / z)`, `a` the angle
//! at 1×.
//!
//! **`CAMERA_FOV_STATUS`** is sent on `MAV_CMD_REQUEST_MESSAGE` and at the interval
//! `MAV_CMD_SET_MESSAGE_INTERVAL` asks for (−1 or 0 stop it: common.xml gives the message no
//! default rate). QGroundControl master asks for it after every `CAMERA_SETTINGS`
//! (`VehicleCameraControl.cc` `_handleSettings`) and uses the angle only within
//! `0 < hfov < 180`. Its fields:
//! - the camera's position: the autopilot's `GLOBAL_POSITION_INT` (latitude, longitude,
//!   altitude above sea level), `INT32_MAX` before one arrives;
//! - the image centre on the ground: the line of sight from the camera's earth-frame
//!   attitude (the postback's pitch, its motor angle turned by the vehicle's heading) down
//!   to flat ground at the home altitude (`alt − relative_alt`, as MAVProxy's footprint
//!   takes it: `_FlatElevationModel`), through the core's WGS84 geometry
//!   ([`idu_gimbal::geo::LineOfSight`]); the ground's altitude as `alt_image`. `INT32_MIN`
//!   in all three when the line does not meet the ground (at or above the horizon), as
//!   common.xml asks; `INT32_MAX` when it cannot be known (no position or attitude, the
//!   vehicle below its home altitude, beyond ±85° of latitude);
//! - `q`: the camera's earth-frame attitude, as in `CAMERA_IMAGE_CAPTURED`;
//! - `hfov`, `vfov` as above.

use core::fmt;

use idu_gimbal::geo::LineOfSight;
use idu_gimbal::Instant;
use mavio::dialects::common::enums::MavResult;
use mavio::dialects::common::messages::CameraFovStatus;

use crate::capture::Vantage;
use crate::command::Interval;
use crate::tx::Tx;

use super::periodic::Periodic;
use super::CameraConfig;

/// A field of view angle outside `(0, 180)` degrees.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AngleOutOfRange {
    /// Which angle: `"horizontal"` or `"vertical"`.
    pub which: &'static str,
    /// The angle given, degrees.
    pub deg: f32,
}

impl fmt::Display for AngleOutOfRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} field of view {}° is out of range: more than 0 and less than 180",
            self.which, self.deg
        )
    }
}

/// The main camera's field of view at 1× zoom.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FieldOfView {
    /// `tan(angle / 2)`, horizontal and vertical: what the zoom divides.
    half_tan: (f32, f32),
}

impl FieldOfView {
    /// The field of view from its horizontal and vertical angles at 1× zoom, degrees.
    ///
    /// ```
    /// use idu_gimbal_mavlink::camera::fov::FieldOfView;
    ///
    /// let fov = FieldOfView::from_degrees(60.0, 34.0).unwrap();
    /// let (h, v) = fov.at_zoom(1.0).unwrap();
    /// assert!((h - 60.0).abs() < 1e-4 && (v - 34.0).abs() < 1e-4);
    /// // 2 atan(tan 30° / 2) = 32.2°.
    /// assert!((fov.at_zoom(2.0).unwrap().0 - 32.204).abs() < 1e-3);
    /// assert!(FieldOfView::from_degrees(180.0, 34.0).is_err());
    /// ```
    ///
    /// # Errors
    ///
    /// [`AngleOutOfRange`] for an angle not strictly between 0 and 180 (or NaN).
    pub fn from_degrees(horizontal: f32, vertical: f32) -> Result<Self, AngleOutOfRange> {
        let half_tan = |which, deg: f32| {
            if deg > 0.0 && deg < 180.0 {
                let (sin, cos) = idu_gimbal::math::sin_cos((deg / 2.0).to_radians());
                Ok(sin / cos)
            } else {
                Err(AngleOutOfRange { which, deg })
            }
        };
        Ok(FieldOfView {
            half_tan: (
                half_tan("horizontal", horizontal)?,
                half_tan("vertical", vertical)?,
            ),
        })
    }

    /// The horizontal and vertical angles at zoom ratio `zoom`, degrees; `None` for a
    /// ratio below 1 or unknown (NaN).
    pub fn at_zoom(&self, zoom: f32) -> Option<(f32, f32)> {
        let angle = |t: f32| 2.0 * libm::atanf(t / zoom).to_degrees();
        (zoom >= 1.0).then(|| (angle(self.half_tan.0), angle(self.half_tan.1)))
    }
}

/// The angles now, degrees: NaN when the lens or the zoom is unknown.
pub(crate) fn angles(config: &CameraConfig, zoom: f32) -> (f32, f32) {
    config
        .fov
        .and_then(|f| f.at_zoom(zoom))
        .unwrap_or((f32::NAN, f32::NAN))
}

/// `VIDEO_STREAM_INFORMATION.hfov` of a visible stream: whole degrees, 0 when unknown.
pub(crate) fn stream_hfov(config: &CameraConfig, zoom: f32) -> u16 {
    let (h, _) = angles(config, zoom);
    // In (0, 180) when known, so the cast is exact after rounding; NaN casts to 0.
    libm::roundf(h) as u16
}

/// `MAV_CMD_SET_MESSAGE_INTERVAL` for the status: µs; −1 and 0 (the default: none) stop
/// it. Below 1 ms or above a minute is out of range.
pub(crate) fn set_interval(schedule: &mut Periodic, interval_us: f32, now: Instant) -> MavResult {
    match Interval::from_us(interval_us) {
        Some(Interval::Stop | Interval::Default) => schedule.set(0, now),
        Some(Interval::Every(ms)) => schedule.set(ms, now),
        None => return MavResult::Denied,
    }
    MavResult::Accepted
}

/// Where the image centre meets the ground: latitude, longitude (1e-7°) and altitude (mm)
/// as `CAMERA_FOV_STATUS` gives them (see the module docs).
fn image_centre(vantage: &Vantage) -> [i32; 3] {
    const UNKNOWN: [i32; 3] = [i32::MAX; 3];
    let (Some([lat, lon, alt, relative_alt]), Some((yaw, pitch))) =
        (vantage.position, vantage.attitude)
    else {
        return UNKNOWN;
    };
    // An autopilot's altitudes are any i32s: a ground they put beyond i32 is unknown.
    let Some(ground_mm) = alt.checked_sub(relative_alt) else {
        return UNKNOWN;
    };
    let sight = LineOfSight {
        lat_deg: lat as f32 / 1e7,
        ground_alt_m: ground_mm as f32 / 1e3,
        height_m: relative_alt as f32 / 1e3,
        bearing_deg: f32::from(yaw) / 100.0,
        elevation_deg: f32::from(pitch) / 100.0,
    };
    match sight.ground_hit() {
        Ok(Some(hit)) => {
            // Offsets of a few degrees at most (the line meets the ground within a few
            // hundred kilometres): their 1e-7° fit i32 (a saturating cast otherwise, which
            // the checked sums then refuse).
            let dlat = libm::roundf(hit.dlat_deg * 1e7) as i32;
            let dlon = libm::roundf(hit.dlon_deg * 1e7) as i32;
            let (Some(lat), Some(lon)) = (lat.checked_add(dlat), lon.checked_add(dlon)) else {
                return UNKNOWN;
            };
            // Across the antimeridian: back into ±180° (from within i32, a turn back never
            // leaves it: the saturating forms never saturate).
            const HALF_TURN: i32 = 1_800_000_000;
            let lon = if lon > HALF_TURN {
                lon.saturating_sub(HALF_TURN).saturating_sub(HALF_TURN)
            } else if lon < -HALF_TURN {
                lon.saturating_add(HALF_TURN).saturating_add(HALF_TURN)
            } else {
                lon
            };
            if lat.abs() > 900_000_000 {
                return UNKNOWN;
            }
            [lat, lon, ground_mm]
        }
        Ok(None) => [i32::MIN; 3],
        Err(_) => UNKNOWN,
    }
}

/// Sends `CAMERA_FOV_STATUS` now (asked for, or due).
pub(crate) fn send_status(
    config: &CameraConfig,
    schedule: &mut Periodic,
    zoom: f32,
    now: Instant,
    tx: &mut Tx<'_>,
) {
    schedule.sent(now);
    let vantage = tx.vantage;
    let [lat_camera, lon_camera, alt_camera] = vantage
        .position
        .map_or([i32::MAX; 3], |[lat, lon, alt, _]| [lat, lon, alt]);
    let [lat_image, lon_image, alt_image] = image_centre(&vantage);
    let (hfov, vfov) = angles(config, zoom);
    let m = CameraFovStatus {
        time_boot_ms: now.as_millis(),
        lat_camera,
        lon_camera,
        alt_camera,
        lat_image,
        lon_image,
        alt_image,
        q: vantage.quaternion(),
        hfov,
        vfov,
        camera_device_id: 0,
    };
    tx.out.send(config.component, &m);
}
