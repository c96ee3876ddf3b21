//! Where the gimbal is: exactly one of `--tcp HOST:PORT` (the Ethernet serial server),
//! `--can IFACE` (Linux SocketCAN) or `--serial PATH[:BAUD]` (the gimbal's UART), parsed,
//! checked and opened here and nowhere else.
//!
//! Every gimbal-facing command (`send`, `monitor`, `control`, `mavlink`) flattens
//! [`GimbalArgs`] into its arguments, turns it into a [`Target`] (usage errors, exit 2,
//! before anything is opened) and hands a [`Job`] to [`Target::run`], which opens the
//! transport and runs the job's one generic body over a [`Session`]: the library's link,
//! the one command surface, and the [`Transport`] that moves its frames:
//!
//! - `--tcp` and `--serial`: a [`StreamTransport`], the library's `SerialPort` over a
//!   non-blocking [`StreamPort`] (a `TcpStream`, or a `serialport` tty at BAUD 8N1);
//! - `--can`: a [`can::CanTransport`], the library's `CanPort<C>` over a [`can::Tap`] around
//!   any `embedded_can::nb::Can`: the SocketCAN socket in non-blocking mode here, the core's
//!   in-memory mock bus in the tests. Only the opening of the socket is SocketCAN's.
//!
//! What ends a session (exit 1, see [`Failure`]): a TCP connection the server closes, a
//! serial port that vanishes (a USB adapter pulled: an I/O error or a hang-up on the tty; the
//! command stops at once rather than wait for a device that may come back under another
//! name), a CAN interface that goes down or away. What does not end it but is counted and
//! shown: bytes that hold no frame (a wrong baud rate), bad CRCs, CAN error frames (bus-off,
//! error-passive, no ACK, ...), transmit refusals.

use std::ops::RangeInclusive;
use std::time::Instant as StdInstant;

use clap::Args;
use idu_gimbal::link::{Config, Link, LinkStats, Medium};
use idu_gimbal::Instant;

use crate::error::Failure;
use crate::tcp::DefaultPort;

pub mod can;
pub mod stream;

pub use can::Seen;
pub use stream::{StreamPort, StreamTransport};

/// The gimbal's UART: 115200 baud, 8N1 (the protocol document's).
pub const GIMBAL_BAUD: u32 = idu_gimbal::interface::UART_BAUD;
/// An autopilot's TELEM port as the firmware bridge runs it.
pub const AUTOPILOT_BAUD: u32 = 921_600;
/// Baud rates taken by `--serial` and `--autopilot-serial`.
pub const BAUD_RANGE: RangeInclusive<u32> = 50..=4_000_000;

/// `--tcp`, `--can` or `--serial`: exactly one (clap says so, exit 2, naming them).
#[derive(Args, Debug, Clone)]
#[group(id = "gimbal", required = true, multiple = false)]
pub struct GimbalArgs {
    /// The gimbal behind the Ethernet serial server (or gimbalctl sim), HOST:PORT (port 2000 when omitted)
    #[arg(long, value_name = "HOST:PORT")]
    pub tcp: Option<String>,
    /// The gimbal on a SocketCAN interface (Linux), e.g. can0 (1 Mbit/s, set with ip link)
    #[arg(long, value_name = "IFACE")]
    pub can: Option<String>,
    /// The gimbal's UART on a serial port: PATH, or PATH:BAUD (115200 8N1 when BAUD is omitted), e.g. /dev/ttyUSB0
    #[arg(long, value_name = "PATH[:BAUD]")]
    pub serial: Option<String>,
}

/// A serial port and its speed (8N1, no flow control).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SerialSpec {
    pub path: String,
    pub baud: u32,
}

impl SerialSpec {
    /// `PATH` or `PATH:BAUD`; `arg` names the option in the usage error. A suffix after the
    /// last `:` is a baud rate only when it is all digits, so paths with colons
    /// (`/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0-port0`) are taken whole.
    pub fn parse(arg: &str, text: &str, default_baud: u32) -> Result<SerialSpec, Failure> {
        let bad = |why: &str| {
            Failure::Usage(format!(
                "{arg} {text}: {why}; expected PATH[:BAUD] with BAUD in [{}, {}] (default {default_baud})",
                BAUD_RANGE.start(),
                BAUD_RANGE.end()
            ))
        };
        let (path, baud) = match text.rsplit_once(':') {
            Some((path, "")) => return Err(bad(&format!("no baud rate after {path}:"))),
            Some((path, digits)) if digits.bytes().all(|b| b.is_ascii_digit()) => {
                let baud = digits
                    .parse::<u32>()
                    .ok()
                    .filter(|b| BAUD_RANGE.contains(b))
                    .ok_or_else(|| bad(&format!("baud rate {digits} is out of range")))?;
                (path, baud)
            }
            _ => (text, default_baud),
        };
        if path.is_empty() {
            return Err(bad("no path"));
        }
        Ok(SerialSpec {
            path: path.to_owned(),
            baud,
        })
    }
}

/// A checked `--tcp`, `--can` or `--serial`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// The serial server, HOST:PORT.
    Tcp(String),
    /// A SocketCAN interface.
    Can(String),
    /// The gimbal's UART.
    Serial(SerialSpec),
}

impl Target {
    /// Checks the arguments (usage errors: exit 2). A host name is resolved here, so an
    /// unknown host fails before a terminal is taken over.
    pub fn from_args(args: &GimbalArgs) -> Result<Target, Failure> {
        match (&args.tcp, &args.can, &args.serial) {
            (Some(tcp), None, None) => {
                // Its form only: the name is looked up when the connection is opened, after
                // every other argument is checked.
                crate::tcp::address("--tcp", tcp, DefaultPort::SerialServer)?;
                Ok(Target::Tcp(tcp.clone()))
            }
            (None, Some(iface), None) => {
                can::check_name(iface)?;
                Ok(Target::Can(iface.clone()))
            }
            (None, None, Some(serial)) => Ok(Target::Serial(SerialSpec::parse(
                "--serial",
                serial,
                GIMBAL_BAUD,
            )?)),
            // clap's group makes this unreachable; a usage error all the same.
            _ => Err(Failure::Usage(
                "give exactly one of --tcp HOST:PORT, --can IFACE, --serial PATH[:BAUD]".into(),
            )),
        }
    }

    /// A longer description for a first line: what and where.
    pub fn describe(&self) -> String {
        match self {
            Target::Tcp(t) => format!("the serial server at {t}"),
            Target::Can(i) => format!("the CAN bus {i}"),
            Target::Serial(s) => format!("the UART on {} at {} baud 8N1", s.path, s.baud),
        }
    }

    /// Whether vehicle and text frames can be sent (CAN only: the serial link carries
    /// control commands and postbacks).
    pub fn carries_vehicle(&self) -> bool {
        matches!(self, Target::Can(_))
    }

    /// Opens the transport and runs `job` over it.
    pub fn run<J: Job>(&self, mode: Mode, job: J) -> Result<J::Out, Failure> {
        match self {
            Target::Tcp(t) => job.run(Session::new(StreamTransport::tcp(t, mode)?)),
            Target::Serial(s) => job.run(Session::new(StreamTransport::serial(s, mode)?)),
            Target::Can(iface) => can::run_socketcan(iface, mode, job),
        }
    }
}

/// What the session is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Commands and postbacks (`send`, `control`, `mavlink`).
    Drive,
    /// `monitor`: every received frame recorded, and at most one postback per poll, so
    /// that each is seen ([`Session::poll`], then the link's postback count).
    Monitor,
}

impl Mode {
    /// The link's timing for this mode, the transport's receive bound `per_poll`.
    pub fn config(self, per_poll: u16) -> Config {
        let mut config = Config::default();
        if self == Mode::Monitor {
            if let Some(n) = core::num::NonZeroU16::new(per_poll) {
                config.max_rx_per_poll = n;
            }
        }
        config
    }
}

/// A command body, generic over the transport.
pub trait Job {
    type Out;
    fn run<T: Transport>(self, session: Session<T>) -> Result<Self::Out, Failure>;
}

/// The gimbal end of one transport: the library's port, and what the host adds to it
/// (a name, faults in words, the end of the connection).
pub trait Transport {
    /// What the transport carries.
    type Medium: Medium;

    /// Whether this is the CAN bus (postbacks have an ID, other frames are seen).
    const IS_CAN: bool = false;

    /// How messages name the transport: `127.0.0.1:2000`, `/dev/ttyUSB0`, `can0`.
    fn name(&self) -> &str;

    /// The link's timing for the mode the transport was opened in (its receive bound,
    /// `max_rx_per_poll`, is the transport's).
    fn config(&self) -> Config;

    /// One poll of the library's port over `link`: a bounded receive, the link's
    /// schedules, what the port or bus takes now. `Err`: the connection, port or interface
    /// is gone (exit 1).
    fn poll(&mut self, link: &mut Link<8, 8, Self::Medium>, now: Instant) -> Result<(), Failure>;

    /// Whether the last poll emptied what was waiting (another poll would read nothing).
    fn drained(&self) -> bool;

    /// Whether anything waits to be written: queued on `link`, or part-written here.
    fn has_transmit(&self, link: &Link<8, 8, Self::Medium>) -> bool;

    /// Queues a text where the transport carries one (CAN); refused otherwise.
    fn send_text(link: &mut Link<8, 8, Self::Medium>, text: &[u8]) -> Result<(), String>;

    /// The link's and the transport's counters as lines for `control`'s panel (three).
    fn counters(&self, link: &LinkStats) -> [String; 3];

    /// Faults new since the last call, one line each for stderr: CAN error frames and
    /// postbacks lost on the bus (from `link`, the link's counters), bytes that held no
    /// frame.
    fn take_notes(&mut self, link: &LinkStats) -> Vec<String>;

    /// Frames received other than postbacks, in order, since the last call ([`Mode::Monitor`]
    /// on CAN; empty otherwise).
    fn take_frames(&mut self) -> Vec<Seen>;

    /// Ends the transport: written data is left to arrive (TCP: a gentle close).
    fn finish(self);
}

/// A gimbal reached through one transport: the link (commands, vehicle data, events,
/// postbacks, its counters) and the transport that moves its frames.
pub struct Session<T: Transport> {
    pub link: Link<8, 8, T::Medium>,
    pub transport: T,
}

impl<T: Transport> Session<T> {
    /// A session over `transport`, the link timed as the transport says.
    pub fn new(transport: T) -> Self {
        Session {
            link: Link::new(transport.config()),
            transport,
        }
    }

    /// One poll of the transport over the link.
    pub fn poll(&mut self, now: Instant) -> Result<(), Failure> {
        self.transport.poll(&mut self.link, now)
    }

    /// Polls until nothing more waits (see [`pump`]).
    pub fn pump(&mut self, now: Instant) -> Result<(), Failure> {
        pump(&mut self.transport, &mut self.link, now)
    }

    /// Whether anything waits to be written.
    pub fn has_transmit(&self) -> bool {
        self.transport.has_transmit(&self.link)
    }

    /// Queues a text (CAN only; the serial link carries none).
    pub fn send_text(&mut self, text: &[u8]) -> Result<(), String> {
        T::send_text(&mut self.link, text)
    }

    /// Faults new since the last call, for stderr ([`Transport::take_notes`]).
    pub fn take_notes(&mut self) -> Vec<String> {
        self.transport.take_notes(&self.link.stats())
    }

    /// The counters as lines for `control`'s panel (three).
    pub fn counters(&self) -> [String; 3] {
        self.transport.counters(&self.link.stats())
    }

    /// Ends the session (see [`Transport::finish`]).
    pub fn finish(self) {
        self.transport.finish()
    }
}

/// Polls `transport` over `link` until nothing more waits (at most 64 polls, so a flood
/// cannot stall the caller's loop).
pub fn pump<T: Transport>(
    transport: &mut T,
    link: &mut Link<8, 8, T::Medium>,
    now: Instant,
) -> Result<(), Failure> {
    for _ in 0..64 {
        transport.poll(link, now)?;
        if transport.drained() {
            break;
        }
    }
    Ok(())
}

/// The host's monotonic clock as the library's millisecond tick, from `start`.
pub fn clock(start: StdInstant) -> impl Fn() -> Instant + Copy {
    move || Instant::from_millis(start.elapsed().as_millis() as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serial_specs() {
        let p = |t: &str| SerialSpec::parse("--serial", t, GIMBAL_BAUD);
        assert_eq!(
            p("/dev/ttyUSB0").unwrap(),
            SerialSpec {
                path: "/dev/ttyUSB0".into(),
                baud: 115_200
            }
        );
        assert_eq!(p("/dev/ttyAMA0:921600").unwrap().baud, 921_600);
        assert_eq!(p("COM3:9600").unwrap().path, "COM3");
        let by_path = "/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0-port0";
        assert_eq!(p(by_path).unwrap().path, by_path);
        assert_eq!(p(&format!("{by_path}:57600")).unwrap().baud, 57_600);
        for bad in [
            "",
            ":115200",
            "/dev/ttyUSB0:",
            "/dev/ttyUSB0:0",
            "/dev/ttyUSB0:99999999999",
        ] {
            let m = usage_message(bad, p(bad));
            assert!(m.contains("--serial") && m.contains("[50, 4000000]"), "{m}");
        }
    }

    /// Each rejected form says what was wrong, whole.
    #[test]
    fn serial_spec_errors_say_what_was_wrong() {
        let message =
            |text: &str| usage_message(text, SerialSpec::parse("--serial", text, GIMBAL_BAUD));
        let expected = "; expected PATH[:BAUD] with BAUD in [50, 4000000] (default 115200)";
        for (text, why) in [
            ("/dev/ttyUSB0:", "no baud rate after /dev/ttyUSB0:"),
            ("/dev/ttyUSB0:49", "baud rate 49 is out of range"),
            ("/dev/ttyUSB0:4000001", "baud rate 4000001 is out of range"),
            (":115200", "no path"),
        ] {
            assert_eq!(message(text), format!("--serial {text}: {why}{expected}"));
        }
        // The bounds themselves are taken.
        for baud in [50, 4_000_000] {
            let spec = SerialSpec::parse("--serial", &format!("/dev/ttyS0:{baud}"), 0).unwrap();
            assert_eq!(spec.baud, baud);
        }
    }

    /// The message of a usage error; any other result fails the test, naming `input`.
    fn usage_message<T: std::fmt::Debug>(
        input: impl std::fmt::Debug,
        result: Result<T, Failure>,
    ) -> String {
        match result {
            Err(Failure::Usage(m)) => m,
            other => panic!("{input:?}: {other:?}"),
        }
    }

    fn gimbal(tcp: Option<&str>, can: Option<&str>, serial: Option<&str>) -> GimbalArgs {
        GimbalArgs {
            tcp: tcp.map(str::to_owned),
            can: can.map(str::to_owned),
            serial: serial.map(str::to_owned),
        }
    }

    /// Each option gives its own target, checked by its own rules.
    #[test]
    fn targets_from_each_option() {
        let target = |args: GimbalArgs| Target::from_args(&args);
        assert_eq!(
            target(gimbal(Some("127.0.0.1:2000"), None, None)).unwrap(),
            Target::Tcp("127.0.0.1:2000".into())
        );
        assert_eq!(
            target(gimbal(None, None, Some("/dev/ttyUSB0:9600"))).unwrap(),
            Target::Serial(SerialSpec {
                path: "/dev/ttyUSB0".into(),
                baud: 9600
            })
        );
        let usage = |args: GimbalArgs| usage_message(&args, Target::from_args(&args));
        assert_eq!(
            usage(gimbal(Some("gimbal:port"), None, None)),
            "--tcp \"gimbal:port\": expected HOST:PORT or HOST (port 2000) with PORT in [0, 65535]"
        );
        let one = "give exactly one of --tcp HOST:PORT, --can IFACE, --serial PATH[:BAUD]";
        assert_eq!(usage(gimbal(None, None, None)), one);
        assert_eq!(usage(gimbal(Some("h:1"), Some("can0"), None)), one);
        if cfg!(target_os = "linux") {
            assert_eq!(
                target(gimbal(None, Some("vcan0"), None)).unwrap(),
                Target::Can("vcan0".into())
            );
            assert_eq!(
                usage(gimbal(None, Some("can 0"), None)),
                "--can \"can 0\": not an interface name (1 to 15 characters, no '/', ':' or \
                 spaces), e.g. can0"
            );
        }
    }

    /// What a target is said to be, and which carry vehicle and text frames (CAN only).
    #[test]
    fn targets_described() {
        let serial = Target::Serial(SerialSpec {
            path: "/dev/ttyUSB0".into(),
            baud: 115_200,
        });
        let tcp = Target::Tcp("10.0.0.2:2000".into());
        let can = Target::Can("can0".into());
        assert_eq!(tcp.describe(), "the serial server at 10.0.0.2:2000");
        assert_eq!(can.describe(), "the CAN bus can0");
        assert_eq!(
            serial.describe(),
            "the UART on /dev/ttyUSB0 at 115200 baud 8N1"
        );
        assert_eq!(
            [&tcp, &can, &serial].map(Target::carries_vehicle),
            [false, true, false]
        );
    }
}
