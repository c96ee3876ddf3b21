//! The serial driver against the simulated gimbal over the in-memory serial pipe, through
//! both adapters (`embedded-io` 0.7 and `embedded-hal-nb`), with every fault the pipe has.

#![cfg(feature = "mock")]

mod common;

use common::Host;

use core::num::NonZeroU32;

use idu_gimbal::geo::Position;
use idu_gimbal::link::Config;
use idu_gimbal::mock::serial::{Pipe, PipeStats, Rx, SerialFaults, Tx};
use idu_gimbal::port::{Io, Nb, SerialPort, Uart};
use idu_gimbal::sim::serial::SerialSimulator;
use idu_gimbal::sim::SimConfig;
use idu_gimbal::wire::control::{Command, GimbalCommand, Heading, Pitch, Rate};
use idu_gimbal::wire::postback::{Postback, MESSAGE_LEN};
use idu_gimbal::wire::serial::{control_frame, StreamItem, StreamParser, FRAME_LEN};
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::{Event, Instant};
use idu_gimbal::{Port, SerialLink};

const N: usize = 256;

/// The driver on port 0, the simulated gimbal on port 1. Everything the gimbal receives
/// also goes through a parser of the test's own, so the test sees each command that
/// arrived.
struct Bench<'p, P: Uart> {
    host: Host<SerialPort<P>, 8, 0>,
    sim: SerialSimulator<512>,
    sim_port: Io<Rx<'p, N>, Tx<'p, N>>,
    sniffer: StreamParser,
    /// Control frames the gimbal received, in order.
    arrived: Vec<[u8; 8]>,
    /// Postbacks the gimbal sent, and those the driver delivered.
    sent_postbacks: Vec<Postback>,
    /// Errors the gimbal's side of the pipe returned.
    sim_errors: u32,
}

fn io_port(pipe: &Pipe<N>, index: usize) -> Io<Rx<'_, N>, Tx<'_, N>> {
    let (rx, tx) = pipe.port(index).unwrap();
    Io::new(rx, tx)
}

fn nb_port(pipe: &Pipe<N>, index: usize) -> Nb<Rx<'_, N>, Tx<'_, N>> {
    let (rx, tx) = pipe.port(index).unwrap();
    Nb::new(rx, tx)
}

impl<'p, P: Uart> Bench<'p, P> {
    fn new(pipe: &'p Pipe<N>, port: P, sim_config: SimConfig, start: u32) -> Self {
        Bench {
            host: Host::new(
                SerialLink::new(Config::default()),
                SerialPort::new(port),
                start,
            ),
            sim: SerialSimulator::new(sim_config, Instant::from_millis(start)),
            sim_port: io_port(pipe, 1),
            sniffer: StreamParser::new(),
            arrived: Vec::new(),
            sent_postbacks: Vec::new(),
            sim_errors: 0,
        }
    }

    /// One millisecond of both sides.
    fn tick(&mut self) {
        self.host.poll();
        let now = self.host.instant();
        // The gimbal's side, by hand so that the sniffer sees what arrives.
        let mut buf = [0u8; 64];
        loop {
            match self.sim_port.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    self.sim.receive(&buf[..n], now);
                    for item in self.sniffer.feed(&buf[..n]) {
                        if let StreamItem::Control(d) = item {
                            self.arrived.push(d);
                        }
                    }
                }
                // Nothing was consumed: the bytes after it are read next.
                Err(_) => self.sim_errors += 1,
            }
        }
        if let Some(p) = self.sim.poll(now) {
            self.sent_postbacks.push(p);
        }
        loop {
            let bytes = self.sim.transmit_bytes();
            if bytes.is_empty() {
                break;
            }
            match self.sim_port.write(bytes) {
                Ok(0) => break,
                Ok(n) => self.sim.transmit_written(n),
                Err(_) => {
                    self.sim_errors += 1;
                    break;
                }
            }
        }
        self.host.now = self.host.now.wrapping_add(1);
    }

    fn run(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick();
        }
    }

    fn latest(&self) -> Postback {
        self.host.latest()
    }
}

fn encode(c: GimbalCommand) -> [u8; 8] {
    Command::from(c).encode()
}

/// Every item of `got` is in `sent`, in the same order (a subsequence).
fn is_subsequence<T: PartialEq>(got: &[T], sent: &[T]) -> bool {
    let mut it = sent.iter();
    got.iter().all(|g| it.any(|s| s == g))
}

fn round_trip<P: Uart>(pipe: &Pipe<N>, port: P) {
    let mut b = Bench::new(pipe, port, SimConfig::default(), 0);
    b.host
        .send(GimbalCommand::Pitch(Pitch::new(-45.0).unwrap()));
    b.host
        .send(GimbalCommand::Heading(Heading::new(90.0).unwrap()));
    b.run(2_000);
    // Both commands arrived, whole and in order; the gimbal slewed there (60°/s).
    assert_eq!(
        b.arrived,
        [
            [0x0F, 0x08, 0x02, 0x3E, 0xFE, 0, 0, 0],
            [0x0F, 0x08, 0x01, 0x84, 0x03, 0, 0, 0]
        ]
    );
    let p = b.latest();
    assert_eq!((p.pitch, p.motor_heading), (-4500, 9000));
    // Nose-referenced: no vehicle attitude on the serial link, so heading = motor.
    assert_eq!(p.heading, 9000);
    assert!(b.host.link.is_link_up());
    assert_eq!(b.host.delivered, b.sent_postbacks);
    // Due at 500, 1000 and 1500 ms within the 2 s run (0 to 1999 ms).
    assert_eq!(b.sent_postbacks.len(), 3);
    assert_eq!(b.host.events.first().map(|e| e.1), Some(Event::LinkUp));
    let (l, s) = (b.host.link.stats(), b.host.port.stats());
    assert_eq!((l.frames_sent, s.bytes_sent), (2, 48));
    assert_eq!(l.postbacks, 3);
    assert_eq!(s.bytes_received, 3 * MESSAGE_LEN as u32);
    assert_eq!(s.stream.skipped_bytes, 0);
}

#[test]
fn round_trip_through_embedded_io() {
    let pipe: Pipe<N> = Pipe::new(1);
    let port = io_port(&pipe, 0);
    round_trip(&pipe, port);
}

#[test]
fn round_trip_through_embedded_hal_nb() {
    let pipe: Pipe<N> = Pipe::new(1);
    let port = nb_port(&pipe, 0);
    round_trip(&pipe, port);
}

/// A write side that takes one byte a call, and one that often takes nothing: every frame
/// is finished before the next starts, so the gimbal sees each whole, in order, with no
/// byte skipped.
#[test]
fn slow_writers_never_interleave_or_lose_a_frame() {
    for (faults, nb) in [
        (
            SerialFaults {
                max_write: 1,
                ..SerialFaults::NONE
            },
            true,
        ),
        (
            SerialFaults {
                max_write: 1,
                ..SerialFaults::NONE
            },
            false,
        ),
        (
            SerialFaults {
                max_write: 7,
                write_stall: 0.6,
                tx_error: 0.1,
                max_read: 5,
                ..SerialFaults::NONE
            },
            false,
        ),
    ] {
        let pipe: Pipe<N> = Pipe::new(3).with_faults(faults);
        let commands: Vec<GimbalCommand> = (0..40)
            .map(|i| GimbalCommand::Pitch(Pitch::new(-(i as f32)).unwrap()))
            .collect();
        let arrived = if nb {
            let mut b = Bench::new(&pipe, nb_port(&pipe, 0), SimConfig::default(), 0);
            send_all(&mut b, &commands);
            (b.arrived, b.sniffer.stats(), b.host.port.stats())
        } else {
            let mut b = Bench::new(&pipe, io_port(&pipe, 0), SimConfig::default(), 0);
            send_all(&mut b, &commands);
            (b.arrived, b.sniffer.stats(), b.host.port.stats())
        };
        let expected: Vec<[u8; 8]> = commands.iter().map(|&c| encode(c)).collect();
        assert_eq!(arrived.0, expected, "{faults:?}");
        assert_eq!(
            (
                arrived.1.skipped_bytes,
                arrived.1.crc_errors,
                arrived.1.invalid_frames
            ),
            (0, 0, 0)
        );
        assert_eq!(arrived.2.bytes_sent, 40 * FRAME_LEN as u32);
        assert_eq!(pipe.stats(0).unwrap().written, 40 * FRAME_LEN as u32);
    }
}

/// Sends every command, waiting for room in the queue, then runs until all went out.
fn send_all<P: Uart>(b: &mut Bench<P>, commands: &[GimbalCommand]) {
    for &c in commands {
        while b.host.link.send(c).is_err() {
            b.tick();
        }
        b.tick();
    }
    b.run(1_000);
}

#[test]
fn the_dead_man_stops_the_gimbal_over_serial() {
    let pipe: Pipe<N> = Pipe::new(5);
    let mut b = Bench::new(&pipe, io_port(&pipe, 0), SimConfig::default(), 0);
    let rate = Rate::new(20.0, 0.0).unwrap();
    // Refreshed every 20 ms from 0 to 980 ms, then released.
    for _ in 0..50 {
        b.host.link.set_rate(rate, b.host.instant()).unwrap();
        b.run(20);
    }
    let last_refresh = 980;
    let yaw_at_release = b.sim.sim().state().motor_yaw_deg;
    b.run(1_000);
    // The dead-man (250 ms) fires at the first poll more than 250 ms after the last
    // refresh; until then the rate repeats every 50 ms: at 0, 50, …, 1200 ms, 25 frames.
    // Then exactly one zero-rate frame.
    let zero = encode(GimbalCommand::Rate(Rate::new(0.0, 0.0).unwrap()));
    assert_eq!(b.arrived.last(), Some(&zero));
    assert_eq!(b.arrived.iter().filter(|&&d| d == zero).count(), 1);
    let repeats = b
        .arrived
        .iter()
        .filter(|&&d| d == encode(GimbalCommand::Rate(rate)))
        .count();
    assert_eq!(repeats, 25);
    let expired: Vec<u32> = b
        .host
        .events
        .iter()
        .filter(|e| e.1 == Event::RateHoldExpired)
        .map(|e| e.0)
        .collect();
    assert_eq!(expired, [last_refresh + 251]);
    // The gimbal turned while held and stopped: yaw at 20°/s for about 1 s, and the zero
    // rate reached it within the dead-man (250 ms) plus the sim's own 200 ms rate timeout.
    // Read at 1,000 ms: 20°/s since the first command's 24 bytes arrived, 1 ms after it
    // left, so 999 ms, 19.98° (the simulator integrates exactly; `f32` sums keep 3e-4 of it).
    assert!((yaw_at_release - 19.98).abs() < 0.01, "{yaw_at_release}");
    let stopped = b.sim.sim().state().motor_yaw_deg;
    b.run(500);
    assert_eq!(b.sim.sim().state().motor_yaw_deg, stopped);
    assert_eq!(b.sim.sim().state().rate, (0.0, 0.0));
    assert!(
        stopped - yaw_at_release < 20.0 * 0.251 + 0.01,
        "{stopped} vs {yaw_at_release}"
    );
}

/// The serial link carries no vehicle frames: the gimbal references headings to the nose,
/// and point-at aims from the vehicle heading it observes.
#[test]
fn headings_are_nose_referenced_and_point_at_aims_from_the_vehicle_heading() {
    let pipe: Pipe<N> = Pipe::new(9);
    let mut b = Bench::new(
        &pipe,
        io_port(&pipe, 0),
        SimConfig {
            slew_dps: f32::INFINITY,
            ..SimConfig::default()
        },
        0,
    );
    let here = (47.397_742, 8.545_594, 450.0);
    // A target 1 km due east of the vehicle, 450 m lower (ground level).
    let east = Position::new(
        here.0,
        here.1 + 1_000.0 / (111_320.0 * here.0.to_radians().cos()),
        0.0,
    )
    .unwrap();
    let observe = |b: &mut Bench<_>| {
        let now = b.host.instant();
        b.host
            .link
            .set_attitude(Attitude::new(0.0, 0.0, 30.0).unwrap(), now);
        b.host.link.set_gps(Gps::new(here.0, here.1).unwrap(), now);
        b.host
            .link
            .set_altitude(Altitude::new(here.2).unwrap(), now);
    };
    observe(&mut b);
    b.host.link.point_at(east);
    for _ in 0..10 {
        observe(&mut b);
        b.run(100);
    }
    // Bearing 90° from a nose at 30°: 60° right of the nose; elevation atan(450/1000) down.
    let s = b.sim.sim().state();
    assert!((s.motor_yaw_deg - 60.0).abs() < 0.2, "{}", s.motor_yaw_deg);
    let elevation = -(450.0_f32 / 1_000.0).atan().to_degrees();
    assert!(
        (s.pitch_deg - elevation).abs() < 0.2,
        "{} vs {elevation}",
        s.pitch_deg
    );
    // No vehicle frame ever went out: nothing but control frames arrived.
    assert_eq!(b.sniffer.stats().skipped_bytes, 0);
    assert_eq!(b.sim.sim().stats().vehicle_frames, 0);
    assert!(b.arrived.iter().all(|d| d[0] == 0x0F && d[1] == 0x08));
}

/// 10^6 bytes and more through a line that loses, corrupts and splits: no wrong postback or
/// command, and every byte is accounted for on both sides.
#[test]
fn soak_a_million_bytes_with_loss_corruption_and_random_splits() {
    let faults = SerialFaults {
        loss: 0.001,
        corruption: 0.001,
        max_read: 9,
        max_write: 11,
        write_stall: 0.2,
        rx_error: 0.01,
        tx_error: 0.01,
    };
    let pipe: Pipe<N> = Pipe::new(0x5eed).with_faults(faults);
    let sim_config = SimConfig {
        postback_period_ms: NonZeroU32::new(2).unwrap(),
        ..SimConfig::default()
    };
    let mut b = Bench::new(&pipe, io_port(&pipe, 0), sim_config, u32::MAX - 20_000);
    let mut sent = Vec::new();
    let mut i = 0u32;
    while pipe.stats(0).unwrap().written + pipe.stats(1).unwrap().written < 1_000_000 {
        let c = GimbalCommand::Pitch(Pitch::new(-((i % 10_000) as f32) / 100.0).unwrap());
        if b.host.link.send(c).is_ok() {
            sent.push(encode(c));
            i += 1;
        }
        b.tick();
    }
    b.run(100);
    let (to_gimbal, to_fc) = (pipe.stats(0).unwrap(), pipe.stats(1).unwrap());
    assert!(to_gimbal.lost > 0 && to_gimbal.corrupted > 0 && to_fc.lost > 0 && to_fc.corrupted > 0);
    // No wrong item got through either way (CRC-16 and the fixed bytes).
    assert!(
        is_subsequence(&b.arrived, &sent),
        "a command that was never sent arrived"
    );
    assert!(
        is_subsequence(&b.host.delivered, &b.sent_postbacks),
        "a wrong postback was delivered"
    );
    // Most got through: loss and corruption hit about 0.2 % of bytes, so about 5 % of frames.
    assert!(
        b.arrived.len() * 10 > sent.len() * 8,
        "{} of {}",
        b.arrived.len(),
        sent.len()
    );
    let received = b.host.link.stats().postbacks as usize;
    assert!(
        received * 10 > b.sent_postbacks.len() * 8,
        "{received} of {}",
        b.sent_postbacks.len()
    );
    // Each poll shows the newest postback only: two arriving in one poll show as one.
    assert!(b.host.delivered.len() <= received && b.host.delivered.len() * 2 > received);
    // Every byte is accounted for, on the wire and in each parser.
    let accounted = |s: PipeStats, pending: usize| {
        assert_eq!(
            s.written,
            s.delivered + s.lost + s.overruns + pending as u32,
            "{s:?}"
        );
    };
    accounted(to_gimbal, pipe.pending(1).unwrap());
    accounted(to_fc, pipe.pending(0).unwrap());
    let g = b.host.port.stats();
    assert_eq!(g.bytes_sent, to_gimbal.written);
    assert_eq!(g.bytes_received, to_fc.delivered);
    assert_eq!(
        g.bytes_received,
        g.stream.postbacks * MESSAGE_LEN as u32
            + g.stream.control_frames * FRAME_LEN as u32
            + g.stream.skipped_bytes
            + b.host.port.stream().parser().pending() as u32
    );
    let p = b.sim.parser().stats();
    assert_eq!(
        to_gimbal.delivered,
        p.postbacks * MESSAGE_LEN as u32
            + p.control_frames * FRAME_LEN as u32
            + p.skipped_bytes
            + b.sim.parser().pending() as u32
    );
    assert_eq!(p.control_frames as usize, b.arrived.len());
    // Each read or write error the pipe injected was counted by the driver.
    let e = b.host.port.stats().port_errors;
    assert!(e.read > 0 && e.write > 0);
    assert_eq!(
        e.read + e.write + b.sim_errors,
        to_gimbal.errors + to_fc.errors
    );
}

/// A scripted `embedded-hal-nb` half: each call takes the next step.
struct Script<T> {
    steps: std::collections::VecDeque<nb::Result<T, Fault>>,
    written: Vec<u8>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Fault(u8);

impl embedded_hal_nb::serial::Error for Fault {
    fn kind(&self) -> embedded_hal_nb::serial::ErrorKind {
        embedded_hal_nb::serial::ErrorKind::Overrun
    }
}

impl<T> Script<T> {
    fn new(steps: impl IntoIterator<Item = nb::Result<T, Fault>>) -> Self {
        Script {
            steps: steps.into_iter().collect(),
            written: Vec::new(),
        }
    }
    fn next(&mut self) -> nb::Result<T, Fault> {
        self.steps.pop_front().unwrap_or(Err(nb::Error::WouldBlock))
    }
}

impl<T> embedded_hal_nb::serial::ErrorType for Script<T> {
    type Error = Fault;
}

impl embedded_hal_nb::serial::Read<u8> for Script<u8> {
    fn read(&mut self) -> nb::Result<u8, Fault> {
        self.next()
    }
}

impl embedded_hal_nb::serial::Write<u8> for Script<()> {
    fn write(&mut self, word: u8) -> nb::Result<(), Fault> {
        let r = self.next();
        if r.is_ok() {
            self.written.push(word);
        }
        r
    }
    fn flush(&mut self) -> nb::Result<(), Fault> {
        Ok(())
    }
}

/// An error after some words were moved is returned by the next call: neither the words
/// nor the error are lost.
#[test]
fn the_nb_adapter_keeps_an_error_that_follows_words() {
    let rx = Script::new([Ok(1), Ok(2), Err(nb::Error::Other(Fault(1))), Ok(3)]);
    let tx = Script::new([
        Ok(()),
        Ok(()),
        Err(nb::Error::Other(Fault(2))),
        Ok(()),
        Err(nb::Error::WouldBlock),
        Ok(()),
    ]);
    let mut port = Nb::new(rx, tx);
    let mut buf = [0u8; 8];
    assert_eq!(port.read(&mut buf), Ok(2));
    assert_eq!(&buf[..2], &[1, 2]);
    // An empty read hands out the kept error and moves nothing (what `release` asks).
    assert_eq!(port.read(&mut []), Err(Fault(1)));
    assert_eq!(port.read(&mut buf), Ok(1));
    assert_eq!(buf[0], 3);
    assert_eq!(port.read(&mut buf), Ok(0));
    assert_eq!(port.write(&[10, 11, 12, 13]), Ok(2));
    assert_eq!(port.write(&[]), Err(Fault(2)));
    assert_eq!(port.write(&[12, 13]), Ok(1));
    assert_eq!(port.write(&[13]), Ok(1));
    // The halves, reached through the adapter: a word written there is not the adapter's.
    let (_, tx) = port.halves_mut();
    tx.steps.push_back(Ok(()));
    assert_eq!(embedded_hal_nb::serial::Write::write(tx, 14), Ok(()));
    let (_, tx) = port.release();
    assert_eq!(tx.written, [10, 11, 12, 13, 14]);
}

/// An error before any word was moved is returned by that same call, not a moment later
/// behind an empty read or write (which would read as "nothing to do").
#[test]
fn the_nb_adapter_returns_an_error_before_any_word_at_once() {
    let rx = Script::new([Err(nb::Error::Other(Fault(3))), Ok(7)]);
    let tx = Script::new([Err(nb::Error::Other(Fault(4))), Ok(())]);
    let mut port = Nb::new(rx, tx);
    let mut buf = [0u8; 4];
    assert_eq!(port.read(&mut buf), Err(Fault(3)));
    assert_eq!(port.read(&mut buf), Ok(1));
    assert_eq!(buf[0], 7);
    assert_eq!(port.write(&[20, 21]), Err(Fault(4)));
    assert_eq!(port.write(&[20]), Ok(1));
    let (_, tx) = port.release();
    assert_eq!(tx.written, [20]);
}

/// An `embedded-io` half that must never be read or written while it says it is not
/// ready (that call would block on a real UART).
struct Gate {
    ready: bool,
    calls: u32,
}

impl embedded_io::ErrorType for Gate {
    type Error = embedded_io::ErrorKind;
}

impl embedded_io::Read for Gate {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        assert!(self.ready, "read while not ready: it would block");
        self.calls += 1;
        buf[0] = 0xAA;
        Ok(1)
    }
}

impl embedded_io::ReadReady for Gate {
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(self.ready)
    }
}

impl embedded_io::Write for Gate {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        assert!(self.ready, "write while not ready: it would block");
        self.calls += 1;
        Ok(buf.len().min(3))
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

impl embedded_io::WriteReady for Gate {
    fn write_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(self.ready)
    }
}

#[test]
fn the_io_adapter_never_calls_what_would_block() {
    let gate = |ready| Gate { ready, calls: 0 };
    let mut port = Io::new(gate(false), gate(false));
    let mut buf = [0u8; 4];
    assert_eq!(port.read(&mut buf), Ok(0));
    assert_eq!(port.write(&[1, 2, 3, 4]), Ok(0));
    let mut port = Io::new(gate(true), gate(true));
    assert_eq!(port.read(&mut buf), Ok(1));
    assert_eq!(port.write(&[1, 2, 3, 4]), Ok(3));
    // An empty write or read asks nothing of the port.
    assert_eq!(port.write(&[]), Ok(0));
    assert_eq!(port.read(&mut []), Ok(0));
    // The halves, reached through the adapter: a half made not ready is not called.
    let (rx, tx) = port.halves_mut();
    (rx.ready, tx.ready) = (false, false);
    assert_eq!(port.read(&mut buf), Ok(0));
    assert_eq!(port.write(&[1, 2, 3, 4]), Ok(0));
    let (rx, tx) = port.release();
    assert_eq!((rx.calls, tx.calls), (1, 1));

    // Through the driver: a port that is never ready leaves the command queued.
    let mut link: SerialLink = SerialLink::new(Config::default());
    let mut port = SerialPort::new(Io::new(gate(false), gate(false)));
    link.send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()))
        .unwrap();
    for ms in 0..100 {
        port.poll(&mut link, Instant::from_millis(ms)).unwrap();
    }
    assert_eq!(link.stats().frames_sent, 0);
    assert!(link.has_transmit());
}

/// The port's UART, reached through the port: what is written or read there passes the
/// link by.
#[test]
fn the_uart_is_reachable_through_the_port_and_passes_the_link_by() {
    let pipe: Pipe<N> = Pipe::new(13);
    let mut link: SerialLink = SerialLink::new(Config::default());
    let mut port = SerialPort::new(io_port(&pipe, 0));
    let mut other = io_port(&pipe, 1);
    assert_eq!(port.uart_mut().write(b"hello"), Ok(5));
    let mut got = [0u8; 8];
    assert_eq!(other.read(&mut got), Ok(5));
    assert_eq!(&got[..5], b"hello");
    // A postback read through the UART never reaches the link.
    let bytes = Postback::default().to_stream_bytes();
    assert_eq!(other.write(&bytes), Ok(MESSAGE_LEN));
    let mut taken = [0u8; MESSAGE_LEN];
    assert_eq!(port.uart_mut().read(&mut taken), Ok(MESSAGE_LEN));
    assert_eq!(taken, bytes);
    port.poll(&mut link, Instant::from_millis(0)).unwrap();
    let s = link.stats();
    assert_eq!((s.frames_sent, s.postbacks), (0, 0));
    assert!(!link.is_link_up());
}

/// A backlog larger than one poll reads (`max_rx_per_poll` reads of up to 32 bytes) is
/// taken over the following polls, every byte of it: the bound spreads the work, it
/// never drops anything.
#[test]
fn a_backlog_beyond_the_per_poll_bound_is_read_over_later_polls() {
    let pipe: Pipe<N> = Pipe::new(11).with_faults(SerialFaults {
        max_read: 3,
        ..SerialFaults::NONE
    });
    let config = Config {
        max_rx_per_poll: core::num::NonZeroU16::new(2).unwrap(),
        ..Config::default()
    };
    let mut gimbal: SerialLink = SerialLink::new(config);
    let mut port = SerialPort::new(io_port(&pipe, 0));
    let mut sim_port = io_port(&pipe, 1);
    // Nine postbacks (243 bytes) waiting at once.
    let sent: Vec<Postback> = (0..9)
        .map(|i| Postback {
            pitch: -100 * i,
            ..Postback::default()
        })
        .collect();
    for p in &sent {
        assert_eq!(sim_port.write(&p.to_stream_bytes()), Ok(MESSAGE_LEN));
    }
    let mut got = Vec::new();
    let mut polls = 0;
    while pipe.pending(0).unwrap() > 0 {
        port.poll(&mut gimbal, Instant::from_millis(polls)).unwrap();
        polls += 1;
        // At most 2 reads of at most 3 bytes a poll.
        assert!(port.stats().bytes_received <= 6 * polls);
        if gimbal.next_event().is_some() {
            got.push(
                gimbal
                    .latest_postback(Instant::from_millis(polls))
                    .unwrap()
                    .0,
            );
        }
        while gimbal.next_event().is_some() {}
    }
    assert_eq!(port.stats().bytes_received, 9 * MESSAGE_LEN as u32);
    assert_eq!(gimbal.stats().postbacks, 9);
    assert_eq!(got, sent);
}

/// A UART that says it read or wrote `over` bytes more than the buffer it was given holds
/// (0: exactly the buffer, the contract's edge): each read hands out the stream form of
/// one postback in a buffer of zeros, each write takes all it was given.
struct Overlong {
    postback: [u8; MESSAGE_LEN],
    reads_left: u32,
    written: Vec<u8>,
    over: usize,
}

impl Uart for Overlong {
    type ReadError = core::convert::Infallible;
    type WriteError = core::convert::Infallible;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::ReadError> {
        if self.reads_left == 0 {
            return Ok(0);
        }
        self.reads_left -= 1;
        buf.fill(0);
        buf[..MESSAGE_LEN].copy_from_slice(&self.postback);
        Ok(buf.len() + self.over)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<usize, Self::WriteError> {
        self.written.extend_from_slice(bytes);
        Ok(bytes.len() + self.over)
    }
}

/// One poll of a link's port over an [`Overlong`] UART reporting `over` bytes more: two
/// reads, each of `postback` in the 32-byte buffer, and a pitch command's frame written.
fn poll_over(postback: Postback, over: usize) -> (SerialLink, SerialPort<Overlong>) {
    let mut link: SerialLink = SerialLink::new(Config::default());
    let mut port = SerialPort::new(Overlong {
        postback: postback.to_stream_bytes(),
        reads_left: 2,
        written: Vec::new(),
        over,
    });
    link.send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()))
        .unwrap();
    port.poll(&mut link, Instant::from_millis(0)).unwrap();
    (link, port)
}

/// A UART that breaks its contract by saying it read or wrote more than the buffer held is
/// counted (`overlong`) each time, never silently: its buffer is taken whole (the postback
/// in it arrives, the zeros after it are skipped bytes), and a write it over-reports
/// finishes the frame once, with nothing written twice.
#[test]
fn a_uart_reporting_more_bytes_than_its_buffer_is_counted() {
    let postback = Postback {
        pitch: -1234,
        ..Postback::default()
    };
    let (link, port) = poll_over(postback, 3);

    // Two reads of the 32-byte buffer and one write of a whole frame, each over-reported.
    let stats = port.stats();
    assert_eq!(stats.port_errors.overlong, 3);
    assert_eq!((stats.port_errors.read, stats.port_errors.write), (0, 0));
    assert_eq!(stats.bytes_received, 64);
    assert_eq!(link.stats().postbacks, 2);
    assert_eq!(
        link.latest_postback(Instant::from_millis(0)).unwrap().0,
        postback
    );
    // The frame went out once, whole, and is counted as its 24 bytes.
    let pitch = encode(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()));
    assert_eq!(port.uart().written, control_frame(&pitch));
    assert_eq!(stats.bytes_sent, FRAME_LEN as u32);
    assert_eq!(link.stats().frames_sent, 1);
    assert!(!link.has_transmit());
}

/// A read that fills the whole buffer and a write that takes the whole frame, reported as
/// exactly that, are the contract kept: nothing counted.
#[test]
fn a_uart_reporting_exactly_its_buffer_is_not_counted() {
    let (link, port) = poll_over(Postback::default(), 0);
    let stats = port.stats();
    assert_eq!(stats.port_errors.overlong, 0);
    assert_eq!(
        (stats.bytes_received, stats.bytes_sent),
        (64, FRAME_LEN as u32)
    );
    assert_eq!(link.stats().postbacks, 2);
    let pitch = encode(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()));
    assert_eq!(port.uart().written, control_frame(&pitch));
}

#[test]
fn the_serial_simulator_takes_only_what_it_gave_from_an_overlong_write_report() {
    // Three postbacks, each written before the next: the third wraps in the 64-byte ring
    // (bytes 54 to 63, then 0 to 16), so the simulator gives 10 bytes, then 17. A port that
    // reports all 27 written after being given 10 wrote 10: the other 17 still wait.
    let mut sim: SerialSimulator =
        SerialSimulator::new(SimConfig::default(), Instant::from_millis(0));
    for ms in [500, 1000] {
        assert!(sim.poll(Instant::from_millis(ms)).is_some());
        assert_eq!(sim.transmit_bytes().len(), MESSAGE_LEN);
        sim.transmit_written(MESSAGE_LEN);
    }
    assert_eq!(sim.overlong_writes(), 0);
    assert!(sim.poll(Instant::from_millis(1500)).is_some());
    assert_eq!(sim.transmit_bytes().len(), 10);
    sim.transmit_written(MESSAGE_LEN);
    assert_eq!(sim.overlong_writes(), 1);
    assert_eq!(sim.transmit_bytes().len(), 17);
}
