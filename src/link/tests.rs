//! Schedules of the link, driven tick by tick with a stand-in CAN driver that accepts
//! every frame.

use super::*;
use crate::wire::control::{Command, DualLightCommand, GimbalCommand, Pitch, Rate};
use crate::wire::vehicle::{Altitude, Attitude, Gps};

/// Polls every `step` ms from `from` to `to` (exclusive), draining the queue into a log of
/// (time, frame).
fn run<const Q: usize, const T: usize>(
    link: &mut Link<Q, T>,
    from: u32,
    to: u32,
    step: u32,
) -> Vec<(u32, Frame)> {
    let mut out = Vec::new();
    let mut t = from;
    while t.wrapping_sub(from) < to.wrapping_sub(from) {
        link.poll(Instant::from_millis(t));
        while let Some(f) = link.next_transmit() {
            out.push((t, f));
            link.transmit_done(None);
        }
        t = t.wrapping_add(step);
    }
    out
}

fn count(log: &[(u32, Frame)], id: u32) -> usize {
    log.iter().filter(|(_, f)| f.id == id).count()
}

fn feed_vehicle<const Q: usize, const T: usize>(link: &mut Link<Q, T>, at: u32) {
    let now = Instant::from_millis(at);
    link.set_attitude(Attitude::new(1.0, 2.0, 3.0).unwrap(), now);
    link.set_gps(Gps::new(47.0, 8.0).unwrap(), now);
    link.set_altitude(Altitude::new(500.0).unwrap(), now);
}

#[test]
fn vehicle_frames_at_their_periods_without_drift() {
    let mut link: Link = Link::new(Config::default());
    let mut log = Vec::new();
    // Fresh data at every poll; a poll every 7 ms (not a divisor of the periods) for 10 s,
    // so that a poll comes after most deadlines, as a schedule that drifted would show.
    let mut t = 0u32;
    while t < 10_000 {
        feed_vehicle(&mut link, t);
        log.extend(run(&mut link, t, t + 1, 1));
        t += 7;
    }
    // Deadlines, not poll times: frame k of a period p is due at p·k ms and goes at the
    // first poll at or after it, ⌈p·k / 7⌉·7 (a next deadline counted from the late poll
    // would fall behind by up to 6 ms a frame).
    let at = |id, period: u32, n: u32| {
        let sent: Vec<u32> = log
            .iter()
            .filter(|(_, f)| f.id == id)
            .map(|(t, _)| *t)
            .collect();
        let due: Vec<u32> = (0..n).map(|k| (period * k).div_ceil(7) * 7).collect();
        assert_eq!(sent, due, "{id:#x}");
    };
    at(ids::ATTITUDE, 100, 100);
    at(ids::GPS, 200, 50);
    at(ids::ALTITUDE, 200, 50);
}

#[test]
fn stale_data_is_not_pushed_and_fresh_data_resumes_at_once() {
    let mut link: Link = Link::new(Config::default());
    feed_vehicle(&mut link, 0);
    let log = run(&mut link, 0, 3000, 1);
    // Pushed while age <= 1000 ms: attitude at 0..=1000 by 100 ms = 11 frames.
    assert_eq!(count(&log, ids::ATTITUDE), 11);
    assert_eq!(count(&log, ids::GPS), 6);
    feed_vehicle(&mut link, 3000);
    let log = run(&mut link, 3000, 3001, 1);
    assert_eq!(
        log.len(),
        3,
        "all three pushed as soon as data is fresh again"
    );
}

#[test]
fn data_stale_for_more_than_half_the_clocks_range_stays_stale() {
    // Data set once and never again, polled every 10 s: stale from 1,000 ms on, and still
    // stale when its stamp is more than 2^31 ms behind (where a wrapping difference reads
    // it as ahead of the clock). Fresh again only with a new value.
    let mut link: Link = Link::new(Config::default());
    feed_vehicle(&mut link, 0);
    assert_eq!(run(&mut link, 0, 1, 1).len(), 3);
    assert!(link.north_referenced(Instant::from_millis(500)));
    let half = 1u32 << 31;
    for at in [
        2_000,
        half - 1_000,
        half,
        half + 1,
        half + 500,
        half + 600_000,
    ] {
        let log = run(&mut link, at, at + 1, 1);
        assert_eq!(log.len(), 0, "pushed at {at}: {log:?}");
        assert!(!link.north_referenced(Instant::from_millis(at)), "at {at}");
    }
    let mut t = 2_000u32;
    let mut pushed = Vec::new();
    while t < half + 600_000 {
        pushed.extend(run(&mut link, t, t + 1, 1));
        t += 10_000;
    }
    assert_eq!(pushed, []);
    feed_vehicle(&mut link, t);
    assert_eq!(run(&mut link, t, t + 1, 1).len(), 3);
    assert!(link.north_referenced(Instant::from_millis(t)));
}

#[test]
fn a_long_gap_between_polls_yields_one_push_not_a_burst() {
    let mut link: Link = Link::new(Config::default());
    feed_vehicle(&mut link, 0);
    assert_eq!(run(&mut link, 0, 1, 1).len(), 3);
    feed_vehicle(&mut link, 950);
    // No poll from 1 to 950 ms: nine attitude periods missed.
    let log = run(&mut link, 950, 951, 1);
    assert_eq!((count(&log, ids::ATTITUDE), count(&log, ids::GPS)), (1, 1));
    // And the schedule continues a period later, not at once.
    assert_eq!(run(&mut link, 951, 1050, 1).len(), 0);
    assert_eq!(count(&run(&mut link, 1050, 1051, 1), ids::ATTITUDE), 1);
}

#[test]
fn latest_vehicle_value_wins_when_not_yet_sent() {
    let mut link: Link = Link::new(Config::default());
    link.set_gps(Gps::new(1.0, 1.0).unwrap(), Instant::from_millis(0));
    link.poll(Instant::from_millis(0));
    link.set_gps(Gps::new(2.0, 2.0).unwrap(), Instant::from_millis(200));
    link.poll(Instant::from_millis(200)); // the first push was never taken by a driver
    let f = link.next_transmit().unwrap();
    assert_eq!(
        VehicleFrame::decode(f.id, &f.data).unwrap(),
        VehicleFrame::Gps(Gps::new(2.0, 2.0).unwrap())
    );
    assert_eq!(link.next_transmit(), None);
    assert_eq!(link.stats().superseded, 1);
}

fn rate_frames(log: &[(u32, Frame)]) -> Vec<(u32, Rate)> {
    log.iter()
        .filter_map(|(t, f)| match Command::decode(&f.data) {
            Ok(Command::Gimbal(GimbalCommand::Rate(r))) => Some((*t, r)),
            _ => None,
        })
        .collect()
}

#[test]
fn rate_hold_repeats_every_50_ms_and_dead_man_stops_it() {
    let mut link: Link = Link::new(Config::default());
    let r = Rate::new(10.0, -5.0).unwrap();
    let mut log = Vec::new();
    for t in 0..1000u32 {
        if t < 500 && t % 100 == 0 {
            link.set_rate(r, Instant::from_millis(t)).unwrap(); // refreshed every 100 ms until 400
        }
        log.extend(run(&mut link, t, t + 1, 1));
    }
    let rates = rate_frames(&log);
    let times: Vec<u32> = rates.iter().map(|(t, _)| *t).collect();
    // Sent at 0, 50, ..., 650 (last refresh 400 + dead-man 250 = 650), then one zero at 651.
    let mut expected: Vec<u32> = (0..=650).step_by(50).collect();
    expected.push(651);
    assert_eq!(times, expected);
    assert!(rates[..rates.len() - 1].iter().all(|(_, x)| *x == r));
    assert_eq!(rates.last().unwrap().1, Rate::ZERO);
    assert!(!link.is_rate_holding());
    assert_eq!(link.next_event(), Some(Event::RateHoldExpired));
}

#[test]
fn stop_rate_sends_one_zero_and_pointing_commands_cancel() {
    let mut link: Link = Link::new(Config::default());
    link.set_rate(Rate::new(1.0, 0.0).unwrap(), Instant::from_millis(0))
        .unwrap();
    link.stop_rate();
    let log = run(&mut link, 0, 500, 1);
    assert_eq!(
        rate_frames(&log)
            .iter()
            .map(|(_, r)| *r)
            .collect::<Vec<_>>(),
        [Rate::new(1.0, 0.0).unwrap(), Rate::ZERO]
    );
    // A pointing command cancels the hold: no more repeats, no zero frame.
    link.set_rate(Rate::new(1.0, 0.0).unwrap(), Instant::from_millis(500))
        .unwrap();
    link.send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()))
        .unwrap();
    let log = run(&mut link, 500, 1500, 1);
    assert_eq!(rate_frames(&log).len(), 1);
    assert!(!link.is_rate_holding());
    // A non-pointing command (palette) keeps it.
    link.set_rate(Rate::new(2.0, 0.0).unwrap(), Instant::from_millis(1500))
        .unwrap();
    link.send(DualLightCommand::Palette(
        crate::wire::control::Palette::Lava,
    ))
    .unwrap();
    assert!(link.is_rate_holding());
}

#[test]
fn full_queue_hands_back_and_zero_rate_is_never_lost() {
    let mut link: Link<2, 2> = Link::new(Config::default());
    let cmd = Command::from(GimbalCommand::Recenter);
    // The room says what `send` takes: two, one, then none.
    assert_eq!(link.command_room(), 2);
    link.send(cmd).unwrap();
    assert_eq!(link.command_room(), 1);
    link.send(cmd).unwrap();
    assert_eq!(link.command_room(), 0);
    assert_eq!(link.send(cmd), Err(QueueFull(cmd)));
    let r = Rate::new(3.0, 0.0).unwrap();
    assert_eq!(link.set_rate(r, Instant::from_millis(0)), Err(QueueFull(r)));
    assert!(!link.is_rate_holding());
    assert_eq!(link.stats().queue_full, 2);
    // Make room, start a hold, fill the queue, stop: the zero goes out once there is room.
    link.next_transmit();
    link.transmit_done(None);
    assert_eq!(link.command_room(), 1);
    link.set_rate(r, Instant::from_millis(0)).unwrap();
    link.stop_rate();
    let log = run(&mut link, 0, 10, 1);
    assert_eq!(
        rate_frames(&log)
            .iter()
            .map(|(_, r)| *r)
            .collect::<Vec<_>>(),
        [r, Rate::ZERO]
    );
    assert_eq!(
        link.send_text(b"0123456789abcdefXYZ"),
        Err(TextQueueError::NoRoom { needed: 3, free: 2 })
    );
    assert!(matches!(
        link.send_text(b""),
        Err(TextQueueError::Invalid(_))
    ));
    assert!(!link.has_transmit(), "nothing of a refused text was queued");
}

fn postback_frames(link: &mut Link, at: u32, pitch: i16) {
    let p = Postback {
        pitch,
        ..Postback::default()
    };
    for d in p.to_can_frames() {
        link.receive(ids::POSTBACK, &d, Instant::from_millis(at));
    }
}

#[test]
fn a_dead_man_with_a_full_queue_still_queues_the_zero_rate_frame_after_the_others() {
    let mut link: Link<2, 2> = Link::new(Config::default());
    let r = Rate::new(3.0, 0.0).unwrap();
    link.set_rate(r, Instant::from_millis(0)).unwrap();
    link.poll(Instant::from_millis(0));
    assert!(link.next_transmit().is_some()); // the first rate frame
    link.transmit_done(None);
    // Two camera commands (not pointing: the hold stays) fill the queue; nothing is sent
    // for a while (a busy bus).
    let zoom = Command::from(GimbalCommand::Zoom(crate::wire::control::Zoom::In));
    let video = Command::from(GimbalCommand::Video(crate::wire::control::Video::Start));
    link.send(zoom).unwrap();
    link.send(video).unwrap();
    for t in 1..=250 {
        link.poll(Instant::from_millis(t)); // repeats find no room (counted)
    }
    let refused = link.stats().queue_full;
    link.poll(Instant::from_millis(251)); // the dead-man fires with no room
    assert_eq!(link.next_event(), Some(Event::RateHoldExpired));
    assert_eq!(
        link.stats().queue_full,
        refused,
        "ending a hold needs no slot"
    );
    // The bus frees the queue: the frames queued before the zero-rate frame, then it, once.
    let sent: Vec<Command> = core::iter::from_fn(|| {
        let f = link.next_transmit()?;
        link.transmit_done(None);
        Some(Command::decode(&f.data).unwrap())
    })
    .collect();
    assert_eq!(
        sent,
        [zoom, video, Command::from(GimbalCommand::Rate(Rate::ZERO))]
    );
}

#[test]
fn a_waiting_zero_rate_frame_gives_way_to_a_newer_pointing_instruction() {
    let mut link: Link<1, 2> = Link::new(Config::default());
    let t0 = Instant::from_millis(0);
    link.set_rate(Rate::new(3.0, 0.0).unwrap(), t0).unwrap();
    // The control slot is taken by the rate frame; the zero-rate waits without a slot.
    link.stop_rate();
    assert_eq!(link.tx.len(), 2);
    assert!(link.next_transmit().is_some());
    link.transmit_done(None);
    // Pitch goes out instead of the zero-rate, which would undo it if it came after.
    let pitch = Command::from(GimbalCommand::Pitch(
        crate::wire::control::Pitch::new(-30.0).unwrap(),
    ));
    link.send(pitch).unwrap();
    assert_eq!(
        Command::decode(&link.next_transmit().unwrap().data),
        Ok(pitch)
    );
    link.transmit_done(None);
    assert_eq!(link.next_transmit(), None);
    // A new rate replaces it too; stopping again queues one zero-rate frame, however often.
    link.set_rate(Rate::new(1.0, 0.0).unwrap(), t0).unwrap();
    link.stop_rate();
    link.stop_rate();
    link.set_rate(Rate::new(2.0, 0.0).unwrap(), t0).unwrap_err(); // the slot is taken
    assert!(!link.is_rate_holding());
    let frames: Vec<Frame> = core::iter::from_fn(|| {
        let f = link.next_transmit()?;
        link.transmit_done(None);
        Some(f)
    })
    .collect();
    assert_eq!(frames.len(), 2);
    assert_eq!(frames[1].data, queue::zero_rate());
    // A zero-rate frame refused by the driver comes back even with the FIFO full.
    link.set_rate(Rate::new(1.0, 0.0).unwrap(), t0).unwrap();
    link.stop_rate();
    assert!(link.next_transmit().is_some());
    link.transmit_done(None);
    let zero = link.next_transmit().unwrap();
    let zoom = Command::from(GimbalCommand::Zoom(crate::wire::control::Zoom::In));
    link.send(zoom).unwrap();
    link.transmit_refused(zero);
    let frames: Vec<[u8; 8]> = core::iter::from_fn(|| {
        let f = link.next_transmit()?;
        link.transmit_done(None);
        Some(f.data)
    })
    .collect();
    assert_eq!(frames, [zoom.encode(), queue::zero_rate()]);
    assert_eq!(link.stats().queue_full, 1, "only the refused set_rate");
}

#[test]
fn link_up_down_and_latest_postback() {
    let mut link: Link = Link::new(Config::default());
    assert!(!link.is_link_up());
    postback_frames(&mut link, 1000, -100);
    assert_eq!(link.next_event(), Some(Event::LinkUp));
    assert_eq!(link.next_event(), Some(Event::Postback));
    assert_eq!(
        link.latest_postback(Instant::from_millis(1000))
            .unwrap()
            .0
            .pitch,
        -100
    );
    assert_eq!(
        link.latest_postback(Instant::from_millis(1300))
            .map(|(p, age)| (p.pitch, age)),
        Some((-100, 300))
    );
    link.poll(Instant::from_millis(2500));
    assert!(link.is_link_up(), "exactly 1.5 s is still up");
    link.poll(Instant::from_millis(2501));
    assert!(!link.is_link_up());
    assert_eq!(link.next_event(), Some(Event::LinkDown));
    postback_frames(&mut link, 3000, -200);
    assert_eq!(link.next_event(), Some(Event::LinkUp));
    assert_eq!(link.gimbal_type(), Some(GimbalType::X30));
    link.receive(ids::CONTROL, &[0; 8], Instant::from_millis(3000));
    link.receive_ignored();
    assert_eq!(link.stats().ignored_frames, 2);
    assert_eq!(link.stats().postbacks, 2);
}

#[test]
fn a_poll_a_little_behind_the_stamps_it_finds_takes_nothing_for_old() {
    // A caller that read its clock, then waited for the link while a frame was taken with
    // a later reading: the poll's `now` is behind the stamps, by much less than any of the
    // link's limits. The partial postback, the rate hold and the link stay as they are.
    let at = Instant::from_millis;
    let mut link: Link = Link::new(Config::default());
    postback_frames(&mut link, 1000, -100);
    link.poll(at(1000));
    let next = Postback {
        pitch: -200,
        ..Postback::default()
    }
    .to_can_frames();
    for d in &next[..3] {
        link.receive(ids::POSTBACK, d, at(1501));
    }
    let r = Rate::new(10.0, 0.0).unwrap();
    link.set_rate(r, at(1501)).unwrap();
    link.poll(at(1500));
    assert!(link.is_rate_holding());
    link.receive(ids::POSTBACK, &next[3], at(1502));
    assert_eq!(link.stats().postbacks, 2);
    assert_eq!(link.stats().dropped_partials, 0);
    assert_eq!(
        link.latest_postback(at(1502))
            .map(|(p, age)| (p.pitch, age)),
        Some((-200, 0))
    );
    // The postback taken at 1502, a poll at 1501: the link stays up.
    link.poll(at(1501));
    assert!(link.is_link_up());
    let mut events = Vec::new();
    while let Some(e) = link.next_event() {
        events.push(e);
    }
    // A set: no `LinkDown`, no `RateHoldExpired` among them.
    assert_eq!(events, [Event::LinkUp, Event::Postback]);
}

#[test]
fn events_wait_as_a_set_and_none_is_lost() {
    let mut link: Link = Link::new(Config::default());
    // Ten postbacks and a link-up, never taken: one of each kind waits.
    for i in 0..10 {
        postback_frames(&mut link, 1000 + i * 10, -i16::try_from(i).unwrap());
    }
    assert_eq!(link.next_event(), Some(Event::LinkUp));
    assert_eq!(link.next_event(), Some(Event::Postback));
    assert_eq!(link.next_event(), None);
    assert_eq!(link.stats().postbacks, 10);
    // The newest is the one to read.
    assert_eq!(
        link.latest_postback(Instant::from_millis(1090))
            .map(|(p, _)| p.pitch),
        Some(-9)
    );
    // Down and up again between two reads: both, in order, ending in the current state.
    link.poll(Instant::from_millis(2591));
    assert!(!link.is_link_up());
    postback_frames(&mut link, 3000, 0);
    assert_eq!(link.next_event(), Some(Event::LinkDown));
    assert_eq!(link.next_event(), Some(Event::LinkUp));
    assert_eq!(link.next_event(), Some(Event::Postback));
    assert_eq!(link.next_event(), None);
}

#[test]
fn a_handed_back_frame_that_is_not_the_links_is_counted_not_queued() {
    // Found by the `link` fuzz property: a vehicle frame handed back for a slot that holds
    // no value was marked, and `next_transmit` then answered None with a text waiting.
    let mut link: Link = Link::new(Config::default());
    link.send(GimbalCommand::Recenter).unwrap();
    link.send_text(b"HI").unwrap();
    assert_eq!(link.next_transmit().map(|f| f.id), Some(ids::CONTROL));
    link.transmit_done(Some(Frame::new(ids::GPS, [0; 8])));
    assert_eq!(link.next_transmit().map(|f| f.id), Some(ids::TEXT_END));
    link.transmit_done(Some(Frame::new(0x123, [0; 8])));
    let s = link.stats();
    assert_eq!(s.queue_full, 2);
    assert_eq!(
        s.frames_sent, 2,
        "neither frame handed back was counted as sent"
    );
    assert_eq!(s.requeued, 0);
    assert!(!link.has_transmit());
}

#[test]
fn displaced_frames_are_requeued_and_refused_frames_go_back() {
    let mut link: Link = Link::new(Config::default());
    link.send_text(b"ABCDEFGHIJ").unwrap();
    let t1 = link.next_transmit().unwrap();
    link.transmit_done(None);
    link.send(GimbalCommand::LookDown).unwrap();
    let c = link.next_transmit().unwrap();
    // The driver took the command and handed back the text frame it displaced.
    link.transmit_done(Some(t1));
    assert_eq!((link.stats().requeued, link.stats().frames_sent), (1, 1));
    assert_eq!(
        link.next_transmit(),
        Some(t1),
        "the displaced frame goes out again first"
    );
    link.transmit_refused(t1);
    assert_eq!(link.next_transmit(), Some(t1));
    assert_eq!(c.id, ids::CONTROL);
}

#[test]
fn a_refused_vehicle_frame_a_newer_value_replaced_is_counted_superseded() {
    // A GPS frame taken, a newer position queued before the driver reports, then the
    // driver refuses the frame: the newer value goes, and the refused one is counted as a
    // displaced one would be.
    let mut link: Link = Link::new(Config::default());
    link.set_gps(Gps::new(1.0, 1.0).unwrap(), Instant::from_millis(0));
    link.poll(Instant::from_millis(0));
    let old = link.next_transmit().unwrap();
    link.set_gps(Gps::new(2.0, 2.0).unwrap(), Instant::from_millis(200));
    link.poll(Instant::from_millis(200));
    let superseded = link.stats().superseded;
    link.transmit_refused(old);
    assert_eq!(link.stats().superseded, superseded + 1);
    let f = link.next_transmit().unwrap();
    assert_eq!(
        VehicleFrame::decode(f.id, &f.data).unwrap(),
        VehicleFrame::Gps(Gps::new(2.0, 2.0).unwrap())
    );
    assert_eq!(link.next_transmit(), None);
}

#[test]
fn schedules_hold_across_the_tick_wrap() {
    let mut link: Link = Link::new(Config::default());
    let start = u32::MAX - 4999;
    let mut log = Vec::new();
    let mut t = start;
    for _ in 0..10_000u32 {
        if t % 20 == 0 {
            feed_vehicle(&mut link, t);
        }
        if t.wrapping_sub(start) % 100 == 0 {
            link.set_rate(Rate::new(5.0, 0.0).unwrap(), Instant::from_millis(t))
                .unwrap();
        }
        log.extend(run(&mut link, t, t.wrapping_add(1), 1));
        t = t.wrapping_add(1);
    }
    assert_eq!(count(&log, ids::ATTITUDE), 100);
    assert_eq!(count(&log, ids::GPS), 50);
    // 10 s of hold: one frame every 50 ms, never a zero (refreshed throughout).
    let rates = rate_frames(&log);
    assert_eq!(rates.len(), 200);
    assert!(rates.iter().all(|(_, r)| !r.is_zero()));
}

mod point_at {
    use super::*;
    use crate::geo::{look_at, Position};
    use crate::wire::control::{Heading, Pitch};

    fn vehicle(link: &mut Link, at: u32, lat: f64, lon: f64, alt: f64, heading: f32) {
        let now = Instant::from_millis(at);
        link.set_gps(Gps::new(lat, lon).unwrap(), now);
        link.set_altitude(Altitude::new(alt).unwrap(), now);
        link.set_attitude(Attitude::new(0.0, 0.0, heading).unwrap(), now);
    }

    fn aims(log: &[(u32, Frame)]) -> Vec<(u32, Command)> {
        log.iter()
            .filter(|(_, f)| f.id == ids::CONTROL)
            .map(|(t, f)| (*t, Command::decode(&f.data).unwrap()))
            .filter(|(_, c)| {
                matches!(
                    c,
                    Command::Gimbal(GimbalCommand::Heading(_) | GimbalCommand::Pitch(_))
                )
            })
            .collect()
    }

    #[test]
    fn sends_heading_and_pitch_from_the_exact_look_at() {
        let mut link: Link = Link::new(Config::default());
        let target = Position::new(47.001, 8.001, 400.0).unwrap();
        vehicle(&mut link, 0, 47.0, 8.0, 500.0, 10.0);
        link.point_at(target);
        let log = run(&mut link, 0, 110, 1);
        let expected = look_at(&Position::new(47.0, 8.0, 500.0).unwrap(), &target).unwrap();
        let heading = |deg: f64| {
            Command::from(GimbalCommand::Heading(
                Heading::new(deg.rem_euclid(360.0) as f32).unwrap(),
            ))
        };
        let pitch = Command::from(GimbalCommand::Pitch(
            Pitch::new(expected.elevation_deg as f32).unwrap(),
        ));
        assert_eq!(
            aims(&log),
            [
                // Before the attitude has reached the gimbal it is nose-referenced: the
                // bearing less the vehicle's 10°, sent ahead of the attitude frame.
                (0, heading(expected.bearing_deg - 10.0)),
                (0, pitch),
                // The attitude went out at 0: the loop's next look (the point-at's period,
                // 100 ms) finds the gimbal north-referenced and sends the bearing itself.
                (100, heading(expected.bearing_deg)),
                (100, pitch),
            ],
        );
    }

    #[test]
    fn dead_band_and_10_hz() {
        let mut link: Link = Link::new(Config::default());
        link.point_at(Position::new(47.001, 8.0, 400.0).unwrap());
        // A static vehicle: one aim, nose-referenced until the attitude has reached the
        // gimbal and north-referenced after, then nothing for 2 s.
        let mut log = Vec::new();
        for t in (0..2000).step_by(10) {
            vehicle(&mut link, t, 47.0, 8.0, 500.0, 0.0);
            log.extend(run(&mut link, t, t + 10, 1));
        }
        let times: Vec<u32> = aims(&log).iter().map(|(t, _)| *t).collect();
        assert_eq!(times, [0, 0, 100, 100]);
        // A vehicle moving east at 20 m/s: the bearing changes by more than the dead-band
        // (0.2°) per 100 ms, so the aim is re-sent at 10 Hz, never faster.
        let mut log = Vec::new();
        for t in (2000..4000u32).step_by(10) {
            let east_m = f64::from(t - 2000) * 0.02;
            vehicle(&mut link, t, 47.0, 8.0 + east_m / 75_900.0, 500.0, 0.0);
            log.extend(run(&mut link, t, t + 10, 1));
        }
        let headings: Vec<u32> = aims(&log)
            .iter()
            .filter(|(_, c)| matches!(c, Command::Gimbal(GimbalCommand::Heading(_))))
            .map(|(t, _)| *t)
            .collect();
        assert!((18..=20).contains(&headings.len()), "{headings:?}");
        assert!(headings.windows(2).all(|w| w[1] - w[0] >= 100));
    }

    #[test]
    fn nose_referenced_when_attitude_is_not_pushed() {
        let mut link: Link = Link::new(Config {
            attitude_period_ms: 0,
            ..Config::default()
        });
        let target = Position::new(47.0, 8.001, 500.0).unwrap(); // due east, same height
        vehicle(&mut link, 0, 47.0, 8.0, 500.0, 30.0);
        link.point_at(target);
        let log = run(&mut link, 0, 1, 1);
        assert_eq!(
            count(&log, ids::ATTITUDE),
            0,
            "the attitude push is disabled"
        );
        let Command::Gimbal(GimbalCommand::Heading(h)) = aims(&log)[0].1 else {
            panic!()
        };
        // Bearing ~90°, vehicle heading 30°: 60° right of the nose.
        assert!((h.degrees() - 60.0).abs() < 0.1, "{}", h.degrees());
    }

    #[test]
    fn unreachable_target_raises_an_event_once_and_holds_the_aim() {
        let mut link: Link = Link::new(Config::default());
        vehicle(&mut link, 0, 47.0, 8.0, 500.0, 0.0);
        link.point_at(Position::new(47.001, 8.0, 400.0).unwrap());
        assert_eq!(aims(&run(&mut link, 0, 1, 1)).len(), 2);
        // The vehicle climbs far below a target... no: the target is now far above it.
        link.point_at(Position::new(47.0001, 8.0, 2000.0).unwrap());
        let mut log = Vec::new();
        for t in (100..1100).step_by(100) {
            vehicle(&mut link, t, 47.0, 8.0, 500.0, 0.0);
            log.extend(run(&mut link, t, t + 100, 1));
        }
        assert!(aims(&log).is_empty(), "nothing is clamped and sent");
        let events: Vec<Event> = core::iter::from_fn(|| link.next_event()).collect();
        assert_eq!(events.len(), 1, "{events:?}");
        let Event::TargetUnreachable { elevation_cdeg } = events[0] else {
            panic!()
        };
        assert!(elevation_cdeg > 8000, "{elevation_cdeg}");
    }

    #[test]
    fn cancelled_by_pointing_commands_and_rate_holds_and_waits_for_position() {
        let mut link: Link = Link::new(Config::default());
        link.point_at(Position::new(47.001, 8.0, 400.0).unwrap());
        assert!(
            aims(&run(&mut link, 0, 500, 1)).is_empty(),
            "no GPS yet: nothing sent"
        );
        vehicle(&mut link, 500, 47.0, 8.0, 500.0, 0.0);
        assert_eq!(aims(&run(&mut link, 500, 501, 1)).len(), 2);
        link.send(GimbalCommand::LookDown).unwrap();
        assert_eq!(link.pointing_target(), None);
        link.point_at(Position::new(47.001, 8.0, 400.0).unwrap());
        link.set_rate(Rate::new(1.0, 0.0).unwrap(), Instant::from_millis(600))
            .unwrap();
        assert_eq!(link.pointing_target(), None);
        link.point_at(Position::new(47.001, 8.0, 400.0).unwrap());
        link.send(GimbalCommand::Zoom(crate::wire::control::Zoom::In))
            .unwrap();
        assert!(
            link.pointing_target().is_some(),
            "a camera command does not cancel it"
        );
    }
}

mod fast_path {
    use super::super::test_ops::{apply, Op};
    use super::*;
    use proptest::prelude::*;

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            8 => (0u32..400).prop_map(Op::Wait),
            2 => (-500i16..500).prop_map(Op::Rate),
            1 => Just(Op::StopRate),
            1 => Just(Op::Pitch),
            3 => (0u32..1500).prop_map(|stamp_back| Op::Vehicle { stamp_back }),
            2 => Just(Op::Postback),
            1 => (0u8..4).prop_map(Op::PostbackFrame),
            1 => (0u32..3000).prop_map(Op::LatePostback),
            1 => Just(Op::PointAt),
            1 => Just(Op::Text),
            2 => (any::<bool>(), 0u16..=3600, -1000i16..=600)
                .prop_map(|(earth, yaw, pitch)| Op::Aim { earth, yaw, pitch }),
            1 => Just(Op::StopAim),
            3 => (-17_000i16..=17_000, -11_000i16..=6_000, 0u8..5, any::<bool>()).prop_map(
                |(motor, pitch, mode, tracking)| Op::PostbackOf { motor, pitch, mode, tracking }
            ),
            1 => any::<bool>().prop_map(Op::Tracking),
        ]
    }

    fn drain<const Q: usize, const T: usize>(link: &mut Link<Q, T>) -> (Vec<Frame>, Vec<Event>) {
        let frames = core::iter::from_fn(|| {
            let f = link.next_transmit();
            if f.is_some() {
                link.transmit_done(None);
            }
            f
        })
        .collect();
        (frames, core::iter::from_fn(|| link.next_event()).collect())
    }

    fn check<const Q: usize, const T: usize>(
        ops: &[Op],
        start: u32,
        drain_every: u32,
    ) -> Result<(), TestCaseError> {
        let mut fast: Link<Q, T> = Link::new(Config::default());
        let mut full: Link<Q, T> = Link::new(Config::default());
        let mut t = start;
        for op in ops {
            let steps = if let Op::Wait(ms) = *op { ms } else { 1 };
            apply(&mut fast, op, Instant::from_millis(t));
            apply(&mut full, op, Instant::from_millis(t));
            for _ in 0..steps {
                let now = Instant::from_millis(t);
                fast.poll(now);
                full.poll_all(now);
                // A slow bus: the queue drains only now and then, so it fills and the
                // retry paths (a zero-rate frame waiting for room, an aim deferred) run.
                if t.wrapping_sub(start).is_multiple_of(drain_every) {
                    prop_assert_eq!(drain(&mut fast), drain(&mut full), "at {}", t);
                    prop_assert_eq!(fast.stats(), full.stats(), "at {}", t);
                    prop_assert_eq!(fast.is_link_up(), full.is_link_up(), "at {}", t);
                }
                t = t.wrapping_add(1);
            }
        }
        prop_assert_eq!(drain(&mut fast), drain(&mut full));
        prop_assert_eq!(fast.stats(), full.stats());
        Ok(())
    }

    proptest! {
        /// With tiny queues drained every 7 ms, the same holds when the queue is full.
        #[test]
        fn fast_path_equals_full_polls_with_full_queues(ops in proptest::collection::vec(op(), 1..60), start: u32) {
            check::<2, 2>(&ops, start, 7)?;
        }

        /// Polling every millisecond through the idle fast path does exactly what full
        /// polls do.
        #[test]
        fn fast_path_equals_full_polls(ops in proptest::collection::vec(op(), 1..60), start: u32) {
            check::<8, 8>(&ops, start, 1)?;
        }
    }
}

#[test]
fn a_refused_first_attitude_leaves_the_gimbal_nose_referenced_and_a_later_one_does_not() {
    let mut link: Link = Link::new(Config::default());
    let at = Instant::from_millis;
    let attitude = |link: &mut Link| {
        let f = link.next_transmit().unwrap();
        assert_eq!(f.id, ids::ATTITUDE);
        f
    };
    link.set_attitude(Attitude::new(0.0, 0.0, 30.0).unwrap(), at(0));
    link.poll(at(0));
    let f = attitude(&mut link);
    link.transmit_refused(f);
    assert!(
        !link.north_referenced(at(0)),
        "the gimbal has no attitude yet"
    );
    attitude(&mut link);
    link.transmit_done(None);
    assert!(link.north_referenced(at(0)));
    // The next push refused: the gimbal still has the one before.
    link.set_attitude(Attitude::new(0.0, 0.0, 31.0).unwrap(), at(100));
    link.poll(at(100));
    let f = attitude(&mut link);
    link.transmit_refused(f);
    assert!(link.north_referenced(at(100)));
}

/// A command sent between taking a frame and reporting it refused takes the slot the
/// frame left: the refused frame finds its class full, and is lost and counted, as
/// `Link::transmit_refused` says.
#[test]
fn a_frame_refused_after_a_send_into_its_slot_is_lost_and_counted() {
    use crate::wire::control::{Command, GimbalCommand, Pitch};

    let pitch = |deg| GimbalCommand::Pitch(Pitch::new(deg).unwrap());
    let mut link: Link<1, 0> = Link::new(Config::default());
    link.send(pitch(-10.0)).unwrap();
    let f = link.next_transmit().unwrap();
    link.send(pitch(-20.0)).unwrap();
    link.transmit_refused(f);
    assert_eq!(link.stats().queue_full, 1);
    let next = link.next_transmit().unwrap();
    assert_eq!(next.data, Command::from(pitch(-20.0)).encode());
    assert_eq!(link.next_transmit(), None);
}
