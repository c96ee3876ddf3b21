//! `gimbalctl mavlink` on UDP: datagrams read into the bridge one at a time, each one's
//! answers sent before the next is read, one frame a datagram to every peer and `--to`
//! address; the peer table kept and what changed in it said ([`super::peer_log`]).

use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};
use std::time::Instant as StdInstant;

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
        peers, splitter, ..
    } = clients;
    loop {
        let bytes = bridge.transmit_bytes().to_vec();
        if bytes.is_empty() {
            break;
        }
        bridge.transmit_written(bytes.len());
        splitter.feed(&bytes, |frame| {
            for peer in peers.addrs().chain(to.iter()) {
                // UDP: a datagram that cannot go now is lost, as on any MAVLink link.
                let _ = socket.send_to(frame.bytes(), peer);
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
            Err(e) if e.kind() == ErrorKind::WouldBlock => return Ok(true),
            // A peer that went away (ICMP port unreachable) must not stop the bridge.
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::ConnectionReset | ErrorKind::ConnectionRefused
                ) => {}
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(Failure::io("UDP socket", e)),
        }
    }
    Ok(false)
}
