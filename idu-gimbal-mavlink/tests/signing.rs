//! MAVLink 2 signing at the bridge (feature `signing`): only what is signed with the key and
//! new is acted on, and everything sent is signed. Signatures here are computed from the
//! specification's formula with `sha2` directly, not through the bridge's code.
#![cfg(feature = "signing")]

mod common;
use common::*;

use idu_gimbal::link::{Config, Link};
use idu_gimbal_mavlink::signing::SigningConfig;
use idu_gimbal_mavlink::BridgeConfig;
use mavio::dialects::common::enums::MavCmd;
use sha2::{Digest, Sha256};

const KEY_PASSPHRASE: &[u8] = b"idu-gimbal";

fn key(passphrase: &[u8]) -> [u8; 32] {
    Sha256::digest(passphrase).into()
}

fn signing_bridge() -> Firmware {
    Firmware::new(
        Link::new(Config::default()),
        BridgeConfig {
            signing: Some(SigningConfig::from_passphrase(KEY_PASSPHRASE, 5)),
            ..BridgeConfig::default()
        },
    )
}

/// `unsigned` (a mavio frame) signed with `key`, link 1, `timestamp`: the signed flag set,
/// the checksum recomputed over the new header, the block appended.
fn sign(unsigned: &[u8], crc_extra: u8, key: &[u8; 32], timestamp: u64) -> Vec<u8> {
    let len = usize::from(unsigned[1]);
    let mut f = unsigned[..10 + len].to_vec();
    f[2] = 0x01;
    let crc = checksum(&f[1..], crc_extra);
    f.extend_from_slice(&crc.to_le_bytes());
    f.push(1);
    f.extend_from_slice(&timestamp.to_le_bytes()[..6]);
    let mut h = Sha256::new();
    h.update(key);
    h.update(&f);
    let sig = h.finalize();
    f.extend_from_slice(&sig[..6]);
    f
}

/// The bridge's output as raw frames: (message id, whether signed and its signature holds
/// with `key`).
fn output(b: &mut Firmware, key: &[u8; 32]) -> Vec<(u32, bool)> {
    let bytes = b.transmit_bytes().to_vec();
    b.transmit_written(bytes.len());
    let mut out = Vec::new();
    let mut rest = &bytes[..];
    while rest.len() > 12 {
        let len = usize::from(rest[1]);
        let signed = rest[2] & 1 != 0;
        let total = 10 + len + 2 + if signed { 13 } else { 0 };
        let (f, tail) = rest.split_at(total);
        let id = u32::from_le_bytes([f[7], f[8], f[9], 0]);
        let holds = signed && {
            let mut h = Sha256::new();
            h.update(key);
            h.update(&f[..total - 6]);
            h.finalize()[..6] == f[total - 6..]
        };
        out.push((id, holds));
        rest = tail;
    }
    assert!(rest.is_empty(), "whole frames only");
    out
}

fn request() -> Vec<u8> {
    frame(
        GCS,
        0,
        &command((1, 154), MavCmd::RequestMessage, 283.0, 0.0),
    )
}

const COMMAND_LONG_CRC_EXTRA: u8 = 152;
const T: u64 = 0x0123_4567_89AB;

#[test]
fn a_signed_request_is_answered_signed_and_nothing_else_is() {
    let k = key(KEY_PASSPHRASE);
    let mut b = signing_bridge();
    b.poll(t(0));
    // The bridge's own heartbeat: signed, its signature the key's.
    let sent = output(&mut b, &k);
    assert!(
        !sent.is_empty() && sent.iter().all(|&(_, ok)| ok),
        "{sent:?}"
    );
    // Unsigned: not acted on.
    b.receive_all(&request(), t(10));
    assert!(output(&mut b, &k).is_empty());
    // Signed with another key: not acted on.
    b.receive_all(
        &sign(&request(), COMMAND_LONG_CRC_EXTRA, &key(b"another"), T),
        t(20),
    );
    assert!(output(&mut b, &k).is_empty());
    // Signed with the key: the ACK and the information, both signed with it.
    let good = sign(&request(), COMMAND_LONG_CRC_EXTRA, &k, T);
    b.receive_all(&good, t(30));
    let sent = output(&mut b, &k);
    assert_eq!(sent, [(77, true), (283, true)]);
    // The same frame again (replayed): not acted on; a newer one is.
    b.receive_all(&good, t(40));
    assert!(output(&mut b, &k).is_empty());
    b.receive_all(&sign(&request(), COMMAND_LONG_CRC_EXTRA, &k, T + 1), t(50));
    assert_eq!(output(&mut b, &k), [(77, true), (283, true)]);
    let s = b.signing_stats().unwrap();
    assert_eq!(
        (s.unsigned, s.bad_signature, s.replayed, s.accepted),
        (1, 1, 1, 2),
        "{s:?}"
    );
}

/// A signed frame changed in transit is a corrupt frame first: a message the bridge knows
/// whose checksum fails is found bad and read past byte by byte, as without a key, so a
/// length made longer does not swallow the frame that follows (its signature, checked
/// first, took it whole as a frame not for the bridge).
#[test]
fn a_corrupt_signed_frame_does_not_swallow_the_next() {
    let k = key(KEY_PASSPHRASE);
    let mut b = signing_bridge();
    let _ = output(&mut b, &k);
    let mut corrupt = sign(&request(), COMMAND_LONG_CRC_EXTRA, &k, T);
    // Its length 16 bytes longer: it would end inside the next frame.
    corrupt[1] += 16;
    let mut bytes = corrupt;
    bytes.extend(sign(&request(), COMMAND_LONG_CRC_EXTRA, &k, T + 1));
    b.receive_all(&bytes, t(10));
    assert_eq!(output(&mut b, &k), [(77, true), (283, true)]);
    let (s, r) = (b.signing_stats().unwrap(), b.stats().reader);
    assert_eq!((s.accepted, s.bad_signature), (1, 0), "{s:?}");
    assert_eq!((r.frames, r.bad_frames), (1, 1), "{r:?}");
}

#[test]
fn the_timestamps_sent_go_on_from_the_newest_known() {
    let k = key(KEY_PASSPHRASE);
    let mut b = signing_bridge();
    b.signing_time_at_least(T + 1_000);
    b.receive_all(
        &sign(&request(), COMMAND_LONG_CRC_EXTRA, &k, T + 5_000),
        t(10),
    );
    let bytes = b.transmit_bytes().to_vec();
    // Every frame's timestamp: newer than the newest received, and increasing; the
    // frames are the request's answers (the ACK and the message asked for).
    let mut rest = &bytes[..];
    let mut last = T + 5_000;
    let mut ids = Vec::new();
    while rest.len() > 12 {
        ids.push(u32::from_le_bytes([rest[7], rest[8], rest[9], 0]));
        let len = usize::from(rest[1]);
        let total = 10 + len + 2 + 13;
        let ts = u64::from_le_bytes({
            let mut t = [0u8; 8];
            t[..6].copy_from_slice(&rest[total - 12..total - 6]);
            t
        });
        assert!(ts > last, "{ts} after {last}");
        last = ts;
        rest = &rest[total..];
    }
    assert!(rest.is_empty(), "{} bytes after the last frame", rest.len());
    assert_eq!(ids, [77, 283], "the ACK, then the message asked for");
}

#[test]
fn without_a_key_nothing_is_signed_or_checked() {
    let mut b = Firmware::new(Link::new(Config::default()), BridgeConfig::default());
    b.receive_all(&request(), t(10));
    assert!(b.signing_stats().is_none());
    let out = output(&mut b, &key(KEY_PASSPHRASE));
    assert_eq!(out, [(77, false), (283, false)]);
}

#[test]
fn the_timestamps_sent_start_from_the_time_given() {
    let k = key(KEY_PASSPHRASE);
    let mut b = signing_bridge();
    // The host's clock, far past anything received: the answers' timestamps go on from it.
    b.signing_time_at_least(T + 1_000_000);
    b.receive_all(
        &sign(&request(), COMMAND_LONG_CRC_EXTRA, &k, T + 5_000),
        t(10),
    );
    let bytes = b.transmit_bytes();
    assert!(bytes.len() > 12);
    let total = 10 + usize::from(bytes[1]) + 2 + 13;
    let mut ts = [0u8; 8];
    ts[..6].copy_from_slice(&bytes[total - 12..total - 6]);
    assert!(u64::from_le_bytes(ts) >= T + 1_000_000);
}
