//! The tracker: a target kept in the image while the gimbal and the vehicle turn, lost
//! after its timeout.

use super::*;

impl<const TX: usize> Simulator<TX> {
    /// While tracking with a timeout: the ms into a `dt` step at which the target is lost,
    /// if within it; otherwise counts the step off the time left.
    pub(super) fn tracking_ends_within(&mut self, dt: u32) -> Option<u32> {
        if !self.state.tracking || self.config.tracking_lost_ms == 0 {
            return None;
        }
        match self.tracking_left_ms.checked_sub(dt) {
            Some(left) if left > 0 => {
                self.tracking_left_ms = left;
                None
            }
            // The step reaches the end.
            _ => Some(self.tracking_left_ms),
        }
    }

    /// The heading tracked targets are kept relative to: the last vehicle heading
    /// received, stale or not (a fixed frame, so that a stale attitude moves nothing), 0
    /// before any.
    pub(super) fn tracking_reference(&self) -> f32 {
        self.state.vehicle.map_or(0.0, |v| v.heading_deg())
    }

    /// While tracking: aims the angle targets at the target (a vehicle turn is made up for
    /// within the motor's range) and moves the box to where the target is in the image.
    pub(super) fn follow_target(&mut self) {
        let Some((azimuth, elevation)) = self.track_target else {
            return;
        };
        let relative = azimuth - self.tracking_reference();
        let s = &mut self.state;
        s.target_yaw_deg = Some(clamp_yaw(wrap_180(relative)));
        s.target_pitch_deg = Some(clamp_pitch(elevation));
        let offset = (
            wrap_180(relative - s.motor_yaw_deg),
            elevation - s.pitch_deg,
        );
        match (image_point(offset, s.zoom_ratio), s.tracking_box) {
            (Some(centre), Some(b)) => {
                s.tracking_box = Some(TrackingBox::from_raw(centre, b.width16(), b.height16()));
            }
            _ => self.lose_target(),
        }
    }

    /// Starts tracking the target at the box centre (replacing any target tracked): it
    /// becomes a fixed direction, the current pointing plus the box's angular offset.
    pub(super) fn start_tracking(&mut self, b: TrackingBox) {
        self.stop_rate();
        let (yaw, pitch) = angular_offset(b.centre(), self.state.zoom_ratio);
        let azimuth = wrap_360(self.tracking_reference() + self.state.motor_yaw_deg + yaw);
        self.track_target = Some((azimuth, self.state.pitch_deg + pitch));
        self.tracking_left_ms = self.config.tracking_lost_ms;
        let s = &mut self.state;
        s.tracking = true;
        s.tracking_box = Some(b);
        s.mode = ControlMode::Lock;
    }

    /// Ends tracking, if on, holding the gimbal where it points now.
    pub(super) fn end_tracking(&mut self) {
        let s = &mut self.state;
        if self.track_target.take().is_some() {
            self.held_north = None;
            s.target_pitch_deg = Some(s.pitch_deg);
            s.target_yaw_deg = Some(s.motor_yaw_deg);
        }
        s.tracking = false;
        s.tracking_box = None;
    }

    /// Ends tracking as [`Self::end_tracking`] and counts the target lost.
    pub(super) fn lose_target(&mut self) {
        self.end_tracking();
        self.state.targets_lost = self.state.targets_lost.wrapping_add(1);
    }
}
