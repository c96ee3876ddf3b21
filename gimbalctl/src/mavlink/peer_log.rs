//! What `gimbalctl mavlink` says of its UDP peers on stderr (joined, left, refused), at most
//! [`PEER_LINES`] lines a second; the lines held back are summed up by kind after.

use std::collections::HashSet;
use std::io::{self, Write};
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

/// The peer table's lines, at most [`PEER_LINES`] a second, written to `W` (stderr for
/// `gimbalctl mavlink`; a buffer in the tests). A line that cannot be written is not
/// reported anywhere: stderr is where it would be reported.
pub(super) struct PeerLog<W = io::Stderr> {
    out: W,
    window: StdInstant,
    said: u32,
    /// Lines held back this second: joined, left, refused.
    held: [u32; 3],
    refused: HashSet<SocketAddr>,
}

impl<W: Write> PeerLog<W> {
    pub(super) fn new(now: StdInstant, out: W) -> Self {
        PeerLog {
            out,
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
                let _ = writeln!(
                    self.out,
                    "gimbalctl mavlink: peer lines held back (at most {PEER_LINES} a second): \
                     {joined} joined, {left} left, {refused} refused"
                );
            }
            (self.window, self.said, self.held) = (now, 0, [0; 3]);
        }
    }

    /// Writes `line` if this second has room for it, or counts it as held back by `event`.
    pub(super) fn say(&mut self, now: StdInstant, event: PeerEvent, line: impl FnOnce() -> String) {
        self.tick(now);
        if self.said < PEER_LINES {
            let _ = writeln!(self.out, "gimbalctl mavlink: {}", line());
            self.said += 1;
        } else if let Some(n) = self.held.get_mut(event as usize) {
            *n += 1;
        }
    }

    /// Whether `addr` is refused for the first time (to be said).
    pub(super) fn first_refusal(&mut self, addr: SocketAddr) -> bool {
        if self.refused.contains(&addr) {
            return false;
        }
        // Forgotten only for a new address: one already remembered is never said twice.
        if self.refused.len() >= REFUSED_REMEMBERED {
            self.refused.clear();
        }
        self.refused.insert(addr)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn addr(port: u16) -> SocketAddr {
        SocketAddr::from(([127, 0, 0, 1], port))
    }

    /// What the log wrote since the last call, line by line.
    fn written(log: &mut PeerLog<Vec<u8>>) -> Vec<String> {
        let text = String::from_utf8(std::mem::take(&mut log.out)).unwrap();
        text.lines().map(str::to_owned).collect()
    }

    const MS: Duration = Duration::from_millis(1);

    #[test]
    fn ten_lines_a_second_then_a_summary_by_kind() {
        let t0 = StdInstant::now();
        let mut log = PeerLog::new(t0, Vec::new());
        for i in 0..12 {
            log.say(t0, PeerEvent::Joined, || format!("joined {i}"));
        }
        log.say(t0 + 500 * MS, PeerEvent::Left, || "left".into());
        let mut called = false;
        log.say(t0 + 999 * MS, PeerEvent::Refused, || {
            called = true;
            String::new()
        });
        // A line held back is never formatted.
        assert!(!called);
        let expected: Vec<String> = (0..10)
            .map(|i| format!("gimbalctl mavlink: joined {i}"))
            .collect();
        assert_eq!(written(&mut log), expected);
        // Still the same second a millisecond before its end.
        log.tick(t0 + 999 * MS);
        assert!(written(&mut log).is_empty());
        // The next second: the summary, then ten lines again.
        log.tick(t0 + 1000 * MS);
        assert_eq!(
            written(&mut log),
            [
                "gimbalctl mavlink: peer lines held back (at most 10 a second): \
                 2 joined, 1 left, 1 refused"
            ]
        );
        for i in 0..11 {
            log.say(t0 + 1500 * MS, PeerEvent::Refused, || {
                format!("refused {i}")
            });
        }
        assert_eq!(written(&mut log).len(), 10);
        // A say that opens the next second writes its summary first.
        log.say(t0 + 2000 * MS, PeerEvent::Joined, || "joined again".into());
        assert_eq!(
            written(&mut log),
            [
                "gimbalctl mavlink: peer lines held back (at most 10 a second): \
                 0 joined, 0 left, 1 refused",
                "gimbalctl mavlink: joined again",
            ]
        );
    }

    #[test]
    fn a_second_with_nothing_held_back_has_no_summary() {
        let t0 = StdInstant::now();
        let mut log = PeerLog::new(t0, Vec::new());
        log.tick(t0 + 1000 * MS);
        for i in 0..10 {
            log.say(t0 + 1500 * MS, PeerEvent::Joined, || format!("joined {i}"));
        }
        log.tick(t0 + 2500 * MS);
        log.tick(t0 + 10_000 * MS);
        assert_eq!(written(&mut log).len(), 10);
    }

    #[test]
    fn each_refused_address_is_said_once_until_too_many_are_remembered() {
        let t0 = StdInstant::now();
        let mut log = PeerLog::new(t0, Vec::new());
        assert!(log.first_refusal(addr(1)));
        assert!(!log.first_refusal(addr(1)));
        for port in 2..=1024 {
            assert!(log.first_refusal(addr(port)), "{port}");
        }
        // 1,024 remembered: still none said twice.
        assert!(!log.first_refusal(addr(1)));
        assert!(!log.first_refusal(addr(1024)));
        // The 1,025th: all forgotten, so the memory stays bounded; each said again once.
        assert!(log.first_refusal(addr(1025)));
        assert_eq!(log.refused.len(), 1);
        assert!(log.first_refusal(addr(1)));
        assert!(!log.first_refusal(addr(1)));
    }
}
