//! `gimbalctl mavlink` on UDP: datagrams read into the bridge one at a time, each one's
//! answers sent before the next is read, one frame a datagram to every peer and `--to`
//! address; the peer table kept and what changed in it said ([`super::peer_log`]).

use std::collections::BTreeMap;
use std::io::{self, ErrorKind};
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant as StdInstant};

use idu_gimbal::link::{Link, Medium};
use idu_gimbal::Instant;
use idu_gimbal_mavlink::framing::{Check, FrameReader};
use idu_gimbal_mavlink::Bridge;

use super::peer_log::{PeerEvent, PeerLog};
use super::peers::{Change, Peers, PEER_TIMEOUT};
use super::DATAGRAMS_PER_TICK;
use crate::error::Failure;

/// The UDP peers, what is said of them, and the frames going to them.
pub(super) struct Clients {
    pub(super) peers: Peers,
    pub(super) log: PeerLog,
    /// Splits the bridge's bytes into frames, one a datagram.
    pub(super) splitter: FrameReader,
    /// Datagrams the socket did not take.
    pub(super) unsent: Unsent,
}

/// Datagrams the socket did not take (a destination it cannot reach from the address it
/// listens on, a broadcast address, a full send buffer): counted by destination and said on
/// stderr, a destination's first at the next note and the rest at most every
/// [`UNSENT_EVERY`], so that a `--to` address that can never be reached is not lost without
/// a word, nor said every second.
#[derive(Default)]
pub(super) struct Unsent {
    /// Not said yet: the count, the latest error's kind and the reason said, by destination.
    recent: BTreeMap<SocketAddr, (u64, ErrorKind, String)>,
    /// When each destination was last said, kept for [`UNSENT_EVERY`].
    said: BTreeMap<SocketAddr, StdInstant>,
    /// Since the start.
    total: u64,
}

/// How often a destination's refused datagrams are said again.
const UNSENT_EVERY: Duration = Duration::from_secs(10);

impl Unsent {
    /// A datagram to `to` that `socket` refused with `e`.
    fn count(&mut self, socket: &UdpSocket, to: SocketAddr, e: &io::Error) {
        self.total += 1;
        let (n, kind, why) = self
            .recent
            .entry(to)
            .or_insert_with(|| (0, e.kind(), String::new()));
        *n += 1;
        // The reason put in words once a destination and kind of error, not per datagram.
        if why.is_empty() || *kind != e.kind() {
            *kind = e.kind();
            *why = e.to_string();
            // Why the kernel refuses most often, said with the remedy.
            if let Ok(local) = socket.local_addr() {
                if local.ip().is_loopback() && !to.ip().is_loopback() {
                    why.push_str(&format!(
                        " (listening on {local}, a loopback address: --listen 0.0.0.0:PORT reaches other hosts)"
                    ));
                }
            }
            if e.kind() == ErrorKind::PermissionDenied {
                why.push_str(" (a broadcast address is not sent to)");
            }
        }
    }

    /// A line for each destination due to be said at `clock` (or for every one, `all`),
    /// which then starts counting again.
    pub(super) fn lines(&mut self, clock: StdInstant, all: bool) -> Vec<String> {
        self.said
            .retain(|_, at| clock.duration_since(*at) < UNSENT_EVERY);
        let (due, wait): (BTreeMap<_, _>, BTreeMap<_, _>) = std::mem::take(&mut self.recent)
            .into_iter()
            .partition(|(to, _)| all || !self.said.contains_key(to));
        self.recent = wait;
        due.into_iter()
            .map(|(to, (n, _, why))| {
                self.said.insert(to, clock);
                format!(
                    "{} to {to} not sent: {why}",
                    crate::counts::counted(n, "datagram")
                )
            })
            .collect()
    }

    /// Datagrams not sent since the start.
    pub(super) fn total(&self) -> u64 {
        self.total
    }
}

/// Sends what the bridge has queued, one frame a datagram (as MAVLink on UDP goes), to
/// every peer and `--to` address.
pub(super) fn send_udp(
    bridge: &mut Bridge,
    socket: &UdpSocket,
    to: &[SocketAddr],
    clients: &mut Clients,
) {
    let Clients {
        peers,
        splitter,
        unsent,
        ..
    } = clients;
    loop {
        let bytes = bridge.transmit_bytes().to_vec();
        if bytes.is_empty() {
            break;
        }
        bridge.transmit_written(bytes.len());
        splitter.feed(&bytes, |frame| {
            for peer in peers.addrs().chain(to.iter()) {
                // UDP: a datagram that cannot go now is lost, as on any MAVLink link, and
                // counted.
                if let Err(e) = socket.send_to(frame.bytes(), peer) {
                    unsent.count(socket, *peer, &e);
                }
            }
            Check::Unhandled
        });
    }
}

/// A datagram from `from` with `good` frames the bridge handled: the peer table kept, and
/// what changed said.
fn heard(clients: &mut Clients, from: SocketAddr, good: u32, clock: StdInstant) {
    let Clients { peers, log, .. } = clients;
    let (len, capacity) = (peers.len(), peers.capacity());
    let silent = PEER_TIMEOUT.as_secs();
    match peers.heard(from, good, clock) {
        Some(Change::Joined(new)) => log.say(clock, PeerEvent::Joined, || {
            format!("peer {new} joined ({} of {capacity})", len + 1)
        }),
        Some(Change::Replaced { old, new }) => log.say(clock, PeerEvent::Joined, || {
            format!("peer {new} joined, replacing {old} (silent {silent} s)")
        }),
        Some(Change::Refused(new)) if log.first_refusal(new) => {
            log.say(clock, PeerEvent::Refused, || {
                format!(
                    "warning: peer {new} refused: all {capacity} slots hold live peers \
                     (a peer is dropped after {silent} s of silence)"
                )
            })
        }
        Some(Change::Refused(_)) | None => {}
    }
}

/// Reads up to [`DATAGRAMS_PER_TICK`] datagrams into the bridge, each on its own, keeping
/// the peer table; whether the socket was emptied.
#[allow(clippy::too_many_arguments)] // the loop's state, lent for one tick
pub(super) fn receive_udp<M: Medium>(
    bridge: &mut Bridge,
    link: &mut Link<8, 8, M>,
    socket: &UdpSocket,
    to: &[SocketAddr],
    clients: &mut Clients,
    buf: &mut [u8],
    t: Instant,
    clock: StdInstant,
    mut move_gimbal: impl FnMut(&mut Link<8, 8, M>) -> Result<(), Failure>,
) -> Result<bool, Failure> {
    let Clients { peers, log, .. } = clients;
    log.tick(clock);
    peers.expire(clock, |gone| {
        log.say(clock, PeerEvent::Left, || {
            format!("peer {gone} left (silent {} s)", PEER_TIMEOUT.as_secs())
        });
    });
    for _ in 0..DATAGRAMS_PER_TICK {
        match socket.recv_from(buf) {
            Ok((n, from)) => {
                // Taken up to a frame whose answer would not fit the outbox, the answers so
                // far sent, the rest offered again: every request answered in full. Its
                // answers at once, too: a burst of datagrams never piles up in the outbox.
                let mut at = 0;
                while at < n {
                    let taken = bridge.receive_datagram(link, &buf[at..n], t);
                    at += taken.bytes;
                    // Before sending: a peer that joins hears its first answers.
                    if !to.contains(&from) {
                        heard(clients, from, taken.good, clock);
                    }
                    send_udp(bridge, socket, to, clients);
                }
                // What the datagram asked of the gimbal leaves before the next is read: a
                // client that sends again as soon as it is answered (QGroundControl's pinch,
                // five zoom steps a command) never finds the gimbal's queue still full.
                move_gimbal(link)?;
            }
            Err(e) => match recv_error(e.kind()) {
                RecvError::Emptied => return Ok(true),
                RecvError::ReadOn => {}
                RecvError::Fatal => return Err(Failure::io("UDP socket", e)),
            },
        }
    }
    Ok(false)
}

/// What an error from the socket's `recv_from` means to [`receive_udp`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RecvError {
    /// Nothing more to read this tick.
    Emptied,
    /// Nothing lost: read on.
    ReadOn,
    /// The socket cannot be read: `gimbalctl mavlink` stops.
    Fatal,
}

fn recv_error(kind: ErrorKind) -> RecvError {
    match kind {
        ErrorKind::WouldBlock => RecvError::Emptied,
        // A peer that went away (ICMP port unreachable, reported by some systems on the
        // next read) must not stop the bridge; nor a signal.
        ErrorKind::ConnectionReset | ErrorKind::ConnectionRefused | ErrorKind::Interrupted => {
            RecvError::ReadOn
        }
        _ => RecvError::Fatal,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A destination is said at the first note after its first refusal, then at most every
    /// `UNSENT_EVERY` with what came since; at the end (`all`) whatever is left; the total
    /// counts every one.
    #[test]
    fn refusals_are_said_first_at_once_then_every_ten_seconds() {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        let to: SocketAddr = "127.0.0.1:9".parse().unwrap();
        let refused = || io::Error::from(ErrorKind::WouldBlock);
        let t0 = StdInstant::now();
        let mut unsent = Unsent::default();
        assert!(unsent.lines(t0, false).is_empty());
        for _ in 0..3 {
            unsent.count(&socket, to, &refused());
        }
        let first = unsent.lines(t0, false);
        assert_eq!(first.len(), 1);
        assert!(
            first[0].starts_with("3 datagrams to 127.0.0.1:9 not sent: "),
            "{first:?}"
        );
        unsent.count(&socket, to, &refused());
        unsent.count(&socket, to, &refused());
        assert!(unsent.lines(t0 + Duration::from_secs(9), false).is_empty());
        let again = unsent.lines(t0 + UNSENT_EVERY, false);
        assert!(
            again.len() == 1 && again[0].starts_with("2 datagrams to "),
            "{again:?}"
        );
        unsent.count(&socket, to, &refused());
        let last = unsent.lines(t0 + UNSENT_EVERY + Duration::from_secs(1), true);
        assert!(
            last.len() == 1 && last[0].starts_with("1 datagram to "),
            "{last:?}"
        );
        assert_eq!(unsent.total(), 6);
        assert!(unsent.lines(t0 + 3 * UNSENT_EVERY, true).is_empty());
        // The reason is the latest error's.
        unsent.count(&socket, to, &refused());
        unsent.count(&socket, to, &io::Error::from(ErrorKind::PermissionDenied));
        let latest = unsent.lines(t0 + 4 * UNSENT_EVERY, false);
        assert!(
            latest.len() == 1
                && latest[0].starts_with("2 datagrams to ")
                && latest[0].ends_with("(a broadcast address is not sent to)"),
            "{latest:?}"
        );
    }

    /// The remedy for a loopback listener is given only where it applies: a destination
    /// off this host, from a socket that listens on a loopback address.
    #[test]
    fn the_loopback_remedy_is_said_only_where_it_applies() {
        let hint = "(listening on 127.0.0.1:";
        let reason = |listen: &str, to: &str| {
            let socket = UdpSocket::bind(listen).unwrap();
            let mut unsent = Unsent::default();
            let to: SocketAddr = to.parse().unwrap();
            unsent.count(&socket, to, &io::Error::from(ErrorKind::NetworkUnreachable));
            let lines = unsent.lines(StdInstant::now(), true);
            assert_eq!(lines.len(), 1);
            lines[0].clone()
        };
        let off_host = reason("127.0.0.1:0", "192.0.2.1:14550");
        assert!(
            off_host.contains(hint)
                && off_host
                    .ends_with("a loopback address: --listen 0.0.0.0:PORT reaches other hosts)"),
            "{off_host}"
        );
        let on_host = reason("127.0.0.1:0", "127.0.0.1:14550");
        assert!(!on_host.contains("(listening on"), "{on_host}");
        let all_addresses = reason("0.0.0.0:0", "192.0.2.1:14550");
        assert!(!all_addresses.contains("(listening on"), "{all_addresses}");
    }

    /// Only an empty socket ends a tick's reading; a peer gone or a signal is read past;
    /// anything else stops the bridge.
    #[test]
    fn each_receive_error_is_read_past_or_fatal() {
        assert_eq!(recv_error(ErrorKind::WouldBlock), RecvError::Emptied);
        for kind in [
            ErrorKind::ConnectionReset,
            ErrorKind::ConnectionRefused,
            ErrorKind::Interrupted,
        ] {
            assert_eq!(recv_error(kind), RecvError::ReadOn, "{kind:?}");
        }
        for kind in [
            ErrorKind::PermissionDenied,
            ErrorKind::NotConnected,
            ErrorKind::InvalidInput,
            ErrorKind::TimedOut,
            ErrorKind::OutOfMemory,
            ErrorKind::Other,
        ] {
            assert_eq!(recv_error(kind), RecvError::Fatal, "{kind:?}");
        }
    }
}
