//! What the public API promises beyond the wire protocol, by behaviour: the texts of its
//! errors, the state the link and the driver report, what reception does with frames that
//! are not a postback's, and pointing at a location. Each asserts behaviour against
//! expectations stated independently of the code (TESTING.md says which mutants of
//! `scripts/mutants.sh` each holds).
#![cfg(feature = "mock")]

use embedded_can::{nb::Can, ErrorKind, ExtendedId, Frame as _};
use idu_gimbal::link::{AimError, Config, Link, QueueFull, TextQueueError};
use idu_gimbal::mock::{Bus, MockFrame};
use idu_gimbal::port::{DriverError, PortError};
use idu_gimbal::wire::control::{Command, GimbalCommand, Pitch, Rate};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::{GimbalType, Postback};
use idu_gimbal::wire::text::TextError;
use idu_gimbal::wire::vehicle::{Attitude, VehicleError};
use idu_gimbal::Instant;
use idu_gimbal::{CanPort, Port};

fn t(ms: u32) -> Instant {
    Instant::from_millis(ms)
}

fn a2000() -> Postback {
    Postback {
        gimbal_type: GimbalType::A2000,
        pitch: -450,
        ..Postback::default()
    }
}

/// The texts of the errors: what was wrong and what range is valid.
mod errors {
    use super::*;

    #[test]
    fn errors_say_what_was_wrong() {
        let full = QueueFull(Command::from(GimbalCommand::Pitch(
            Pitch::new(-45.0).unwrap(),
        )));
        assert_eq!(full.to_string(), "transmit queue is full");
        let no_room = TextQueueError::NoRoom { needed: 3, free: 1 };
        assert_eq!(
            no_room.to_string(),
            "text needs 3 frames, the queue has 1 free"
        );
        let e = DriverError(ErrorKind::Overrun);
        assert_eq!(
            e.to_string(),
            format!("CAN driver error: {}", ErrorKind::Overrun)
        );
        assert_eq!(
            AimError::NoVehicleHeading.to_string(),
            "an earth-frame yaw needs the vehicle's heading, and none is fresh \
             (set the vehicle attitude first)"
        );
        let read: PortError<&str, u8> = PortError::Read("overrun");
        assert_eq!(read.to_string(), "serial read error: \"overrun\"");
        let write: PortError<&str, u8> = PortError::Write(7);
        assert_eq!(write.to_string(), "serial write error: 7");
    }

    #[test]
    fn text_and_vehicle_errors_say_what_was_wrong() {
        let cases = [
            (
                TextError::Empty,
                "text is empty: it needs at least one byte",
            ),
            (
                TextError::InvalidByte {
                    index: 4,
                    byte: 0x80,
                },
                "byte 0x80 at index 4 is not ASCII 0x01..=0x7F",
            ),
            (
                TextError::Overflow { capacity: 64 },
                "text longer than 64 bytes",
            ),
            (
                TextError::WrongLength { len: 5 },
                "text frame has 5 bytes, expected 8",
            ),
            (
                TextError::NotText { id: 0x0000_0F01 },
                "CAN ID 0x00000F01 is not a text ID (0x02008201, 0x02008202)",
            ),
        ];
        for (e, text) in cases {
            assert_eq!(e.to_string(), text);
        }
        assert_eq!(
            VehicleError::NotVehicle { id: 0x0000_0F01 }.to_string(),
            "CAN ID 0x00000F01 is not a vehicle frame (0x0000FF13, 0x0000FF15, 0x0000FF16)"
        );
        assert_eq!(
            VehicleError::WrongLength { len: 7 }.to_string(),
            "vehicle frame has 7 bytes, expected 8"
        );
        assert_eq!(
            VehicleError::NonZeroPadding { id: 0x0000_FF16 }.to_string(),
            "unused bytes of frame 0x0000FF16 are not zero"
        );
        // A value out of range says what the range error says: the field, the value, the range.
        let range = Attitude::new(91.0, 0.0, 0.0).unwrap_err();
        let text = VehicleError::Value(range).to_string();
        assert_eq!(text, range.to_string());
        assert!(text.contains("pitch") && text.contains("91"), "{text}");
    }
}

/// The state the link and the driver report.
mod state {
    use super::*;

    #[test]
    fn the_gimbal_type_is_the_latest_postbacks() {
        let mut link: Link = Link::new(Config::default());
        assert_eq!(link.gimbal_type(), None, "no postback yet");
        for d in a2000().to_can_frames() {
            link.receive(ids::POSTBACK, &d, t(10));
        }
        assert_eq!(link.gimbal_type(), Some(GimbalType::A2000));
    }

    #[test]
    fn quiet_right_after_a_poll_with_nothing_to_do_and_not_long_after() {
        let mut link: Link = Link::new(Config::default());
        link.poll(t(1000));
        link.poll(t(1001));
        assert!(link.is_quiet(t(1002)), "nothing received, queued or due");
        assert!(
            !link.is_quiet(t(1000 + 3_600_000)),
            "an hour later something is due"
        );
    }

    /// The command surface and the state queries, through the driver, reach its link.
    #[test]
    fn the_command_surface_reaches_the_drivers_link() {
        let bus: Bus<2, 64> = Bus::new(4);
        let mut gimbal: Link = Link::new(Config::default());
        let mut port = CanPort::new(bus.endpoint(0).unwrap());
        let mut other = bus.endpoint(1).unwrap();
        assert!(!gimbal.is_link_up());
        assert_eq!(gimbal.gimbal_type(), None);
        for d in a2000().to_can_frames() {
            let f = MockFrame::extended(ids::POSTBACK, &d).unwrap();
            Can::transmit(&mut other, &f).unwrap();
        }
        port.poll(&mut gimbal, t(0)).unwrap();
        assert!(gimbal.is_link_up());
        assert_eq!(gimbal.gimbal_type(), Some(GimbalType::A2000));

        // A rate hold, then stop_rate: exactly one zero-rate frame ends it.
        let drain = |other: &mut idu_gimbal::mock::Endpoint<'_, 2, 64>| {
            let mut frames = Vec::new();
            while let Ok(f) = Can::receive(other) {
                frames.push(f.data().to_vec());
            }
            frames
        };
        gimbal
            .set_rate(Rate::new(10.0, 0.0).unwrap(), t(10))
            .unwrap();
        port.poll(&mut gimbal, t(10)).unwrap();
        let _ = drain(&mut other);
        gimbal.stop_rate();
        port.poll(&mut gimbal, t(11)).unwrap();
        let zero = Command::from(GimbalCommand::Rate(Rate::new(0.0, 0.0).unwrap())).encode();
        let sent = drain(&mut other);
        assert_eq!(
            sent.iter().filter(|d| d[..] == zero[..]).count(),
            1,
            "{sent:?}"
        );
        // No more repeats of the hold afterwards.
        port.poll(&mut gimbal, t(200)).unwrap();
        assert!(drain(&mut other).iter().all(|d| d[..]
            != Command::from(GimbalCommand::Rate(Rate::new(10.0, 0.0).unwrap())).encode()[..]));
    }
}

/// The port's CAN driver, reached through the port: what is done there passes the link by.
#[test]
fn the_can_driver_is_reachable_through_the_port_and_passes_the_link_by() {
    let bus: Bus<2, 16> = Bus::new(7);
    let mut gimbal: Link = Link::new(Config::default());
    let mut port = CanPort::new(bus.endpoint(0).unwrap());
    let mut other = bus.endpoint(1).unwrap();
    // Sent through the driver: on the bus, in no count of the link's.
    let mine = MockFrame::extended(0x123, &[1, 2, 3]).unwrap();
    assert_eq!(Can::transmit(port.can_mut(), &mine), Ok(None));
    assert_eq!(Can::receive(&mut other), Ok(mine));
    // A postback frame taken through the driver never reaches the link.
    let first = a2000().to_can_frames()[0];
    let frame = MockFrame::extended(ids::POSTBACK, &first).unwrap();
    Can::transmit(&mut other, &frame).unwrap();
    assert_eq!(Can::receive(port.can_mut()), Ok(frame));
    port.poll(&mut gimbal, t(0)).unwrap();
    let s = gimbal.stats();
    assert_eq!((s.frames_sent, s.frames_received), (0, 0));
    assert_eq!(port.stats().driver_errors.total(), 0);
}

/// What reception does with frames that are not a postback's: remote, short, broken.
mod reception {
    use super::*;

    /// A remote frame on the postback ID carries no data: the driver counts it as ignored and
    /// never hands it to the postback assembler.
    #[test]
    fn a_remote_frame_on_the_postback_id_is_ignored() {
        let bus: Bus<2, 16> = Bus::new(3);
        let mut gimbal: Link = Link::new(Config::default());
        let mut port = CanPort::new(bus.endpoint(0).unwrap());
        let mut other = bus.endpoint(1).unwrap();
        let id = ExtendedId::new(ids::POSTBACK).unwrap();
        let remote = MockFrame::new_remote(id, 8).unwrap();
        Can::transmit(&mut other, &remote).unwrap();
        port.poll(&mut gimbal, t(0)).unwrap();
        let s = gimbal.stats();
        assert_eq!(s.ignored_frames, 1);
        assert_eq!(s.frames_received, 1);
        assert!(!gimbal.is_link_up(), "no postback, no link");
        assert_eq!(gimbal.gimbal_type(), None);
    }

    /// A frame on the postback ID that is not 8 bytes long, between the frames of a postback,
    /// through the driver: counted as malformed, and it breaks the message (the two frames
    /// before it and itself discarded, the two after it too short to be a message).
    #[test]
    fn a_short_frame_on_the_postback_id_breaks_the_message_and_is_counted() {
        let bus: Bus<2, 16> = Bus::new(5);
        let mut gimbal: Link = Link::new(Config::default());
        let mut port = CanPort::new(bus.endpoint(0).unwrap());
        let mut other = bus.endpoint(1).unwrap();
        let frames = a2000().to_can_frames();
        for (i, d) in frames.iter().enumerate() {
            if i == 2 {
                let short = MockFrame::extended(ids::POSTBACK, &d[..5]).unwrap();
                Can::transmit(&mut other, &short).unwrap();
            }
            Can::transmit(&mut other, &MockFrame::extended(ids::POSTBACK, d).unwrap()).unwrap();
        }
        port.poll(&mut gimbal, t(0)).unwrap();
        let s = gimbal.stats();
        assert_eq!(s.frames_received, 5);
        assert_eq!((s.malformed, s.dropped_partials, s.postbacks), (1, 1, 0));
        assert!(!gimbal.is_link_up(), "no whole postback, no link");
        // The next whole postback is taken.
        for d in frames {
            Can::transmit(&mut other, &MockFrame::extended(ids::POSTBACK, &d).unwrap()).unwrap();
        }
        port.poll(&mut gimbal, t(100)).unwrap();
        assert_eq!(gimbal.stats().postbacks, 1);
        assert!(gimbal.is_link_up());
    }

    /// The postback assembler's gap bound, its expiry time (the last frame + the bound + 1 ms)
    /// and its frame accounting when a malformed frame breaks a partial message.
    #[test]
    fn the_assembler_reports_its_bound_expiry_and_discards() {
        use idu_gimbal::link::postback::PostbackAssembler;
        let mut a = PostbackAssembler::with_max_gap(250);
        assert_eq!(a.max_gap_ms(), 250);
        assert_eq!(a.expiry(), None);
        let frames = Postback::default().to_can_frames();
        assert!(a.feed(ids::POSTBACK, &frames[0], t(1000)).is_none());
        assert!(a.feed(ids::POSTBACK, &frames[1], t(1010)).is_none());
        assert_eq!(a.expiry(), Some(t(1010 + 250 + 1)));
        // A 5-byte frame on the postback ID: the two held and itself are discarded.
        assert!(a.feed(ids::POSTBACK, &frames[2][..5], t(1020)).is_none());
        let s = a.stats();
        assert_eq!(
            (s.malformed, s.dropped_partials, s.discarded_frames),
            (1, 1, 3)
        );
        assert_eq!(a.expiry(), None);
    }
}

/// Pointing at a location: the aim goes out whole, and stops when asked.
mod pointing {
    use super::*;

    fn is_aim(data: &[u8]) -> bool {
        matches!(
            Command::decode(data),
            Ok(Command::Gimbal(
                GimbalCommand::Heading(_) | GimbalCommand::Pitch(_)
            ))
        )
    }

    /// A point-at needs heading and pitch together: with exactly two control slots free both
    /// go; with one, neither (and the queue-full counter says so).
    #[test]
    fn aim_goes_out_when_exactly_two_slots_are_free() {
        use idu_gimbal::geo::Position;
        use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
        for free in [1usize, 2] {
            let mut link: Link = Link::new(Config::default());
            let now = t(0);
            link.set_gps(Gps::new(47.0, 8.0).unwrap(), now);
            link.set_altitude(Altitude::new(600.0).unwrap(), now);
            link.set_attitude(Attitude::new(0.0, 0.0, 0.0).unwrap(), now);
            // Drain what the vehicle data queued, then fill the control FIFO to `free` slots.
            link.poll(now);
            while link.next_transmit().is_some() {
                link.transmit_done(None);
            }
            let mut queued = 0;
            while link
                .send(Command::from(GimbalCommand::Pitch(
                    Pitch::new(-10.0).unwrap(),
                )))
                .is_ok()
            {
                queued += 1;
            }
            for _ in 0..free {
                assert!(link.next_transmit().is_some());
                link.transmit_done(None);
            }
            let full_before = link.stats().queue_full;
            link.point_at(Position::new(47.001, 8.0, 400.0).unwrap());
            link.poll(t(1));
            let mut aims = 0;
            while let Some(f) = link.next_transmit() {
                if f.data
                    != Command::from(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap())).encode()
                {
                    aims += 1;
                }
                link.transmit_done(None);
            }
            assert!(queued >= 2);
            if free == 2 {
                assert_eq!(aims, 2, "heading and pitch both queued");
            } else {
                assert_eq!(aims, 0, "neither of the two queued");
                assert!(link.stats().queue_full > full_before);
            }
        }
    }

    /// After `stop_pointing`, a moving vehicle no longer re-aims the gimbal; before it, it does.
    #[test]
    fn stop_pointing_ends_the_point_at() {
        use idu_gimbal::geo::Position;
        use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
        for stop in [false, true] {
            let bus: Bus<2, 256> = Bus::new(5);
            let mut gimbal: Link = Link::new(Config::default());
            let mut port = CanPort::new(bus.endpoint(0).unwrap());
            let mut other = bus.endpoint(1).unwrap();
            let mut aims = Vec::new();
            type Ep<'a> = idu_gimbal::mock::Endpoint<'a, 2, 256>;
            let fly = |gimbal: &mut Link,
                       port: &mut CanPort<Ep<'_>>,
                       other: &mut Ep<'_>,
                       aims: &mut Vec<u32>,
                       from: u32,
                       to: u32| {
                for ms in (from..to).step_by(100) {
                    let now = t(ms);
                    // Moving north 10 m a step: the bearing to the target keeps changing.
                    let lat = 47.0 + f64::from(ms) * 1e-6;
                    gimbal.set_gps(Gps::new(lat, 8.0).unwrap(), now);
                    gimbal.set_altitude(Altitude::new(600.0).unwrap(), now);
                    gimbal.set_attitude(Attitude::new(0.0, 0.0, 0.0).unwrap(), now);
                    port.poll(gimbal, now).unwrap();
                    while let Ok(f) = Can::receive(other) {
                        if is_aim(f.data()) {
                            aims.push(ms);
                        }
                    }
                }
            };
            gimbal.point_at(Position::new(47.0, 8.001, 400.0).unwrap());
            fly(&mut gimbal, &mut port, &mut other, &mut aims, 0, 1000);
            assert!(aims.iter().any(|&ms| ms < 1000), "point-at aims at first");
            if stop {
                gimbal.stop_pointing();
            }
            fly(&mut gimbal, &mut port, &mut other, &mut aims, 1000, 5000);
            // From the first poll after the stop: none when stopped.
            let later = aims.iter().filter(|&&ms| ms >= 1000).count();
            if stop {
                assert_eq!(later, 0, "no aim after stop_pointing: {aims:?}");
            } else {
                assert!(later > 0, "a moving vehicle re-aims: {aims:?}");
            }
        }
    }
}
