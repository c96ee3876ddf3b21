//! The one command surface of a gimbal, whatever carries it.
//!
//! [`GimbalControl`] is what an application asks of a gimbal: commands, a rate hold,
//! point-at, the vehicle's data, events and the latest postback. The sans-IO
//! [`Link`] implements it; every transport over a link (the CAN driver
//! [`Gimbal`](crate::Gimbal), the serial driver [`SerialGimbal`](crate::SerialGimbal), the
//! sans-IO [`SerialLink`](crate::link::serial::SerialLink)) gets it from its link through
//! [`Transport`], and keeps only what is its own: `poll`, `next_deadline`, `stats`,
//! `release`. As smoltcp keeps socket operations on sockets and lets the interface only
//! move packets, the drivers here only move frames and bytes.
//!
//! ```
//! use idu_gimbal::wire::control::{GimbalCommand, Pitch};
//! use idu_gimbal::{GimbalControl, Instant};
//!
//! /// Works the same on CAN, on the UART, or on the sans-IO link in a test.
//! fn look_down_a_bit(gimbal: &mut impl GimbalControl, now: Instant) -> bool {
//!     let ok = gimbal.send(GimbalCommand::Pitch(Pitch::new(-30.0).unwrap())).is_ok();
//!     ok && gimbal.latest_postback(now).is_some()
//! }
//! # let mut link: idu_gimbal::link::Link = idu_gimbal::link::Link::new(Default::default());
//! # assert!(!look_down_a_bit(&mut link, Instant::from_millis(0)));
//! ```

use crate::geo::Position;
use crate::link::{Aim, AimError, AimState, Event, Link, QueueFull};
use crate::time::Instant;
use crate::wire::control::{Command, Rate};
use crate::wire::postback::{GimbalType, Postback};
use crate::wire::vehicle::{Altitude, Attitude, Gps};

/// What an application asks of a gimbal, on any transport; see the [module docs](self).
pub trait GimbalControl {
    /// Queues a command. A pointing command ends a rate hold or a point-at. A full queue
    /// hands the command back and ends nothing (see [`Link::send`]).
    fn send(&mut self, command: impl Into<Command>) -> Result<(), QueueFull<Command>>;

    /// How many commands [`GimbalControl::send`] takes now (see [`Link::command_room`]).
    fn command_room(&self) -> usize;

    /// Starts, changes or refreshes a rate hold, which the dead-man ends when refreshes
    /// stop; a full queue hands the rate back (see [`Link::set_rate`]).
    fn set_rate(&mut self, rate: Rate, now: Instant) -> Result<(), QueueFull<Rate>>;

    /// Ends a rate hold with one zero-rate command (see [`Link::stop_rate`]).
    fn stop_rate(&mut self);

    /// Whether a rate hold is active.
    fn is_rate_holding(&self) -> bool;

    /// Keeps the gimbal pointed at a ground target while the vehicle moves (see
    /// [`Link::point_at`]); it needs the vehicle's attitude, GPS and altitude, fresh.
    fn point_at(&mut self, target: Position);

    /// Stops pointing at a target; the gimbal keeps its last aim.
    fn stop_pointing(&mut self);

    /// The target being pointed at, if any.
    fn pointing_target(&self) -> Option<Position>;

    /// Holds the gimbal at an orientation in the earth or the vehicle frame, closed loop
    /// (see [`Link::aim`]).
    fn aim(&mut self, aim: Aim, now: Instant) -> Result<(), AimError>;

    /// Stops holding an aim; the gimbal keeps its last command.
    fn stop_aiming(&mut self);

    /// The aim held (by [`GimbalControl::aim`] or a point-at) and how it stands.
    fn aim_state(&self) -> Option<AimState>;

    /// Whether the gimbal's yaw is held in the earth frame (an earth-frame aim or a
    /// point-at).
    fn holds_earth_yaw(&self) -> bool;

    /// The vehicle's attitude, measured at `stamp`: pushed to the gimbal where the
    /// transport carries vehicle frames (CAN), kept for point-at otherwise (the UART).
    fn set_attitude(&mut self, attitude: Attitude, stamp: Instant);

    /// The vehicle's position, measured at `stamp` (as [`GimbalControl::set_attitude`]).
    fn set_gps(&mut self, gps: Gps, stamp: Instant);

    /// The vehicle's altitude, measured at `stamp` (as [`GimbalControl::set_attitude`]).
    fn set_altitude(&mut self, altitude: Altitude, stamp: Instant);

    /// Whether the gimbal references headings to north now (its attitude is being
    /// pushed, fresh); to the vehicle's nose otherwise, and always on the UART.
    fn north_referenced(&self, now: Instant) -> bool;

    /// The next event (see [`Event`] for how events wait).
    fn next_event(&mut self) -> Option<Event>;

    /// Whether the link is up (a valid postback within the link timeout).
    fn is_link_up(&self) -> bool;

    /// The latest valid postback and its age in milliseconds.
    fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)>;

    /// The gimbal model as last reported.
    fn gimbal_type(&self) -> Option<GimbalType>;
}

/// A transport over a link: a driver, or a sans-IO link for one transport. It gets
/// [`GimbalControl`] from [`Transport::link`].
pub trait Transport {
    /// The link it carries.
    type Link: GimbalControl;

    /// The link, for what the transport does not wrap.
    fn link(&self) -> &Self::Link;

    /// The link, mutably.
    fn link_mut(&mut self) -> &mut Self::Link;
}

impl<const Q: usize, const T: usize> GimbalControl for Link<Q, T> {
    fn send(&mut self, command: impl Into<Command>) -> Result<(), QueueFull<Command>> {
        Link::send(self, command)
    }
    #[inline]
    fn command_room(&self) -> usize {
        Link::command_room(self)
    }
    #[inline]
    fn set_rate(&mut self, rate: Rate, now: Instant) -> Result<(), QueueFull<Rate>> {
        Link::set_rate(self, rate, now)
    }
    #[inline]
    fn stop_rate(&mut self) {
        Link::stop_rate(self)
    }
    #[inline]
    fn is_rate_holding(&self) -> bool {
        Link::is_rate_holding(self)
    }
    #[inline]
    fn point_at(&mut self, target: Position) {
        Link::point_at(self, target)
    }
    #[inline]
    fn stop_pointing(&mut self) {
        Link::stop_pointing(self)
    }
    #[inline]
    fn pointing_target(&self) -> Option<Position> {
        Link::pointing_target(self)
    }
    #[inline]
    fn aim(&mut self, aim: Aim, now: Instant) -> Result<(), AimError> {
        Link::aim(self, aim, now)
    }
    #[inline]
    fn stop_aiming(&mut self) {
        Link::stop_aiming(self)
    }
    #[inline]
    fn aim_state(&self) -> Option<AimState> {
        Link::aim_state(self)
    }
    #[inline]
    fn holds_earth_yaw(&self) -> bool {
        Link::holds_earth_yaw(self)
    }
    #[inline]
    fn set_attitude(&mut self, attitude: Attitude, stamp: Instant) {
        Link::set_attitude(self, attitude, stamp)
    }
    #[inline]
    fn set_gps(&mut self, gps: Gps, stamp: Instant) {
        Link::set_gps(self, gps, stamp)
    }
    #[inline]
    fn set_altitude(&mut self, altitude: Altitude, stamp: Instant) {
        Link::set_altitude(self, altitude, stamp)
    }
    #[inline]
    fn north_referenced(&self, now: Instant) -> bool {
        Link::north_referenced(self, now)
    }
    #[inline]
    fn next_event(&mut self) -> Option<Event> {
        Link::next_event(self)
    }
    #[inline]
    fn is_link_up(&self) -> bool {
        Link::is_link_up(self)
    }
    #[inline]
    fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)> {
        Link::latest_postback(self, now)
    }
    #[inline]
    fn gimbal_type(&self) -> Option<GimbalType> {
        Link::gimbal_type(self)
    }
}

/// Every transport answers for its link.
impl<D: Transport> GimbalControl for D {
    fn send(&mut self, command: impl Into<Command>) -> Result<(), QueueFull<Command>> {
        self.link_mut().send(command)
    }
    #[inline]
    fn command_room(&self) -> usize {
        self.link().command_room()
    }
    #[inline]
    fn set_rate(&mut self, rate: Rate, now: Instant) -> Result<(), QueueFull<Rate>> {
        self.link_mut().set_rate(rate, now)
    }
    #[inline]
    fn stop_rate(&mut self) {
        self.link_mut().stop_rate()
    }
    #[inline]
    fn is_rate_holding(&self) -> bool {
        self.link().is_rate_holding()
    }
    #[inline]
    fn point_at(&mut self, target: Position) {
        self.link_mut().point_at(target)
    }
    #[inline]
    fn stop_pointing(&mut self) {
        self.link_mut().stop_pointing()
    }
    #[inline]
    fn pointing_target(&self) -> Option<Position> {
        self.link().pointing_target()
    }
    #[inline]
    fn aim(&mut self, aim: Aim, now: Instant) -> Result<(), AimError> {
        self.link_mut().aim(aim, now)
    }
    #[inline]
    fn stop_aiming(&mut self) {
        self.link_mut().stop_aiming()
    }
    #[inline]
    fn aim_state(&self) -> Option<AimState> {
        self.link().aim_state()
    }
    #[inline]
    fn holds_earth_yaw(&self) -> bool {
        self.link().holds_earth_yaw()
    }
    #[inline]
    fn set_attitude(&mut self, attitude: Attitude, stamp: Instant) {
        self.link_mut().set_attitude(attitude, stamp)
    }
    #[inline]
    fn set_gps(&mut self, gps: Gps, stamp: Instant) {
        self.link_mut().set_gps(gps, stamp)
    }
    #[inline]
    fn set_altitude(&mut self, altitude: Altitude, stamp: Instant) {
        self.link_mut().set_altitude(altitude, stamp)
    }
    #[inline]
    fn north_referenced(&self, now: Instant) -> bool {
        self.link().north_referenced(now)
    }
    #[inline]
    fn next_event(&mut self) -> Option<Event> {
        self.link_mut().next_event()
    }
    #[inline]
    fn is_link_up(&self) -> bool {
        self.link().is_link_up()
    }
    #[inline]
    fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)> {
        self.link().latest_postback(now)
    }
    #[inline]
    fn gimbal_type(&self) -> Option<GimbalType> {
        self.link().gimbal_type()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::serial::SerialLink;
    use crate::link::Config;
    use crate::wire::control::{GimbalCommand, Pitch};

    /// The same calls through the trait on CAN's link and on the serial link: what each
    /// transport can carry decides, not which methods it has.
    fn drive(g: &mut impl GimbalControl, now: Instant) -> (bool, bool) {
        let sent = g
            .send(GimbalCommand::Pitch(Pitch::new(-30.0).unwrap()))
            .is_ok();
        g.set_attitude(Attitude::new(0.0, 0.0, 90.0).unwrap(), now);
        (sent, g.north_referenced(now))
    }

    #[test]
    fn the_attitude_is_pushed_on_can_and_kept_on_the_uart() {
        let now = Instant::from_millis(10);
        let mut can: Link = Link::new(Config::default());
        let mut uart: SerialLink = SerialLink::new(Config::default());
        // Queued, not yet sent: the gimbal does not have the attitude.
        assert_eq!(drive(&mut can, now), (true, false));
        assert_eq!(drive(&mut uart, now), (true, false));
        can.poll(now);
        let mut ids = Vec::new();
        while let Some(f) = can.next_transmit() {
            ids.push(f.id);
            can.transmit_done(None);
        }
        // The pitch first (control before vehicle), then the attitude: north from here.
        assert_eq!(ids, [crate::wire::ids::CONTROL, crate::wire::ids::ATTITUDE]);
        assert!(can.north_referenced(now));
        uart.poll(now);
        while !uart.transmit_bytes().is_empty() {
            let n = uart.transmit_bytes().len();
            uart.transmit_written(n);
        }
        assert!(!uart.north_referenced(now), "never on the UART");
        assert!(!can.is_link_up() && !uart.is_link_up());
    }
}
