//! The lens: `MAV_CMD_SET_CAMERA_ZOOM` and `MAV_CMD_SET_CAMERA_FOCUS` to the camera core's
//! zoom (0x12) and focus (0x13).
//!
//! **Zoom.** Range (0 to 100 % of the zoom range) → zoom ratio; continuous → zoom in, out
//! or stop by the value's sign (common.xml: "a rate ... the sign decides the direction");
//! step (any whole number but 0) → 2× in or out per step, at most five sent (2^5 spans any
//! of the document's ranges); focal length and field of view → `UNSUPPORTED`.
//! The level reported is the ratio last set, unknown (NaN) after a continuous zoom, which
//! the gimbal does not report the end of.
//!
//! **Focus.** The core has focus +, −, stop and auto, and reports no focus position:
//! - `FOCUS_TYPE_CONTINUOUS`: the sign of the rate, as common.xml gives it ("negative:
//!   focus in, positive: focus out towards infinity, 0 to stop"; values beyond ±1
//!   "clipped"): positive → focus + (taken as farther: the document does not say),
//!   negative → focus −, 0 → stop;
//! - `FOCUS_TYPE_AUTO`, `AUTO_SINGLE`, `AUTO_CONTINUOUS` → auto-focus, the core's one
//!   automatic focus (the document does not say whether it holds focus continuously);
//! - `FOCUS_TYPE_STEP`, `RANGE` and `METERS` need a focus position the gimbal neither takes
//!   nor reports: `DENIED`, which common.xml's `MAV_RESULT` gives for "supported but one
//!   or more parameter values are invalid", the command itself being supported.
//!
//! The focus level in `CAMERA_SETTINGS` stays NaN (unknown).
//!
//! What sends it: MAVSDK's `focus_in_start`, `focus_out_start` and `focus_stop` (continuous
//! −1, +1, 0), `focus_auto`, `focus_auto_single` and `focus_auto_continuous` (types 4 to 6),
//! `focus_range` (type 2; `camera_impl.cpp`:264-310 at mavlink/MAVSDK 158e339, and the 4.1
//! library); ArduPilot's `AP_Camera_MAVLinkCamV2::set_focus` (continuous, range or auto, only
//! with `HAS_BASIC_FOCUS`). QGroundControl sends no focus command from any screen (its
//! `setFocusLevel` is unused), hence the `CAM_FOCUS` setting ([`super::settings`]).

use idu_gimbal::wire::control::{Command as GimbalCmd, Focus, GimbalCommand, Zoom, ZoomRatio};
use idu_gimbal::wire::postback::GimbalType;
use mavio::dialects::common::enums::{CameraZoomType, MavResult, SetFocusType};

use idu_gimbal::link::{Link, Medium};

use super::{CameraComponent, CameraConfig};

/// `kind` is the enum value `e` (a command's float param).
fn is(kind: f32, e: u8) -> bool {
    kind == f32::from(e)
}

/// `MAV_CMD_SET_CAMERA_FOCUS`: param1 the focus type, param2 the value.
pub(crate) fn focus<const Q: usize, const T: usize, M: Medium>(
    gimbal: &mut Link<Q, T, M>,
    params: [f32; 4],
) -> MavResult {
    let [kind, v, _, _] = params;
    let f = if is(kind, SetFocusType::FocusTypeContinuous as u8) {
        // common.xml: "Other values should be clipped to the range": only the sign counts.
        if v.is_nan() {
            return MavResult::Denied;
        } else if v > 0.0 {
            Focus::Plus
        } else if v < 0.0 {
            Focus::Minus
        } else {
            Focus::Stop
        }
    } else if [
        SetFocusType::FocusTypeAuto,
        SetFocusType::FocusTypeAutoSingle,
        SetFocusType::FocusTypeAutoContinuous,
    ]
    .iter()
    .any(|&t| is(kind, t as u8))
    {
        Focus::Auto
    } else {
        return MavResult::Denied;
    };
    if gimbal
        .send(GimbalCmd::from(GimbalCommand::Focus(f)))
        .is_err()
    {
        return MavResult::TemporarilyRejected;
    }
    MavResult::Accepted
}

/// The most zoom steps sent to the gimbal for one `ZOOM_TYPE_STEP`.
const MAX_STEPS: usize = 5;

impl CameraComponent {
    pub(crate) fn zoom<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        config: &CameraConfig,
        params: [f32; 4],
        gimbal_type: Option<GimbalType>,
    ) -> MavResult {
        let [kind, v, _, _] = params;
        let (commands, ratio): ([Option<GimbalCommand>; MAX_STEPS], f32) =
            if kind == CameraZoomType::ZoomTypeRange as u8 as f32 {
                if !(0.0..=100.0).contains(&v) {
                    return MavResult::Denied;
                }
                let Some(max) = self.zoom_max(config, gimbal_type) else {
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
                // Any whole number of steps: QGroundControl's pinch sends round(scale × −10)
                // when zooming out (FlightDisplayViewVideo.qml), −10 to −6 for a pinch.
                if !(v.is_finite() && v == libm::truncf(v) && v != 0.0) {
                    return MavResult::Denied;
                }
                // Not 0 (above): in or out.
                let zoom_in = v > 0.0;
                let z = if zoom_in { Zoom::Double } else { Zoom::Half };
                // A step doubles or halves the ratio: MAX_STEPS of them span the document's
                // ranges (2^5 = 32 ≥ 30), and further ones would reach a gimbal already at
                // its end. Whole and at most 5: exact.
                let n = libm::fabsf(v).min(MAX_STEPS as f32) as usize;
                let mut c = [None; MAX_STEPS];
                for slot in c.iter_mut().take(n) {
                    *slot = Some(GimbalCommand::Zoom(z));
                }
                // The gimbal stops at its ends; an unknown level stays unknown (NaN through
                // the arithmetic: f32::max/min would turn it into a bound).
                // 2^n for n ≤ 5: a shift, exact (no powf).
                let factor = (1u8 << n) as f32;
                let stepped = if zoom_in {
                    self.zoom * factor
                } else {
                    self.zoom / factor
                };
                let ratio = match self.zoom_max(config, gimbal_type) {
                    _ if stepped.is_nan() => f32::NAN,
                    Some(max) => stepped.max(1.0).min(max),
                    None => stepped.max(1.0),
                };
                (c, ratio)
            } else {
                return MavResult::Unsupported;
            };
        // All the steps or none: a part of them would move the lens where the level kept
        // here does not say. A full queue is the client's to try again.
        if commands.iter().flatten().count() > gimbal.command_room() {
            return MavResult::TemporarilyRejected;
        }
        for c in commands.into_iter().flatten() {
            if gimbal.send(GimbalCmd::from(c)).is_err() {
                return MavResult::TemporarilyRejected;
            }
        }
        self.zoom = ratio;
        MavResult::Accepted
    }
}
