//! [`Link::next_deadline`]: hand-computed deadlines, and a driver that polls only at the
//! deadline (and on input) doing exactly what one polling every millisecond does.

use super::*;
use crate::geo::Position;
use crate::wire::control::Rate;
use crate::wire::vehicle::Gps;
use proptest::prelude::*;

use super::test_ops::{apply, Op};

fn at(ms: u32) -> Instant {
    Instant::from_millis(ms)
}

/// Takes every queued frame, as a CAN driver with room would.
fn send_all<const Q: usize, const T: usize>(link: &mut Link<Q, T>) -> Vec<Frame> {
    let mut out = Vec::new();
    while let Some(f) = link.next_transmit() {
        out.push(f);
        link.transmit_done(None);
    }
    out
}

// ---- hand-computed cases ----

#[test]
fn a_new_link_is_due_at_once_then_idles_for_60_s() {
    let mut link: Link = Link::new(Config::default());
    for now in [0, 12_345, u32::MAX] {
        assert_eq!(link.next_deadline(at(now)), at(now));
    }
    // Nothing scheduled: the longest idle interval, 60 s, across the wrap.
    let t0 = u32::MAX - 5;
    link.poll(at(t0));
    assert_eq!(link.next_deadline(at(t0)), at(59_994));
    // The same deadline seen from later, from just before it, and at it (due: `now`).
    assert_eq!(link.next_deadline(at(100)), at(59_994));
    assert_eq!(link.next_deadline(at(59_993)), at(59_994));
    assert_eq!(link.next_deadline(at(59_994)), at(59_994));
    assert_eq!(link.next_deadline(at(70_000)), at(70_000));
    // A clock behind the last poll: due at once (never a sleep of ~49 days).
    assert_eq!(link.next_deadline(at(t0 - 1)), at(t0 - 1));
}

#[test]
fn vehicle_push_then_staleness() {
    let mut link: Link = Link::new(Config::default());
    let t0 = 1_000_000;
    link.poll(at(t0));
    link.set_gps(Gps::new(47.0, 8.0).unwrap(), at(t0));
    // The first value is pushed at once.
    assert_eq!(link.next_deadline(at(t0)), at(t0));
    link.poll(at(t0));
    assert_eq!(send_all(&mut link).len(), 1);
    // Next push at +200 (GPS period); staleness at +1001 is later.
    assert_eq!(link.next_deadline(at(t0)), at(t0 + 200));
    // Newer data moves nothing earlier.
    link.set_gps(Gps::new(47.0, 8.0).unwrap(), at(t0 + 50));
    assert_eq!(link.next_deadline(at(t0 + 50)), at(t0 + 200));
    for k in 1..=5 {
        link.poll(at(t0 + 200 * k));
        assert_eq!(send_all(&mut link).len(), 1, "push {k}");
    }
    // At +1000 the next push (+1200) is after the data (stamped +50) goes stale at +1051.
    assert_eq!(link.next_deadline(at(t0 + 1000)), at(t0 + 1051));
    link.poll(at(t0 + 1051));
    // Stale: nothing to push, nothing scheduled but the idle bound.
    assert_eq!(link.next_deadline(at(t0 + 1051)), at(t0 + 1051 + 60_000));
    // Fresh data again: due at once.
    link.set_gps(Gps::new(47.0, 8.0).unwrap(), at(t0 + 2000));
    assert_eq!(link.next_deadline(at(t0 + 2000)), at(t0 + 2000));
}

#[test]
fn rate_hold_repeat_then_dead_man_across_the_wrap() {
    let mut link: Link = Link::new(Config::default());
    let t0 = u32::MAX - 100;
    link.poll(at(t0));
    link.set_rate(Rate::from_centi(1000, 0).unwrap(), at(t0))
        .unwrap();
    assert_eq!(link.next_deadline(at(t0)), at(t0));
    link.poll(at(t0));
    assert_eq!(send_all(&mut link).len(), 1);
    // Repeat every 50 ms: the dead-man (+251) is later.
    assert_eq!(link.next_deadline(at(t0)), at(t0.wrapping_add(50)));
    for k in 1..=4u32 {
        let t = t0.wrapping_add(50 * k);
        link.poll(at(t));
        assert_eq!(send_all(&mut link).len(), 1, "repeat {k}");
    }
    // At +200: the repeat at +250, then the dead-man at +251.
    assert_eq!(
        link.next_deadline(at(t0.wrapping_add(200))),
        at(t0.wrapping_add(250))
    );
    link.poll(at(t0.wrapping_add(250)));
    assert_eq!(send_all(&mut link).len(), 1);
    assert_eq!(
        link.next_deadline(at(t0.wrapping_add(250))),
        at(t0.wrapping_add(251))
    );
    // A refresh of the same rate moves the dead-man later, never earlier: the deadline
    // stays (an early wake-up costs one poll, a late one would lose the repeat).
    link.set_rate(Rate::from_centi(1000, 0).unwrap(), at(t0.wrapping_add(250)))
        .unwrap();
    assert_eq!(
        link.next_deadline(at(t0.wrapping_add(250))),
        at(t0.wrapping_add(251))
    );
    link.poll(at(t0.wrapping_add(251)));
    // Nothing happened at +251 (refreshed): the next repeat is at +300.
    assert!(send_all(&mut link).is_empty());
    assert_eq!(
        link.next_deadline(at(t0.wrapping_add(251))),
        at(t0.wrapping_add(300))
    );
    // Not refreshed again: repeats at +300, ..., +500, then the dead-man at +250 + 251.
    for k in 6..=9u32 {
        let t = t0.wrapping_add(50 * k);
        link.poll(at(t));
        assert_eq!(send_all(&mut link).len(), 1, "repeat {k}");
        assert_eq!(link.next_deadline(at(t)), at(t.wrapping_add(50)));
    }
    assert_eq!(
        link.next_deadline(at(t0.wrapping_add(480))),
        at(t0.wrapping_add(500))
    );
    link.poll(at(t0.wrapping_add(500)));
    send_all(&mut link);
    assert_eq!(
        link.next_deadline(at(t0.wrapping_add(500))),
        at(t0.wrapping_add(501))
    );
    link.poll(at(t0.wrapping_add(501)));
    assert_eq!(link.next_event(), Some(Event::RateHoldExpired));
    assert_eq!(
        send_all(&mut link),
        [Frame::new(ids::CONTROL, queue::zero_rate())]
    );
    assert_eq!(
        link.next_deadline(at(t0.wrapping_add(501))),
        at(t0.wrapping_add(60_501))
    );
}

#[test]
fn postback_window_expiry_and_link_health() {
    let mut link: Link = Link::new(Config::default());
    let t0 = 5_000;
    link.poll(at(t0));
    let frames = Postback::default().to_can_frames();
    // One frame of a postback: the window expires at last frame + 100 + 1 ms.
    link.receive(ids::POSTBACK, &frames[0], at(t0 + 10));
    assert_eq!(link.next_deadline(at(t0 + 10)), at(t0 + 111));
    link.receive(ids::POSTBACK, &frames[1], at(t0 + 30));
    // Not woken by a later frame: the poll at +111 is early, harmlessly.
    assert_eq!(link.next_deadline(at(t0 + 30)), at(t0 + 111));
    link.poll(at(t0 + 111));
    // Still held (the last frame came at +30): its window now ends at +131.
    assert_eq!(link.next_deadline(at(t0 + 111)), at(t0 + 131));
    link.poll(at(t0 + 131));
    assert_eq!(link.stats().dropped_partials, 1);
    assert_eq!(link.next_deadline(at(t0 + 131)), at(t0 + 131 + 60_000));
    // A whole postback: the link is up until 1500 ms pass without one.
    for d in frames {
        link.receive(ids::POSTBACK, &d, at(t0 + 200));
    }
    // The window that opened with its first frame asked for a wake-up at its expiry
    // (+301); the whole postback closed it, and that poll finds nothing to do (early, never
    // late). Then the health timeout, 1500 + 1 ms after the postback.
    assert_eq!(link.next_deadline(at(t0 + 200)), at(t0 + 301));
    link.poll(at(t0 + 301));
    assert_eq!(link.next_deadline(at(t0 + 301)), at(t0 + 1701));
    link.poll(at(t0 + 1700));
    assert!(link.is_link_up());
    assert_eq!(link.next_deadline(at(t0 + 1700)), at(t0 + 1701));
    link.poll(at(t0 + 1701));
    assert!(!link.is_link_up());
}

#[test]
fn point_at_steps_and_pending_frames_are_not_a_deadline() {
    let config = Config {
        point_at_period_ms: NonZeroU16::new(70).unwrap(),
        ..Config::default()
    };
    let mut link: Link = Link::new(config);
    let t0 = 0;
    link.poll(at(t0));
    link.point_at(Position::new(47.001, 8.001, 400.0).unwrap());
    assert_eq!(link.next_deadline(at(t0)), at(t0));
    link.poll(at(t0));
    assert_eq!(link.next_deadline(at(t0)), at(t0 + 70));
    // A text queued and not taken: still no poll before +70.
    link.send_text(b"HELLO").unwrap();
    assert!(link.has_transmit());
    assert_eq!(link.next_deadline(at(t0 + 1)), at(t0 + 70));
    link.poll(at(t0 + 70));
    assert_eq!(link.next_deadline(at(t0 + 70)), at(t0 + 140));
}

// ---- polling only at the deadline ----

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        3 => (-500i16..500).prop_map(Op::Rate),
        1 => Just(Op::StopRate),
        1 => Just(Op::Pitch),
        3 => (0u32..1500).prop_map(|stamp_back| Op::Vehicle { stamp_back }),
        1 => (0u32..300).prop_map(|stamp_back| Op::Gps { stamp_back }),
        2 => Just(Op::Postback),
        1 => Just(Op::BadPostback),
        2 => (0u8..4).prop_map(Op::PostbackFrame),
        1 => (0u32..3000).prop_map(Op::LatePostback),
        1 => Just(Op::PointAt),
        1 => Just(Op::StopPointing),
        1 => Just(Op::Text),
        2 => (any::<bool>(), 0u16..=3600, -1000i16..=600)
            .prop_map(|(earth, yaw, pitch)| Op::Aim { earth, yaw, pitch }),
        1 => Just(Op::StopAim),
        2 => (-17_000i16..=17_000, 0u8..5, any::<bool>())
            .prop_map(|(motor, mode, tracking)| Op::PostbackOf { motor, pitch: 0, mode, tracking }),
    ]
}

fn config() -> impl Strategy<Value = Config> {
    (
        (0u16..300, 0u16..300, 0u16..300, 1u16..1500),
        (1u16..120, 1u16..400, 1u16..2000, 1u16..200, 1u16..200),
    )
        .prop_map(
            |((att, gps, alt, stale), (repeat, deadman, timeout, gap, point))| Config {
                attitude_period_ms: att,
                gps_period_ms: gps,
                altitude_period_ms: alt,
                vehicle_stale_ms: stale,
                rate_repeat_ms: NonZeroU16::new(repeat).unwrap(),
                rate_deadman_ms: deadman,
                link_timeout_ms: timeout,
                postback_max_gap_ms: gap,
                point_at_period_ms: NonZeroU16::new(point).unwrap(),
                ..Config::default()
            },
        )
}

/// Hands queued frames to a CAN driver that is busy (refuses the next frame) at the
/// milliseconds `busy` says: the same for both links, so that refusals match.
fn transmit<const Q: usize, const T: usize>(
    link: &mut Link<Q, T>,
    busy: bool,
    log: &mut Vec<Frame>,
) {
    while let Some(f) = link.next_transmit() {
        if busy {
            link.transmit_refused(f);
            return;
        }
        log.push(f);
        link.transmit_done(None);
    }
}

/// One millisecond of both drivers. `reference` is fully polled every millisecond.
/// `lazy` wakes only at its last `next_deadline` (`now` while frames wait, as
/// [`crate::Port::next_deadline`]) or on input; when `poll_on_input` is false, an input
/// alone does not make it poll: only a deadline that has come (`next_deadline(now) ==
/// now`) does. Its polls are full polls too (no idle fast path): the deadline alone
/// decides.
struct Pair<const Q: usize, const T: usize> {
    reference: Link<Q, T>,
    lazy: Link<Q, T>,
    wake: Instant,
    poll_on_input: bool,
    lazy_polls: u32,
}

impl<const Q: usize, const T: usize> Pair<Q, T> {
    fn step(&mut self, now: Instant, input: Option<&Op>, busy: bool) -> Result<(), TestCaseError> {
        if let Some(op) = input {
            apply(&mut self.reference, op, now);
            apply(&mut self.lazy, op, now);
        }
        let (mut sent_ref, mut sent_lazy) = (Vec::new(), Vec::new());
        self.reference.poll_all(now);
        transmit(&mut self.reference, busy, &mut sent_ref);

        if input.is_some() || now.is_at_or_after(self.wake) {
            let deadline = self.lazy.next_deadline(now);
            prop_assert!(deadline.is_at_or_after(now));
            prop_assert!(deadline.millis_since(now) <= MAX_QUIET_MS);
            if (input.is_some() && self.poll_on_input) || deadline == now {
                self.lazy.poll_all(now);
                self.lazy_polls += 1;
            }
            transmit(&mut self.lazy, busy, &mut sent_lazy);
            self.wake = if self.lazy.has_transmit() {
                now
            } else {
                self.lazy.next_deadline(now)
            };
        }
        prop_assert_eq!(sent_ref, sent_lazy, "frames at {}", now.as_millis());
        let events_ref: Vec<Event> = core::iter::from_fn(|| self.reference.next_event()).collect();
        let events_lazy: Vec<Event> = core::iter::from_fn(|| self.lazy.next_event()).collect();
        prop_assert_eq!(events_ref, events_lazy, "events at {}", now.as_millis());
        prop_assert_eq!(
            self.reference.stats(),
            self.lazy.stats(),
            "stats at {}",
            now.as_millis()
        );
        prop_assert_eq!(self.reference.is_link_up(), self.lazy.is_link_up());
        prop_assert_eq!(
            self.reference.is_rate_holding(),
            self.lazy.is_rate_holding()
        );
        prop_assert_eq!(
            self.reference.pointing_target(),
            self.lazy.pointing_target()
        );
        Ok(())
    }
}

fn check<const Q: usize, const T: usize>(
    config: Config,
    script: &[(u32, Op)],
    start: u32,
    busy_every: u32,
    poll_on_input: bool,
) -> Result<u32, TestCaseError> {
    let mut pair: Pair<Q, T> = Pair {
        reference: Link::new(config),
        lazy: Link::new(config),
        wake: at(start),
        poll_on_input,
        lazy_polls: 0,
    };
    let mut t = start;
    let mut tick = 0u32;
    let mut step = |t: u32, tick: u32, input: Option<&Op>| {
        // A bus busy one millisecond in `busy_every` (0: never).
        let busy = busy_every != 0 && tick.is_multiple_of(busy_every);
        pair.step(at(t), input, busy)
    };
    for (gap, op) in script {
        for _ in 0..*gap {
            step(t, tick, None)?;
            t = t.wrapping_add(1);
            tick += 1;
        }
        step(t, tick, Some(op))?;
        t = t.wrapping_add(1);
        tick += 1;
    }
    // Let every schedule run out: dead-man, staleness, link timeout, window expiry.
    for _ in 0..2_500 {
        step(t, tick, None)?;
        t = t.wrapping_add(1);
        tick += 1;
    }
    Ok(pair.lazy_polls)
}

fn start() -> impl Strategy<Value = u32> {
    prop_oneof![any::<u32>(), (0u32..20_000).prop_map(|k| u32::MAX - k)]
}

fn script() -> impl Strategy<Value = Vec<(u32, Op)>> {
    proptest::collection::vec((0u32..400, op()), 1..25)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Polling at the deadline and on every input does what polling every millisecond does.
    #[test]
    fn polling_at_the_deadline_and_on_input_equals_polling_every_ms(
        config in config(), script in script(), start in start(), busy_every in 0u32..5,
    ) {
        check::<8, 8>(config, &script, start, busy_every, true)?;
    }

    /// The same when an input alone does not poll: every input that needs a poll makes
    /// the deadline `now`.
    #[test]
    fn polling_only_when_the_deadline_has_come_equals_polling_every_ms(
        config in config(), script in script(), start in start(), busy_every in 0u32..5,
    ) {
        check::<8, 8>(config, &script, start, busy_every, false)?;
    }

    /// With tiny queues (full-queue retries, deferred aims) and a bus often busy.
    #[test]
    fn the_same_with_full_queues(
        config in config(), script in script(), start in start(), busy_every in 1u32..4,
        poll_on_input: bool,
    ) {
        check::<2, 2>(config, &script, start, busy_every, poll_on_input)?;
    }
}

/// The lazy driver does poll far less than every millisecond when little is scheduled:
/// the equivalence above is not that of two drivers polling alike.
#[test]
fn an_idle_link_with_vehicle_pushes_polls_at_their_periods_only() {
    let script = [(0, Op::Vehicle { stamp_back: 0 })];
    for start in [0, u32::MAX - 700] {
        let polls = check::<8, 8>(Config::default(), &script, start, 0, false).unwrap();
        // 2,501 ms: the data is fresh for 1000 ms; pushes at 0, 100, ..., 1000 (attitude;
        // GPS and altitude on every other), then staleness at 1001, then idle.
        assert_eq!(polls, 12, "start {start}");
    }
}
