//! The stateful link: reassembly, the transmit queue and the schedules, with no I/O.
//!
//! [`Link`] is a sans-IO state machine. Feed it received frames with [`Link::receive`],
//! call [`Link::poll`] with the current time, and move the frames it hands out with
//! [`Link::next_transmit`] to whatever CAN stack you have, reporting back with
//! [`Link::transmit_done`] or [`Link::transmit_refused`]. The CAN port
//! ([`CanPort`](crate::CanPort)) does exactly this over an `embedded-can` driver; an async
//! (embassy) or non-`embedded-can` stack can do the same. The link is the one command
//! surface: a port only moves its frames (see [`crate::port`]).
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

pub mod aim;
mod event;
pub mod medium;
mod point;
pub mod postback;
mod queue;
mod quiet;
mod rate;
mod receive;
mod ring;
mod schedule;
mod send;
pub mod text;
mod transmit;
mod vehicle;

use core::fmt;
use core::num::NonZeroU16;

use crate::time::Instant;
use crate::wire::control::{Command, GimbalCommand, Rate};
use crate::wire::postback::{GimbalType, Postback};
use crate::wire::vehicle::{Altitude, Attitude, Gps, VehicleFrame};
use crate::wire::{ids, text as wire_text, Frame};
pub use aim::{Aim, AimError, AimState, Yaw};
pub use event::Event;
pub use medium::{Can, Medium, Serial};
use postback::PostbackAssembler;
use queue::{Requeued, TxQueue, VehicleSlot};
use rate::RateHold;
pub use receive::RxId;
use vehicle::VehicleSources;

/// Timing of the link. Every field is in milliseconds (at most 65 535) unless it says
/// otherwise. A vehicle push period of 0 disables that push; the periods of what the link
/// repeats by itself (a rate hold's command, the closed loop's and a point-at's looks) are
/// never 0, in their type.
///
/// ```
/// use core::num::NonZeroU16;
/// use idu_gimbal::Config;
///
/// // The closed loop and a rate hold's command every 20 ms, no altitude push.
/// let period = NonZeroU16::new(20).ok_or("a period is at least 1 ms")?;
/// let config = Config {
///     aim_period_ms: period,
///     rate_repeat_ms: period,
///     altitude_period_ms: 0,
///     ..Config::default()
/// };
/// assert_eq!(config.point_at_period_ms.get(), 100);
/// # Ok::<(), &str>(())
/// ```
///
/// A repeat period of 0 does not build:
///
/// ```compile_fail
/// let config = idu_gimbal::Config {
///     rate_repeat_ms: 0,
///     ..idu_gimbal::Config::default()
/// };
/// ```
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
    pub rate_repeat_ms: NonZeroU16,
    /// A rate hold not refreshed within this stops with one zero-rate command (default 250).
    pub rate_deadman_ms: u16,
    /// The link is up while a valid postback arrived within this (default 1500: three
    /// postback periods).
    pub link_timeout_ms: u16,
    /// Bound on the gap between frames of one postback (default 100).
    pub postback_max_gap_ms: u16,
    /// Period at which [`Link::point_at`] recomputes the aim at its target (default 100:
    /// 10 Hz).
    pub point_at_period_ms: NonZeroU16,
    /// An aim held ([`Link::aim`], [`Link::point_at`]) is sent again when it, or the
    /// vehicle's heading, moved by more than this since the last command, in millidegrees
    /// (default 200: twice the command's 0.1°, so that rounding alone never re-sends).
    pub aim_deadband_mdeg: u16,
    /// A postback off an aim held by more than this (either axis, millidegrees) is off
    /// target (default 500: five times the command's resolution; the simulator lands
    /// exactly, a real gimbal settles within its stabiliser's accuracy, which the document
    /// does not give: widen it for a gimbal that settles farther).
    pub aim_tolerance_mdeg: u16,
    /// The closed loop's period: an aim held is looked at this often, and re-commanded at
    /// most this often (default 50, the document's period for a repeated rate command).
    pub aim_period_ms: NonZeroU16,
    /// Frames a port's [`poll`](crate::Port::poll) receives at most in one call, so that a
    /// flooded bus cannot starve the rest of the main loop (default 32; a poll always
    /// tries at least one).
    pub max_rx_per_poll: NonZeroU16,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            attitude_period_ms: 100,
            gps_period_ms: 200,
            altitude_period_ms: 200,
            vehicle_stale_ms: 1000,
            rate_repeat_ms: non_zero!(NonZeroU16, 50),
            rate_deadman_ms: 250,
            link_timeout_ms: 1500,
            postback_max_gap_ms: postback::DEFAULT_MAX_GAP_MS,
            point_at_period_ms: non_zero!(NonZeroU16, 100),
            aim_deadband_mdeg: 200,
            aim_tolerance_mdeg: 500,
            aim_period_ms: non_zero!(NonZeroU16, 50),
            max_rx_per_poll: non_zero!(NonZeroU16, 32),
        }
    }
}

/// Counters for diagnosing a bus. All wrap at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// Frames received (including ignored ones): `ignored_frames` plus the assembler's
    /// frames, plus on a serial link its whole postbacks (a frame each).
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
    /// An aim held sent again after its first command: the vehicle turned, the gimbal's
    /// reference changed, or a postback showed the gimbal off it (see [`aim`]).
    pub aim_recommands: u32,
    /// Aims not reached after [`aim::ATTEMPTS`] re-commands (see [`aim`]).
    pub aim_not_reached: u32,
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

/// What keeps the gimbal moving besides single commands. A rate hold, an aim and a
/// point-at are all pointing, and any pointing ends the others: one place holds any.
#[derive(Clone, Copy, Debug)]
enum Steering<const Q: usize, const T: usize, M: Medium> {
    /// Nothing: the gimbal does what it was last told.
    Manual,
    /// A rate hold.
    Rate(RateHold),
    /// An orientation held closed loop.
    Aim(aim::Hold<Q, T, M>),
    /// Pointing at a location.
    Point(point::PointAt<Q, T, M>),
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
pub struct Link<const Q: usize = 8, const T: usize = 8, M: Medium = Can> {
    config: Config,
    tx: TxQueue<Q, T>,
    assembler: PostbackAssembler,
    vehicle: VehicleSources,
    steering: Steering<Q, T, M>,
    latest: Option<(Postback, Instant)>,
    status: event::Status,
    /// Nothing is due within `quiet` after `last_poll` (0: poll fully next time): the idle
    /// fast paths, one load pair and a compare each. Kept next to each other.
    last_poll: Instant,
    quiet: quiet::Quiet,
    stats: Counters,
    medium: core::marker::PhantomData<M>,
}

/// The link to a gimbal over its UART: control commands and postbacks only (see
/// [`medium`]), no text slots. The serial port ([`SerialPort`](crate::port::SerialPort),
/// or the sans-IO [`SerialStream`](crate::port::serial::SerialStream)) moves its bytes.
pub type SerialLink<const Q: usize = 8> = Link<Q, 0, Serial>;

/// The counters the link itself keeps; the rest of [`LinkStats`] is the assembler's or
/// derived.
#[derive(Clone, Copy, Debug, Default)]
struct Counters {
    frames_sent: u32,
    queue_full: u32,
    requeued: u32,
    superseded: u32,
    ignored_frames: u32,
    aim_recommands: u32,
    aim_not_reached: u32,
    /// Postbacks that arrived whole (the serial stream's).
    whole_postbacks: u32,
}

use queue::VehicleSlot::{Altitude as ALTITUDE, Attitude as ATTITUDE, Gps as GPS};

impl<const Q: usize, const T: usize, M: Medium> Link<Q, T, M> {
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
            medium: core::marker::PhantomData,
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

    /// Counters, including the postback assembler's.
    pub fn stats(&self) -> LinkStats {
        let a = self.assembler.stats();
        let c = self.stats;
        LinkStats {
            // Every received frame is ignored or fed to the assembler, which accounts for
            // each: counting them once more on the hot path would be redundant.
            frames_received: c
                .ignored_frames
                .wrapping_add(a.frames)
                .wrapping_add(c.whole_postbacks),
            frames_sent: c.frames_sent,
            postbacks: a.messages.wrapping_add(c.whole_postbacks),
            crc_errors: a.crc_errors,
            restarts: a.restarts,
            dropped_partials: a.dropped_partials,
            malformed: a.malformed,
            queue_full: c.queue_full,
            requeued: c.requeued,
            superseded: c.superseded,
            ignored_frames: c.ignored_frames,
            aim_recommands: c.aim_recommands,
            aim_not_reached: c.aim_not_reached,
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
mod test_ops;
#[cfg(test)]
mod tests;
