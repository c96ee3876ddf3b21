//! The UDP peers `gimbalctl mavlink` answers: source addresses that sent MAVLink the bridge
//! understood, dropped when they fall silent. A live peer is never dropped for a newcomer:
//! when the table is full of live peers, the newcomer is refused.
//!
//! The table takes the time as a parameter (`now`) rather than reading the clock, so that
//! expiry and eviction are tested without sleeping.

use std::net::SocketAddr;
use std::num::NonZeroUsize;
use std::time::{Duration, Instant};

/// How long a peer may stay silent before it is dropped. Ground stations and autopilots send
/// a HEARTBEAT every second, so this is ten missed heartbeats: a live peer never expires,
/// and one that went away (a ground station reconnecting from a new port) frees its slot
/// soon after. QGroundControl itself declares a link lost after 3.5 s without a heartbeat.
pub const PEER_TIMEOUT: Duration = Duration::from_secs(10);

/// Peers kept at once. Every frame the bridge sends goes to each, so the table is bounded;
/// a host has room for many more than a link has ground stations and autopilots. When it is
/// full of live peers a newcomer is refused: evicting a live ground station (16 sockets
/// beating at 2 Hz would leave a 1 Hz one without a heartbeat for seconds) is worse than
/// turning away the 65th address.
pub const PEER_CAPACITY: NonZeroUsize = NonZeroUsize::new(64).unwrap();

/// What one datagram changed in the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// `0` became a peer.
    Joined(SocketAddr),
    /// `new` became a peer in the slot of `old`, silent for the timeout (a table whose
    /// silent peers were not yet expired).
    Replaced { old: SocketAddr, new: SocketAddr },
    /// `0` was not taken: every slot holds a live peer.
    Refused(SocketAddr),
}

#[derive(Clone, Copy, Debug)]
struct Peer {
    addr: SocketAddr,
    heard: Instant,
}

/// A bounded set of peers, each with when it was last heard.
#[derive(Debug)]
pub struct Peers {
    slots: Vec<Peer>,
    capacity: usize,
    timeout: Duration,
}

impl Peers {
    /// A table of at most `capacity` peers, each dropped after `timeout`
    /// of silence.
    pub fn new(capacity: NonZeroUsize, timeout: Duration) -> Self {
        let capacity = capacity.get();
        Peers {
            slots: Vec::with_capacity(capacity),
            capacity,
            timeout,
        }
    }

    /// A datagram from `from` arrived at `now` holding `good_frames` frames the bridge
    /// handled with a good CRC. A peer is kept by any datagram (it may send messages the
    /// bridge does not handle); a stranger joins only with at least one good frame, so
    /// garbage never takes a slot. When the table is full, the stranger takes the slot of
    /// a peer silent for the timeout, or is refused: a live peer is never evicted.
    pub fn heard(&mut self, from: SocketAddr, good_frames: u32, now: Instant) -> Option<Change> {
        if let Some(peer) = self.slots.iter_mut().find(|p| p.addr == from) {
            peer.heard = peer.heard.max(now);
            return None;
        }
        if good_frames == 0 {
            return None;
        }
        let new = Peer {
            addr: from,
            heard: now,
        };
        if self.slots.len() < self.capacity {
            self.slots.push(new);
            return Some(Change::Joined(from));
        }
        // Full (capacity >= 1, so there is a slot): the least recently heard, if silent.
        let timeout = self.timeout;
        let Some(oldest) = self
            .slots
            .iter_mut()
            .min_by_key(|p| p.heard)
            .filter(|p| now.saturating_duration_since(p.heard) >= timeout)
        else {
            return Some(Change::Refused(from));
        };
        let old = std::mem::replace(oldest, new).addr;
        Some(Change::Replaced { old, new: from })
    }

    /// Drops the peers silent for the timeout or longer at `now`, telling `left` of each.
    pub fn expire(&mut self, now: Instant, mut left: impl FnMut(SocketAddr)) {
        let timeout = self.timeout;
        self.slots.retain(|p| {
            let alive = now.saturating_duration_since(p.heard) < timeout;
            if !alive {
                left(p.addr);
            }
            alive
        });
    }

    /// The peers, in no particular order.
    pub fn addrs(&self) -> impl Iterator<Item = &SocketAddr> {
        self.slots.iter().map(|p| &p.addr)
    }

    /// How many peers there are.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// The most peers kept at once.
    pub fn capacity(&self) -> usize {
        self.capacity
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn addr(port: u16) -> SocketAddr {
        SocketAddr::from(([127, 0, 0, 1], port))
    }

    fn expired(peers: &mut Peers, now: Instant) -> Vec<SocketAddr> {
        let mut gone = Vec::new();
        peers.expire(now, |a| gone.push(a));
        gone
    }

    fn has(peers: &Peers, a: SocketAddr) -> bool {
        peers.addrs().any(|p| *p == a)
    }

    fn sorted(peers: &Peers) -> Vec<SocketAddr> {
        let mut v: Vec<SocketAddr> = peers.addrs().copied().collect();
        v.sort();
        v
    }

    const S: Duration = Duration::from_secs(1);

    #[test]
    fn garbage_never_joins() {
        let t0 = Instant::now();
        let mut peers = Peers::new(NonZeroUsize::new(2).unwrap(), PEER_TIMEOUT);
        for port in 1..=100 {
            assert_eq!(peers.heard(addr(port), 0, t0), None);
        }
        assert_eq!(peers.len(), 0);
        // Even in a full table a garbage sender takes no one's slot.
        peers.heard(addr(1000), 1, t0);
        peers.heard(addr(1001), 3, t0);
        assert_eq!(peers.heard(addr(1), 0, t0 + S), None);
        assert_eq!(sorted(&peers), [addr(1000), addr(1001)]);
    }

    #[test]
    fn a_good_frame_joins_once() {
        let t0 = Instant::now();
        let mut peers = Peers::new(PEER_CAPACITY, PEER_TIMEOUT);
        assert_eq!(peers.heard(addr(1), 1, t0), Some(Change::Joined(addr(1))));
        assert_eq!(peers.heard(addr(1), 1, t0), None);
        assert_eq!(peers.heard(addr(1), 2, t0 + S), None);
        assert_eq!(peers.len(), 1);
        assert!(has(&peers, addr(1)));
        assert!(!has(&peers, addr(2)));
    }

    #[test]
    fn a_silent_peer_expires_after_the_timeout_and_not_before() {
        let t0 = Instant::now();
        let mut peers = Peers::new(PEER_CAPACITY, PEER_TIMEOUT);
        peers.heard(addr(1), 1, t0);
        peers.heard(addr(2), 1, t0 + 5 * S);
        let just_before = t0 + PEER_TIMEOUT - Duration::from_millis(1);
        assert!(expired(&mut peers, just_before).is_empty());
        // Silent for exactly the timeout: gone, said once.
        assert_eq!(expired(&mut peers, t0 + PEER_TIMEOUT), [addr(1)]);
        assert!(expired(&mut peers, t0 + PEER_TIMEOUT).is_empty());
        assert_eq!(sorted(&peers), [addr(2)]);
        assert_eq!(expired(&mut peers, t0 + 5 * S + PEER_TIMEOUT), [addr(2)]);
        assert_eq!(peers.len(), 0);
        // An expired peer that speaks again joins again.
        assert_eq!(
            peers.heard(addr(1), 1, t0 + 20 * S),
            Some(Change::Joined(addr(1)))
        );
    }

    #[test]
    fn every_datagram_refreshes_a_peer_even_without_a_good_frame() {
        let t0 = Instant::now();
        let mut peers = Peers::new(PEER_CAPACITY, PEER_TIMEOUT);
        peers.heard(addr(1), 1, t0);
        // A heartbeat a second for a minute, then messages the bridge does not handle
        // (0 good frames) for another minute: never silent, never dropped.
        for s in 1..=120 {
            let now = t0 + s * S;
            peers.heard(addr(1), u32::from(s <= 60), now);
            assert!(expired(&mut peers, now).is_empty(), "{s} s");
        }
        // Measured from the last datagram.
        let last = t0 + 120 * S;
        assert!(expired(&mut peers, last + PEER_TIMEOUT - S).is_empty());
        assert_eq!(expired(&mut peers, last + PEER_TIMEOUT), [addr(1)]);
    }

    #[test]
    fn a_full_table_of_live_peers_refuses_the_newcomer() {
        let t0 = Instant::now();
        let mut peers = Peers::new(NonZeroUsize::new(3).unwrap(), PEER_TIMEOUT);
        assert_eq!(peers.capacity(), 3);
        peers.heard(addr(1), 1, t0);
        peers.heard(addr(2), 1, t0 + S);
        peers.heard(addr(3), 1, t0 + 2 * S);
        // All live: the newcomer is refused, whoever was heard least recently.
        assert_eq!(
            peers.heard(addr(4), 1, t0 + 3 * S),
            Some(Change::Refused(addr(4)))
        );
        assert_eq!(sorted(&peers), [addr(1), addr(2), addr(3)]);
        // Still refused while they keep talking, however often it asks.
        for s in 4..30 {
            let now = t0 + s * S;
            for p in 1..=3 {
                peers.heard(addr(p), 1, now);
            }
            expired(&mut peers, now);
            assert_eq!(peers.heard(addr(4), 1, now), Some(Change::Refused(addr(4))));
        }
        // One falls silent: its slot goes to the newcomer, once expired or not yet.
        let last = t0 + 29 * S;
        peers.heard(addr(1), 1, last + PEER_TIMEOUT);
        peers.heard(addr(3), 1, last + PEER_TIMEOUT);
        assert_eq!(
            peers.heard(addr(4), 1, last + PEER_TIMEOUT),
            Some(Change::Replaced {
                old: addr(2),
                new: addr(4)
            })
        );
        assert_eq!(sorted(&peers), [addr(1), addr(3), addr(4)]);
    }

    #[test]
    fn many_reconnections_never_lock_a_client_out() {
        // A ground station reconnecting from a new port every second, more often than the
        // timeout: each new port is answered, its old ones expiring as it goes.
        let t0 = Instant::now();
        let mut peers = Peers::new(PEER_CAPACITY, PEER_TIMEOUT);
        for i in 0..200u16 {
            let now = t0 + u32::from(i) * S;
            expired(&mut peers, now);
            assert!(
                matches!(
                    peers.heard(addr(10_000 + i), 1, now),
                    Some(Change::Joined(_) | Change::Replaced { .. })
                ),
                "client {i}"
            );
            assert!(has(&peers, addr(10_000 + i)));
            assert!(peers.len() <= PEER_CAPACITY.get());
        }
    }

    #[test]
    fn the_clock_is_the_one_passed_in() {
        let t0 = Instant::now();
        let mut peers = Peers::new(PEER_CAPACITY, Duration::from_millis(50));
        peers.heard(addr(1), 1, t0 + 10 * S);
        // A `now` earlier than the last datagram (the caller's clock is monotonic, but the
        // table must not care) neither expires the peer nor moves its time back.
        assert!(expired(&mut peers, t0).is_empty());
        peers.heard(addr(1), 1, t0);
        assert!(expired(&mut peers, t0 + 10 * S + Duration::from_millis(49)).is_empty());
        assert_eq!(
            expired(&mut peers, t0 + 10 * S + Duration::from_millis(50)),
            [addr(1)]
        );
        // A capacity of 1: a good stranger is answered, the next refused while the first
        // is live, and given its slot once it is not.
        let mut one = Peers::new(NonZeroUsize::MIN, PEER_TIMEOUT);
        assert_eq!(one.heard(addr(1), 1, t0), Some(Change::Joined(addr(1))));
        assert_eq!(one.heard(addr(2), 1, t0), Some(Change::Refused(addr(2))));
        assert_eq!(
            one.heard(addr(2), 1, t0 + PEER_TIMEOUT),
            Some(Change::Replaced {
                old: addr(1),
                new: addr(2)
            })
        );
    }
}
