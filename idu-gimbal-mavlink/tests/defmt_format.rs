//! The `defmt` encoding of what a firmware logs of the bridge, captured by a host logger:
//! counters that differ in one field, and errors of different kinds, must come out distinct.
#![cfg(feature = "defmt")]

use std::sync::Mutex;

use idu_gimbal_mavlink::framing::DecodeError;
use idu_gimbal_mavlink::BridgeStats;

static LOG: Mutex<Vec<u8>> = Mutex::new(Vec::new());

#[defmt::global_logger]
struct Capture;

// SAFETY: one test in this binary logs, and the buffer is behind a mutex anyway.
unsafe impl defmt::Logger for Capture {
    fn acquire() {}
    unsafe fn flush() {}
    unsafe fn release() {}
    unsafe fn write(bytes: &[u8]) {
        LOG.lock().unwrap().extend_from_slice(bytes);
    }
}

// A constant timestamp, so that two records differ only by what they format.
defmt::timestamp!("{=u8}", 0);

fn record(value: &impl defmt::Format) -> Vec<u8> {
    LOG.lock().unwrap().clear();
    defmt::println!("{}", value);
    LOG.lock().unwrap().clone()
}

#[test]
fn counters_and_errors_encode_what_tells_them_apart() {
    let zero = BridgeStats::default();
    let acks = BridgeStats {
        acks: 1,
        ..BridgeStats::default()
    };
    let full = BridgeStats {
        outbox_full: 1,
        ..BridgeStats::default()
    };
    let stats = [record(&zero), record(&acks), record(&full)];
    assert_eq!(record(&zero), stats[0], "the same value, the same record");
    assert!(stats.iter().all(|r| !r.is_empty()));
    assert_ne!(stats[0], stats[1]);
    assert_ne!(
        stats[1], stats[2],
        "one field's count is told from another's"
    );
    let errors = [
        record(&DecodeError::OtherMessage(0)),
        record(&DecodeError::OtherMessage(1)),
        record(&DecodeError::Checksum),
        record(&DecodeError::Payload),
    ];
    for (i, a) in errors.iter().enumerate() {
        for b in errors.iter().skip(i + 1) {
            assert_ne!(a, b);
        }
    }
}
