//! What each control command does to the model.

use super::*;

impl<const TX: usize> Simulator<TX> {
    pub(super) fn apply(&mut self, command: Command) {
        self.state.last_command = Some(command);
        match command {
            Command::Gimbal(c) => self.apply_gimbal(c),
            Command::DualLight(c) => self.apply_dual_light(c),
        }
    }

    pub(super) fn apply_gimbal(&mut self, command: GimbalCommand) {
        let s = &mut self.state;
        match command {
            GimbalCommand::PointingZoom(_) => {
                s.pointing_zooms = s.pointing_zooms.wrapping_add(1);
                let doubled = s.zoom_ratio * 2.0;
                self.set_zoom(doubled);
            }
            GimbalCommand::NoseFollowing => {
                self.end_tracking();
                self.stop_rate();
                self.held_north = None;
                self.state.mode = ControlMode::HeadingFollow;
                self.state.target_yaw_deg = Some(0.0);
            }
            GimbalCommand::Recenter => {
                self.end_tracking();
                self.stop_rate_keep_mode();
                self.held_north = None;
                self.state.target_pitch_deg = Some(0.0);
                self.state.target_yaw_deg = Some(0.0);
            }
            GimbalCommand::Rate(r) => self.start_rate(r),
            GimbalCommand::StartTracking(b) => self.start_tracking(b),
            GimbalCommand::StopTracking => self.end_tracking(),
            GimbalCommand::LookDown => {
                self.end_tracking();
                self.stop_rate_keep_mode();
                self.state.target_pitch_deg = Some(LOOK_DOWN_PITCH_DEG);
            }
            GimbalCommand::Heading(h) => {
                self.end_tracking();
                self.stop_rate();
                let reference = if self.state.north_referenced {
                    self.state.vehicle.map_or(0.0, |v| v.heading_deg())
                } else {
                    0.0
                };
                self.state.target_yaw_deg = Some(clamp_yaw(wrap_180(h.degrees() - reference)));
                self.state.mode = ControlMode::Lock;
                // Held as commanded, even where the motor stops at its limit.
                self.held_north = self.state.north_referenced.then(|| wrap_360(h.degrees()));
            }
            GimbalCommand::Pitch(p) => {
                self.end_tracking();
                self.stop_rate();
                self.state.target_pitch_deg = Some(clamp_pitch(p.degrees()));
                self.state.mode = ControlMode::Lock;
            }
            GimbalCommand::ZoomRatio(z) => self.set_zoom(z.ratio()),
            GimbalCommand::Photo(p) => self.photo(p),
            GimbalCommand::Video(v) => s.recording = v == Video::Start,
            GimbalCommand::Zoom(z) => match z {
                Zoom::In | Zoom::Out => s.zooming = Some(z),
                Zoom::Stop => s.zooming = None,
                Zoom::Reset => self.set_zoom(ZOOM_MIN),
                Zoom::Double => {
                    let z = s.zoom_ratio * 2.0;
                    self.set_zoom(z);
                }
                Zoom::Half => {
                    let z = s.zoom_ratio / 2.0;
                    self.set_zoom(z);
                }
            },
            GimbalCommand::Focus(f) => {
                s.focus_commands = s.focus_commands.wrapping_add(1);
                match f {
                    Focus::Plus | Focus::Minus => {
                        s.focusing = Some(f);
                        s.auto_focus = false;
                        s.focus_point = None;
                    }
                    Focus::Stop => s.focusing = None,
                    Focus::Auto => {
                        s.focusing = None;
                        s.auto_focus = true;
                        s.focus_point = None;
                    }
                }
            }
            GimbalCommand::PointingFocus(p) => {
                s.focus_commands = s.focus_commands.wrapping_add(1);
                s.focusing = None;
                s.auto_focus = true;
                s.focus_point = Some(p);
            }
            GimbalCommand::FastCalibration => {
                s.calibrations = s.calibrations.wrapping_add(1);
                s.calibrating = true;
                self.calibration_left_ms = CALIBRATION_MS;
            }
        }
    }

    pub(super) fn apply_dual_light(&mut self, command: DualLightCommand) {
        let s = &mut self.state;
        match command {
            DualLightCommand::PointingZoom(_) => {
                s.pointing_zooms = s.pointing_zooms.wrapping_add(1);
            }
            DualLightCommand::Palette(p) => s.palette = Some(p),
            DualLightCommand::Rate(r) => self.start_rate(r),
            DualLightCommand::StartTracking(b) => self.start_tracking(b),
            DualLightCommand::StopTracking => self.end_tracking(),
            DualLightCommand::ElectronicZoom(z) => {
                s.electronic_zooming = match z {
                    ElectronicZoom::In | ElectronicZoom::Out => Some(z),
                    ElectronicZoom::Stop => None,
                };
            }
        }
    }

    pub(super) fn start_rate(&mut self, rate: Rate) {
        if rate.is_zero() && self.state.tracking {
            // A joystick at rest is no manual input: the tracker keeps the gimbal.
            return;
        }
        self.end_tracking();
        let s = &mut self.state;
        s.mode = ControlMode::FullLock;
        s.target_pitch_deg = None;
        s.target_yaw_deg = None;
        if rate.is_zero() {
            s.rate = (0.0, 0.0);
            self.rate_left_ms = 0;
        } else {
            s.rate = (rate.yaw_dps(), rate.pitch_dps());
            self.rate_left_ms = self.config.rate_timeout_ms;
        }
    }

    /// Ends rate motion (an angle command follows and sets the mode).
    pub(super) fn stop_rate(&mut self) {
        self.state.rate = (0.0, 0.0);
        self.rate_left_ms = 0;
    }

    /// Ends rate motion for recenter and look down: full lock becomes lock, other modes
    /// stay.
    pub(super) fn stop_rate_keep_mode(&mut self) {
        self.stop_rate();
        if self.state.mode == ControlMode::FullLock {
            self.state.mode = ControlMode::Lock;
        }
    }

    pub(super) fn photo(&mut self, p: Photo) {
        let s = &mut self.state;
        match p {
            Photo::Single => s.photos = s.photos.saturating_add(1),
            Photo::Burst(n) => s.photos = s.photos.saturating_add(n.get().into()),
            Photo::TimeLapse(secs) | Photo::Timer(secs) => {
                s.photo_mode = Some(p);
                self.photo_left_ms = u32::from(secs.get()) * 1000;
            }
            Photo::Stop => s.photo_mode = None,
        }
    }
}
