//! `gimbalctl mavlink`'s MAVLink 2 signing: the key from a passphrase or a key file, the
//! clock it signs with, and the line its counters are said in.

use idu_gimbal_mavlink::signing::{SigningConfig, SigningStats, STREAMS};

use crate::error::Failure;

/// Where the MAVLink 2 signing key comes from.
pub enum SigningKey<'a> {
    /// Its SHA-256 is the key, as MAVProxy and QGroundControl derive it.
    Passphrase(&'a str),
    /// A file of 64 hex digits.
    File(&'a str),
}

/// The link id gimbalctl signs with.
const LINK_ID: u8 = 1;

/// The signing configuration `key` names: usage errors for a key file that is not 64 hex
/// digits, a runtime failure for one that cannot be read.
pub(super) fn config(key: &SigningKey<'_>) -> Result<SigningConfig, Failure> {
    match key {
        SigningKey::Passphrase(p) => Ok(SigningConfig::from_passphrase(p.as_bytes(), LINK_ID)),
        SigningKey::File(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| {
                Failure::Runtime(format!("--signing-key-file: cannot read {path}: {e}"))
            })?;
            let hex = text.trim();
            let usage = || {
                Failure::Usage(format!(
                    "--signing-key-file: {path} holds no key: 64 hex digits (32 bytes) expected"
                ))
            };
            // Hex digits only: `from_str_radix` would take a sign (`+f`) as well.
            if hex.len() != 64 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
                return Err(usage());
            }
            let mut key = [0u8; 32];
            for (i, k) in key.iter_mut().enumerate() {
                *k = u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).map_err(|_| usage())?;
            }
            Ok(SigningConfig {
                key,
                link_id: LINK_ID,
            })
        }
    }
}

/// What signing let through and turned away, for stderr.
pub(super) fn line(s: &SigningStats) -> String {
    format!(
        "frames accepted: {}; turned away: {} unsigned, {} with a bad signature, {} replayed, {} from a new stream while {} were remembered",
        s.accepted, s.unsigned, s.bad_signature, s.replayed, s.streams_full, STREAMS
    )
}

/// `at` as MAVLink 2 signing counts time: 10 µs units since 2015-01-01 00:00 GMT (0 for
/// a clock set before then).
pub(super) fn timestamp(at: std::time::SystemTime) -> u64 {
    const EPOCH_2015_S: u64 = 1_420_070_400;
    at.duration_since(std::time::UNIX_EPOCH).map_or(0, |d| {
        (d.as_micros() / 10).saturating_sub(u128::from(EPOCH_2015_S) * 100_000) as u64
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// MAVLink 2 signing's clock: 10 µs units from 2015-01-01 00:00 UTC (Unix time
    /// 1,420,070,400 s); none before.
    #[test]
    fn the_timestamp_counts_10_us_from_2015() {
        use std::time::{Duration, UNIX_EPOCH};
        let epoch_2015 = UNIX_EPOCH + Duration::from_secs(1_420_070_400);
        assert_eq!(timestamp(epoch_2015), 0);
        assert_eq!(timestamp(epoch_2015 + Duration::from_micros(19)), 1);
        assert_eq!(timestamp(epoch_2015 + Duration::from_micros(20)), 2);
        assert_eq!(timestamp(epoch_2015 + Duration::from_secs(1)), 100_000);
        // 2026-11-28 00:00 UTC: Unix time 1,795,824,000 s.
        let day = UNIX_EPOCH + Duration::from_secs(1_795_824_000);
        assert_eq!(timestamp(day), 37_575_360_000_000);
        assert_eq!(timestamp(epoch_2015 - Duration::from_secs(1)), 0);
        assert_eq!(timestamp(UNIX_EPOCH), 0);
    }

    #[test]
    fn the_line_names_each_count() {
        let stats = SigningStats {
            accepted: 1,
            unsigned: 2,
            bad_signature: 3,
            replayed: 4,
            streams_full: 5,
        };
        assert_eq!(
            line(&stats),
            format!(
                "frames accepted: 1; turned away: 2 unsigned, 3 with a bad signature, \
                 4 replayed, 5 from a new stream while {STREAMS} were remembered"
            )
        );
    }
}
