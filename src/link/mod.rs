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
//! assert_eq!(link.next_event(), Some(Event::Postback));
//! assert_eq!(link.latest_postback(now).map(|(p, _age)| p.pitch), Some(-4500));
//! # Ok::<(), idu_gimbal::wire::RangeError>(())
//! ```

mod event;
mod point;
pub mod postback;
pub mod queue;
mod quiet;
mod ring;
pub mod serial;
pub mod text;

use core::fmt;

use crate::geo::Position;
use crate::time::Instant;
use crate::wire::control::{Command, GimbalCommand, Rate};
use crate::wire::postback::{GimbalType, Postback};
use crate::wire::vehicle::{Altitude, Attitude, Gps, VehicleFrame};
use crate::wire::{ids, text as wire_text, Frame};
pub use event::Event;
use postback::PostbackAssembler;
use queue::{Requeued, TxQueue};

/// Timing of the link. Every field is in milliseconds (at most 65 535) unless it says
/// otherwise. A vehicle push period of 0 disables that push.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Period of the attitude push (default 100).
    pub attitude_period_ms: u16,
    /// Period of the GPS push (default 200).
    pub gps_period_ms: u16,
    /// Period of the altitude push (default 200).
    pub altitude_period_ms: u16,
    /// Vehicle data older than this is not pushed (default 1000).
    pub vehicle_stale_ms: u16,
    /// Period at which a rate hold repeats its rate command (default 50, as the document
    /// recommends).
    pub rate_repeat_ms: u16,
    /// A rate hold not refreshed within this stops with one zero-rate command (default 250).
    pub rate_deadman_ms: u16,
    /// The link is up while a valid postback arrived within this (default 1500: three
    /// postback periods).
    pub link_timeout_ms: u16,
    /// Bound on the gap between frames of one postback (default 100).
    pub postback_max_gap_ms: u16,
    /// Period at which [`Link::point_at`] recomputes the aim (default 100: 10 Hz).
    pub point_at_period_ms: u16,
    /// [`Link::point_at`] re-commands the gimbal only when the aim moved by more than this,
    /// in millidegrees (default 100: 0.1°).
    pub point_at_deadband_mdeg: u16,
    /// Frames [`Gimbal::poll`](crate::Gimbal::poll) receives at most in one call, so that a
    /// flooded bus cannot starve the rest of the main loop (default 32; a poll always
    /// tries at least one).
    pub max_rx_per_poll: core::num::NonZeroU16,
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
            // 32 is not zero.
            max_rx_per_poll: match core::num::NonZeroU16::new(32) {
                Some(n) => n,
                None => core::num::NonZeroU16::MIN,
            },
        }
    }
}

/// Counters for diagnosing a bus. All wrap at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// Frames received (including ignored ones): `ignored_frames` plus the assembler's
    /// frames.
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
    /// scheduled frames that had to wait for room), and frames the CAN driver handed back
    /// that could not be re-queued (no room, or not this link's frames).
    pub queue_full: u32,
    /// Frames handed back by the CAN driver (displaced from a mailbox) and re-queued.
    pub requeued: u32,
    /// Vehicle frames replaced by a newer value before they were sent.
    pub superseded: u32,
    /// Received frames that are not for this node (other IDs, standard IDs, remote frames).
    pub ignored_frames: u32,
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

/// The latest attitude, GPS and altitude with their stamps and push deadlines, by slot
/// (0 attitude, 1 GPS, 2 altitude, as in the transmit queue). Values are kept typed (18
/// bytes, not three 8-byte frames); a frame is encoded when it leaves.
#[derive(Clone, Copy, Debug)]
struct VehicleSources {
    attitude: Attitude,
    gps: Gps,
    altitude: Altitude,
    stamp: [Instant; 3],
    next: [Instant; 3],
    /// Bit `i`: slot `i` holds a value.
    has: u8,
    /// Bit `i`: push slot `i` at the next poll, whatever `next` says (new data after none
    /// or stale data).
    due: u8,
}

impl VehicleSources {
    const EMPTY: Self = VehicleSources {
        attitude: Attitude::ZERO,
        gps: Gps::ZERO,
        altitude: Altitude::from_cm(0),
        stamp: [Instant::from_millis(0); 3],
        next: [Instant::from_millis(0); 3],
        has: 0,
        due: 0b111,
    };

    fn bit(slot: usize) -> u8 {
        1 << (slot & 7)
    }

    fn has(&self, slot: usize) -> bool {
        self.has & Self::bit(slot) != 0
    }

    fn due(&self, slot: usize) -> bool {
        self.due & Self::bit(slot) != 0
    }

    fn set_due(&mut self, slot: usize, due: bool) {
        if due {
            self.due |= Self::bit(slot);
        } else {
            self.due &= !Self::bit(slot);
        }
    }

    /// When the value in `slot` was measured, if one was set.
    fn stamp(&self, slot: usize) -> Option<Instant> {
        if !self.has(slot) {
            return None;
        }
        self.stamp.get(slot).copied()
    }

    /// Records that `slot` now holds a value measured at `stamp`.
    fn stamped(&mut self, slot: usize, stamp: Instant) {
        if let Some(s) = self.stamp.get_mut(slot) {
            *s = stamp;
            self.has |= Self::bit(slot);
        }
    }

    /// The value in `slot`, if one was set.
    fn value(&self, slot: usize) -> Option<VehicleFrame> {
        if !self.has(slot) {
            return None;
        }
        match slot {
            ATTITUDE => Some(VehicleFrame::Attitude(self.attitude)),
            GPS => Some(VehicleFrame::Gps(self.gps)),
            ALTITUDE => Some(VehicleFrame::Altitude(self.altitude)),
            _ => None,
        }
    }
}

/// A rate hold: the rate command repeats until the dead-man.
#[derive(Clone, Copy, Debug)]
struct RateHold {
    rate: Rate,
    refreshed: Instant,
    next: Instant,
}

/// What keeps the gimbal moving besides single commands. A rate hold and a point-at are
/// both pointing, and any pointing ends the other: one place holds either.
#[derive(Clone, Copy, Debug)]
enum Steering<const Q: usize, const T: usize> {
    /// Nothing: the gimbal does what it was last told.
    Manual,
    /// A rate hold.
    Rate(RateHold),
    /// Pointing at a location.
    Point(point::PointAt<Q, T>),
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

/// The earliest of the deadlines offered to it, as seen from `now` (wrap-safe).
pub(crate) struct Earliest {
    now: Instant,
    ahead: u32,
}

impl Earliest {
    fn offer(&mut self, at: Instant) {
        let ahead = if at.is_at_or_after(self.now) {
            at.millis_since(self.now)
        } else {
            0
        };
        self.ahead = self.ahead.min(ahead);
    }
}

/// The longest a poll may be skipped even when no deadline is near: keeps every deadline
/// within the wrap-safe range of `Instant`.
const MAX_QUIET_MS: u32 = 60_000;

/// The sans-IO link to one gimbal; see the [module docs](self).
///
/// `Q` is the number of control-frame slots, `T` the number of text-frame slots; each is at
/// most 255 (checked when the link is built).
#[derive(Clone, Debug)]
pub struct Link<const Q: usize = 8, const T: usize = 8> {
    config: Config,
    tx: TxQueue<Q, T>,
    assembler: PostbackAssembler,
    vehicle: VehicleSources,
    steering: Steering<Q, T>,
    latest: Option<(Postback, Instant)>,
    status: event::Status,
    /// Nothing is due within `quiet` after `last_poll` (0: poll fully next time): the idle
    /// fast paths, one load pair and a compare each. Kept next to each other.
    last_poll: Instant,
    quiet: quiet::Quiet,
    stats: Counters,
}

/// The counters the link itself keeps; the rest of [`LinkStats`] is the assembler's or
/// derived.
#[derive(Clone, Copy, Debug, Default)]
struct Counters {
    frames_sent: u32,
    queue_full: u32,
    requeued: u32,
    superseded: u32,
    ignored_frames: u32,
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
            vehicle: VehicleSources::EMPTY,
            steering: Steering::Manual,
            latest: None,
            status: event::Status::new(),
            last_poll: Instant::from_millis(0),
            quiet: quiet::Quiet::NONE,
            stats: Counters::default(),
        }
    }

    /// The timing in use.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The next event; see [`Event`] for how events wait. Nothing is ever dropped: an
    /// event of a kind already waiting merges with it.
    #[inline]
    pub fn next_event(&mut self) -> Option<Event> {
        self.status.take()
    }

    // ---- receiving ----

    /// Takes a received frame with a 29-bit extended ID.
    #[inline]
    pub fn receive(&mut self, id: u32, data: &[u8], now: Instant) {
        if id != ids::POSTBACK {
            self.receive_ignored();
            return;
        }
        self.receive_postback_frame(data, now);
    }

    /// Takes a received data frame whose ID the caller has found to be
    /// [`ids::POSTBACK`]: [`Link::receive`] without the ID check, for a driver that
    /// rejects foreign frames itself before anything else.
    pub fn receive_postback_frame(&mut self, data: &[u8], now: Instant) {
        match <&[u8; 8]>::try_from(data) {
            Ok(d) => self.receive_postback_u64(now, u64::from_le_bytes(*d)),
            Err(_) => self.assembler.malformed(),
        }
    }

    /// [`Link::receive_postback_frame`] for a frame whose length is not 8: counted as
    /// malformed. Out of line, taking only the link: a driver's receive loop then keeps
    /// nothing in registers for it.
    #[cold]
    #[inline(never)]
    pub(crate) fn receive_malformed(&mut self) {
        self.assembler.malformed();
    }

    /// [`Link::receive_postback_frame`] for a frame of 8 bytes (every good one), its data
    /// read as a little-endian `u64`: passed in two registers, so that a driver need not
    /// copy its frame to memory. Out of line: the driver's poll then keeps few registers,
    /// which is what an idle poll pays for.
    #[inline(never)]
    pub fn receive_postback_u64(&mut self, now: Instant, data: u64) {
        let held = self.assembler.pending() != 0;
        if self.assembler.push(&data.to_le_bytes(), now) {
            self.complete_postback(now);
        } else if !held {
            // A window that starts brings its expiry deadline; while it holds frames the
            // deadline only moves later (a frame too late or too early empties it), so a
            // poll woken for the first is never too late for the others.
            if let Some(at) = self.assembler.expiry() {
                self.wake_by(at);
            }
        }
    }

    /// The assembler's window is full: the CRC decides. Out of line, so that the three
    /// frames before it pay nothing for its registers.
    #[inline(never)]
    fn complete_postback(&mut self, now: Instant) {
        if let Some(p) = self.assembler.complete() {
            self.receive_postback(p, now);
        }
    }

    /// Takes a whole postback that arrived in one piece, as on the serial link, where the
    /// stream parser has already checked its header, length byte and CRC. The assembler
    /// (and its counters) is for CAN frames only and is not involved.
    pub fn receive_postback(&mut self, postback: Postback, now: Instant) {
        // The health deadline follows this postback: earlier than the one the idle fast
        // path knows of when the link was down (none) or `now` is behind the last postback.
        // While the link is up the fast path wakes for the last postback's deadline (the
        // full poll offers it, or this call did when the link came up), and a postback at
        // or after that one only moves it later: no need to cut the interval then.
        let later =
            self.status.is_up() && self.latest.is_some_and(|(_, at)| now.is_at_or_after(at));
        if !later {
            self.wake_by(now.add_millis(u32::from(self.config.link_timeout_ms).saturating_add(1)));
        }
        self.latest = Some((postback, now));
        self.status.set_up(true);
        self.status.raise(Event::Postback);
    }

    /// Counts a received frame that cannot be for this node (a standard ID or a remote
    /// frame); the driver calls it for what it does not pass to [`Link::receive`].
    pub fn receive_ignored(&mut self) {
        self.stats.ignored_frames = self.stats.ignored_frames.wrapping_add(1);
    }

    /// Whether a valid postback arrived within the link timeout (as of the last poll).
    pub fn is_up(&self) -> bool {
        self.status.is_up()
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

    /// Queues a command. A pointing command (see [`Command::is_pointing`]) ends a rate hold
    /// (without a zero-rate command: it is the gimbal's new instruction) or a point-at. A
    /// full queue hands the command back and ends nothing.
    pub fn send(&mut self, command: impl Into<Command>) -> Result<(), QueueFull<Command>> {
        let command = command.into();
        if self.tx.push_control(command.encode()).is_err() {
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
            return Err(QueueFull(command));
        }
        self.quiet.hold_idle();
        if command.is_pointing() {
            self.steering = Steering::Manual;
            // A zero-rate frame still waiting would arrive after this command and undo it.
            self.tx.cancel_zero_rate();
        }
        Ok(())
    }

    /// Starts, changes or refreshes a rate hold on the gimbal: the rate command is repeated
    /// every `rate_repeat_ms` while this is called again within `rate_deadman_ms`. A rate
    /// hold is a pointing command: it ends a point-at.
    ///
    /// Starting a hold or changing its rate queues the command at once; a full queue hands
    /// the rate back and leaves the hold as it was. Refreshing the same rate queues nothing.
    pub fn set_rate(&mut self, rate: Rate, now: Instant) -> Result<(), QueueFull<Rate>> {
        if let Steering::Rate(hold) = &mut self.steering {
            if hold.rate == rate {
                // Only the dead-man moves, later: no need to wake the next poll. (Called at
                // every turn of a main loop, this must not defeat the idle fast path.)
                hold.refreshed = now;
                return Ok(());
            }
        }
        if self
            .tx
            .push_control(Command::from(GimbalCommand::Rate(rate)).encode())
            .is_err()
        {
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
            return Err(QueueFull(rate));
        }
        self.steering = Steering::Rate(RateHold {
            rate,
            refreshed: now,
            next: now.add_millis(u32::from(self.config.rate_repeat_ms)),
        });
        // The new rate supersedes a zero-rate frame still waiting.
        self.tx.cancel_zero_rate();
        self.quiet = quiet::Quiet::NONE;
        Ok(())
    }

    /// Ends a rate hold with one zero-rate command. The zero-rate command needs no queue
    /// slot, so it is never refused: it leaves after the control frames already queued.
    pub fn stop_rate(&mut self) {
        if let Steering::Rate(_) = self.steering {
            self.end_rate_hold();
        }
    }

    /// Whether a rate hold is active.
    pub fn is_rate_holding(&self) -> bool {
        matches!(self.steering, Steering::Rate(_))
    }

    fn end_rate_hold(&mut self) {
        self.steering = Steering::Manual;
        self.tx.mark_zero_rate();
        self.quiet.hold_idle();
    }

    /// Queues a text message, all of it or nothing.
    pub fn send_text(&mut self, text: &[u8]) -> Result<(), TextQueueError> {
        let frames = wire_text::chunks(text).map_err(TextQueueError::Invalid)?;
        let free = self.tx.text_free();
        let slots = frames.map(|f| queue::TextSlot {
            data: f.data,
            last: f.id == ids::TEXT_END,
        });
        self.tx.push_text(slots).map_err(|needed| {
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
            TextQueueError::NoRoom { needed, free }
        })?;
        self.quiet.hold_idle();
        Ok(())
    }

    // ---- vehicle data ----

    /// Bookkeeping before slot `slot` takes a value measured at `stamp`.
    fn set_vehicle(&mut self, slot: usize, stamp: Instant) {
        if !self.vehicle.has(slot) {
            self.vehicle.set_due(slot, true);
        }
        // Newer data replacing fresh data moves no deadline earlier, so the next poll need
        // only wake for a slot waiting to push at once (first value, or after going stale)
        // or for an older stamp, which brings staleness closer. (Called at every turn of a
        // main loop, this must not defeat the idle fast path.)
        let older = self
            .vehicle
            .stamp(slot)
            .is_some_and(|old| !stamp.is_at_or_after(old));
        if self.vehicle.due(slot) || older {
            self.quiet = quiet::Quiet::NONE;
        }
        self.vehicle.stamped(slot, stamp);
    }

    /// Sets the latest vehicle attitude, measured at `stamp`.
    pub fn set_attitude(&mut self, attitude: Attitude, stamp: Instant) {
        self.set_vehicle(ATTITUDE, stamp);
        self.vehicle.attitude = attitude;
    }

    /// Sets the latest vehicle position, measured at `stamp`.
    pub fn set_gps(&mut self, gps: Gps, stamp: Instant) {
        self.set_vehicle(GPS, stamp);
        self.vehicle.gps = gps;
    }

    /// Sets the latest vehicle altitude, measured at `stamp`.
    pub fn set_altitude(&mut self, altitude: Altitude, stamp: Instant) {
        self.set_vehicle(ALTITUDE, stamp);
        self.vehicle.altitude = altitude;
    }

    fn age(stamp: Instant, now: Instant) -> u32 {
        // A stamp slightly ahead of `now` (clock skew between producer and poller) is fresh.
        if now.is_at_or_after(stamp) {
            now.millis_since(stamp)
        } else {
            0
        }
    }

    /// Whether vehicle slot `slot` holds data that is fresh at `now`.
    fn is_fresh(&self, slot: usize, now: Instant) -> bool {
        self.vehicle
            .stamp(slot)
            .is_some_and(|stamp| Self::age(stamp, now) <= u32::from(self.config.vehicle_stale_ms))
    }

    /// Whether attitude is being pushed (its push is enabled and the data fresh), so that
    /// the gimbal references its heading to north rather than to the nose.
    pub fn attitude_is_pushed(&self, now: Instant) -> bool {
        self.config.attitude_period_ms != 0 && self.is_fresh(ATTITUDE, now)
    }

    /// The latest vehicle attitude set, fresh or not.
    pub fn attitude(&self) -> Option<Attitude> {
        self.vehicle.has(ATTITUDE).then_some(self.vehicle.attitude)
    }

    // ---- time ----

    /// Runs the schedules up to `now`: vehicle pushes, the rate hold and its dead-man, link
    /// health, point-at, and expiry of partial postbacks.
    ///
    /// When nothing is due and nothing changed since the last poll, this returns after one
    /// comparison.
    #[inline]
    pub fn poll(&mut self, now: Instant) {
        if self.is_quiet(now) {
            return;
        }
        self.poll_all(now);
    }

    /// Whether [`Link::poll`] at `now` would have nothing to do: nothing changed since the
    /// last poll and no deadline has come.
    #[inline]
    pub fn is_quiet(&self, now: Instant) -> bool {
        // A clock that went backwards reads as a huge interval: a full poll, never a skip.
        now.millis_since(self.last_poll) < self.quiet.schedules()
    }

    /// Whether [`Link::poll`] at `now` would have nothing to do and no frame waits to be
    /// sent: a driver's idle fast path, one compare for both. (Frames queued outside a
    /// poll end it; the driver ends a poll that found nothing waiting with
    /// [`Link::release_idle`].)
    #[inline(always)]
    pub(crate) fn is_idle(&self, now: Instant) -> bool {
        now.millis_since(self.last_poll) < self.quiet.idle()
    }

    /// The driver found nothing waiting after a poll: [`Link::is_idle`] holds again until
    /// the schedules' next deadline or the next frame queued.
    #[inline(always)]
    pub(crate) fn release_idle(&mut self) {
        self.quiet.release_idle();
    }

    /// Something waits to be sent outside the queue (a serial frame part-written): ends
    /// the idle check until the driver finds nothing waiting.
    #[inline]
    pub(crate) fn hold_idle(&mut self) {
        self.quiet.hold_idle();
    }

    /// The instant by which [`Link::poll`] must next be called if nothing is received and
    /// nothing else is asked of the link before then, as seen from `now`, the caller's
    /// current time: smoltcp's `poll_at`.
    ///
    /// It is the earliest of the link's deadlines: the vehicle pushes (and vehicle data
    /// going stale), the rate hold's next repeat and its dead-man, the next point-at step,
    /// the expiry of a partial postback, and the link health timeout. It is `now` itself
    /// when a poll is due at once: something changed since the last poll that the schedules
    /// must see (the first vehicle value, a new rate hold, a point-at, a full queue to
    /// retry, ...), a deadline has come, or `now` is behind the last poll. With nothing
    /// scheduled, it is at most 60 s after the last poll.
    ///
    /// Exactly: [`Link::poll`] at every instant from `now` up to, not including, the
    /// deadline does nothing. So an async driver may sleep until the deadline or until a
    /// frame arrives, whichever comes first, and poll then; every call that feeds the link
    /// ([`Link::receive`], [`Link::send`], [`Link::set_rate`], [`Link::set_gps`],
    /// [`Link::point_at`], ...) can move the deadline earlier, so ask again after one.
    ///
    /// Frames waiting for transmission are not a deadline of `poll`, which does not send
    /// them: hand them to the CAN driver while [`Link::has_transmit`] and the driver has
    /// room. ([`Gimbal::next_deadline`](crate::Gimbal::next_deadline), whose `poll` does
    /// transmit, is `now` while frames wait.)
    ///
    /// While a rate hold or point-at has a frame to queue and the transmit queue is full
    /// (the driver takes nothing: a dead bus, full mailboxes), the deadline stays `now`
    /// until room is made. An async loop that sleeps until the deadline should then also
    /// wait for the driver to have room, or sleep at least one tick, so it does not spin
    /// and starve its other tasks (`boards/embassy_stm32f405` does both).
    ///
    /// The result is at or after `now` and less than 2^31 ms ahead of it, whatever the
    /// wrap: the time to sleep is `deadline.millis_since(now)`.
    ///
    /// ```
    /// use idu_gimbal::link::{Config, Link};
    /// use idu_gimbal::wire::vehicle::Gps;
    /// use idu_gimbal::Instant;
    ///
    /// let mut link: Link = Link::new(Config::default());
    /// // Ten milliseconds before the tick wraps.
    /// let t0 = Instant::from_millis(u32::MAX - 9);
    /// link.set_gps(Gps::new(47.0, 8.0).unwrap(), t0);
    /// assert_eq!(link.next_deadline(t0), t0); // the first value: push it at once
    /// link.poll(t0);
    /// while link.next_transmit().is_some() {
    ///     link.transmit_done(None);
    /// }
    /// // The next GPS push, 200 ms later (the data goes stale only after 1000 ms).
    /// assert_eq!(link.next_deadline(t0), Instant::from_millis(190));
    /// assert_eq!(link.next_deadline(t0).millis_since(t0), 200);
    /// ```
    pub fn next_deadline(&self, now: Instant) -> Instant {
        if self.is_quiet(now) {
            // Quiet: `now` is within the interval after the last poll, so this is after it.
            self.last_poll.add_millis(self.quiet.schedules())
        } else {
            now
        }
    }

    /// Makes sure the idle fast path does not skip the poll at `at` (a new deadline): the
    /// quiet interval is cut to end there. Cheaper than a full poll at the next call, and
    /// the same: that poll would find the deadline and cut the interval alike. A deadline
    /// before the last poll (a caller's `now` behind it) ends the interval at once.
    fn wake_by(&mut self, at: Instant) {
        let ahead = if at.is_at_or_after(self.last_poll) {
            at.millis_since(self.last_poll)
        } else {
            0
        };
        self.quiet.cut_to(ahead);
    }

    #[inline(never)]
    fn poll_all(&mut self, now: Instant) {
        let mut earliest = Earliest {
            now,
            ahead: MAX_QUIET_MS,
        };
        self.assembler.expire(now);
        if let Some(at) = self.assembler.expiry() {
            earliest.offer(at);
        }
        self.poll_rate(now, &mut earliest);
        self.poll_vehicle(now, &mut earliest);
        self.poll_point(now, &mut earliest);
        if let Some((_, at)) = self.latest {
            if self.status.is_up() && now.millis_since(at) > u32::from(self.config.link_timeout_ms)
            {
                self.status.set_up(false);
            }
            if self.status.is_up() {
                earliest
                    .offer(at.add_millis(u32::from(self.config.link_timeout_ms).saturating_add(1)));
            }
        }
        self.last_poll = now;
        self.quiet.set(earliest.ahead);
    }

    fn poll_rate(&mut self, now: Instant, earliest: &mut Earliest) {
        let Steering::Rate(mut hold) = self.steering else {
            return;
        };
        let deadman = u32::from(self.config.rate_deadman_ms);
        if now.millis_since(hold.refreshed) > deadman {
            self.end_rate_hold();
            self.status.raise(Event::RateHoldExpired);
            return;
        }
        if now.is_at_or_after(hold.next) {
            if self
                .tx
                .push_control(Command::from(GimbalCommand::Rate(hold.rate)).encode())
                .is_ok()
            {
                hold.next = advance(hold.next, u32::from(self.config.rate_repeat_ms), now);
                self.steering = Steering::Rate(hold);
            } else {
                // Try again at the next poll.
                self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
                earliest.offer(now);
            }
        }
        earliest.offer(hold.next);
        earliest.offer(hold.refreshed.add_millis(deadman.saturating_add(1)));
    }

    fn poll_vehicle(&mut self, now: Instant, earliest: &mut Earliest) {
        let periods = [
            u32::from(self.config.attitude_period_ms),
            u32::from(self.config.gps_period_ms),
            u32::from(self.config.altitude_period_ms),
        ];
        let stale = u32::from(self.config.vehicle_stale_ms);
        for (slot, period) in periods.into_iter().enumerate() {
            let Some(stamp) = self.vehicle.stamp(slot) else {
                continue;
            };
            let Some(&next) = self.vehicle.next.get(slot) else {
                continue;
            };
            if period == 0 {
                continue;
            }
            if Self::age(stamp, now) > stale {
                // Push again as soon as fresh data arrives (which marks the link dirty).
                self.vehicle.set_due(slot, true);
                continue;
            }
            let due = self.vehicle.due(slot);
            let mut next = next;
            if due || now.is_at_or_after(next) {
                next = if due {
                    now.add_millis(period)
                } else {
                    advance(next, period, now)
                };
                if let Some(n) = self.vehicle.next.get_mut(slot) {
                    *n = next;
                }
                self.vehicle.set_due(slot, false);
                if self.tx.mark_vehicle(slot) {
                    self.stats.superseded = self.stats.superseded.wrapping_add(1);
                }
            }
            earliest.offer(next);
            // Going stale changes what fresh data will do: wake up for it too.
            earliest.offer(stamp.add_millis(stale.saturating_add(1)));
        }
    }

    // ---- pointing at a location ----

    /// Keeps the gimbal pointed at `target` while the vehicle moves; see
    /// [`point`](self#pointing-at-a-location). Ends a rate hold (the heading and pitch
    /// commands that follow replace it).
    pub fn point_at(&mut self, target: Position) {
        self.quiet = quiet::Quiet::NONE;
        // A zero-rate frame still waiting would arrive after the aim and could undo it.
        self.tx.cancel_zero_rate();
        self.steering = Steering::Point(point::PointAt::new(target));
    }

    /// Stops pointing at a location (the gimbal keeps its last aim).
    pub fn stop_pointing(&mut self) {
        if let Steering::Point(_) = self.steering {
            self.steering = Steering::Manual;
        }
    }

    /// The target being pointed at, if any (kept to 1e-7° and 1 cm).
    pub fn pointing_target(&self) -> Option<Position> {
        match self.steering {
            Steering::Point(p) => p.target.position(),
            _ => None,
        }
    }

    fn poll_point(&mut self, now: Instant, earliest: &mut Earliest) {
        if let Steering::Point(p) = self.steering {
            (p.step)(self, now, earliest);
        }
    }

    /// One point-at step; see [`point::PointAt::step`].
    fn point_step(&mut self, now: Instant, earliest: &mut Earliest) {
        let Steering::Point(mut p) = self.steering else {
            return;
        };
        if p.due || now.is_at_or_after(p.next) {
            let period = u32::from(self.config.point_at_period_ms);
            p.next = if p.due {
                now.add_millis(period)
            } else {
                advance(p.next, period, now)
            };
            p.due = false;
            // North-referenced while attitude is pushed; otherwise nose-referenced, which
            // needs the vehicle heading (none fresh: the aim cannot be known).
            let reference = if self.attitude_is_pushed(now) {
                Some(point::Reference::North)
            } else {
                self.is_fresh(ATTITUDE, now)
                    .then(|| point::Reference::Nose(self.vehicle.attitude.heading_centideg()))
            };
            if let (true, true, Some(reference)) = (
                self.is_fresh(GPS, now),
                self.is_fresh(ALTITUDE, now),
                reference,
            ) {
                let aim = point::solve(
                    &p.target,
                    &self.vehicle.gps,
                    &self.vehicle.altitude,
                    reference,
                );
                self.aim(&mut p, aim);
            }
        }
        // Due again (no room for the aim): the next poll retries.
        earliest.offer(if p.due { now } else { p.next });
        self.steering = Steering::Point(p);
    }

    fn aim(&mut self, p: &mut point::PointAt<Q, T>, aim: point::Aim) {
        match aim {
            point::Aim::Unknown => {}
            point::Aim::Unreachable { elevation_cdeg } => {
                if !p.unreachable {
                    p.unreachable = true;
                    self.status
                        .raise(Event::TargetUnreachable { elevation_cdeg });
                }
            }
            point::Aim::At(heading, pitch) => {
                p.unreachable = false;
                let wire = (heading.deci(), pitch.deci());
                if !point::moved(p.sent, wire, u32::from(self.config.point_at_deadband_mdeg)) {
                    return;
                }
                if self.tx.control_free() < 2 {
                    // Both or neither; try again at the next poll.
                    self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
                    p.due = true;
                    return;
                }
                let _ = self
                    .tx
                    .push_control(Command::from(GimbalCommand::Heading(heading)).encode());
                let _ = self
                    .tx
                    .push_control(Command::from(GimbalCommand::Pitch(pitch)).encode());
                p.sent = Some(wire);
            }
        }
    }

    // ---- transmitting ----

    /// Takes the next frame to transmit, highest priority first. Report what happened to
    /// it with [`Link::transmit_done`] or [`Link::transmit_refused`].
    #[inline]
    pub fn next_transmit(&mut self) -> Option<Frame> {
        // Inline: nothing waiting, or a control frame (what most polls that send send).
        if let Some(data) = self.next_control() {
            return Some(Frame::new(ids::CONTROL, data));
        }
        self.next_transmit_after_control()
    }

    /// [`Link::next_transmit`] when it is a control frame (ID [`ids::CONTROL`]): its data.
    /// `None` when nothing waits or the next frame is of another class.
    #[inline]
    pub(crate) fn next_control(&mut self) -> Option<[u8; 8]> {
        if !self.has_transmit() {
            return None;
        }
        self.tx.pop_control()
    }

    /// [`Link::next_transmit`] once [`Link::next_control`] has found no control frame:
    /// `None` in line when nothing waits, the other classes out of line.
    #[inline]
    pub(crate) fn next_transmit_after_control(&mut self) -> Option<Frame> {
        if !self.has_transmit() {
            return None;
        }
        self.next_transmit_other()
    }

    /// [`Link::next_transmit`] past the control frames, out of line: a driver's transmit
    /// loop then keeps nothing of the vehicle values or the text FIFO in registers.
    #[inline(never)]
    fn next_transmit_other(&mut self) -> Option<Frame> {
        loop {
            let frame = match self.tx.pop()? {
                queue::Next::Control(data) => Some(Frame::new(ids::CONTROL, data)),
                queue::Next::ZeroRate => Some(Frame::new(ids::CONTROL, queue::zero_rate())),
                // Only a slot holding a value is ever marked (see `requeue`); were one not,
                // the frames behind it would still come out now.
                queue::Next::Vehicle(slot) => self.vehicle.value(slot).map(|v| v.to_frame()),
                queue::Next::Text(t) => Some(Frame::new(
                    if t.last { ids::TEXT_END } else { ids::TEXT },
                    t.data,
                )),
            };
            if frame.is_some() {
                return frame;
            }
        }
    }

    /// Whether frames wait for transmission.
    #[inline]
    pub fn has_transmit(&self) -> bool {
        !self.tx.is_empty()
    }

    /// The driver accepted the frame last taken. `displaced` is a frame it handed back
    /// (a pending lower-priority frame it took out of a mailbox): it is re-queued.
    #[inline]
    pub fn transmit_done(&mut self, displaced: Option<Frame>) {
        self.stats.frames_sent = self.stats.frames_sent.wrapping_add(1);
        if let Some(frame) = displaced {
            self.displaced(frame);
        }
    }

    /// A frame the driver handed back (see [`Link::transmit_done`]), out of line: rare.
    #[inline(never)]
    fn displaced(&mut self, frame: Frame) {
        let requeued = self.requeue(frame);
        if requeued != Requeued::Foreign {
            // The displaced frame had been counted as sent; it is not yet.
            self.stats.frames_sent = self.stats.frames_sent.wrapping_sub(1);
        }
        match requeued {
            Requeued::Queued => self.stats.requeued = self.stats.requeued.wrapping_add(1),
            Requeued::Superseded => self.stats.superseded = self.stats.superseded.wrapping_add(1),
            Requeued::NoRoom | Requeued::Foreign => {
                self.stats.queue_full = self.stats.queue_full.wrapping_add(1)
            }
        }
    }

    /// The driver did not take the frame last taken (it was busy or failed): it goes back
    /// to the front of its class.
    pub fn transmit_refused(&mut self, frame: Frame) {
        if let Requeued::NoRoom | Requeued::Foreign = self.requeue(frame) {
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
        }
    }

    fn requeue(&mut self, frame: Frame) -> Requeued {
        // A vehicle frame is re-sent from the value the link holds: with none, the frame
        // cannot have been this link's.
        if let queue::Class::Vehicle(slot) = queue::Class::of(frame.id) {
            if !self.vehicle.has(slot) {
                return Requeued::Foreign;
            }
        }
        self.quiet.hold_idle();
        self.tx.requeue(frame.id, frame.data)
    }

    /// Counters, including the postback assembler's.
    pub fn stats(&self) -> LinkStats {
        let a = self.assembler.stats();
        let c = self.stats;
        LinkStats {
            // Every received frame is ignored or fed to the assembler, which accounts for
            // each: counting them once more on the hot path would be redundant.
            frames_received: c.ignored_frames.wrapping_add(a.frames),
            frames_sent: c.frames_sent,
            postbacks: a.messages,
            crc_errors: a.crc_errors,
            restarts: a.restarts,
            dropped_partials: a.dropped_partials,
            malformed: a.malformed,
            queue_full: c.queue_full,
            requeued: c.requeued,
            superseded: c.superseded,
            ignored_frames: c.ignored_frames,
        }
    }

    /// The postback assembler.
    pub fn assembler(&self) -> &PostbackAssembler {
        &self.assembler
    }
}

#[cfg(test)]
mod deadline_tests;
#[cfg(test)]
mod tests;
