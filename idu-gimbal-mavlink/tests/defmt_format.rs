//! The `defmt` encoding of what a firmware logs of the bridge, captured by a host logger:
//! counters that differ in one field, and errors of different kinds, must come out distinct.
#![cfg(feature = "defmt")]

use idu_gimbal_mavlink::framing::DecodeError;
use idu_gimbal_mavlink::BridgeStats;

#[path = "../../tests/common/defmt_capture.rs"]
mod defmt_capture;

use defmt_capture::record;

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
