//! What `gimbalctl mavlink` says of its UDP peers on stderr (joined, left, refused), at most
//! [`PEER_LINES`] lines a second; the lines held back are summed up by kind after.

use std::collections::HashSet;
use std::net::SocketAddr;
use std::time::{Duration, Instant as StdInstant};

/// Lines about peers written to stderr a second at most: churn (sockets joining, leaving,
/// refused) would otherwise write hundreds a second.
pub const PEER_LINES: u32 = 10;

/// Addresses remembered as refused, so that each is said once (forgotten all at once when
/// there are more: said again, never unbounded).
const REFUSED_REMEMBERED: usize = 1024;

/// What a peer line says.
#[derive(Clone, Copy)]
pub(super) enum PeerEvent {
    Joined,
    Left,
    Refused,
}

/// The peer table's lines on stderr, at most [`PEER_LINES`] a second.
pub(super) struct PeerLog {
    window: StdInstant,
    said: u32,
    /// Lines held back this second: joined, left, refused.
    held: [u32; 3],
    refused: HashSet<SocketAddr>,
}

impl PeerLog {
    pub(super) fn new(now: StdInstant) -> Self {
        PeerLog {
            window: now,
            said: 0,
            held: [0; 3],
            refused: HashSet::new(),
        }
    }

    /// Starts a new second when the last is over, summing up what it held back.
    pub(super) fn tick(&mut self, now: StdInstant) {
        if now.saturating_duration_since(self.window) >= Duration::from_secs(1) {
            let [joined, left, refused] = self.held;
            if joined + left + refused > 0 {
                eprintln!(
                    "gimbalctl mavlink: peer lines held back (at most {PEER_LINES} a second): \
                     {joined} joined, {left} left, {refused} refused"
                );
            }
            (self.window, self.said, self.held) = (now, 0, [0; 3]);
        }
    }

    pub(super) fn say(&mut self, now: StdInstant, event: PeerEvent, line: impl FnOnce() -> String) {
        self.tick(now);
        if self.said < PEER_LINES {
            eprintln!("gimbalctl mavlink: {}", line());
            self.said += 1;
        } else if let Some(n) = self.held.get_mut(event as usize) {
            *n += 1;
        }
    }

    /// Whether `addr` is refused for the first time (to be said).
    pub(super) fn first_refusal(&mut self, addr: SocketAddr) -> bool {
        if self.refused.len() >= REFUSED_REMEMBERED {
            self.refused.clear();
        }
        self.refused.insert(addr)
    }
}
