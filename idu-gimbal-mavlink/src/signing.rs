//! MAVLink 2 message signing (mavlink.io "Message signing"), feature `signing`, off until a
//! key is configured ([`crate::BridgeConfig::signing`]).
//!
//! With a key, a frame is acted on only when it is signed with that key and is newer than
//! the last its stream sent: the signature is the first 6 bytes of SHA-256 over the key,
//! the frame from its start byte to its checksum, the link id and the 48-bit timestamp (10 µs
//! units since 2015-01-01 GMT), and a stream is (link id, system, component). Frames that
//! are unsigned, signed with another key, or replayed (a timestamp not newer than the
//! stream's last, or a new stream's more than a minute behind the newest timestamp known)
//! are dropped and counted ([`SigningStats`]). Everything the bridge sends is signed, with
//! timestamps that never go back: at least one more than the last sent, and at least the
//! newest received or given ([`crate::Bridge::signing_time_at_least`], for a host with a
//! clock). A device without a clock signs with small timestamps until it hears a signed
//! frame, whose timestamp it then goes on from; receivers that know the time refuse those
//! first frames as too old, as the specification has it.
//!
//! On a microcontroller, build with `--cfg sha2_backend_soft="compact"` (in the target's
//! `rustflags`, as this repository's `.cargo/config.toml` does): `sha2`'s compact SHA-256 is
//! 446 B of code on the Cortex-M4 where its unrolled one is 7,120 B.
//!
//! Streams are remembered up to [`STREAMS`]; a new one beyond takes the slot of the stream
//! heard least recently once that stream's frames are more than a minute behind the newest
//! timestamp (too old to pass as a new stream's, so that forgetting it lets none of them
//! be replayed), and is refused until then, counted (only a frame with a good signature
//! makes or moves a stream, so only a key holder can). The key is never printed (`Debug`
//! says so).

use core::fmt;

use sha2::{Digest, Sha256};

/// Streams (link id, system, component) whose last timestamp is remembered.
pub const STREAMS: usize = 16;

/// A new stream's timestamp may be this far behind the newest known (10 µs units: one
/// minute), as the specification allows.
pub const NEW_STREAM_SLACK: u64 = 6_000_000;

/// The signature block after a signed frame's checksum: link id, timestamp, signature.
pub const SIGNATURE_LEN: usize = 13;

/// The largest timestamp (48 bits).
const TIMESTAMP_MAX: u64 = (1 << 48) - 1;

/// The key and link id to sign with.
#[derive(Clone, PartialEq, Eq)]
pub struct SigningConfig {
    /// The 32-byte secret key (MAVProxy and QGroundControl derive it as the SHA-256 of a
    /// passphrase: [`SigningConfig::from_passphrase`]).
    pub key: [u8; 32],
    /// The link id written into what the bridge sends.
    pub link_id: u8,
}

impl SigningConfig {
    /// The key as MAVProxy's `signing setup` and QGroundControl derive it from a
    /// passphrase: its SHA-256.
    pub fn from_passphrase(passphrase: &[u8], link_id: u8) -> Self {
        SigningConfig {
            key: Sha256::digest(passphrase).into(),
            link_id,
        }
    }
}

impl fmt::Debug for SigningConfig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SigningConfig")
            .field("key", &"(secret)")
            .field("link_id", &self.link_id)
            .finish()
    }
}

/// What signing turned away, and what it let through, each wrapping at `u32::MAX`.
#[derive(Clone, Copy, Default, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SigningStats {
    /// Frames with a good signature and a newer timestamp: acted on.
    pub accepted: u32,
    /// Frames without a signature: dropped.
    pub unsigned: u32,
    /// Frames whose signature is not the key's: dropped.
    pub bad_signature: u32,
    /// Frames with a good signature but a timestamp not newer than their stream's (or a new
    /// stream's more than a minute old): dropped.
    pub replayed: u32,
    /// Frames with a good signature from a new stream while [`STREAMS`] are remembered and
    /// none can be forgotten yet (each could still come back as a new stream): dropped.
    pub streams_full: u32,
}

#[derive(Clone, Copy, Debug)]
struct Stream {
    id: (u8, u8, u8),
    timestamp: u64,
}

/// The signing state: the key, the newest timestamp, the streams.
#[derive(Clone)]
pub(crate) struct Signing {
    config: SigningConfig,
    /// The newest timestamp known: sent, received or given.
    timestamp: u64,
    streams: heapless::Vec<Stream, STREAMS>,
    stats: SigningStats,
}

impl fmt::Debug for Signing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Signing")
            .field("config", &self.config)
            .field("timestamp", &self.timestamp)
            .field("stats", &self.stats)
            .finish()
    }
}

fn bump(n: &mut u32) {
    *n = n.wrapping_add(1);
}

impl Signing {
    pub(crate) fn new(config: SigningConfig) -> Self {
        Signing {
            config,
            timestamp: 0,
            streams: heapless::Vec::new(),
            stats: SigningStats::default(),
        }
    }

    pub(crate) fn stats(&self) -> SigningStats {
        self.stats
    }

    /// The newest timestamp is at least `timestamp` (a clock's, 10 µs since 2015).
    pub(crate) fn at_least(&mut self, timestamp: u64) {
        self.timestamp = self.timestamp.max(timestamp.min(TIMESTAMP_MAX));
    }

    /// The 6-byte signature of `signed` (start byte to checksum, then the link id and the
    /// timestamp).
    fn signature(&self, signed: &[&[u8]]) -> [u8; 6] {
        let mut h = Sha256::new();
        h.update(self.config.key);
        for part in signed {
            h.update(part);
        }
        let digest = h.finalize();
        let mut sig = [0u8; 6];
        for (s, d) in sig.iter_mut().zip(digest.iter()) {
            *s = *d;
        }
        sig
    }

    /// The signature block for `frame` (start byte to checksum, its signed flag set):
    /// link id, the next timestamp, the signature.
    pub(crate) fn sign(&mut self, frame: &[u8]) -> [u8; SIGNATURE_LEN] {
        self.timestamp = self.timestamp.saturating_add(1).min(TIMESTAMP_MAX);
        let ts = self.timestamp.to_le_bytes();
        let [t0, t1, t2, t3, t4, t5, ..] = ts;
        let link = [self.config.link_id];
        let stamp = [t0, t1, t2, t3, t4, t5];
        let sig = self.signature(&[frame, &link, &stamp]);
        let mut block = [0u8; SIGNATURE_LEN];
        for (b, v) in block
            .iter_mut()
            .zip(link.iter().chain(stamp.iter()).chain(sig.iter()))
        {
            *b = *v;
        }
        block
    }

    /// Whether a received `frame` (whole, with its signature block when it has one) may be
    /// acted on: signed with the key, and newer than its stream's last. Counted either way.
    pub(crate) fn verify(&mut self, frame: &[u8], signed: bool, system: u8, component: u8) -> bool {
        let Some(body_len) = frame.len().checked_sub(SIGNATURE_LEN).filter(|_| signed) else {
            bump(&mut self.stats.unsigned);
            return false;
        };
        let (body, block) = frame.split_at(body_len);
        let [link, t0, t1, t2, t3, t4, t5, s @ ..] = block else {
            bump(&mut self.stats.unsigned);
            return false;
        };
        if self.signature(&[body, &[*link], &[*t0, *t1, *t2, *t3, *t4, *t5]]) != s {
            bump(&mut self.stats.bad_signature);
            return false;
        }
        let ts = u64::from_le_bytes([*t0, *t1, *t2, *t3, *t4, *t5, 0, 0]);
        let id = (*link, system, component);
        let fresh = match self.streams.iter().position(|s| s.id == id) {
            Some(i) => self.streams.get(i).is_some_and(|s| ts > s.timestamp),
            None => ts.saturating_add(NEW_STREAM_SLACK) >= self.timestamp,
        };
        if !fresh {
            bump(&mut self.stats.replayed);
            return false;
        }
        if !self.remember(id, ts) {
            bump(&mut self.stats.streams_full);
            return false;
        }
        self.timestamp = self.timestamp.max(ts);
        bump(&mut self.stats.accepted);
        true
    }

    /// Keeps `timestamp` as the stream's last; false when the table is full and no stream
    /// in it can be forgotten yet.
    fn remember(&mut self, id: (u8, u8, u8), timestamp: u64) -> bool {
        let stream = Stream { id, timestamp };
        if let Some(s) = self.streams.iter_mut().find(|s| s.id == id) {
            *s = stream;
            return true;
        }
        let Err(stream) = self.streams.push(stream) else {
            return true;
        };
        // Full: the stream heard least recently (the oldest timestamp) gives way, once its
        // frames are too old to pass as a new stream's (forgotten sooner, its last frame
        // replayed would be taken as a new stream's first).
        let newest = self.timestamp;
        match self.streams.iter_mut().min_by_key(|s| s.timestamp) {
            Some(oldest) if oldest.timestamp.saturating_add(NEW_STREAM_SLACK) < newest => {
                *oldest = stream;
                true
            }
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// pymavlink 2.4.50: COMMAND_LONG REQUEST_MESSAGE(283) from 255/190 to 1/154, signed
    /// with SHA-256("idu-gimbal"), link id 3, timestamp 0x0123456789AB.
    const PYMAVLINK: &str = "fd20010000ffbe4c000000808d430000000000000000000000000000000000000000000000000002019ad45503ab8967452301613a5d5b16c4";

    fn hex(s: &str) -> Vec<u8> {
        (0..s.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
            .collect()
    }

    fn signing() -> Signing {
        Signing::new(SigningConfig::from_passphrase(b"idu-gimbal", 7))
    }

    /// pymavlink's frame signed by `tx` with its next timestamp at or after `ts`.
    fn signed_at(tx: &mut Signing, ts: u64) -> Vec<u8> {
        let body = hex(PYMAVLINK);
        tx.at_least(ts);
        let mut f = body[..44].to_vec();
        f.extend_from_slice(&tx.sign(&body[..44]));
        f
    }

    #[test]
    fn the_key_is_the_passphrase_s_sha256_and_never_printed() {
        let c = SigningConfig::from_passphrase(b"idu-gimbal", 7);
        assert_eq!(
            c.key.to_vec(),
            hex("2ab9d578e7d386546ce6422fde6d34849e5f089ce600fe0dbd334ef7fc4300a0")
        );
        let printed = format!("{c:?}");
        assert!(
            printed.contains("(secret)") && !printed.contains("42"),
            "{printed}"
        );
    }

    #[test]
    fn timestamps_stop_at_48_bits_and_the_state_prints_without_the_key() {
        let mut s = signing();
        s.at_least(u64::MAX);
        let body = &hex(PYMAVLINK)[..44];
        for _ in 0..2 {
            // The six timestamp bytes all ones, never wrapping to small values.
            assert_eq!(s.sign(body)[1..7], [0xFF; 6]);
        }
        let printed = format!("{s:?}");
        assert!(
            printed.contains("timestamp: 281474976710655") && printed.contains("(secret)"),
            "{printed}"
        );
    }

    #[test]
    fn each_stream_keeps_its_own_timestamp() {
        // Frames from streams A and B, signed by a sender whose clock moves on.
        let mut tx = signing();
        let mut frame_at = |ts: u64| signed_at(&mut tx, ts);
        // Each signature one past the time given: 11, 21, 31, 32.
        let (a11, b21, a31, b32) = (frame_at(10), frame_at(20), frame_at(30), frame_at(31));
        let mut rx = signing();
        assert!(rx.verify(&a11, true, 1, 1));
        assert!(rx.verify(&b21, true, 2, 1));
        assert!(rx.verify(&a31, true, 1, 1));
        // B's last is still 21: its frame at 32 is new; A's at 11 again is a replay of A.
        assert!(rx.verify(&b32, true, 2, 1));
        assert!(!rx.verify(&a11, true, 1, 1));
        assert_eq!(rx.stats().replayed, 1);
    }

    #[test]
    fn pymavlink_s_signed_frame_is_accepted_once() {
        let frame = hex(PYMAVLINK);
        let mut s = signing();
        assert!(s.verify(&frame, true, 255, 190));
        assert_eq!(s.timestamp, 0x0123_4567_89AB);
        // The same again: replayed.
        assert!(!s.verify(&frame, true, 255, 190));
        assert_eq!(
            s.stats(),
            SigningStats {
                accepted: 1,
                replayed: 1,
                ..SigningStats::default()
            }
        );
    }

    #[test]
    fn any_changed_byte_or_another_key_is_refused() {
        let frame = hex(PYMAVLINK);
        for i in 0..frame.len() {
            let mut f = frame.clone();
            f[i] ^= 0x20;
            let mut s = signing();
            assert!(!s.verify(&f, true, 255, 190), "byte {i}");
            assert_eq!(s.stats().accepted, 0);
        }
        let mut other = Signing::new(SigningConfig::from_passphrase(b"not it", 7));
        assert!(!other.verify(&frame, true, 255, 190));
        assert_eq!(other.stats().bad_signature, 1);
        // Unsigned (the flag clear), or too short to hold a signature.
        let mut s = signing();
        assert!(!s.verify(&frame, false, 255, 190));
        assert!(!s.verify(&frame[..10], true, 255, 190));
        assert_eq!(s.stats().unsigned, 2);
    }

    #[test]
    fn what_is_signed_verifies_with_newer_timestamps() {
        let mut tx = signing();
        let mut rx = signing();
        tx.at_least(1_000_000);
        let body = &hex(PYMAVLINK)[..44];
        let mut last = 0;
        for _ in 0..3 {
            let block = tx.sign(body);
            let ts = u64::from_le_bytes([
                block[1], block[2], block[3], block[4], block[5], block[6], 0, 0,
            ]);
            assert!(ts > last && ts > 1_000_000);
            last = ts;
            assert_eq!(block[0], 7, "the link id");
            let mut frame = body.to_vec();
            frame.extend_from_slice(&block);
            assert!(rx.verify(&frame, true, 1, 154));
        }
    }

    /// A full table makes room only by forgetting a stream whose frames could not pass as
    /// a new stream's (more than a minute behind the newest): a forgotten stream's last
    /// frame, replayed, would otherwise be taken as a new stream's.
    #[test]
    fn a_full_table_forgets_only_streams_too_old_to_come_back_as_new() {
        let mut tx = signing();
        let mut frame_at = |ts: u64| signed_at(&mut tx, ts);
        let mut rx = signing();
        // STREAMS streams, systems 1 to 16, each heard at about the same time.
        let first: Vec<Vec<u8>> = (0..STREAMS as u64).map(|i| frame_at(100 + i)).collect();
        for (system, f) in (1u8..).zip(&first) {
            assert!(rx.verify(f, true, system, 1));
        }
        // One more, while every stream known could still come back as new: refused.
        let late = frame_at(200);
        assert!(!rx.verify(&late, true, 100, 1));
        assert_eq!(rx.stats().streams_full, 1);
        // Had system 1 been forgotten for it, its first frame again would pass as new.
        assert!(!rx.verify(&first[0], true, 1, 1));
        assert_eq!(rx.stats().replayed, 1);
        // Over a minute on, from system 2: system 1 (the oldest) can be forgotten now, and
        // its first frame, replayed, is refused as too old for a new stream.
        let on = frame_at(300 + NEW_STREAM_SLACK);
        assert!(rx.verify(&on, true, 2, 1));
        let new = frame_at(400 + NEW_STREAM_SLACK);
        assert!(rx.verify(&new, true, 100, 1));
        assert!(!rx.verify(&first[0], true, 1, 1));
        assert_eq!(rx.stats().replayed, 2);
        assert_eq!(rx.stats().streams_full, 1);
    }

    #[test]
    fn a_new_stream_more_than_a_minute_old_is_refused() {
        let frame = hex(PYMAVLINK);
        let mut s = signing();
        s.at_least(0x0123_4567_89AB + NEW_STREAM_SLACK + 1);
        assert!(!s.verify(&frame, true, 255, 190));
        assert_eq!(s.stats().replayed, 1);
        let mut s = signing();
        s.at_least(0x0123_4567_89AB + NEW_STREAM_SLACK);
        assert!(s.verify(&frame, true, 255, 190));
    }
}
