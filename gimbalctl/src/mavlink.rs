//! `gimbalctl mavlink`: the library's MAVLink bridge (`idu-gimbal-mavlink`) between an
//! autopilot (UDP, or a serial port with `--autopilot-serial`) and a gimbal: the in-process
//! simulated gimbal (`--sim`), or a real one on any transport (`--tcp`, `--can`,
//! `--serial`; see [`crate::transport`]).
//!
//! One thread, non-blocking sockets, a 1 ms tick on the host's monotonic clock. Each tick
//! reads at most [`DATAGRAMS_PER_TICK`] datagrams, sending each one's answers and moving
//! the gimbal side before the next is read (so a burst of requests never piles up in the
//! bridge's outbox or the gimbal's command queue), then moves the gimbal side, polls the
//! bridge and sends, so a flood of datagrams cannot starve the
//! bridge's own traffic. A datagram of more requests than the outbox holds answers for is
//! taken in parts, each part's answers sent before the next part is offered
//! ([`idu_gimbal_mavlink::ANSWER_ROOM`]); on a serial port, the bytes after a frame waiting
//! for room are held and offered again first.
//!
//! Each datagram is parsed on its own ([`Bridge::receive_datagram`]): MAVLink on UDP carries
//! whole frames, so a frame cut at a datagram's end is dropped rather than joined to the next
//! datagram, which may come from another sender. A source address becomes a peer when one
//! of its datagrams held a frame the bridge handles with a good CRC (garbage never takes a
//! slot); any datagram keeps it; it is dropped after [`peers::PEER_TIMEOUT`] (10 s, ten
//! missed heartbeats) of silence. At most [`peers::PEER_CAPACITY`] (64) peers are kept, and
//! a live one is never evicted: when all slots hold live peers a new address is refused
//! (said once per address, and counted). What the bridge sends goes, one frame a datagram,
//! to every peer and to each `--to` address (those are permanent and outside the table);
//! a datagram the socket refuses is counted by address and said ([`udp::Unsent`]).
//! Joins, departures and refusals go to stderr, at most [`peer_log::PEER_LINES`] lines a second; the
//! lines held back are summed up after.
//!
//! On a serial port (`--autopilot-serial PATH[:BAUD]`, 921600 baud by default as the firmware
//! runs its TELEM port) the autopilot's bytes go to [`Bridge::receive`] as a stream, in any
//! split, and the bridge's bytes go back as the port takes them; a port that vanishes ends
//! the run (exit 1). UDP and the serial port are not mixed: the bridge is one MAVLink node
//! on one link (a router such as mavlink-router joins links).
//!
//! With `--sim` the gimbal is the library's `Simulator` on an in-memory CAN link (the `Link`
//! the firmware uses, so the vehicle attitude is pushed and headings are north-referenced as
//! on a real CAN bus), of the `--camera` family's gimbal type, holding in lock what
//! `--sim-lock-holds` says (its north heading, or its motor angle), restarted by a `reboot`
//! line on stdin, and what its camera does (tracking, focus, palette, calibration) goes to
//! stderr ([`sim_watch`]); with `--can` it is the library's link and `CanPort<C>` on the bus, and the
//! autopilot's attitude, GPS and altitude are pushed to the gimbal as the firmware does; with
//! `--tcp` or `--serial` it is the library's `SerialLink` and `SerialPort` (nose-referenced: the serial link
//! carries no vehicle frames).

use std::io::Write;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant as StdInstant};

use idu_gimbal::link::{Can, Config, Link, LinkStats, Medium};
use idu_gimbal::sim::{LockHolds, SimConfig, Simulator};
use idu_gimbal::video::{Camera, Family};
use idu_gimbal::wire::postback::GimbalType;
use idu_gimbal::Instant;
use idu_gimbal_mavlink::camera::fov::FieldOfView;
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::framing::FrameReader;
use idu_gimbal_mavlink::{Bridge, BridgeConfig};

use crate::counts::{counted, grown};
use crate::error::Failure;
use crate::tcp::{address, resolve, DefaultPort};
use crate::transport::stream::Ended;
use crate::transport::{
    self, clock, Job, Mode, SerialSpec, Session, StreamPort, Target, Transport,
};

mod peer_log;
mod peers;
mod signing;
mod sim_watch;
mod udp;

use peer_log::PeerLog;
use peers::{Peers, PEER_CAPACITY, PEER_TIMEOUT};
pub use signing::SigningKey;
use sim_watch::SimWatch;
use udp::{receive_udp, send_udp, Clients, Unsent};

/// How often the loop runs.
const TICK: Duration = Duration::from_millis(1);
/// Datagrams read at most per tick before the bridge is polled (each one's answers sent
/// before the next is read): a flood delays the bridge's own output (heartbeats, status) by
/// one such batch, never indefinitely.
pub const DATAGRAMS_PER_TICK: usize = 256;
/// The receive buffer: the largest UDP payload (65,507 bytes over IPv4) fits, so no datagram
/// is cut short, whatever number of frames it holds.
const DATAGRAM_BUFFER: usize = 65_536;
/// Serial reads at most per tick (4 KiB each: more than a tick of 921600 baud).
const SERIAL_READS_PER_TICK: usize = 16;
/// How often the gimbal side's faults (bus errors, bytes that held no frame) go to stderr.
const NOTE_EVERY: Duration = Duration::from_secs(1);

/// Where the gimbal is.
pub enum Gimbal<'a> {
    /// The in-process simulated gimbal.
    Sim,
    /// A gimbal on `--tcp`, `--can` or `--serial`.
    Target(&'a Target),
}

/// Where the autopilot (and any ground station) is.
pub enum Autopilot<'a> {
    /// MAVLink on UDP: listen here, also send to these.
    Udp { listen: &'a str, to: &'a [String] },
    /// MAVLink on a serial port (a TELEM port).
    Serial(&'a SerialSpec),
}

/// What the simulated gimbal holds in lock while the vehicle turns (`--sim-lock-holds`).
#[derive(Clone, Copy, PartialEq, Eq, Debug, clap::ValueEnum)]
pub enum SimLock {
    /// Its north heading, from the pushed attitude.
    North,
    /// Its motor angle: it turns with the vehicle.
    Motor,
}

/// What `gimbalctl mavlink` was asked to do.
pub struct Options<'a> {
    pub gimbal: Gimbal<'a>,
    pub autopilot: Autopilot<'a>,
    pub system_id: Option<u8>,
    pub camera: &'a str,
    /// `--camera-fov HFOV,VFOV`, unparsed.
    pub camera_fov: Option<&'a str>,
    /// `--camera-resolution WIDTHxHEIGHT`, unparsed.
    pub camera_resolution: Option<&'a str>,
    /// `--signing-passphrase` or `--signing-key-file`.
    pub signing: Option<SigningKey<'a>>,
    pub sim_lock_holds: SimLock,
    pub exit_after_ms: Option<u64>,
}

/// The gimbal side, moved each tick.
trait Pump {
    /// What the link to the gimbal carries.
    type Medium: Medium;
    /// Moves frames or bytes between the gimbal and the link; `Err` ends the run.
    fn pump(&mut self, link: &mut Link<8, 8, Self::Medium>, now: Instant) -> Result<(), Failure>;
    /// Faults new since the last call, for stderr (`link`: the link's counters).
    fn notes(&mut self, _link: &LinkStats) -> Vec<String> {
        Vec::new()
    }
}

/// The simulated gimbal on an in-memory CAN link.
struct SimSide {
    sim: Simulator,
    watch: SimWatch,
    /// Lines typed on stdin (`reboot`), from a thread that reads them.
    stdin: std::sync::mpsc::Receiver<String>,
}

/// Reads stdin's lines on a thread of their own (the loop never blocks on them): how a
/// user or a test drives the simulated gimbal (`reboot`). Ends at stdin's end.
fn stdin_lines() -> std::sync::mpsc::Receiver<String> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

impl Pump for SimSide {
    type Medium = Can;
    fn pump(&mut self, link: &mut Link, now: Instant) -> Result<(), Failure> {
        let side = self;
        link.poll(now);
        while let Some(f) = link.next_transmit() {
            link.transmit_done(None);
            let _ = side.sim.receive(f.id, &f.data, now);
        }
        let _ = side.sim.poll(now);
        while let Some(f) = side.sim.pop_frame() {
            link.receive(f.id, &f.data, now);
        }
        for change in side.watch.changes(side.sim.state()) {
            eprintln!("gimbalctl mavlink: {change}");
        }
        while let Ok(line) = side.stdin.try_recv() {
            match line.trim() {
                "reboot" => {
                    side.sim.reboot(now);
                    eprintln!(
                        "gimbalctl mavlink: simulated gimbal: rebooting ({} ms without postbacks)",
                        side.sim.config().boot_ms
                    );
                }
                "" => {}
                other => {
                    eprintln!("gimbalctl mavlink: stdin: unknown command {other:?} (known: reboot)")
                }
            }
        }
        Ok(())
    }
}

/// A real gimbal: the transport moves the link's frames.
struct TransportSide<T>(T);

impl<T: Transport> Pump for TransportSide<T> {
    type Medium = T::Medium;
    fn pump(&mut self, link: &mut Link<8, 8, T::Medium>, now: Instant) -> Result<(), Failure> {
        transport::pump(&mut self.0, link, now)
    }
    fn notes(&mut self, link: &LinkStats) -> Vec<String> {
        self.0.take_notes(link)
    }
}

/// The autopilot's link, open.
enum Port {
    Udp {
        socket: UdpSocket,
        to: Vec<SocketAddr>,
    },
    Serial(StreamPort),
}

/// `gimbalctl mavlink (--sim | --tcp HOST:PORT | --can IFACE | --serial PATH[:BAUD])
/// [--listen HOST:PORT] [--to HOST:PORT]... | --autopilot-serial PATH[:BAUD]`.
pub fn run(opts: &Options<'_>) -> Result<(), Failure> {
    let family =
        Family::from_name(opts.camera).map_err(|e| Failure::Usage(format!("--camera: {e}")))?;
    let mut camera = CameraConfig::with_streams_of(&Camera::new(family))
        .map_err(|e| Failure::Usage(format!("--camera: {e}")))?;
    camera.fov = opts.camera_fov.map(parse_fov).transpose()?;
    camera.resolution = opts.camera_resolution.map(parse_resolution).transpose()?;
    let config = BridgeConfig {
        system_id: opts.system_id,
        camera: Some(camera),
        signing: opts.signing.as_ref().map(signing::config).transpose()?,
        ..BridgeConfig::default()
    }
    .check()
    .map_err(|e| Failure::Usage(format!("gimbalctl mavlink: {e}")))?;
    let bridge = Bridge::new(config);
    // Every argument checked (exit 2) before anything is opened.
    let udp = match opts.autopilot {
        Autopilot::Udp { listen, to: tos } => {
            // Each address's form first (exit 2), then the lookups (exit 1).
            address("--listen", listen, DefaultPort::None)?;
            for t in tos {
                address("--to", t, DefaultPort::None)?;
            }
            let mut to = Vec::new();
            for t in tos {
                let addrs = resolve("--to", t, DefaultPort::None)?;
                to.extend(addrs.into_iter().take(1));
            }
            let addrs = resolve("--listen", listen, DefaultPort::None)?;
            Some((listen, addrs, to))
        }
        Autopilot::Serial(_) => None,
    };
    let (port, where_) = match (udp, &opts.autopilot) {
        (Some((listen, addrs, to)), _) => {
            let socket = UdpSocket::bind(&addrs[..])
                .map_err(|e| Failure::Runtime(format!("cannot listen on {listen}: {e}")))?;
            socket
                .set_nonblocking(true)
                .map_err(|e| Failure::io("UDP socket", e))?;
            let local = socket
                .local_addr()
                .map_err(|e| Failure::io("UDP socket", e))?;
            (Port::Udp { socket, to }, format!("listening on {local}"))
        }
        (None, Autopilot::Serial(spec)) => (
            Port::Serial(StreamPort::serial(spec, "--autopilot-serial")?),
            format!("autopilot on {} at {} baud", spec.path, spec.baud),
        ),
        (None, Autopilot::Udp { .. }) => unreachable!("checked above"),
    };
    let now = clock(StdInstant::now());
    match opts.gimbal {
        Gimbal::Sim => {
            // The simulated gimbal is of the family's type: the dual light's postback says
            // so, and the camera's model and zoom range follow it.
            let sim_config = SimConfig {
                gimbal_type: if family == Family::DualLight {
                    GimbalType::DualLight30x
                } else {
                    SimConfig::default().gimbal_type
                },
                lock_holds: match opts.sim_lock_holds {
                    SimLock::North => LockHolds::North,
                    SimLock::Motor => LockHolds::Motor,
                },
                ..SimConfig::default()
            };
            let side = SimSide {
                sim: Simulator::new(sim_config, now()),
                watch: SimWatch::default(),
                stdin: stdin_lines(),
            };
            announce(&where_, "the simulated gimbal (in-process, CAN)")?;
            let link = Link::new(Config::default());
            serve(bridge, link, side, port, now, opts.exit_after_ms)
        }
        Gimbal::Target(target) => {
            let mut what = target.describe();
            if target.carries_vehicle() {
                what.push_str(" (the autopilot's attitude, GPS and altitude pushed to it)");
            }
            target.run(
                Mode::Drive,
                Bridged {
                    bridge,
                    port,
                    announce: (where_, what),
                    exit_after_ms: opts.exit_after_ms,
                },
            )
        }
    }
}

/// `--camera-fov HFOV,VFOV`: degrees, each more than 0 and less than 180.
fn parse_fov(s: &str) -> Result<FieldOfView, Failure> {
    let usage = || {
        Failure::Usage(format!(
            "--camera-fov: {s:?} is not HFOV,VFOV in degrees (each more than 0 and less than 180)"
        ))
    };
    let (h, v) = s.split_once(',').ok_or_else(usage)?;
    let (h, v) = (
        h.trim().parse::<f32>().map_err(|_| usage())?,
        v.trim().parse::<f32>().map_err(|_| usage())?,
    );
    FieldOfView::from_degrees(h, v).map_err(|e| Failure::Usage(format!("--camera-fov: {e}")))
}

/// `--camera-resolution WIDTHxHEIGHT`: pixels, each 1-65535.
fn parse_resolution(s: &str) -> Result<(u16, u16), Failure> {
    let usage = || {
        Failure::Usage(format!(
            "--camera-resolution: {s:?} is not WIDTHxHEIGHT in pixels (each 1-65535)"
        ))
    };
    let (w, h) = s.split_once('x').ok_or_else(usage)?;
    match (w.parse::<u16>(), h.parse::<u16>()) {
        (Ok(w), Ok(h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(usage()),
    }
}

/// The bridge over an open gimbal session.
struct Bridged {
    bridge: Bridge,
    port: Port,
    announce: (String, String),
    exit_after_ms: Option<u64>,
}

impl Job for Bridged {
    type Out = ();

    fn run<T: Transport>(self, session: Session<T>) -> Result<(), Failure> {
        announce(&self.announce.0, &self.announce.1)?;
        let bridge = self.bridge;
        let now = clock(StdInstant::now());
        serve(
            bridge,
            session.link,
            TransportSide(session.transport),
            self.port,
            now,
            self.exit_after_ms,
        )
    }
}

/// The first stdout line says where the autopilot is reached (the UDP port, useful with
/// port 0) and what the gimbal is; flushed at once for scripts that wait for it.
fn announce(where_: &str, gimbal: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "gimbalctl mavlink: {where_}, gimbal: {gimbal}")
        .and_then(|()| out.flush())
        .map_err(Failure::stdout)
}

fn serve<S: Pump>(
    mut bridge: Bridge,
    mut link: Link<8, 8, S::Medium>,
    mut side: S,
    mut port: Port,
    now: impl Fn() -> Instant,
    exit_after_ms: Option<u64>,
) -> Result<(), Failure> {
    let start = StdInstant::now();
    let mut clients = Clients {
        peers: Peers::new(PEER_CAPACITY, PEER_TIMEOUT),
        log: PeerLog::new(start, std::io::stderr()),
        splitter: FrameReader::new(),
        unsent: Unsent::default(),
    };
    // Allocated once; see DATAGRAM_BUFFER.
    let mut buf = vec![0u8; DATAGRAM_BUFFER];
    // Serial bytes the bridge handed back (a frame waiting for room in its outbox).
    let mut held = Vec::new();
    let mut was_up = false;
    let mut notes_at = start + NOTE_EVERY;
    // Said at most once a NOTE_EVERY, as the count grows.
    let mut other_autopilots = [0u32];
    let mut refused_vehicle_updates = [0u32];
    // The reader's faults and the bridge's drops as last said.
    let mut reader_faults = [0u32; 3];
    let mut bridge_drops = [0u32; 3];
    let mut signing_turned = (0, 0, 0, 0);
    loop {
        if exit_after_ms.is_some_and(|ms| start.elapsed() >= Duration::from_millis(ms)) {
            if let Some(s) = bridge.signing_stats() {
                eprintln!("gimbalctl mavlink: signing: {}", signing::line(&s));
            }
            for line in clients.unsent.lines(StdInstant::now(), true) {
                eprintln!("gimbalctl mavlink: warning: {line}");
            }
            let unsent = clients.unsent.total();
            if unsent != 0 {
                eprintln!(
                    "gimbalctl mavlink: {} not sent in all",
                    counted(unsent, "datagram")
                );
            }
            eprintln!(
                "gimbalctl mavlink: exiting after {} ms",
                exit_after_ms.unwrap_or(0)
            );
            return Ok(());
        }
        let t = now();
        // The host's clock, when signing: the first signed frames already carry the time
        // receivers know.
        if bridge.signing_stats().is_some() {
            bridge.signing_time_at_least(signing::timestamp(std::time::SystemTime::now()));
        }
        let clock = StdInstant::now();
        let drained = match &mut port {
            Port::Udp { socket, to } => receive_udp(
                &mut bridge,
                &mut link,
                socket,
                to,
                &mut clients,
                &mut buf,
                t,
                clock,
                |link| side.pump(link, t),
            )?,
            Port::Serial(serial) => receive_serial(
                &mut bridge,
                &mut link,
                |b| serial.read_now(b),
                &mut buf,
                &mut held,
                t,
            )?,
        };
        side.pump(&mut link, t)?;
        bridge.poll(&mut link, t);
        let up = link.is_link_up();
        if up != was_up {
            eprintln!(
                "gimbalctl mavlink: gimbal link {}",
                if up { "up" } else { "down" }
            );
            was_up = up;
        }
        if clock >= notes_at {
            for note in side
                .notes(&link.stats())
                .into_iter()
                .chain(clients.unsent.lines(clock, false))
            {
                eprintln!("gimbalctl mavlink: warning: {note}");
            }
            let stats = bridge.stats();
            if let Some([n]) = grown([stats.other_autopilots], &mut other_autopilots) {
                eprintln!(
                    "gimbalctl mavlink: warning: {} of another autopilot ignored: following system {} (--system-id pins it)",
                    counted(n.into(), "heartbeat"),
                    bridge.system_id()
                );
            }
            if let Some([n]) = grown(
                [stats.refused_vehicle_updates],
                &mut refused_vehicle_updates,
            ) {
                eprintln!(
                    "gimbalctl mavlink: warning: {} not passed to the gimbal: a quaternion that gives no finite attitude, or a latitude or longitude out of range",
                    counted(n.into(), "vehicle update")
                );
            }
            // What came from the autopilot's link and held no frame for the bridge.
            let r = stats.reader;
            if let Some([skipped, bad, unsupported]) = grown(
                [r.skipped_bytes, r.bad_frames, r.unsupported],
                &mut reader_faults,
            ) {
                eprintln!(
                    "gimbalctl mavlink: warning: from the autopilot's link: {} that held no frame (MAVLink 1 among them: the bridge speaks MAVLink 2), {} whose checksum failed, {} with flags the bridge cannot read",
                    counted(skipped.into(), "byte"),
                    counted(bad.into(), "frame"),
                    counted(unsupported.into(), "frame"),
                );
            }
            // What the bridge could not follow or send.
            if let Some([refused, queue_full, outbox_full]) = grown(
                [stats.refused_setpoints, stats.queue_full, stats.outbox_full],
                &mut bridge_drops,
            ) {
                eprintln!(
                    "gimbalctl mavlink: warning: {} not followed (out of the gimbal's range, rolled, or in a frame that needs the vehicle's heading), {} the gimbal's queue had no room for, {} not sent (the outbox full)",
                    counted(refused.into(), "setpoint"),
                    counted(queue_full.into(), "command"),
                    counted(outbox_full.into(), "frame"),
                );
            }
            // Frames signing turned away, said as their count grows.
            if let Some(s) = bridge.signing_stats() {
                let turned = (s.unsigned, s.bad_signature, s.replayed, s.streams_full);
                if turned != signing_turned {
                    eprintln!("gimbalctl mavlink: warning: signing: {}", signing::line(&s));
                    signing_turned = turned;
                }
            }
            notes_at = clock + NOTE_EVERY;
        }
        match &mut port {
            Port::Udp { socket, to } => send_udp(&mut bridge, socket, to, &mut clients),
            // A byte stream: what the port takes now; the rest waits in the bridge.
            Port::Serial(serial) => loop {
                let bytes = bridge.transmit_bytes();
                if bytes.is_empty() {
                    break;
                }
                let n = serial.write_now(bytes).map_err(|e| Failure::Runtime(e.0))?;
                bridge.transmit_written(n);
                if n == 0 {
                    break;
                }
            },
        }
        // Datagrams or bytes still waiting: the next tick at once, so a burst is read at
        // full speed.
        if drained {
            std::thread::sleep(TICK);
        }
    }
}

/// Reads what the serial port has (bounded; `read` is the port's non-blocking read) into
/// the bridge as a byte stream; whether the port was emptied. A port that went away ends
/// the run.
fn receive_serial<M: Medium>(
    bridge: &mut Bridge,
    link: &mut Link<8, 8, M>,
    mut read: impl FnMut(&mut [u8]) -> Result<usize, Ended>,
    buf: &mut [u8],
    held: &mut Vec<u8>,
    t: Instant,
) -> Result<bool, Failure> {
    // The bytes after a frame that waited for room in the outbox, before anything newer.
    if !held.is_empty() {
        let taken = bridge.receive(link, held, t);
        held.drain(..taken);
        if !held.is_empty() {
            // Still waiting: the port keeps what came since until the outbox drains.
            return Ok(true);
        }
    }
    let chunk = buf.len().min(4096);
    for _ in 0..SERIAL_READS_PER_TICK {
        match read(&mut buf[..chunk]) {
            Ok(0) => return Ok(true),
            Ok(n) => {
                let taken = bridge.receive(link, &buf[..n], t);
                if taken < n {
                    held.extend_from_slice(&buf[taken..n]);
                    return Ok(true);
                }
            }
            Err(e) => return Err(Failure::Runtime(e.0)),
        }
    }
    Ok(false)
}

/// The bridge over the library's `CanPort<C>` on the core's in-memory CAN bus (the transport
/// `--can` runs over SocketCAN), with the library's simulated gimbal at the other end.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::can::CanTransport;
    use embedded_can::{nb::Can, Frame as _};
    use idu_gimbal::mock::{Bus, Endpoint, MockFrame};
    use idu_gimbal_mavlink::attitude::YawPitch;
    use idu_gimbal_mavlink::mavio;
    use mavio::dialects::common::enums::{GimbalDeviceFlags, MavAutopilot, MavType};
    use mavio::dialects::common::messages::{
        AutopilotStateForGimbalDevice, GimbalDeviceSetAttitude, GlobalPositionInt, Heartbeat,
    };
    use mavio::protocol::{Frame, V2};
    use mavio::Message;

    const AP: (u8, u8) = (1, 1);

    fn frame(seq: u8, message: &dyn Message) -> Vec<u8> {
        let f = Frame::builder()
            .version(V2)
            .sequence(seq)
            .system_id(AP.0)
            .component_id(AP.1)
            .message(message)
            .unwrap()
            .build();
        let mut buf = [0u8; 300];
        let n = f.serialize(&mut buf).unwrap();
        buf[..n].to_vec()
    }

    /// Each 1-65535 pixels, as `WIDTHxHEIGHT`; anything else is a usage error.
    #[test]
    fn a_camera_resolution_is_width_x_height() {
        assert_eq!(parse_resolution("1920x1080").unwrap(), (1920, 1080));
        assert_eq!(parse_resolution("1x65535").unwrap(), (1, 65535));
        for bad in [
            "0x1080",
            "1920x0",
            "65536x1",
            "1920",
            "1920X1080",
            "x",
            "-1x1",
            "",
        ] {
            assert!(
                matches!(parse_resolution(bad), Err(Failure::Usage(_))),
                "{bad:?}"
            );
        }
    }

    /// Degrees, `HFOV,VFOV`, each more than 0 and less than 180.
    #[test]
    fn a_camera_fov_is_two_angles() {
        let fov = parse_fov("61.9, 37.2").unwrap();
        assert_eq!(fov, FieldOfView::from_degrees(61.9, 37.2).unwrap());
        for bad in ["60", "60,180", "0,30", "60,", "a,b", ""] {
            assert!(matches!(parse_fov(bad), Err(Failure::Usage(_))), "{bad:?}");
        }
    }

    /// The autopilot's serial bytes that wait for room in the bridge's outbox go before
    /// anything newer: while they wait, the port is not read; once they are taken, it is.
    #[test]
    fn serial_bytes_held_for_the_outbox_go_first() {
        use mavio::dialects::common::enums::MavCmd;
        use mavio::dialects::common::messages::{CommandLong, GimbalDeviceInformation};
        let mut bridge = Bridge::new(BridgeConfig::default().check().unwrap());
        let mut link: Link = Link::new(Config::default());
        let now = Instant::from_millis(0);
        let request = CommandLong {
            target_system: 1,
            target_component: 154,
            command: MavCmd::RequestMessage,
            param1: GimbalDeviceInformation::spec().id() as f32,
            ..Default::default()
        };
        // More requests than the outbox has room to answer, in one read.
        let mut stream = Vec::new();
        for seq in 0..64 {
            stream.extend(frame(seq, &request));
        }
        let reads = std::cell::Cell::new(0);
        let mut port = [stream.clone(), frame(64, &request)].into_iter();
        let mut read = |buf: &mut [u8]| -> Result<usize, Ended> {
            reads.set(reads.get() + 1);
            let Some(chunk) = port.next() else {
                return Ok(0);
            };
            buf[..chunk.len()].copy_from_slice(&chunk);
            Ok(chunk.len())
        };
        let (mut buf, mut held) = (vec![0u8; 4096], Vec::new());
        let emptied = receive_serial(&mut bridge, &mut link, &mut read, &mut buf, &mut held, now);
        assert!(emptied.unwrap());
        assert_eq!(reads.get(), 1);
        assert!(
            !held.is_empty() && held.len() < stream.len(),
            "{}",
            held.len()
        );
        assert!(stream.ends_with(&held));
        // The outbox still full: the held bytes wait, and the port is not read.
        let before = held.len();
        let emptied = receive_serial(&mut bridge, &mut link, &mut read, &mut buf, &mut held, now);
        assert!(emptied.unwrap());
        assert_eq!((reads.get(), held.len()), (1, before));
        // Room made as the answers are sent: the held requests are taken, then the port
        // is read on.
        for _ in 0..stream.len() {
            if held.is_empty() {
                break;
            }
            let n = bridge.transmit_bytes().len();
            bridge.transmit_written(n);
            receive_serial(&mut bridge, &mut link, &mut read, &mut buf, &mut held, now).unwrap();
        }
        assert!(held.is_empty());
        assert!(reads.get() >= 2, "{}", reads.get());
    }

    type MockEnd<'a> = Endpoint<'a, 2, 64>;

    /// The gimbal's end of `bus` (endpoint 1), the bridge's gimbal side over CAN on the
    /// other (named `mock0`), and a new link.
    fn can_side(bus: &Bus<2, 64>) -> (MockEnd<'_>, TransportSide<CanTransport<MockEnd<'_>>>, Link) {
        let side = TransportSide(CanTransport::new(
            bus.endpoint(0).unwrap(),
            "mock0",
            Mode::Drive,
        ));
        (bus.endpoint(1).unwrap(), side, Link::new(Config::default()))
    }

    /// The gimbal side's notes: a postback whose CRC fails is said once, at the next
    /// note after it, with the count.
    #[test]
    fn a_real_gimbals_lost_postbacks_are_noted_as_they_grow() {
        use idu_gimbal::wire::ids;
        use idu_gimbal::wire::postback::Postback;
        let bus: Bus<2, 64> = Bus::new(5);
        let (mut gimbal_end, mut side, mut link) = can_side(&bus);
        let t = Instant::from_millis;
        let mut send = |frames: [[u8; 8]; 4]| {
            for data in frames {
                gimbal_end
                    .transmit(&MockFrame::extended(ids::POSTBACK, &data).unwrap())
                    .unwrap();
            }
        };
        send(Postback::default().to_can_frames());
        side.pump(&mut link, t(10)).unwrap();
        assert!(side.notes(&link.stats()).is_empty());
        let mut bad = Postback::default().to_can_frames();
        // A payload byte of the second frame flipped: the CRC no longer holds.
        bad[1][4] ^= 0x01;
        send(bad);
        side.pump(&mut link, t(20)).unwrap();
        let notes = side.notes(&link.stats());
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(
            notes[0].starts_with("mock0: postbacks lost: 1 with a bad CRC, 0 cut short")
                && notes[0].ends_with("postbacks so far: 1"),
            "{notes:?}"
        );
        assert!(side.notes(&link.stats()).is_empty());
    }

    #[test]
    fn the_autopilots_attitude_gps_and_altitude_reach_the_can_gimbal() {
        let bus: Bus<2, 64> = Bus::new(5);
        let (mut gimbal_end, mut side, mut link) = can_side(&bus);
        let mut bridge = Bridge::new(BridgeConfig::default().check().unwrap());
        let t = Instant::from_millis;
        let mut sim: Simulator = Simulator::new(SimConfig::default(), t(0));
        let heartbeat = Heartbeat {
            type_: MavType::Quadrotor,
            autopilot: MavAutopilot::Px4,
            mavlink_version: 3,
            ..Default::default()
        };
        let state = AutopilotStateForGimbalDevice {
            target_system: AP.0,
            target_component: 154,
            q: YawPitch {
                yaw_rad: 30f32.to_radians(),
                pitch_rad: 0.0,
            }
            .to_quaternion(),
            ..Default::default()
        };
        let position = GlobalPositionInt {
            lat: 473_977_420,
            lon: 85_455_940,
            alt: 488_123,
            ..Default::default()
        };
        let down = GimbalDeviceSetAttitude {
            target_system: AP.0,
            target_component: 154,
            flags: GimbalDeviceFlags::YAW_LOCK,
            q: YawPitch {
                yaw_rad: 0.0,
                pitch_rad: (-45f32).to_radians(),
            }
            .to_quaternion(),
            angular_velocity_x: f32::NAN,
            angular_velocity_y: f32::NAN,
            angular_velocity_z: f32::NAN,
        };
        for ms in (0..3_000u32).step_by(5) {
            let now = t(ms);
            if ms % 100 == 0 {
                let mut bytes = frame(0, &heartbeat);
                bytes.extend(frame(1, &state));
                bytes.extend(frame(2, &position));
                if ms >= 2_000 {
                    bytes.extend(frame(3, &down));
                }
                // A byte stream, as from --autopilot-serial, in two pieces.
                let (a, b) = bytes.split_at(bytes.len() / 3);
                // Drained every tick: every byte is taken at once.
                assert_eq!(bridge.receive(&mut link, a, now), a.len());
                assert_eq!(bridge.receive(&mut link, b, now), b.len());
            }
            side.pump(&mut link, now).unwrap();
            bridge.poll(&mut link, now);
            let n = bridge.transmit_bytes().len();
            bridge.transmit_written(n);
            while let Ok(f) = gimbal_end.receive() {
                let _ = sim.receive(f.raw_id(), f.data(), now);
            }
            let _ = sim.poll(now);
            while let Some(f) = sim.pop_frame() {
                gimbal_end
                    .transmit(&MockFrame::extended(f.id, &f.data).unwrap())
                    .unwrap();
            }
        }
        let state = sim.state();
        let att = state.vehicle.expect("the attitude pushed on CAN");
        assert!((att.heading_deg() - 30.0).abs() < 0.01, "{att:?}");
        let gps = state.gps.expect("the position pushed on CAN");
        assert_eq!((gps.lat_e7(), gps.lon_e7()), (473_977_420, 85_455_940));
        // MAVLink's millimetres above sea level, 488 123, in the document's centimetres:
        // 48 812.
        assert_eq!(state.altitude.map(|a| a.cm()), Some(48_812));
        assert!(state.north_referenced, "headings north-referenced on CAN");
        assert!(link.is_link_up());
        assert!(link.north_referenced(t(3_000)));
        // The setpoint became a pitch command on the bus.
        assert_eq!(state.target_pitch_deg, Some(-45.0));
        assert!(sim.stats().vehicle_frames >= 20, "{:?}", sim.stats());
    }
}
