//! `next_deadline` of the drivers, whose `poll` also transmits: the link's deadline, or
//! `now` while the CAN driver or the serial port had no room for what waits.
#![cfg(feature = "mock")]

use idu_gimbal::mock::serial::{Pipe, SerialFaults};
use idu_gimbal::mock::Bus;
use idu_gimbal::port::Io;
use idu_gimbal::wire::control::{GimbalCommand, Pitch, Rate};
use idu_gimbal::wire::vehicle::Gps;
use idu_gimbal::{CanPort, Link, Port, SerialLink, SerialPort};
use idu_gimbal::{Config, Instant};

fn at(ms: u32) -> Instant {
    Instant::from_millis(ms)
}

#[test]
fn gimbal_is_due_at_once_while_the_mailboxes_are_full() {
    let bus: Bus<2, 16> = Bus::new(3);
    bus.set_auto_deliver(false);
    assert!(bus.set_mailboxes(0, 1));
    let mut gimbal: Link = Link::new(Config::default());
    let mut port = CanPort::new(bus.endpoint(0).unwrap());
    let _peer = bus.endpoint(1).unwrap();
    let t0 = u32::MAX - 20;
    assert_eq!(port.next_deadline(&gimbal, at(t0)), at(t0));
    port.poll(&mut gimbal, at(t0)).unwrap();
    assert_eq!(
        port.next_deadline(&gimbal, at(t0)),
        at(t0.wrapping_add(60_000))
    );

    gimbal.set_gps(Gps::new(47.0, 8.0).unwrap(), at(t0));
    gimbal
        .send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()))
        .unwrap();
    port.poll(&mut gimbal, at(t0)).unwrap();
    // One mailbox, not delivered: the pitch command went, the GPS frame waits.
    assert_eq!(gimbal.stats().frames_sent, 1);
    assert_eq!(port.next_deadline(&gimbal, at(t0)), at(t0));
    assert_eq!(port.next_deadline(&gimbal, at(t0 + 5)), at(t0 + 5));
    // The link itself schedules nothing before the next GPS push.
    assert_eq!(gimbal.next_deadline(at(t0 + 5)), at(t0.wrapping_add(200)));
    assert_eq!(bus.deliver(), 1);
    port.poll(&mut gimbal, at(t0 + 6)).unwrap();
    assert_eq!(gimbal.stats().frames_sent, 2);
    assert_eq!(
        port.next_deadline(&gimbal, at(t0 + 6)),
        at(t0.wrapping_add(200))
    );
}

#[test]
fn serial_gimbal_is_due_at_once_while_bytes_wait() {
    let pipe: Pipe<64> = Pipe::new(5);
    let (rx, tx) = pipe.port(0).unwrap();
    let _peer = pipe.port(1).unwrap();
    let mut gimbal: SerialLink = SerialLink::new(Config::default());
    let mut port = SerialPort::new(Io::new(rx, tx));
    let t0 = 1_000;
    port.poll(&mut gimbal, at(t0)).unwrap();
    assert_eq!(port.next_deadline(&gimbal, at(t0)), at(t0 + 60_000));

    gimbal
        .set_rate(Rate::from_centi(500, 0).unwrap(), at(t0))
        .unwrap();
    assert_eq!(port.next_deadline(&gimbal, at(t0)), at(t0));
    port.poll(&mut gimbal, at(t0)).unwrap();
    // The rate command was written whole: the next repeat at +50, the dead-man at +251.
    assert_eq!(port.next_deadline(&gimbal, at(t0)), at(t0 + 50));
    assert_eq!(gimbal.next_deadline(at(t0)), at(t0 + 50));
    // The port stalls: the repeat waits.
    pipe.set_faults(SerialFaults {
        write_stall: 1.0,
        ..SerialFaults::NONE
    });
    port.poll(&mut gimbal, at(t0 + 50)).unwrap();
    assert!(gimbal.has_transmit());
    assert_eq!(port.next_deadline(&gimbal, at(t0 + 50)), at(t0 + 50));
    assert_eq!(port.next_deadline(&gimbal, at(t0 + 51)), at(t0 + 51));
    assert_eq!(gimbal.next_deadline(at(t0 + 51)), at(t0 + 100));
    pipe.set_faults(SerialFaults::NONE);
    port.poll(&mut gimbal, at(t0 + 52)).unwrap();
    assert_eq!(pipe.stats(0).unwrap().written, 48);
    assert_eq!(port.next_deadline(&gimbal, at(t0 + 52)), at(t0 + 100));
}
