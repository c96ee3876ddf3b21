//! What the link tells the application: [`Event`], and the set in which events wait until
//! taken.

/// Something the application may want to act on.
///
/// Events wait as a set of flags, as a peripheral's status register does, not in a queue:
/// each kind waits at most once until [`Link::next_event`](super::Link::next_event) takes it,
/// and a second occurrence before then merges with the first. So nothing can be lost to a
/// full queue, whatever the application's pace, and the whole set costs four bytes.
///
/// - [`Event::Postback`] means "at least one new postback": read the newest with
///   [`Link::latest_postback`](super::Link::latest_postback); the count is in
///   [`LinkStats::postbacks`](super::LinkStats::postbacks).
/// - [`Event::LinkUp`] and [`Event::LinkDown`] always alternate and end with the link's
///   current state: between two reads, the link going down and up again shows as both;
///   more changes than that merge into the net change (down, up, down shows as down).
/// - [`Event::TargetUnreachable`] carries the latest elevation reported.
///
/// Taken in this order: link transitions, postback, rate hold expired, target unreachable,
/// aim not reached.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// At least one valid postback arrived since this was last taken: read the newest with
    /// [`Link::latest_postback`](super::Link::latest_postback).
    Postback,
    /// The first valid postback after start or after the link was down.
    LinkUp,
    /// No valid postback within the link timeout.
    LinkDown,
    /// A rate hold was not refreshed in time: one zero-rate command was queued.
    RateHoldExpired,
    /// [`Link::point_at`](super::Link::point_at)'s target needs a pitch outside the gimbal's
    /// [-100°, 60°]; the gimbal holds the last reachable aim. Raised once each time the
    /// target leaves reach.
    TargetUnreachable {
        /// The elevation the target needs, in 0.01°.
        elevation_cdeg: i16,
    },
    /// An aim held ([`Link::aim`](super::Link::aim), [`Link::point_at`](super::Link::point_at))
    /// was not reached after [`aim::ATTEMPTS`](super::aim::ATTEMPTS) re-commands; see
    /// [`Link::aim_state`](super::Link::aim_state).
    AimNotReached,
}

// Events waiting, in the order they are taken.
const POSTBACK: u8 = 1 << 0;
const RATE_HOLD_EXPIRED: u8 = 1 << 1;
const TARGET_UNREACHABLE: u8 = 1 << 2;
const AIM_NOT_REACHED: u8 = 1 << 6;
const EVENTS: u8 = POSTBACK | RATE_HOLD_EXPIRED | TARGET_UNREACHABLE | AIM_NOT_REACHED;
// The link's state, the state the application was last told, and whether the link left
// that state and came back since.
const UP: u8 = 1 << 3;
const TOLD_UP: u8 = 1 << 4;
const RETURNED: u8 = 1 << 5;
// What the steering has not yet seen (`Status::steering`): a postback, the link coming up.
const FRESH_POSTBACK: u8 = 1 << 0;
const CAME_UP: u8 = 1 << 1;

/// The link's state and the events waiting (see [`Event`]). Link transitions are not
/// stored as events: [`Status::take`] derives them from the state the application was last
/// told and the state now.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub(crate) struct Status {
    flags: u8,
    /// For the steering, apart from the application's events (in what was padding).
    steering: u8,
    elevation_cdeg: i16,
}

impl Status {
    /// Link down, nothing waiting.
    pub(crate) const fn new() -> Self {
        Status {
            flags: 0,
            steering: 0,
            elevation_cdeg: 0,
        }
    }

    /// Whether a postback arrived since the steering last asked.
    pub(crate) fn take_fresh_postback(&mut self) -> bool {
        let fresh = self.steering & FRESH_POSTBACK != 0;
        self.steering &= !FRESH_POSTBACK;
        fresh
    }

    /// Whether the link came up since the steering last asked.
    pub(crate) fn take_came_up(&mut self) -> bool {
        let came = self.steering & CAME_UP != 0;
        self.steering &= !CAME_UP;
        came
    }

    /// Whether the link is up.
    pub(crate) fn is_up(&self) -> bool {
        self.flags & UP != 0
    }

    fn told_up(&self) -> bool {
        self.flags & TOLD_UP != 0
    }

    /// Sets the link's state.
    pub(crate) fn set_up(&mut self, up: bool) {
        if self.is_up() == up {
            return;
        }
        self.flags ^= UP;
        if up {
            self.steering |= CAME_UP;
        }
        if up == self.told_up() {
            // Back where the application last saw it: it must still see it leave and return.
            self.flags |= RETURNED;
        }
    }

    /// Marks `event` as waiting (merging it with one of its kind already waiting). Link
    /// transitions come from [`Status::set_up`] instead.
    pub(crate) fn raise(&mut self, event: Event) {
        self.flags |= match event {
            Event::Postback => {
                self.steering |= FRESH_POSTBACK;
                POSTBACK
            }
            Event::RateHoldExpired => RATE_HOLD_EXPIRED,
            Event::TargetUnreachable { elevation_cdeg } => {
                self.elevation_cdeg = elevation_cdeg;
                TARGET_UNREACHABLE
            }
            Event::AimNotReached => AIM_NOT_REACHED,
            Event::LinkUp | Event::LinkDown => 0,
        };
    }

    /// Takes the next event. In line, and what an application's event loop meets most
    /// (nothing, or a postback) is two tests of the flags; the rest out of line.
    #[inline]
    pub(crate) fn take(&mut self) -> Option<Event> {
        let f = self.flags;
        // A transition to tell: the state differs from the one last told (`TOLD_UP` is
        // the bit above `UP`), or the link left that state and came back.
        let transition = ((f ^ (f >> 1)) & UP) | (f & RETURNED);
        if transition == 0 {
            if f & POSTBACK != 0 {
                self.flags = f & !POSTBACK;
                return Some(Event::Postback);
            }
            if f & EVENTS == 0 {
                return None;
            }
        }
        self.take_slow()
    }

    /// [`Status::take`], every case.
    #[inline(never)]
    fn take_slow(&mut self) -> Option<Event> {
        let told = self.told_up();
        if self.is_up() != told || self.flags & RETURNED != 0 {
            // Tell the change from the state last told: the net change, or the first leg of
            // a round trip (its return is told next).
            self.flags ^= TOLD_UP;
            if self.is_up() != told {
                self.flags &= !RETURNED;
            }
            return Some(if told { Event::LinkDown } else { Event::LinkUp });
        }
        let events = self.flags & EVENTS;
        // The lowest waiting bit: postback, rate hold expired, target unreachable, aim not
        // reached.
        let bit = events & events.wrapping_neg();
        self.flags &= !bit;
        match bit {
            POSTBACK => Some(Event::Postback),
            RATE_HOLD_EXPIRED => Some(Event::RateHoldExpired),
            TARGET_UNREACHABLE => Some(Event::TargetUnreachable {
                elevation_cdeg: self.elevation_cdeg,
            }),
            AIM_NOT_REACHED => Some(Event::AimNotReached),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drain(s: &mut Status) -> Vec<Event> {
        core::iter::from_fn(|| s.take()).collect()
    }

    #[test]
    fn each_kind_waits_once_in_a_fixed_order() {
        let mut s = Status::new();
        assert_eq!(s.take(), None);
        let unreachable = |e| Event::TargetUnreachable { elevation_cdeg: e };
        s.raise(unreachable(7000));
        s.raise(Event::Postback);
        s.raise(Event::RateHoldExpired);
        s.raise(Event::Postback);
        s.raise(unreachable(8000));
        s.set_up(true);
        s.set_up(true); // no change, no event
        assert_eq!(
            drain(&mut s),
            [
                Event::LinkUp,
                Event::Postback,
                Event::RateHoldExpired,
                unreachable(8000)
            ]
        );
        assert_eq!(s.take(), None);
        assert!(s.is_up());
    }

    #[test]
    fn link_transitions_alternate_and_end_in_the_current_state() {
        let mut s = Status::new();
        s.set_up(true);
        assert_eq!(drain(&mut s), [Event::LinkUp]);
        // Down and up again between two reads: both.
        s.set_up(false);
        s.set_up(true);
        assert_eq!(drain(&mut s), [Event::LinkDown, Event::LinkUp]);
        // From down (as told) with nothing else waiting: up and down again between two
        // reads is both, in order.
        let mut fresh = Status::new();
        fresh.set_up(true);
        fresh.set_up(false);
        assert_eq!(drain(&mut fresh), [Event::LinkUp, Event::LinkDown]);
        assert!(!fresh.is_up());
        // Down, up, down: the net change.
        s.set_up(false);
        s.set_up(true);
        s.set_up(false);
        assert_eq!(drain(&mut s), [Event::LinkDown]);
        // Up, down, up, down, up... back and forth any number of times: what was told
        // always alternates and ends in the current state.
        for flips in 1..9 {
            let told_before = s.is_up();
            for _ in 0..flips {
                s.set_up(!s.is_up());
            }
            s.raise(Event::Postback);
            let events = drain(&mut s);
            let (link, rest) = events.split_at(events.len() - 1);
            assert_eq!(rest, [Event::Postback]);
            let mut told = told_before;
            for e in link {
                assert_eq!(*e, if told { Event::LinkDown } else { Event::LinkUp });
                told = !told;
            }
            assert_eq!(told, s.is_up(), "{flips} flips: {events:?}");
            assert_eq!(link.len(), if flips % 2 == 1 { 1 } else { 2 });
        }
    }
}
