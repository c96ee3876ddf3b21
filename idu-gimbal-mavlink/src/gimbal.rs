//! The gimbal side of the bridge: what it needs of the core, over either transport.

use idu_gimbal::geo::Position;
use idu_gimbal::link::serial::SerialLink;
use idu_gimbal::link::Link;
use idu_gimbal::wire::control::{Command, Rate};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::{Gimbal, Instant, SerialGimbal};

/// What the bridge asks of the gimbal. Implemented for the core's sans-IO links
/// ([`Link`] on CAN, [`SerialLink`] on the UART) and for its drivers ([`Gimbal`],
/// [`SerialGimbal`]); the application keeps polling the driver as usual.
pub trait GimbalControl {
    /// Queues a command; `false` when the queue is full.
    fn send(&mut self, command: Command) -> bool;
    /// Starts or refreshes a rate hold (the core's dead-man stops it when refreshes stop);
    /// `false` when the queue is full.
    fn set_rate(&mut self, rate: Rate, now: Instant) -> bool;
    /// The vehicle attitude, measured at `stamp`: pushed to the gimbal where the transport
    /// carries it, kept for point-at otherwise.
    fn set_attitude(&mut self, attitude: Attitude, stamp: Instant);
    /// The vehicle position, measured at `stamp` (as [`GimbalControl::set_attitude`]).
    fn set_gps(&mut self, gps: Gps, stamp: Instant);
    /// The vehicle altitude, measured at `stamp` (as [`GimbalControl::set_attitude`]).
    fn set_altitude(&mut self, altitude: Altitude, stamp: Instant);
    /// Whether the gimbal references headings to north now (attitude is being pushed); nose
    /// otherwise.
    fn north_referenced(&self, now: Instant) -> bool;
    /// The latest postback and its age in milliseconds.
    fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)>;
    /// Whether the link to the gimbal is up.
    fn is_link_up(&self) -> bool;
    /// Keeps the gimbal pointed at a ground location while the vehicle moves (the core's
    /// point-at); any angle or rate command ends it.
    fn point_at(&mut self, target: Position);
    /// Stops pointing at a location; the gimbal keeps its aim.
    fn stop_pointing(&mut self);
}

impl<const Q: usize, const T: usize> GimbalControl for Link<Q, T> {
    fn send(&mut self, command: Command) -> bool {
        Link::send(self, command).is_ok()
    }
    fn set_rate(&mut self, rate: Rate, now: Instant) -> bool {
        Link::set_rate(self, rate, now).is_ok()
    }
    fn set_attitude(&mut self, attitude: Attitude, stamp: Instant) {
        Link::set_attitude(self, attitude, stamp)
    }
    fn set_gps(&mut self, gps: Gps, stamp: Instant) {
        Link::set_gps(self, gps, stamp)
    }
    fn set_altitude(&mut self, altitude: Altitude, stamp: Instant) {
        Link::set_altitude(self, altitude, stamp)
    }
    fn north_referenced(&self, now: Instant) -> bool {
        self.attitude_is_pushed(now)
    }
    fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)> {
        Link::latest_postback(self, now)
    }
    fn is_link_up(&self) -> bool {
        self.is_up()
    }
    fn point_at(&mut self, target: Position) {
        Link::point_at(self, target)
    }
    fn stop_pointing(&mut self) {
        Link::stop_pointing(self)
    }
}

/// The serial link carries no vehicle frames: vehicle data is kept for point-at, and
/// headings are always nose-referenced.
impl<const Q: usize> GimbalControl for SerialLink<Q> {
    fn send(&mut self, command: Command) -> bool {
        self.link_mut().send(command).is_ok()
    }
    fn set_rate(&mut self, rate: Rate, now: Instant) -> bool {
        self.link_mut().set_rate(rate, now).is_ok()
    }
    fn set_attitude(&mut self, attitude: Attitude, stamp: Instant) {
        self.link_mut().set_attitude(attitude, stamp)
    }
    fn set_gps(&mut self, gps: Gps, stamp: Instant) {
        self.link_mut().set_gps(gps, stamp)
    }
    fn set_altitude(&mut self, altitude: Altitude, stamp: Instant) {
        self.link_mut().set_altitude(altitude, stamp)
    }
    fn north_referenced(&self, _now: Instant) -> bool {
        false
    }
    fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)> {
        self.link().latest_postback(now)
    }
    fn is_link_up(&self) -> bool {
        self.link().is_up()
    }
    fn point_at(&mut self, target: Position) {
        self.link_mut().point_at(target)
    }
    fn stop_pointing(&mut self) {
        self.link_mut().stop_pointing()
    }
}

impl<C: embedded_can::nb::Can, const Q: usize, const T: usize> GimbalControl for Gimbal<C, Q, T> {
    fn send(&mut self, command: Command) -> bool {
        self.link_mut().send(command).is_ok()
    }
    fn set_rate(&mut self, rate: Rate, now: Instant) -> bool {
        GimbalControl::set_rate(self.link_mut(), rate, now)
    }
    fn set_attitude(&mut self, attitude: Attitude, stamp: Instant) {
        Gimbal::set_attitude(self, attitude, stamp)
    }
    fn set_gps(&mut self, gps: Gps, stamp: Instant) {
        Gimbal::set_gps(self, gps, stamp)
    }
    fn set_altitude(&mut self, altitude: Altitude, stamp: Instant) {
        Gimbal::set_altitude(self, altitude, stamp)
    }
    fn north_referenced(&self, now: Instant) -> bool {
        self.link().attitude_is_pushed(now)
    }
    fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)> {
        Gimbal::latest_postback(self, now)
    }
    fn is_link_up(&self) -> bool {
        Gimbal::is_link_up(self)
    }
    fn point_at(&mut self, target: Position) {
        Gimbal::point_at(self, target)
    }
    fn stop_pointing(&mut self) {
        Gimbal::stop_pointing(self)
    }
}

impl<P: idu_gimbal::driver::SerialPort, const Q: usize> GimbalControl for SerialGimbal<P, Q> {
    fn send(&mut self, command: Command) -> bool {
        GimbalControl::send(self.link_mut(), command)
    }
    fn set_rate(&mut self, rate: Rate, now: Instant) -> bool {
        GimbalControl::set_rate(self.link_mut(), rate, now)
    }
    fn set_attitude(&mut self, attitude: Attitude, stamp: Instant) {
        self.observe_attitude(attitude, stamp)
    }
    fn set_gps(&mut self, gps: Gps, stamp: Instant) {
        self.observe_gps(gps, stamp)
    }
    fn set_altitude(&mut self, altitude: Altitude, stamp: Instant) {
        self.observe_altitude(altitude, stamp)
    }
    fn north_referenced(&self, _now: Instant) -> bool {
        false
    }
    fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)> {
        SerialGimbal::latest_postback(self, now)
    }
    fn is_link_up(&self) -> bool {
        SerialGimbal::is_link_up(self)
    }
    fn point_at(&mut self, target: Position) {
        SerialGimbal::point_at(self, target)
    }
    fn stop_pointing(&mut self) {
        SerialGimbal::stop_pointing(self)
    }
}
