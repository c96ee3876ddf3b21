//! `gimbalctl mavlink`: the library's MAVLink bridge (`idu-gimbal-mavlink`) on UDP, in front
//! of the in-process simulated gimbal (`--sim`) or the serial server (`--tcp`).
//!
//! One thread, non-blocking sockets, a 1 ms tick on the host's monotonic clock. Each tick
//! reads at most [`DATAGRAMS_PER_TICK`] datagrams, then moves the gimbal side, polls the
//! bridge and sends, so a flood of datagrams cannot starve the bridge's own traffic.
//!
//! Each datagram is parsed on its own ([`Bridge::receive_datagram`]): MAVLink on UDP carries
//! whole frames, so a frame cut at a datagram's end is dropped rather than joined to the next
//! datagram, which may come from another sender. A source address becomes a peer when one
//! of its datagrams held a frame the bridge handles with a good CRC (garbage never takes a
//! slot); any datagram keeps it; it is dropped after [`peers::PEER_TIMEOUT`] (10 s, ten
//! missed heartbeats) of silence. At most [`peers::PEER_CAPACITY`] (16) peers are kept: a new
//! one replaces the peer heard least recently, so no client is ever locked out. What the
//! bridge sends goes, one frame a datagram, to every peer and to each `--to` address (those
//! are permanent and outside the table). Joins, departures and replacements go to stderr.
//!
//! With `--sim` the gimbal is the library's `Simulator` on an in-memory CAN link (the `Link`
//! the firmware uses, so the vehicle attitude is pushed and headings are north-referenced as
//! on a real CAN bus); with `--tcp` it is the serial server, through the core's `SerialLink`
//! (nose-referenced: the serial link carries no vehicle frames).

use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream, UdpSocket};
use std::time::{Duration, Instant as StdInstant};

use idu_gimbal::link::serial::SerialLink;
use idu_gimbal::link::{Config, Link};
use idu_gimbal::sim::{SimConfig, Simulator};
use idu_gimbal::video::{Camera, Family, Stream};
use idu_gimbal::Instant;
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::framing::{Check, FrameReader};
use idu_gimbal_mavlink::{Bridge, BridgeConfig, GimbalControl};

use crate::error::Failure;

mod peers;

use peers::{Change, Peers, PEER_CAPACITY, PEER_TIMEOUT};

/// How often the loop runs.
const TICK: Duration = Duration::from_millis(1);
/// Datagrams read at most per tick before the bridge is polled and its frames sent: a
/// flood delays the bridge's own output (heartbeats, status, answers) by one such batch,
/// never indefinitely.
pub const DATAGRAMS_PER_TICK: usize = 256;
/// The receive buffer: the largest UDP payload (65,507 bytes over IPv4) fits, so no datagram
/// is cut short, whatever number of frames it holds.
const DATAGRAM_BUFFER: usize = 65_536;

/// Where the gimbal is.
pub enum Gimbal<'a> {
    /// The in-process simulated gimbal.
    Sim,
    /// The serial server (or `gimbalctl sim`), HOST:PORT.
    Tcp(&'a str),
}

/// What `gimbalctl mavlink` was asked to do.
pub struct Options<'a> {
    pub gimbal: Gimbal<'a>,
    pub listen: &'a str,
    pub to: &'a [String],
    pub system_id: Option<u8>,
    pub camera: &'a str,
    pub exit_after_ms: Option<u64>,
}

/// The gimbal side, moved each tick.
trait Pump {
    type G: GimbalControl;
    /// Moves frames or bytes between the gimbal and the link; `Err` ends the run.
    fn pump(bridge: &mut Bridge<Self::G>, side: &mut Self, now: Instant) -> Result<(), Failure>;
}

/// The simulated gimbal on an in-memory CAN link.
struct SimSide {
    sim: Simulator,
}

impl Pump for SimSide {
    type G = Link;
    fn pump(bridge: &mut Bridge<Link>, side: &mut Self, now: Instant) -> Result<(), Failure> {
        let link = bridge.gimbal_mut();
        link.poll(now);
        while let Some(f) = link.next_transmit() {
            link.transmit_done(None);
            let _ = side.sim.receive(f.id, &f.data, now);
        }
        let _ = side.sim.poll(now);
        while let Some(f) = side.sim.pop_frame() {
            link.receive(f.id, &f.data, now);
        }
        Ok(())
    }
}

/// The serial server over TCP.
struct TcpSide {
    stream: TcpStream,
    peer: String,
}

impl Pump for TcpSide {
    type G = SerialLink;
    fn pump(bridge: &mut Bridge<SerialLink>, side: &mut Self, now: Instant) -> Result<(), Failure> {
        let link = bridge.gimbal_mut();
        let mut buf = [0u8; 1024];
        loop {
            match side.stream.read(&mut buf) {
                Ok(0) => {
                    return Err(Failure::Runtime(format!(
                        "{}: the serial server closed the connection",
                        side.peer
                    )))
                }
                Ok(n) => link.receive(&buf[..n], now),
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(Failure::io(&side.peer, e)),
            }
        }
        link.poll(now);
        loop {
            let bytes = link.transmit_bytes();
            if bytes.is_empty() {
                break;
            }
            match side.stream.write(bytes) {
                Ok(n) => link.transmit_written(n),
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    link.transmit_written(0);
                    break;
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(Failure::io(&side.peer, e)),
            }
        }
        Ok(())
    }
}

/// `gimbalctl mavlink (--sim | --tcp HOST:PORT) [--listen ADDR] [--to ADDR]...`.
pub fn run(opts: &Options<'_>) -> Result<(), Failure> {
    let family =
        Family::from_name(opts.camera).map_err(|e| Failure::Usage(format!("--camera: {e}")))?;
    let uri = Camera::new(family)
        .url(Stream::Main)
        .map_err(|e| Failure::Usage(format!("--camera: {e}")))?;
    let camera = CameraConfig::new(&uri).map_err(|e| Failure::Usage(format!("--camera: {e}")))?;
    let mut to = Vec::new();
    for t in opts.to {
        let addrs = crate::net::resolve(t)
            .map_err(|_| Failure::Usage(format!("--to: {t:?} is not a HOST:PORT address")))?;
        to.extend(addrs.into_iter().take(1));
    }
    let listen = crate::net::resolve(opts.listen).map_err(|_| {
        Failure::Usage(format!(
            "--listen: {:?} is not a HOST:PORT address",
            opts.listen
        ))
    })?;
    let config = BridgeConfig {
        system_id: opts.system_id,
        camera: Some(camera),
        ..BridgeConfig::default()
    };
    let socket = UdpSocket::bind(&listen[..])
        .map_err(|e| Failure::Runtime(format!("cannot listen on {}: {e}", opts.listen)))?;
    socket
        .set_nonblocking(true)
        .map_err(|e| Failure::io("UDP socket", e))?;
    let local = socket
        .local_addr()
        .map_err(|e| Failure::io("UDP socket", e))?;
    let start = StdInstant::now();
    let now = move || Instant::from_millis(start.elapsed().as_millis() as u32);
    match opts.gimbal {
        Gimbal::Sim => {
            let bridge = Bridge::new(Link::new(Config::default()), config);
            let side = SimSide {
                sim: Simulator::new(SimConfig::default(), now()),
            };
            announce(local, "the simulated gimbal (in-process, CAN)")?;
            serve(bridge, side, &socket, &to, now, opts.exit_after_ms)
        }
        Gimbal::Tcp(target) => {
            let stream = crate::net::connect(target)?;
            stream
                .set_nonblocking(true)
                .map_err(|e| Failure::io(target, e))?;
            let _ = stream.set_nodelay(true);
            let bridge = Bridge::new(SerialLink::new(Config::default()), config);
            let side = TcpSide {
                stream,
                peer: target.to_string(),
            };
            announce(local, &format!("the serial server at {target}"))?;
            serve(bridge, side, &socket, &to, now, opts.exit_after_ms)
        }
    }
}

/// The first stdout line says where we listen (useful with port 0); flushed at once for
/// scripts that wait for it.
fn announce(local: SocketAddr, gimbal: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "gimbalctl mavlink: listening on {local}, gimbal: {gimbal}"
    )
    .and_then(|()| out.flush())
    .map_err(Failure::stdout)
}

fn serve<S: Pump>(
    mut bridge: Bridge<S::G>,
    mut side: S,
    socket: &UdpSocket,
    to: &[SocketAddr],
    now: impl Fn() -> Instant,
    exit_after_ms: Option<u64>,
) -> Result<(), Failure> {
    let start = StdInstant::now();
    let mut peers = Peers::new(PEER_CAPACITY, PEER_TIMEOUT);
    // Allocated once; see DATAGRAM_BUFFER.
    let mut buf = vec![0u8; DATAGRAM_BUFFER];
    let mut was_up = false;
    let mut splitter = FrameReader::new();
    loop {
        if exit_after_ms.is_some_and(|ms| start.elapsed() >= Duration::from_millis(ms)) {
            eprintln!(
                "gimbalctl mavlink: exiting after {} ms",
                exit_after_ms.unwrap_or(0)
            );
            return Ok(());
        }
        let t = now();
        let clock = StdInstant::now();
        peers.expire(clock, |gone| {
            eprintln!(
                "gimbalctl mavlink: peer {gone} left (silent {} s)",
                PEER_TIMEOUT.as_secs()
            );
        });
        let mut drained = false;
        for _ in 0..DATAGRAMS_PER_TICK {
            match socket.recv_from(&mut buf) {
                Ok((n, from)) => {
                    let good = bridge.receive_datagram(&buf[..n], t);
                    if to.contains(&from) {
                        continue;
                    }
                    match peers.heard(from, good, clock) {
                        Some(Change::Joined(new)) => eprintln!(
                            "gimbalctl mavlink: peer {new} joined ({} of {})",
                            peers.len(),
                            peers.capacity()
                        ),
                        Some(Change::Replaced { old, new }) => eprintln!(
                            "gimbalctl mavlink: peer {new} joined, replacing {old} \
                             (all {} slots taken; {old} heard least recently)",
                            peers.capacity()
                        ),
                        None => {}
                    }
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    drained = true;
                    break;
                }
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
        S::pump(&mut bridge, &mut side, t)?;
        bridge.poll(t);
        let up = bridge.gimbal().is_link_up();
        if up != was_up {
            eprintln!(
                "gimbalctl mavlink: gimbal link {}",
                if up { "up" } else { "down" }
            );
            was_up = up;
        }
        // One frame a datagram, as MAVLink on UDP goes.
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
        // Datagrams still waiting: the next tick at once, so a burst is read at full speed.
        if drained {
            std::thread::sleep(TICK);
        }
    }
}
