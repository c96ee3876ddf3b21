//! Each CAN driver error kind is reported and counted in its own bucket.
#![cfg(feature = "mock")]

use embedded_can::ErrorKind;
use idu_gimbal::link::Config;
use idu_gimbal::mock::Bus;
use idu_gimbal::port::DriverErrors;
use idu_gimbal::Instant;
use idu_gimbal::{CanPort, Link, Port};

#[test]
fn every_error_kind_is_counted_in_its_own_field() {
    let one = |kind| {
        let mut e = DriverErrors::default();
        match kind {
            ErrorKind::Overrun => e.overrun = 1,
            ErrorKind::Bit => e.bit = 1,
            ErrorKind::Stuff => e.stuff = 1,
            ErrorKind::Crc => e.crc = 1,
            ErrorKind::Form => e.form = 1,
            ErrorKind::Acknowledge => e.acknowledge = 1,
            _ => e.other = 1,
        }
        e
    };
    for kind in [
        ErrorKind::Overrun,
        ErrorKind::Bit,
        ErrorKind::Stuff,
        ErrorKind::Crc,
        ErrorKind::Form,
        ErrorKind::Acknowledge,
        ErrorKind::Other,
    ] {
        let bus: Bus<2, 16> = Bus::new(1);
        let mut gimbal: Link = Link::new(Config::default());
        let mut port = CanPort::new(bus.endpoint(0).unwrap());
        // The next receive of the driver's endpoint fails with exactly this kind.
        assert!(bus.inject_error(0, kind));
        assert_eq!(
            port.poll(&mut gimbal, Instant::from_millis(0))
                .unwrap_err()
                .0,
            kind
        );
        let errors = port.stats().driver_errors;
        assert_eq!(errors, one(kind), "{kind:?}");
        assert_eq!(errors.total(), 1);
    }
}
