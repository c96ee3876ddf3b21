//! The model's motion: time advanced in steps, rates integrated, angles slewed, zoom,
//! focus, calibration and photo timers run, the reported heading derived.

use super::*;

impl<const TX: usize> Simulator<TX> {
    /// Moves the model from `self.last` to `now` (never backwards).
    pub(super) fn advance(&mut self, now: Instant) {
        if !now.is_at_or_after(self.last) {
            return;
        }
        let dt = now.millis_since(self.last);
        self.last = now;
        if dt == 0 {
            return;
        }
        self.integrate_rate(dt);
        if let Some(ms) = self.tracking_ends_within(dt) {
            // Slew toward the target until the instant it is lost, then hold there.
            self.slew(ms);
            self.lose_target();
        }
        // After a loss the targets are where the gimbal stopped: this moves nothing more.
        self.slew(dt);
        self.integrate_zoom(dt);
        self.integrate_focus(dt);
        self.run_photo_timers(dt);
        self.run_calibration(dt);
        self.booting_left_ms = self.booting_left_ms.saturating_sub(dt);
        self.attitude_age_ms = self.attitude_age_ms.map(|a| a.saturating_add(dt));
        self.refresh();
    }

    pub(super) fn integrate_rate(&mut self, dt: u32) {
        if self.rate_left_ms == 0 {
            return;
        }
        let t = dt.min(self.rate_left_ms);
        let seconds = t as f32 / 1000.0;
        let (yaw, pitch) = self.state.rate;
        self.state.motor_yaw_deg = clamp_yaw(self.state.motor_yaw_deg + yaw * seconds);
        self.state.pitch_deg = clamp_pitch(self.state.pitch_deg + pitch * seconds);
        // Counted down to 0 at most (`t` is no more than what is left).
        self.rate_left_ms = self.rate_left_ms.saturating_sub(t);
        if self.rate_left_ms == 0 {
            self.state.rate = (0.0, 0.0);
        }
    }

    pub(super) fn slew(&mut self, dt: u32) {
        // NaN and non-positive speeds do not slew; +inf reaches the target at once.
        let dps = if self.config.slew_dps > 0.0 {
            self.config.slew_dps
        } else {
            0.0
        };
        let step = dps * (dt as f32 / 1000.0);
        if let Some(target) = self.state.target_pitch_deg {
            self.state.pitch_deg = approach(self.state.pitch_deg, target, step);
        }
        if let Some(target) = self.state.target_yaw_deg {
            self.state.motor_yaw_deg = approach(self.state.motor_yaw_deg, target, step);
        }
    }

    pub(super) fn integrate_focus(&mut self, dt: u32) {
        let delta = FOCUS_SPEED_PER_S * (dt as f32 / 1000.0);
        self.state.focus = match self.state.focusing {
            Some(Focus::Plus) => (self.state.focus + delta).min(1.0),
            Some(Focus::Minus) => (self.state.focus - delta).max(0.0),
            _ => return,
        };
    }

    pub(super) fn run_calibration(&mut self, dt: u32) {
        if !self.state.calibrating {
            return;
        }
        self.calibration_left_ms = self.calibration_left_ms.saturating_sub(dt);
        if self.calibration_left_ms == 0 {
            self.state.calibrating = false;
        }
    }

    pub(super) fn integrate_zoom(&mut self, dt: u32) {
        let delta = ZOOM_SPEED_PER_S * (dt as f32 / 1000.0);
        self.state.zoom_ratio = match self.state.zooming {
            Some(Zoom::In) => clamp_zoom(self.state.zoom_ratio + delta),
            Some(Zoom::Out) => clamp_zoom(self.state.zoom_ratio - delta),
            _ => return,
        };
    }

    pub(super) fn run_photo_timers(&mut self, dt: u32) {
        match self.state.photo_mode {
            Some(Photo::Timer(_)) => match self.photo_left_ms.checked_sub(dt) {
                Some(left) if left > 0 => self.photo_left_ms = left,
                _ => {
                    self.state.photos = self.state.photos.saturating_add(1);
                    self.state.photo_mode = None;
                }
            },
            Some(Photo::TimeLapse(s)) => match self.photo_left_ms.checked_sub(dt) {
                Some(left) if left > 0 => self.photo_left_ms = left,
                _ => {
                    // 1 to 255 s, in ms: not zero, no overflow.
                    let period = NonZeroU32::from(s).saturating_mul(SECOND_MS);
                    // The step runs `over` ms past the photo due: one photo then, one more
                    // per whole period after it, and the next one is 1 to `period` ms away.
                    let over = dt.saturating_sub(self.photo_left_ms);
                    let taken = (over / period).saturating_add(1);
                    self.state.photos = self.state.photos.saturating_add(taken);
                    self.photo_left_ms = period.get().saturating_sub(over % period);
                }
            },
            _ => {}
        }
    }

    /// Recomputes the derived fields: reference and reported heading, and while tracking
    /// the angle targets and the box (losing a target now out of the image).
    pub(super) fn refresh(&mut self) {
        self.refresh_heading();
        self.hold_north();
        self.follow_target();
    }

    /// [`LockHolds::North`]: in lock or full lock, north-referenced, neither tracking nor
    /// at a rate, the yaw target keeps the north heading held (taken from where the yaw is
    /// aimed when the hold begins).
    pub(super) fn hold_north(&mut self) {
        let s = &self.state;
        let vehicle = match (self.config.lock_holds, s.north_referenced, s.vehicle) {
            (LockHolds::North, true, Some(v))
                if matches!(s.mode, ControlMode::Lock | ControlMode::FullLock)
                    && !s.tracking
                    && self.rate_left_ms == 0 =>
            {
                v.heading_deg()
            }
            _ => {
                self.held_north = None;
                return;
            }
        };
        let aimed = s.target_yaw_deg.unwrap_or(s.motor_yaw_deg);
        let held = *self
            .held_north
            .get_or_insert_with(|| wrap_360(vehicle + aimed));
        self.state.target_yaw_deg = Some(clamp_yaw(wrap_180(held - vehicle)));
    }

    pub(super) fn refresh_heading(&mut self) {
        let fresh = self
            .attitude_age_ms
            .is_some_and(|age| age <= self.config.attitude_timeout_ms);
        let vehicle_heading = match (fresh, self.state.vehicle) {
            (true, Some(v)) => Some(v.heading_deg()),
            _ => None,
        };
        self.state.north_referenced = vehicle_heading.is_some();
        self.state.heading_deg =
            wrap_360(vehicle_heading.unwrap_or(0.0) + self.state.motor_yaw_deg);
    }

    /// Sets the optical zoom (clamped) and ends continuous zooming.
    pub(super) fn set_zoom(&mut self, ratio: f32) {
        self.state.zoom_ratio = clamp_zoom(ratio);
        self.state.zooming = None;
    }
}

/// Within this of a target after a step, the gimbal lands on it, degrees: below the
/// postback's resolution, and large enough to absorb the rounding of many small steps.
pub(super) const SNAP_DEG: f32 = 1e-3;

/// Moves `current` toward `target` by at most `step` (plus [`SNAP_DEG`]), landing on it
/// exactly.
pub(super) fn approach(current: f32, target: f32, step: f32) -> f32 {
    let distance = target - current;
    if libm::fabsf(distance) <= step + SNAP_DEG {
        target
    } else if distance > 0.0 {
        current + step
    } else {
        current - step
    }
}

pub(super) fn clamp_pitch(deg: f32) -> f32 {
    deg.clamp(PITCH_TRAVEL_MIN_DEG, PITCH_TRAVEL_MAX_DEG)
}

pub(super) fn clamp_yaw(deg: f32) -> f32 {
    deg.clamp(-MOTOR_YAW_LIMIT_DEG, MOTOR_YAW_LIMIT_DEG)
}

pub(super) fn clamp_zoom(ratio: f32) -> f32 {
    ratio.clamp(ZOOM_MIN, OPTICAL_ZOOM_MAX)
}

/// `deg` in [0, 360).
pub(super) fn wrap_360(deg: f32) -> f32 {
    let r = libm::fmodf(deg, 360.0);
    let r = if r < 0.0 { r + 360.0 } else { r };
    // A tiny negative remainder plus 360 rounds to 360; NaN cannot occur but maps to 0.
    if (0.0..360.0).contains(&r) {
        r
    } else {
        0.0
    }
}

/// `deg` in [−180, 180).
pub(super) fn wrap_180(deg: f32) -> f32 {
    wrap_360(deg + 180.0) - 180.0
}

/// `deg` ×100, rounded, clamped to [min, max] (wire units; the caller casts).
pub(super) fn centi(deg: f32, min: f32, max: f32) -> f32 {
    libm::roundf(deg * 100.0).clamp(min, max)
}
