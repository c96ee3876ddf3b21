//! The `defmt` encoding of what a log must get right, captured by a host logger: every
//! driver error kind distinct (or an operator cannot tell an acknowledge error, no other
//! node on the bus, from a CRC error, noise), a range error's value, and the camera's
//! credentials without their password.
#![cfg(feature = "defmt")]

use embedded_can::ErrorKind;
use idu_gimbal::port::DriverError;

#[path = "common/defmt_capture.rs"]
mod defmt_capture;

use defmt_capture::record;

fn encode(kind: ErrorKind) -> Vec<u8> {
    record(&DriverError(kind))
}

#[test]
fn every_error_kind_has_its_own_encoding() {
    let kinds = [
        ErrorKind::Overrun,
        ErrorKind::Bit,
        ErrorKind::Stuff,
        ErrorKind::Crc,
        ErrorKind::Form,
        ErrorKind::Acknowledge,
        ErrorKind::Other,
    ];
    let encoded: Vec<Vec<u8>> = kinds.iter().map(|&k| encode(k)).collect();
    // The same kind twice encodes the same: the records differ by kind, not by chance.
    assert_eq!(encode(ErrorKind::Bit), encoded[1]);
    for (i, a) in encoded.iter().enumerate() {
        assert!(!a.is_empty());
        for (j, b) in encoded.iter().enumerate().skip(i + 1) {
            assert_ne!(a, b, "{:?} and {:?} encode alike", kinds[i], kinds[j]);
        }
    }
}

/// A range error's defmt record carries its value: two out-of-range pitches encode
/// differently, and both differ from an empty record.
#[test]
fn a_range_error_encodes_its_value() {
    use idu_gimbal::wire::control::Pitch;
    let pitch = |degrees: f32| record(&Pitch::new(degrees).unwrap_err());
    let empty = record(&"");
    let (a, b) = (pitch(200.0), pitch(300.0));
    assert_ne!(a, b);
    for r in [&a, &b] {
        assert!(
            r.len() > empty.len() + 3 * 8,
            "a name and three f64s: {r:?}"
        );
    }
}

/// Camera credentials log their user and never their password: the record holds the
/// user's bytes and not the password's, and two passwords log alike.
#[test]
fn credentials_log_the_user_and_never_the_password() {
    use idu_gimbal::video::Credentials;
    let contains =
        |haystack: &[u8], needle: &[u8]| haystack.windows(needle.len()).any(|w| w == needle);
    let a = record(&Credentials::new("operator", "hunter2-secret"));
    assert!(contains(&a, b"operator"), "{a:?}");
    assert!(
        !contains(&a, b"hunter2"),
        "the password is in the record: {a:?}"
    );
    assert_eq!(a, record(&Credentials::new("operator", "another-one")));
    assert_ne!(a, record(&Credentials::new("viewer", "hunter2-secret")));
}
