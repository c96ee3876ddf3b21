//! Holding an orientation: closed-loop aiming in the earth or the vehicle frame.
//!
//! [`Link::aim`](super::Link::aim) holds the gimbal at a yaw and a pitch, the yaw in the
//! **earth** frame (from north: the camera keeps its bearing while the vehicle turns) or in
//! the **vehicle** frame (from the nose: it turns with the vehicle). The gimbal takes a
//! heading command in its own reference, north while it has the vehicle's attitude and the
//! nose otherwise (section 2.1, "Specify angle"), and the document does not say what it
//! holds afterwards in lock mode while the vehicle turns: its north heading, or its motor
//! angle. So the link does not leave the aim to the gimbal. It sends the heading and pitch
//! commands again
//!
//! - at once for a new aim, one that moved past the dead-band
//!   ([`Config::aim_deadband_mdeg`](super::Config::aim_deadband_mdeg)) from the one last
//!   commanded;
//! - when the vehicle's heading has moved past the dead-band since the last command: one of
//!   the two behaviours needs the command again, and to the other it changes nothing;
//! - when the gimbal's reference has changed since the last command (the attitude reached
//!   it, or went stale): the same command means another direction now;
//! - when a postback shows the gimbal off the aim by more than the tolerance
//!   ([`Config::aim_tolerance_mdeg`](super::Config::aim_tolerance_mdeg)) and not getting
//!   closer: a lost command, a gimbal that rebooted, a start-up race, a mode changed by
//!   someone else. The postback is read in the aim's frame: its motor angle (from the nose)
//!   and pitch, and for the earth frame the motor angle plus the vehicle's heading. (Its
//!   heading field pairs the motor with the attitude the gimbal last received and is
//!   nose-referenced on the UART: the motor angle means the same on both transports.) A
//!   postback whose control mode is heading follow is off the aim whatever its angles.
//!
//! Bounds, so that a gimbal that cannot follow is not hammered:
//! - re-commands (all but a new aim's) come at most once per
//!   [`Config::aim_period_ms`](super::Config::aim_period_ms) (50 ms, the document's
//!   period for a repeated rate command);
//! - a postback is judged for progress only from the second one after a command (the
//!   first may predate any movement); a gimbal off the aim and not getting closer is
//!   re-commanded at most [`ATTEMPTS`] times, then the aim is **not reached**: counted in
//!   [`LinkStats::aim_not_reached`](super::LinkStats::aim_not_reached), raised once as
//!   [`Event::AimNotReached`], and not re-commanded for that error again until the aim,
//!   the vehicle's heading or the gimbal's reference changes, or the link comes up again
//!   (a gimbal that restarted);
//! - a yaw the motor cannot reach (beyond its travel: ±170°, ±325° on the 3.5× models) is
//!   commanded as it is, the gimbal stops at its limit, and the aim reports
//!   [`AimState::at_yaw_limit`]: the limit is what the postback is held to, so the gimbal
//!   sitting there is on target and not re-commanded;
//! - while the postback says the gimbal tracks a target, its tracker owns the yaw and pitch:
//!   nothing but a new aim is sent.
//!
//! An earth-frame yaw needs the vehicle's heading wherever the gimbal is nose-referenced
//! (the UART, or CAN before the attitude reaches the gimbal); while that is stale nothing
//! is sent and the aim reports [`AimState::waiting_for_heading`].

use crate::time::Instant;
use crate::wire::control::{Command, GimbalCommand, Heading, Pitch};
use crate::wire::postback::ControlMode;
use crate::wire::vehicle::wrap_centideg as angle_cdeg;

use super::*;

/// How many times a gimbal off the aim and not getting closer is re-commanded before the
/// aim is reported not reached.
pub const ATTEMPTS: u8 = 3;

/// The frame an aim's yaw is in.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Yaw {
    /// Degrees clockwise from true north: the camera keeps this bearing while the vehicle
    /// turns.
    Earth(Heading),
    /// Degrees clockwise from the vehicle's nose (350 is 10° left): the camera turns with
    /// the vehicle.
    Vehicle(Heading),
}

impl Yaw {
    /// The angle, 0.1° in [0, 3600].
    pub const fn deci(self) -> u16 {
        self.heading().deci()
    }

    /// The angle, whatever the frame.
    pub const fn heading(self) -> Heading {
        match self {
            Yaw::Earth(h) | Yaw::Vehicle(h) => h,
        }
    }

    /// Whether the yaw is in the earth frame.
    pub const fn is_earth(self) -> bool {
        matches!(self, Yaw::Earth(_))
    }
}

/// An orientation for the gimbal to hold: a yaw in its frame and a pitch from the horizon.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Aim {
    /// The yaw, in the earth or the vehicle frame.
    pub yaw: Yaw,
    /// The pitch, from the horizon (up is positive).
    pub pitch: Pitch,
}

/// Why [`Link::aim`](super::Link::aim) refused an aim (the link's steering is unchanged).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AimError {
    /// An earth-frame yaw while the gimbal is nose-referenced needs the vehicle's heading,
    /// and the attitude set is stale or missing (see
    /// [`Config::vehicle_stale_ms`](super::Config::vehicle_stale_ms)).
    NoVehicleHeading,
}

impl fmt::Display for AimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AimError::NoVehicleHeading => f.write_str(
                "an earth-frame yaw needs the vehicle's heading, and none is fresh \
                 (set the vehicle attitude first)",
            ),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for AimError {}

/// How an aim stands ([`Link::aim_state`](super::Link::aim_state)).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AimState {
    /// The aim held (for a point-at, the latest aim at the target).
    pub aim: Aim,
    /// The yaw needs the motor beyond its travel: the gimbal holds its limit.
    pub at_yaw_limit: bool,
    /// The latest postback judged showed the gimbal within the tolerance of the aim.
    pub on_target: bool,
    /// The gimbal was re-commanded [`ATTEMPTS`] times without getting closer: see the
    /// [module docs](self) for when it is tried again.
    pub not_reached: bool,
    /// Nothing can be sent: the aim needs the vehicle's heading, which is stale.
    pub waiting_for_heading: bool,
    /// The gimbal's tracker was started (a start-tracking command went through the link):
    /// it owns the gimbal, and the aim sends nothing until the tracker is stopped through
    /// the link, its postback stops saying it tracks, or a new aim or point-at target is
    /// given. A point-at's aim moving with the vehicle leaves the tracker in charge.
    pub yielded_to_tracker: bool,
}

// `Hold::flags`.
/// The yaw is in the earth frame.
const EARTH: u8 = 1 << 0;
/// A new aim: command at once, whatever the ceiling.
const NEW: u8 = 1 << 1;
/// A re-command is wanted, at the ceiling's next slot.
const PENDING: u8 = 1 << 2;
/// A command was sent; `sent_*` describe it.
const SENT: u8 = 1 << 3;
/// The last command was sent north-referenced.
const SENT_NORTH: u8 = 1 << 4;
const AT_LIMIT: u8 = 1 << 5;
const ON_TARGET: u8 = 1 << 6;
const NOT_REACHED: u8 = 1 << 7;

// `Hold::state`.
/// Nothing can be sent: the aim needs a vehicle heading, which is stale.
const WAITING: u8 = 1 << 0;
/// The gimbal's tracker was started: it owns the gimbal until it lets go.
const SUSPENDED: u8 = 1 << 1;
/// A postback has shown the tracker tracking since the aim was suspended.
const TRACK_SEEN: u8 = 1 << 2;

/// `Hold::prev_err_cdeg` with no postback judged since the last command.
const NO_ERROR: u16 = u16::MAX;
/// `Hold::sent_vehicle_cdeg` when the vehicle's heading was not known at the command.
const NO_HEADING: i16 = i16::MIN;

/// An aim being held: the state of the closed loop (see the [module docs](self)).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hold<const Q: usize, const T: usize, M: Medium> {
    /// The yaw, in the frame `flags` names.
    yaw: Heading,
    pitch: Pitch,
    flags: u8,
    /// Re-commands for an error since the gimbal was last on target.
    attempts: u8,
    /// [`WAITING`], [`SUSPENDED`], [`TRACK_SEEN`].
    state: u8,
    /// The vehicle's heading the gimbal turned the last command into a motor angle with,
    /// 0.01° ([`NO_HEADING`]: unknown).
    sent_vehicle_cdeg: i16,
    /// The larger axis error at the last postback judged, 0.01° ([`NO_ERROR`]: a command
    /// went since, so the next postback is not judged: it may predate any movement).
    prev_err_cdeg: u16,
    /// The loop's next look (its grid), and the earliest a re-command may go.
    pub(crate) next: Instant,
    /// The steering's step, stored when the aim or point-at starts: firmware that never
    /// aims links none of this.
    pub(crate) step: fn(&mut Link<Q, T, M>, Instant, &mut Earliest),
}

impl<const Q: usize, const T: usize, M: Medium> Hold<Q, T, M> {
    /// A hold of `aim` started at `now`: its first look is `now` (a deadline taken from
    /// any other instant could read as up to 2^31 ms ahead of a clock far from it).
    pub(crate) fn new(
        aim: Aim,
        step: fn(&mut Link<Q, T, M>, Instant, &mut Earliest),
        now: Instant,
    ) -> Self {
        let mut hold = Hold {
            yaw: aim.yaw.heading(),
            pitch: aim.pitch,
            flags: 0,
            attempts: 0,
            state: 0,
            sent_vehicle_cdeg: NO_HEADING,
            prev_err_cdeg: NO_ERROR,
            next: now,
            step,
        };
        hold.set_aim(aim);
        hold
    }

    /// The aim held.
    pub(crate) fn aim(&self) -> Aim {
        Aim {
            yaw: if self.flags & EARTH != 0 {
                Yaw::Earth(self.yaw)
            } else {
                Yaw::Vehicle(self.yaw)
            },
            pitch: self.pitch,
        }
    }

    /// Takes `aim` as new: commanded at the next step, the loop's judgement restarted; or,
    /// while the hold has yielded to a tracker, once the tracker lets go.
    fn set_aim(&mut self, aim: Aim) {
        self.yaw = aim.yaw.heading();
        self.pitch = aim.pitch;
        let when = if self.state & SUSPENDED != 0 {
            PENDING
        } else {
            NEW
        };
        // Nothing of the last command is kept: a postback is judged only against an aim
        // sent.
        self.flags = when | if aim.yaw.is_earth() { EARTH } else { 0 };
        self.attempts = 0;
    }

    /// The gimbal's tracker was started: nothing is sent but a new aim until it lets go.
    pub(crate) fn suspend(&mut self) {
        self.state = (self.state | SUSPENDED) & !TRACK_SEEN;
    }

    /// The tracker was stopped: the aim is sent again at the loop's next look.
    pub(crate) fn resume(&mut self) {
        if self.state & SUSPENDED != 0 {
            self.state &= !(SUSPENDED | TRACK_SEEN);
            self.flags |= PENDING;
            self.prev_err_cdeg = NO_ERROR;
        }
    }

    /// Whether `aim` differs from the aim held by more than `band_cdeg` on either axis, or
    /// in its frame.
    pub(crate) fn differs(&self, aim: Aim, band_cdeg: i32) -> bool {
        aim.yaw.is_earth() != (self.flags & EARTH != 0)
            || angle_cdeg(cdeg(aim.yaw.deci()).saturating_sub(cdeg(self.yaw.deci()))).abs()
                > band_cdeg
            || cdeg(aim.pitch.deci())
                .saturating_sub(cdeg(self.pitch.deci()))
                .abs()
                > band_cdeg
    }

    /// Takes `aim` when it differs from the aim held past the dead-band (a point-at's aim
    /// moving with the vehicle). A tracker the hold yielded to keeps the gimbal: the aim
    /// goes once it lets go.
    pub(crate) fn update(&mut self, aim: Aim, band_cdeg: i32) {
        if self.differs(aim, band_cdeg) {
            self.set_aim(aim);
        }
    }

    pub(crate) fn state(&self) -> AimState {
        AimState {
            aim: self.aim(),
            at_yaw_limit: self.flags & AT_LIMIT != 0,
            on_target: self.flags & ON_TARGET != 0,
            not_reached: self.flags & NOT_REACHED != 0,
            waiting_for_heading: self.state & WAITING != 0,
            yielded_to_tracker: self.state & SUSPENDED != 0,
        }
    }

    pub(crate) fn is_earth(&self) -> bool {
        self.flags & EARTH != 0
    }
}

/// 0.1° to 0.01°.
///
/// The loop's angles in 0.01° all come from 16-bit fields (tenths here, hundredths in the
/// attitude and the postback, the limits, tolerances and dead-band): `i32` holds every sum
/// and difference of two of them exactly, so the loop's saturating operations never
/// saturate (they are `i32` arithmetic without a panic path).
fn cdeg(deci: impl Into<i32>) -> i32 {
    deci.into().saturating_mul(10)
}

impl<const Q: usize, const T: usize, M: Medium> Link<Q, T, M> {
    /// Holds the gimbal at `aim`, closed loop: see the [module docs](aim). Ends a rate
    /// hold or a point-at (and any aim held). An aim within the dead-band of the one held
    /// changes nothing (a setpoint stream re-sending it); any other is commanded at once,
    /// both axes, and the link keeps it there from the postbacks and the vehicle's heading.
    ///
    /// Refused, changing nothing, when the yaw is in the earth frame, the gimbal is
    /// nose-referenced and no fresh vehicle heading was set. A full queue refuses nothing:
    /// the aim is held and its commands go at the next poll with room (counted in
    /// [`LinkStats::queue_full`] meanwhile).
    ///
    /// An aim's heading and pitch go together, so it needs a queue of at least two control
    /// slots: with `Q` below 2 a call does not compile.
    ///
    /// ```
    /// use idu_gimbal::link::{Aim, Config, Link, Yaw};
    /// use idu_gimbal::wire::control::{Heading, Pitch};
    /// use idu_gimbal::Instant;
    /// let mut link: Link<2, 8> = Link::new(Config::default());
    /// let level = Aim { yaw: Yaw::Vehicle(Heading::NORTH), pitch: Pitch::LEVEL };
    /// assert!(link.aim(level, Instant::from_millis(0)).is_ok());
    /// ```
    ///
    /// ```compile_fail
    /// use idu_gimbal::link::{Aim, Config, Link, Yaw};
    /// use idu_gimbal::wire::control::{Heading, Pitch};
    /// use idu_gimbal::Instant;
    /// let mut link: Link<1, 8> = Link::new(Config::default());
    /// let level = Aim { yaw: Yaw::Vehicle(Heading::NORTH), pitch: Pitch::LEVEL };
    /// assert!(link.aim(level, Instant::from_millis(0)).is_ok());
    /// ```
    pub fn aim(&mut self, aim: Aim, now: Instant) -> Result<(), AimError> {
        const {
            assert!(
                Q >= 2,
                "an aim sends a heading and a pitch together: Q >= 2"
            )
        };
        if aim.yaw.is_earth() && !self.north_referenced(now) && !self.is_fresh(ATTITUDE, now) {
            return Err(AimError::NoVehicleHeading);
        }
        let band = i32::from(self.config.aim_deadband_mdeg) / 10;
        if let Steering::Aim(h) = &self.steering {
            if !h.differs(aim, band) {
                return Ok(());
            }
        }
        // A zero-rate frame still waiting would arrive after the aim and undo it.
        self.tx.cancel_zero_rate();
        // A new hold: a new aim takes the gimbal back from a tracker, as any manual
        // pointing does, and starts the loop's judgement afresh.
        let mut hold = Hold::new(aim, Self::aim_step, now);
        // Commanded now rather than at the next poll: a setpoint's latency.
        let mut earliest = Earliest {
            now,
            ahead: MAX_QUIET_MS,
        };
        let period = u32::from(self.config.aim_period_ms.get());
        self.hold_step(&mut hold, now, period, &mut earliest);
        self.steering = Steering::Aim(hold);
        // The next poll runs the loop's step.
        self.quiet = quiet::Quiet::NONE;
        Ok(())
    }

    /// Stops holding an aim; the gimbal keeps its last command. (A point-at is stopped
    /// with [`Link::stop_pointing`].)
    pub fn stop_aiming(&mut self) {
        if let Steering::Aim(_) = self.steering {
            self.steering = Steering::Manual;
        }
    }

    /// The aim held, by [`Link::aim`] or by a point-at, and how it stands; `None` when
    /// neither is active (or a point-at has no aim yet).
    pub fn aim_state(&self) -> Option<AimState> {
        match &self.steering {
            Steering::Aim(h) => Some(h.state()),
            Steering::Point(p) => p.aim_hold().map(|h| h.state()),
            _ => None,
        }
    }

    /// Whether the gimbal's yaw is held in the earth frame: an earth-frame aim, or a
    /// point-at (a ground target is fixed in the earth frame).
    pub fn holds_earth_yaw(&self) -> bool {
        match &self.steering {
            Steering::Aim(h) => h.is_earth(),
            Steering::Point(_) => true,
            _ => false,
        }
    }

    /// The aim's step at a poll.
    pub(super) fn aim_step(&mut self, now: Instant, earliest: &mut Earliest) {
        let Steering::Aim(mut hold) = self.steering else {
            return;
        };
        let period = u32::from(self.config.aim_period_ms.get());
        self.hold_step(&mut hold, now, period, earliest);
        self.steering = Steering::Aim(hold);
    }

    /// One step of the closed loop (see the [module docs](aim)). A new aim is sent at
    /// once; everything else happens on the loop's grid, every `period` ms (an aim's
    /// `aim_period_ms`, a point-at's `point_at_period_ms`): what came since (a postback,
    /// the vehicle's heading, the gimbal's reference) is looked at there, and a re-command
    /// goes there. So what the loop does depends on the grid, not on how often the link is
    /// polled.
    // `period` before `earliest`, so that it is passed in a register: fifth, it goes on
    // the stack, 7 instructions a step.
    pub(super) fn hold_step(
        &mut self,
        h: &mut Hold<Q, T, M>,
        now: Instant,
        period: u32,
        earliest: &mut Earliest,
    ) {
        if h.flags & NEW == 0 && !now.is_at_or_after(h.next) {
            earliest.offer(h.next);
            return;
        }
        self.hold_look(h, now, period, earliest);
    }

    /// The loop's look at `now`, a time on its grid or a new aim's: what came since, and
    /// what to send (see [`Link::hold_step`]).
    pub(super) fn hold_look(
        &mut self,
        h: &mut Hold<Q, T, M>,
        now: Instant,
        period: u32,
        earliest: &mut Earliest,
    ) {
        let new = h.flags & NEW != 0;
        let north = self.north_referenced(now);
        let vehicle = self
            .is_fresh(ATTITUDE, now)
            .then(|| i32::from(self.vehicle.attitude.heading_centideg()));
        let yaw = cdeg(h.yaw.deci());
        let earth = h.flags & EARTH != 0;
        // Where the motor must be, from the nose.
        let motor = if earth {
            vehicle.map(|v| angle_cdeg(yaw.saturating_sub(v)))
        } else {
            Some(angle_cdeg(yaw))
        };
        // The heading command in the gimbal's reference.
        let command = match (north, earth) {
            (true, true) | (false, false) => Some(yaw),
            (true, false) => vehicle.map(|v| yaw.saturating_add(v)),
            (false, true) => vehicle.map(|v| yaw.saturating_sub(v)),
        };
        // What the latest postback says, read once (no copy of the whole postback).
        let (limit, tracking, reading) = match &self.latest {
            Some((p, _)) => (
                p.gimbal_type.motor_yaw_limit_cdeg(),
                p.tracking,
                Some((
                    p.motor_heading,
                    p.pitch,
                    p.mode == ControlMode::HeadingFollow,
                )),
            ),
            None => (GimbalType::X30.motor_yaw_limit_cdeg(), false, None),
        };
        let limit = i32::from(limit);
        match motor {
            Some(m) if m.abs() > limit => h.flags |= AT_LIMIT,
            Some(_) => h.flags &= !AT_LIMIT,
            None => {}
        }
        if self.status.take_came_up() {
            // The gimbal (re)started: a new chance. Its first postback is judged against
            // the last one before (a gimbal back at rest is no closer), unless a command
            // went since, which it may predate.
            h.attempts = 0;
            h.flags &= !NOT_REACHED;
        }
        let fresh = self.status.take_fresh_postback();
        // While the gimbal tracks a target its tracker owns the yaw and pitch: started
        // through the link (the aim suspended until the tracker lets go), or otherwise
        // (the postback says so).
        if h.state & SUSPENDED != 0 {
            if fresh && tracking {
                h.state |= TRACK_SEEN;
            } else if fresh && h.state & TRACK_SEEN != 0 {
                // The tracker let go (lost its target, or was stopped): the aim again.
                h.resume();
            }
        }
        let owned = tracking || h.state & SUSPENDED != 0;
        // The vehicle's heading the gimbal turns a command into a motor angle with: the
        // attitude it last received while north-referenced, ours otherwise.
        let reference = if north {
            Some(i32::from(self.vehicle.attitude_sent_cdeg))
        } else {
            vehicle
        };
        if h.flags & SENT != 0 && !owned {
            if let (true, Some(reading), Some(m)) = (fresh, reading, motor) {
                self.judge(h, reading, m.clamp(limit.saturating_neg(), limit));
            }
            if (h.flags & SENT_NORTH != 0) != north {
                h.flags |= PENDING;
            }
            let band = i32::from(self.config.aim_deadband_mdeg) / 10;
            if let (Some(r), true) = (reference, h.sent_vehicle_cdeg != NO_HEADING) {
                if angle_cdeg(r.saturating_sub(i32::from(h.sent_vehicle_cdeg))).abs() > band {
                    // A turn changes what the gimbal must do: a new chance.
                    h.flags = (h.flags | PENDING) & !NOT_REACHED;
                    h.attempts = 0;
                }
            }
        }
        if command.is_none() {
            h.state |= WAITING;
        } else {
            h.state &= !WAITING;
        }
        let due = new || (h.flags & PENDING != 0 && !owned);
        match command {
            Some(command) if due => {
                if self.tx.control_free() < 2 {
                    // Both or neither: the next poll tries again.
                    self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
                    earliest.offer(now);
                    return;
                }
                self.send_aim(h, command, north, reference);
                if !new {
                    self.stats.aim_recommands = self.stats.aim_recommands.wrapping_add(1);
                }
                h.next = now.add_millis(period);
            }
            _ => h.next = advance(h.next, period, now),
        }
        earliest.offer(h.next);
    }

    /// Queues the heading command `command_cdeg` (in the gimbal's reference now, north or
    /// not, which it turns into a motor angle with the vehicle heading `reference_cdeg`)
    /// and the aim's pitch; there is room for both.
    fn send_aim(
        &mut self,
        h: &mut Hold<Q, T, M>,
        command_cdeg: i32,
        north: bool,
        reference_cdeg: Option<i32>,
    ) {
        let heading = Heading::from_centideg_wrapped(command_cdeg);
        // Room for both was checked by the caller.
        let _ = self.tx.push_control(
            Command::from(GimbalCommand::Heading(heading)).encode(),
            &mut self.quiet,
        );
        let _ = self.tx.push_control(
            Command::from(GimbalCommand::Pitch(h.pitch)).encode(),
            &mut self.quiet,
        );
        h.flags = (h.flags & !(NEW | PENDING | SENT_NORTH | ON_TARGET))
            | SENT
            | if north { SENT_NORTH } else { 0 };
        // A heading in [-18000, 17999] (the attitude's) fits.
        h.sent_vehicle_cdeg = reference_cdeg.map_or(NO_HEADING, |v| v as i16);
        h.prev_err_cdeg = NO_ERROR;
    }

    /// Judges a postback (its motor angle and pitch, 0.01°, and whether its mode is heading
    /// follow) against the aim, the motor expected at `motor_cdeg` (within its travel): on
    /// target, getting closer, or off and due a re-command (or not reached).
    fn judge(
        &mut self,
        h: &mut Hold<Q, T, M>,
        (motor, pitch, followed): (i16, i16, bool),
        motor_cdeg: i32,
    ) {
        let yaw_err = angle_cdeg(i32::from(motor).saturating_sub(motor_cdeg)).abs();
        let pitch_err = i32::from(pitch).saturating_sub(cdeg(h.pitch.deci())).abs();
        let err = yaw_err.max(pitch_err);
        let tolerance = i32::from(self.config.aim_tolerance_mdeg) / 10;
        let prev = h.prev_err_cdeg;
        h.prev_err_cdeg = err.min(i32::from(NO_ERROR - 1)) as u16;
        if err <= tolerance && !followed {
            h.flags = (h.flags | ON_TARGET) & !NOT_REACHED;
            h.attempts = 0;
            return;
        }
        h.flags &= !ON_TARGET;
        if prev == NO_ERROR {
            // The first postback since a command: it may predate any movement.
            return;
        }
        let closer = err.saturating_add(tolerance) < i32::from(prev) && !followed;
        if closer || h.flags & NOT_REACHED != 0 {
            return;
        }
        if h.attempts < ATTEMPTS {
            h.attempts = h.attempts.saturating_add(1);
            h.flags |= PENDING;
        } else {
            h.flags |= NOT_REACHED;
            self.stats.aim_not_reached = self.stats.aim_not_reached.wrapping_add(1);
            self.status.raise(Event::AimNotReached);
        }
    }
}
