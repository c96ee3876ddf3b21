//! The stateful link: reassembly, the transmit queue and the schedules, with no I/O.
//!
//! [`Link`] is a sans-IO state machine. Feed it received frames with [`Link::receive`],
//! call [`Link::poll`] with the current time, and move the frames it hands out with
//! [`Link::next_transmit`] to whatever CAN stack you have, reporting back with
//! [`Link::transmit_done`] or [`Link::transmit_refused`]. The [`Gimbal`](crate::Gimbal)
//! driver does exactly this over an `embedded-can` driver; an async (embassy) or
//! non-`embedded-can` stack can do the same.
//!
//! ```
//! use idu_gimbal::link::{Config, Event, Link};
//! use idu_gimbal::wire::control::{GimbalCommand, Pitch};
//! use idu_gimbal::wire::postback::Postback;
//! use idu_gimbal::{wire::ids, Instant};
//!
//! let mut link: Link = Link::new(Config::default());
//! let now = Instant::from_millis(0);
//! link.send(GimbalCommand::Pitch(Pitch::new(-45.0)?)).unwrap();
//! link.poll(now);
//! let frame = link.next_transmit().unwrap();
//! assert_eq!(frame.data, [0x0F, 0x08, 0x02, 0x3E, 0xFE, 0, 0, 0]);
//! link.transmit_done(None); // the CAN driver took it
//!
//! for data in (Postback { pitch: -4500, ..Postback::default() }).to_can_frames() {
//!     link.receive(ids::POSTBACK, &data, now);
//! }
//! assert_eq!(link.next_event(), Some(Event::LinkUp));
//! assert!(matches!(link.next_event(), Some(Event::Postback(p)) if p.pitch == -4500));
//! # Ok::<(), idu_gimbal::wire::RangeError>(())
//! ```

mod point;
pub mod postback;
pub mod queue;
pub mod text;

use core::fmt;

use crate::geo::{self, Position};
use crate::time::Instant;
use crate::wire::control::{Command, GimbalCommand, Heading, Pitch, Rate};
use crate::wire::postback::{GimbalType, Postback};
use crate::wire::vehicle::{Altitude, Attitude, Gps, VehicleFrame};
use crate::wire::{ids, text as wire_text, Frame};
use postback::PostbackAssembler;
use queue::{Requeued, TxQueue};

/// Timing of the link. Every field is in milliseconds unless it says otherwise. A vehicle
/// push period of 0 disables that push.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Period of the attitude push (default 100).
    pub attitude_period_ms: u32,
    /// Period of the GPS push (default 200).
    pub gps_period_ms: u32,
    /// Period of the altitude push (default 200).
    pub altitude_period_ms: u32,
    /// Vehicle data older than this is not pushed (default 1000).
    pub vehicle_stale_ms: u32,
    /// Period at which a rate hold repeats its rate command (default 50, as the document
    /// recommends).
    pub rate_repeat_ms: u32,
    /// A rate hold not refreshed within this stops with one zero-rate command (default 250).
    pub rate_deadman_ms: u32,
    /// The link is up while a valid postback arrived within this (default 1500: three
    /// postback periods).
    pub link_timeout_ms: u32,
    /// Bound on the gap between frames of one postback (default 100).
    pub postback_max_gap_ms: u32,
    /// Period at which [`Link::point_at`] recomputes the aim (default 100: 10 Hz).
    pub point_at_period_ms: u32,
    /// [`Link::point_at`] re-commands the gimbal only when the aim moved by more than this,
    /// in millidegrees (default 100: 0.1°).
    pub point_at_deadband_mdeg: u32,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            attitude_period_ms: 100,
            gps_period_ms: 200,
            altitude_period_ms: 200,
            vehicle_stale_ms: 1000,
            rate_repeat_ms: 50,
            rate_deadman_ms: 250,
            link_timeout_ms: 1500,
            postback_max_gap_ms: postback::DEFAULT_MAX_GAP_MS,
            point_at_period_ms: 100,
            point_at_deadband_mdeg: 100,
        }
    }
}

/// Something the application may want to act on.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// A valid postback arrived.
    Postback(Postback),
    /// The first valid postback after start or after the link was down.
    LinkUp,
    /// No valid postback within the link timeout.
    LinkDown,
    /// A rate hold was not refreshed in time: one zero-rate command was queued.
    RateHoldExpired,
    /// [`Link::point_at`]'s target needs a pitch outside the gimbal's [-100°, 60°]; the
    /// gimbal holds the last reachable aim. Raised once each time the target leaves reach.
    TargetUnreachable {
        /// The elevation the target needs, in 0.01°.
        elevation_cdeg: i32,
    },
}

/// Counters for diagnosing a bus. All wrap at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// Frames received (including ignored ones).
    pub frames_received: u32,
    /// Frames the CAN driver accepted for transmission.
    pub frames_sent: u32,
    /// Valid postbacks received.
    pub postbacks: u32,
    /// Postback candidates whose CRC failed.
    pub crc_errors: u32,
    /// Postbacks restarted by a newer header after lost frames.
    pub restarts: u32,
    /// Partial postbacks dropped for a gap between frames.
    pub dropped_partials: u32,
    /// Postback-ID frames that were not 8 bytes.
    pub malformed: u32,
    /// Commands, rate holds or texts refused because the queue was full (including
    /// scheduled frames that had to wait for room).
    pub queue_full: u32,
    /// Frames handed back by the CAN driver (displaced from a mailbox) and re-queued.
    pub requeued: u32,
    /// Vehicle frames replaced by a newer value before they were sent.
    pub superseded: u32,
    /// Received frames that are not for this node (other IDs, standard IDs, remote frames).
    pub ignored_frames: u32,
    /// Events dropped because the application did not take them in time.
    pub events_dropped: u32,
    /// Vehicle frames scheduled for transmission.
    pub vehicle_pushes: u32,
}

/// A full queue: the item is handed back.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QueueFull<T>(pub T);

impl<T> fmt::Display for QueueFull<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("transmit queue is full")
    }
}

#[cfg(feature = "std")]
impl<T: fmt::Debug> std::error::Error for QueueFull<T> {}

/// Why a text was not queued. Nothing of it was queued.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TextQueueError {
    /// The text itself is invalid.
    Invalid(wire_text::TextError),
    /// Not enough free text slots for all of its frames.
    NoRoom {
        /// Frames the text needs.
        needed: usize,
        /// Free slots.
        free: usize,
    },
}

impl fmt::Display for TextQueueError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TextQueueError::Invalid(e) => e.fmt(f),
            TextQueueError::NoRoom { needed, free } => {
                write!(f, "text needs {needed} frames, the queue has {free} free")
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for TextQueueError {}

#[derive(Clone, Copy, Debug)]
struct VehicleSource {
    latest: Option<(Frame, Instant)>,
    next: Instant,
    /// Push at the next poll, whatever `next` says (new data after none or stale data).
    due: bool,
}

impl VehicleSource {
    const EMPTY: Self = VehicleSource {
        latest: None,
        next: Instant::from_millis(0),
        due: true,
    };
}

#[derive(Clone, Copy, Debug)]
enum RateState {
    Idle,
    Holding {
        rate: Rate,
        frame: Frame,
        refreshed: Instant,
        next: Instant,
    },
    /// The hold ended; its zero-rate frame waits for room in the queue.
    Stopping {
        zero: Frame,
    },
}

/// Advances a deadline by one period; after a long gap, resynchronises to `now` so that it
/// yields one action, not a burst.
fn advance(deadline: Instant, period: u32, now: Instant) -> Instant {
    let next = deadline.add_millis(period);
    if now.is_at_or_after(next) {
        now.add_millis(period)
    } else {
        next
    }
}

/// The sans-IO link to one gimbal; see the [module docs](self).
///
/// `Q` is the number of control-frame slots, `T` the number of text-frame slots.
#[derive(Clone, Debug)]
pub struct Link<const Q: usize = 8, const T: usize = 16> {
    config: Config,
    tx: TxQueue<Q, T>,
    assembler: PostbackAssembler,
    /// Attitude, GPS, altitude.
    vehicle: [VehicleSource; 3],
    rate: RateState,
    point: Option<point::PointAt>,
    latest: Option<(Postback, Instant)>,
    up: bool,
    events: heapless::Deque<Event, 8>,
    stats: LinkStats,
}

const ATTITUDE: usize = 0;
const GPS: usize = 1;
const ALTITUDE: usize = 2;

impl<const Q: usize, const T: usize> Link<Q, T> {
    /// A link with the given timing, link down, nothing queued.
    pub fn new(config: Config) -> Self {
        Link {
            config,
            tx: TxQueue::new(),
            assembler: PostbackAssembler::with_max_gap(config.postback_max_gap_ms),
            vehicle: [VehicleSource::EMPTY; 3],
            rate: RateState::Idle,
            point: None,
            latest: None,
            up: false,
            events: heapless::Deque::new(),
            stats: LinkStats::default(),
        }
    }

    /// The timing in use.
    pub fn config(&self) -> &Config {
        &self.config
    }

    fn event(&mut self, e: Event) {
        if self.events.push_back(e).is_err() {
            self.stats.events_dropped = self.stats.events_dropped.wrapping_add(1);
        }
    }

    /// The next event, oldest first. Up to 8 wait; later ones are dropped and counted.
    pub fn next_event(&mut self) -> Option<Event> {
        self.events.pop_front()
    }

    // ---- receiving ----

    /// Takes a received frame with a 29-bit extended ID.
    pub fn receive(&mut self, id: u32, data: &[u8], now: Instant) {
        self.stats.frames_received = self.stats.frames_received.wrapping_add(1);
        if id != ids::POSTBACK {
            self.stats.ignored_frames = self.stats.ignored_frames.wrapping_add(1);
            return;
        }
        if let Some(p) = self.assembler.feed(id, data, now) {
            self.latest = Some((p, now));
            if !self.up {
                self.up = true;
                self.event(Event::LinkUp);
            }
            self.event(Event::Postback(p));
        }
    }

    /// Counts a received frame that cannot be for this node (a standard ID or a remote
    /// frame); the driver calls it for what it does not pass to [`Link::receive`].
    pub fn receive_ignored(&mut self) {
        self.stats.frames_received = self.stats.frames_received.wrapping_add(1);
        self.stats.ignored_frames = self.stats.ignored_frames.wrapping_add(1);
    }

    /// Whether a valid postback arrived within the link timeout (as of the last poll).
    pub fn is_up(&self) -> bool {
        self.up
    }

    /// The latest valid postback and its age in milliseconds.
    pub fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)> {
        self.latest.map(|(p, at)| (p, now.millis_since(at)))
    }

    /// The gimbal model as last reported.
    pub fn gimbal_type(&self) -> Option<GimbalType> {
        self.latest.map(|(p, _)| p.gimbal_type)
    }

    // ---- commands ----

    /// Queues a command. A pointing command (see [`Command::is_pointing`]) cancels a rate
    /// hold. A full queue hands the command back and cancels nothing.
    pub fn send(&mut self, command: impl Into<Command>) -> Result<(), QueueFull<Command>> {
        let command = command.into();
        if self.tx.push_control(command.to_frame()).is_err() {
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
            return Err(QueueFull(command));
        }
        if command.is_pointing() {
            if let RateState::Holding { .. } = self.rate {
                self.rate = RateState::Idle;
            }
            self.point = None;
        }
        Ok(())
    }

    /// Starts, changes or refreshes a rate hold on the gimbal: the rate command is repeated
    /// every `rate_repeat_ms` while this is called again within `rate_deadman_ms`.
    ///
    /// Starting a hold or changing its rate queues the command at once; a full queue hands
    /// the rate back and leaves the hold as it was. Refreshing the same rate queues nothing.
    pub fn set_rate(&mut self, rate: Rate, now: Instant) -> Result<(), QueueFull<Rate>> {
        let period = self.config.rate_repeat_ms;
        match &mut self.rate {
            RateState::Holding {
                rate: held,
                refreshed,
                ..
            } if *held == rate => {
                *refreshed = now;
                Ok(())
            }
            _ => {
                let frame = Command::from(GimbalCommand::Rate(rate)).to_frame();
                if self.tx.push_control(frame).is_err() {
                    self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
                    return Err(QueueFull(rate));
                }
                self.rate = RateState::Holding {
                    rate,
                    frame,
                    refreshed: now,
                    next: now.add_millis(period),
                };
                // A rate hold is a pointing command: it ends a point-at.
                self.point = None;
                Ok(())
            }
        }
    }

    /// Ends a rate hold with one zero-rate command. The zero-rate command is never lost: if
    /// the queue is full it is sent as soon as there is room.
    pub fn stop_rate(&mut self) {
        if let RateState::Holding { .. } = self.rate {
            self.end_rate_hold();
        }
    }

    /// Whether a rate hold is active.
    pub fn is_rate_holding(&self) -> bool {
        matches!(self.rate, RateState::Holding { .. })
    }

    fn end_rate_hold(&mut self) {
        let zero = Command::from(GimbalCommand::Rate(Rate::ZERO)).to_frame();
        self.rate = match self.tx.push_control(zero) {
            Ok(()) => RateState::Idle,
            Err(zero) => {
                self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
                RateState::Stopping { zero }
            }
        };
    }

    /// Queues a text message, all of it or nothing.
    pub fn send_text(&mut self, text: &[u8]) -> Result<(), TextQueueError> {
        let frames = wire_text::chunks(text).map_err(TextQueueError::Invalid)?;
        let free = self.tx.text_free();
        self.tx.push_text(frames).map_err(|needed| {
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
            TextQueueError::NoRoom { needed, free }
        })
    }

    // ---- vehicle data ----

    fn set_vehicle(&mut self, index: usize, frame: VehicleFrame, stamp: Instant) {
        if let Some(source) = self.vehicle.get_mut(index) {
            if source.latest.is_none() {
                source.due = true;
            }
            source.latest = Some((frame.to_frame(), stamp));
        }
    }

    /// Sets the latest vehicle attitude, measured at `stamp`.
    pub fn set_attitude(&mut self, attitude: Attitude, stamp: Instant) {
        self.set_vehicle(ATTITUDE, attitude.into(), stamp);
    }

    /// Sets the latest vehicle position, measured at `stamp`.
    pub fn set_gps(&mut self, gps: Gps, stamp: Instant) {
        self.set_vehicle(GPS, gps.into(), stamp);
    }

    /// Sets the latest vehicle altitude, measured at `stamp`.
    pub fn set_altitude(&mut self, altitude: Altitude, stamp: Instant) {
        self.set_vehicle(ALTITUDE, altitude.into(), stamp);
    }

    fn age(stamp: Instant, now: Instant) -> u32 {
        // A stamp slightly ahead of `now` (clock skew between producer and poller) is fresh.
        if now.is_at_or_after(stamp) {
            now.millis_since(stamp)
        } else {
            0
        }
    }

    /// Whether attitude is being pushed (its push is enabled and the data fresh), so that
    /// the gimbal references its heading to north rather than to the nose.
    pub fn attitude_is_pushed(&self, now: Instant) -> bool {
        self.config.attitude_period_ms != 0 && self.fresh_vehicle(ATTITUDE, now).is_some()
    }

    /// The latest vehicle attitude set, fresh or not.
    pub fn attitude(&self) -> Option<Attitude> {
        let (frame, _) = self.vehicle.get(ATTITUDE)?.latest?;
        match VehicleFrame::decode(frame.id, &frame.data) {
            Ok(VehicleFrame::Attitude(a)) => Some(a),
            _ => None,
        }
    }

    // ---- time ----

    /// Runs the schedules up to `now`: vehicle pushes, the rate hold and its dead-man, link
    /// health, and expiry of partial postbacks.
    pub fn poll(&mut self, now: Instant) {
        self.assembler.expire(now);
        self.poll_rate(now);
        self.poll_vehicle(now);
        self.poll_point(now);
        if let Some((_, at)) = self.latest {
            if self.up && now.millis_since(at) > self.config.link_timeout_ms {
                self.up = false;
                self.event(Event::LinkDown);
            }
        }
    }

    fn poll_rate(&mut self, now: Instant) {
        match self.rate {
            RateState::Idle => {}
            RateState::Stopping { zero } => {
                if self.tx.push_control(zero).is_ok() {
                    self.rate = RateState::Idle;
                }
            }
            RateState::Holding {
                rate,
                frame,
                refreshed,
                next,
            } => {
                if now.millis_since(refreshed) > self.config.rate_deadman_ms {
                    self.end_rate_hold();
                    self.event(Event::RateHoldExpired);
                } else if now.is_at_or_after(next) {
                    if self.tx.push_control(frame).is_ok() {
                        let next = advance(next, self.config.rate_repeat_ms, now);
                        self.rate = RateState::Holding {
                            rate,
                            frame,
                            refreshed,
                            next,
                        };
                    } else {
                        // Try again at the next poll.
                        self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
                    }
                }
            }
        }
    }

    fn poll_vehicle(&mut self, now: Instant) {
        let periods = [
            self.config.attitude_period_ms,
            self.config.gps_period_ms,
            self.config.altitude_period_ms,
        ];
        let stale = self.config.vehicle_stale_ms;
        for (source, period) in self.vehicle.iter_mut().zip(periods) {
            let Some((frame, stamp)) = source.latest else {
                continue;
            };
            if period == 0 {
                continue;
            }
            if Self::age(stamp, now) > stale {
                // Push again as soon as fresh data arrives.
                source.due = true;
                continue;
            }
            if !(source.due || now.is_at_or_after(source.next)) {
                continue;
            }
            source.next = if source.due {
                now.add_millis(period)
            } else {
                advance(source.next, period, now)
            };
            source.due = false;
            if let Ok(true) = self.tx.put_vehicle(frame) {
                self.stats.superseded = self.stats.superseded.wrapping_add(1);
            }
            self.stats.vehicle_pushes = self.stats.vehicle_pushes.wrapping_add(1);
        }
    }

    // ---- pointing at a location ----

    /// Keeps the gimbal pointed at `target` while the vehicle moves; see
    /// [`point`](self#pointing-at-a-location). Cancels a rate hold.
    pub fn point_at(&mut self, target: Position) {
        if let RateState::Holding { .. } = self.rate {
            self.rate = RateState::Idle;
        }
        self.point = Some(point::PointAt::new(target));
    }

    /// Stops pointing at a location (the gimbal keeps its last aim).
    pub fn stop_pointing(&mut self) {
        self.point = None;
    }

    /// The target being pointed at, if any.
    pub fn pointing_target(&self) -> Option<Position> {
        self.point.map(|p| p.target)
    }

    fn fresh_vehicle(&self, index: usize, now: Instant) -> Option<VehicleFrame> {
        let (frame, stamp) = self.vehicle.get(index)?.latest?;
        if Self::age(stamp, now) > self.config.vehicle_stale_ms {
            return None;
        }
        VehicleFrame::decode(frame.id, &frame.data).ok()
    }

    fn poll_point(&mut self, now: Instant) {
        let Some(mut p) = self.point else { return };
        if !(p.due || now.is_at_or_after(p.next)) {
            return;
        }
        p.next = if p.due {
            now.add_millis(self.config.point_at_period_ms)
        } else {
            advance(p.next, self.config.point_at_period_ms, now)
        };
        p.due = false;
        self.point = Some(p);
        let (Some(VehicleFrame::Gps(gps)), Some(VehicleFrame::Altitude(alt))) = (
            self.fresh_vehicle(GPS, now),
            self.fresh_vehicle(ALTITUDE, now),
        ) else {
            return;
        };
        let Ok(vehicle) = Position::new(gps.lat_deg(), gps.lon_deg(), alt.metres()) else {
            return;
        };
        let Ok(aim) = geo::look_at(&vehicle, &p.target) else {
            return;
        };
        let bearing = if self.attitude_is_pushed(now) {
            aim.bearing_deg
        } else {
            match self.fresh_vehicle(ATTITUDE, now) {
                Some(VehicleFrame::Attitude(att)) => aim.bearing_deg - f64::from(att.heading_deg()),
                _ => return,
            }
        };
        let (Ok(heading), Ok(pitch)) = (
            Heading::new(point::wrap_360(bearing) as f32),
            Pitch::new(aim.elevation_deg as f32),
        ) else {
            if !p.unreachable {
                p.unreachable = true;
                self.point = Some(p);
                self.event(Event::TargetUnreachable {
                    elevation_cdeg: libm::round(aim.elevation_deg * 100.0) as i32,
                });
            }
            return;
        };
        p.unreachable = false;
        let aim_wire = (heading.deci(), pitch.deci());
        if !point::moved(p.sent, aim_wire, self.config.point_at_deadband_mdeg) {
            self.point = Some(p);
            return;
        }
        if self.tx.control_free() < 2 {
            // Both or neither; try again at the next poll.
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
            p.due = true;
        } else {
            let _ = self
                .tx
                .push_control(Command::from(GimbalCommand::Heading(heading)).to_frame());
            let _ = self
                .tx
                .push_control(Command::from(GimbalCommand::Pitch(pitch)).to_frame());
            p.sent = Some(aim_wire);
        }
        self.point = Some(p);
    }

    // ---- transmitting ----

    /// Takes the next frame to transmit, highest priority first. Report what happened to
    /// it with [`Link::transmit_done`] or [`Link::transmit_refused`].
    pub fn next_transmit(&mut self) -> Option<Frame> {
        self.tx.pop()
    }

    /// Whether frames wait for transmission.
    pub fn has_transmit(&self) -> bool {
        !self.tx.is_empty()
    }

    /// The driver accepted the frame last taken. `displaced` is a frame it handed back
    /// (a pending lower-priority frame it took out of a mailbox): it is re-queued.
    pub fn transmit_done(&mut self, displaced: Option<Frame>) {
        self.stats.frames_sent = self.stats.frames_sent.wrapping_add(1);
        if let Some(frame) = displaced {
            // The displaced frame had been counted as sent; it is not yet.
            self.stats.frames_sent = self.stats.frames_sent.wrapping_sub(1);
            match self.tx.requeue(frame) {
                Requeued::Queued => self.stats.requeued = self.stats.requeued.wrapping_add(1),
                Requeued::Superseded => {
                    self.stats.superseded = self.stats.superseded.wrapping_add(1)
                }
                Requeued::NoRoom => self.stats.queue_full = self.stats.queue_full.wrapping_add(1),
            }
        }
    }

    /// The driver did not take the frame last taken (it was busy or failed): it goes back
    /// to the front of its class.
    pub fn transmit_refused(&mut self, frame: Frame) {
        if self.tx.unpop(frame) == Requeued::NoRoom {
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
        }
    }

    /// Counters, including the postback assembler's.
    pub fn stats(&self) -> LinkStats {
        let a = self.assembler.stats();
        LinkStats {
            postbacks: a.messages,
            crc_errors: a.crc_errors,
            restarts: a.restarts,
            dropped_partials: a.dropped_partials,
            malformed: a.malformed,
            ..self.stats
        }
    }

    /// The postback assembler's own counters.
    pub fn assembler_stats(&self) -> postback::AssemblerStats {
        self.assembler.stats()
    }

    /// The postback assembler.
    pub fn assembler(&self) -> &PostbackAssembler {
        &self.assembler
    }
}

#[cfg(test)]
mod tests;
