//! The `defmt` encoding of what a log must get right, captured by a host logger: every
//! driver error kind distinct (or an operator cannot tell an acknowledge error, no other
//! node on the bus, from a CRC error, noise), the mock bus's errors by name, a range
//! error's value, and the camera's credentials without their password.
#![cfg(feature = "defmt")]

use embedded_can::ErrorKind;
use idu_gimbal::port::DriverError;

#[path = "common/defmt_capture.rs"]
mod defmt_capture;

use defmt_capture::record;

/// Whether `needle` is in `haystack`.
fn contains(haystack: &[u8], needle: &[u8]) -> bool {
    haystack.windows(needle.len()).any(|w| w == needle)
}

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

/// The mock bus's error names its kind in its record (a test's log says which fault was
/// injected): each kind's name, and `Other` for the rest.
#[test]
fn a_mock_error_names_its_kind() {
    use idu_gimbal::mock::MockError;
    for (kind, name) in [
        (ErrorKind::Overrun, "Overrun"),
        (ErrorKind::Bit, "Bit"),
        (ErrorKind::Stuff, "Stuff"),
        (ErrorKind::Crc, "Crc"),
        (ErrorKind::Form, "Form"),
        (ErrorKind::Acknowledge, "Acknowledge"),
        (ErrorKind::Other, "Other"),
    ] {
        let r = record(&MockError::new(kind));
        // The name as a length-prefixed `str` argument: its length, then its bytes.
        let mut arg = (name.len() as u32).to_le_bytes().to_vec();
        arg.extend_from_slice(name.as_bytes());
        assert!(contains(&r, &arg), "{kind:?}: {r:?}");
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
    let a = record(&Credentials::new("operator", "hunter2-secret"));
    assert!(contains(&a, b"operator"), "{a:?}");
    assert!(
        !contains(&a, b"hunter2"),
        "the password is in the record: {a:?}"
    );
    assert_eq!(a, record(&Credentials::new("operator", "another-one")));
    assert_ne!(a, record(&Credentials::new("viewer", "hunter2-secret")));
}
