//! The CAN transport: the library's `CanPort<C>` over a [`Tap`] around any
//! `embedded_can::nb::Can` driver: a SocketCAN socket in non-blocking mode on Linux, the
//! core's in-memory mock bus in the tests (the same session code, only the socket's opening
//! differs).
//!
//! The tap passes every call through unchanged and notes, for the session: each frame
//! received (for `monitor`, which shows the frames the port does not take: control,
//! vehicle, text, foreign IDs), each driver error by what it says (CAN error frames: bus-off,
//! error-passive, no ACK, ...), and an error that means the interface is gone.

use std::cell::RefCell;
use std::fmt::Write as _;
use std::rc::Rc;

use embedded_can::{nb::Can, Frame as _, Id};
use idu_gimbal::link::{Can as CanMedium, Config, Link, LinkStats};
use idu_gimbal::port::{CanPort, Port};
use idu_gimbal::Instant;

use super::{Mode, Transport};
use crate::counts::grown;
use crate::error::Failure;

/// What a CAN driver's error means to the user.
pub trait BusFault {
    /// In words, with a hint where one helps (`bus off: ...`).
    fn describe(&self) -> String;
    /// Whether the interface is gone (down, removed): the session ends.
    fn is_fatal(&self) -> bool;
}

/// A received frame, as `monitor` shows it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Seen {
    pub id: Id,
    pub remote: bool,
    /// The length code: the data's length, or for a remote frame the length it asks for.
    pub dlc: usize,
    pub data: Vec<u8>,
}

impl Seen {
    /// The raw ID (11 or 29 bits).
    pub fn raw_id(&self) -> u32 {
        match self.id {
            Id::Standard(id) => u32::from(id.as_raw()),
            Id::Extended(id) => id.as_raw(),
        }
    }

    /// The ID as candump writes it: 3 hex digits standard, 8 extended.
    pub fn id_text(&self) -> String {
        match self.id {
            Id::Standard(id) => format!("{:03X}", id.as_raw()),
            Id::Extended(id) => format!("{:08X}", id.as_raw()),
        }
    }

    /// Whether this is an extended data frame on `id`.
    pub fn is(&self, id: u32) -> bool {
        !self.remote && matches!(self.id, Id::Extended(e) if e.as_raw() == id)
    }
}

/// A driver error of one kind: how many, how many already told.
#[derive(Debug)]
struct Fault {
    what: String,
    count: u64,
    told: u64,
}

/// What the tap noted, shared with the session.
#[derive(Debug, Default)]
pub struct TapLog {
    /// Record received frames (monitor).
    record: bool,
    frames: Vec<Seen>,
    faults: Vec<Fault>,
    last_fault: Option<String>,
    fatal: Option<String>,
}

impl TapLog {
    fn fault(&mut self, what: String, fatal: bool) {
        if fatal && self.fatal.is_none() {
            self.fatal = Some(what.clone());
        }
        // Bounded: a driver has few kinds of error, but an error frame's text can carry a
        // number (the bit where arbitration was lost); past MAX_KINDS kinds, the rest are
        // counted together.
        let first = |what: String| Fault {
            what,
            count: 1,
            told: 0,
        };
        let full = self.faults.len() >= MAX_KINDS;
        match self.faults.iter_mut().find(|f| f.what == what) {
            Some(f) => f.count += 1,
            None if !full => self.faults.push(first(what.clone())),
            None => match self.faults.iter_mut().find(|f| f.what == MORE_KINDS) {
                Some(f) => f.count += 1,
                None => self.faults.push(first(MORE_KINDS.to_owned())),
            },
        }
        self.last_fault = Some(what);
    }
}

/// The kinds of driver error [`TapLog`] counts apart.
const MAX_KINDS: usize = 64;

/// Where [`TapLog`] counts the kinds beyond [`MAX_KINDS`].
const MORE_KINDS: &str = "errors of other kinds";

/// The received-frame bound of [`TapLog`] between two `take_frames` (a monitor that stops
/// reading them loses the oldest rather than grow without end).
const MAX_FRAMES: usize = 4096;

/// An `embedded_can::nb::Can` driver with its traffic noted in a shared [`TapLog`].
pub struct Tap<C> {
    can: C,
    log: Rc<RefCell<TapLog>>,
}

impl<C> Tap<C> {
    /// Wraps `can`; the log is shared with whoever else holds it.
    pub fn new(can: C, log: Rc<RefCell<TapLog>>) -> Self {
        Tap { can, log }
    }
}

impl<C> Can for Tap<C>
where
    C: Can,
    C::Error: BusFault,
{
    type Frame = C::Frame;
    type Error = C::Error;

    fn transmit(&mut self, frame: &C::Frame) -> nb::Result<Option<C::Frame>, C::Error> {
        let r = self.can.transmit(frame);
        if let Err(nb::Error::Other(e)) = &r {
            self.log.borrow_mut().fault(e.describe(), e.is_fatal());
        }
        r
    }

    fn receive(&mut self) -> nb::Result<C::Frame, C::Error> {
        let r = self.can.receive();
        let mut log = self.log.borrow_mut();
        match &r {
            Ok(f) if log.record => {
                if log.frames.len() >= MAX_FRAMES {
                    log.frames.remove(0);
                }
                log.frames.push(Seen {
                    id: f.id(),
                    remote: f.is_remote_frame(),
                    dlc: f.dlc(),
                    data: f.data().to_vec(),
                });
            }
            Ok(_) | Err(nb::Error::WouldBlock) => {}
            Err(nb::Error::Other(e)) => log.fault(e.describe(), e.is_fatal()),
        }
        r
    }
}

/// The library's `CanPort<C>` over a tapped CAN driver.
pub struct CanTransport<C> {
    port: CanPort<Tap<C>>,
    log: Rc<RefCell<TapLog>>,
    name: String,
    /// The link's timing for the mode opened in.
    config: Config,
    /// Whether the last poll consumed fewer frames and errors than its bound.
    drained: bool,
    /// The link's postback faults as last said: CRC errors, partials dropped for a gap,
    /// restarts, malformed frames.
    postback_faults: [u32; 4],
}

/// Frames one poll receives in [`Mode::Monitor`]: a postback is four frames, so one poll
/// completes at most one.
const MONITOR_FRAMES: u16 = 4;

impl<C> CanTransport<C>
where
    C: Can,
    C::Error: BusFault,
{
    /// A transport on `can`, named `name` (the interface) in messages.
    pub fn new(can: C, name: &str, mode: Mode) -> Self {
        let log = Rc::new(RefCell::new(TapLog {
            record: mode == Mode::Monitor,
            ..TapLog::default()
        }));
        CanTransport {
            port: CanPort::new(Tap::new(can, log.clone())),
            log,
            name: name.to_owned(),
            config: mode.config(MONITOR_FRAMES),
            drained: true,
            postback_faults: [0; 4],
        }
    }

    /// Frames received and driver errors so far: what a poll's receive loop consumed.
    fn consumed(&self, link: &Link) -> u64 {
        u64::from(link.stats().frames_received) + u64::from(self.port.stats().driver_errors.total())
    }
}

impl<C> Transport for CanTransport<C>
where
    C: Can,
    C::Error: BusFault,
{
    type Medium = CanMedium;
    const IS_CAN: bool = true;

    fn name(&self) -> &str {
        &self.name
    }

    fn config(&self) -> Config {
        self.config
    }

    fn poll(&mut self, link: &mut Link, now: Instant) -> Result<(), Failure> {
        let before = self.consumed(link);
        // A driver error is counted by the port and noted by the tap; the poll went on.
        let _ = self.port.poll(link, now);
        let consumed = self.consumed(link).wrapping_sub(before);
        self.drained = consumed < u64::from(self.config.max_rx_per_poll.get());
        match &self.log.borrow().fatal {
            Some(why) => Err(Failure::Runtime(format!("{}: {why}", self.name))),
            None => Ok(()),
        }
    }

    fn drained(&self) -> bool {
        self.drained
    }

    fn has_transmit(&self, link: &Link) -> bool {
        link.has_transmit()
    }

    fn send_text(link: &mut Link, text: &[u8]) -> Result<(), String> {
        link.send_text(text).map_err(|e| format!("{e:?}"))
    }

    fn counters(&self, s: &LinkStats) -> [String; 3] {
        let log = self.log.borrow();
        let errors: u64 = log.faults.iter().map(|f| f.count).sum();
        [
            format!(
                "postbacks {}  crc errors {}  frames received {}  other frames {}",
                s.postbacks, s.crc_errors, s.frames_received, s.ignored_frames
            ),
            format!(
                "frames sent {}  queue full {}  requeued {}",
                s.frames_sent, s.queue_full, s.requeued
            ),
            match &log.last_fault {
                Some(last) => format!("bus errors {errors}  last: {last}"),
                None => "bus errors 0".to_owned(),
            },
        ]
    }

    fn take_notes(&mut self, link: &LinkStats) -> Vec<String> {
        let mut log = self.log.borrow_mut();
        let name = self.name.clone();
        let mut notes: Vec<String> = log
            .faults
            .iter_mut()
            .filter(|f| f.count > f.told)
            .map(|f| {
                let new = f.count - f.told;
                f.told = f.count;
                let mut line = format!("{name}: {}", f.what);
                let _ = write!(line, " ({new} new, {} in all)", f.count);
                line
            })
            .collect();
        // Postbacks the link could not take (a corrupt or cut frame on the bus), said as
        // their counts grow; a stream transport says its own bytes.
        let faults = [
            link.crc_errors,
            link.dropped_partials,
            link.restarts,
            link.malformed,
        ];
        if let Some([crc, gap, restart, malformed]) = grown(faults, &mut self.postback_faults) {
            notes.push(format!(
                "{name}: postbacks lost: {crc} with a bad CRC, {gap} cut short (a frame missing \
                 or late), {restart} restarted by a new header, {malformed} postback-ID frames \
                 not 8 bytes; postbacks so far: {}",
                link.postbacks
            ));
        }
        notes
    }

    fn take_frames(&mut self) -> Vec<Seen> {
        std::mem::take(&mut self.log.borrow_mut().frames)
    }

    fn finish(self) {}
}

/// `--can IFACE`: a network interface name (1 to 15 bytes, no `/`, no whitespace); on a
/// system without SocketCAN, a usage error.
pub fn check_name(iface: &str) -> Result<(), Failure> {
    if cfg!(not(target_os = "linux")) {
        return Err(Failure::Usage(format!(
            "--can {iface}: SocketCAN exists only on Linux; here use --serial PATH[:BAUD] \
             (the gimbal's UART) or --tcp HOST:PORT (its serial server)"
        )));
    }
    let ok = (1..=15).contains(&iface.len())
        && !iface.contains('/')
        && !iface.chars().any(|c| c.is_whitespace() || c == ':')
        && iface != "."
        && iface != "..";
    if ok {
        Ok(())
    } else {
        Err(Failure::Usage(format!(
            "--can {iface:?}: not an interface name (1 to 15 characters, no '/', ':' or \
             spaces), e.g. can0"
        )))
    }
}

/// Opens `iface` with SocketCAN and runs `job` over it.
#[cfg(target_os = "linux")]
pub fn run_socketcan<J: super::Job>(iface: &str, mode: Mode, job: J) -> Result<J::Out, Failure> {
    let socket = socketcan_open::open(iface)?;
    job.run(super::Session::new(CanTransport::new(socket, iface, mode)))
}

/// SocketCAN is Linux only ([`check_name`] already said so).
#[cfg(not(target_os = "linux"))]
pub fn run_socketcan<J: super::Job>(iface: &str, _mode: Mode, _job: J) -> Result<J::Out, Failure> {
    check_name(iface).map(|()| unreachable!("SocketCAN is Linux only"))
}

#[cfg(target_os = "linux")]
mod socketcan_open {
    //! Opening a SocketCAN interface, with the state of the interface read from
    //! /sys/class/net first so that the usual mistakes get their own message. The one part
    //! of the CAN path the tests cannot run without a (v)can interface.

    use std::path::Path;

    use socketcan::{CanSocket, Socket, SocketOptions};

    use super::BusFault;
    use crate::error::Failure;

    /// ARPHRD_CAN, /sys/class/net/IFACE/type of a CAN interface.
    const ARPHRD_CAN: u32 = 280;
    /// IFF_UP in /sys/class/net/IFACE/flags.
    const IFF_UP: u32 = 0x1;

    fn read_sys(iface: &str, what: &str) -> Option<String> {
        std::fs::read_to_string(Path::new("/sys/class/net").join(iface).join(what))
            .ok()
            .map(|s| s.trim().to_owned())
    }

    /// The CAN interfaces of this machine, for the messages.
    fn can_interfaces() -> String {
        let mut names: Vec<String> = std::fs::read_dir("/sys/class/net")
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| e.file_name().into_string().ok())
            .filter(|n| read_sys(n, "type").and_then(|t| t.parse().ok()) == Some(ARPHRD_CAN))
            .collect();
        names.sort();
        if names.is_empty() {
            "none".into()
        } else {
            names.join(", ")
        }
    }

    /// Opens `iface`: it must exist, be a CAN interface, and be up. The socket is
    /// non-blocking and receives error frames (counted and shown as bus errors).
    pub fn open(iface: &str) -> Result<CanSocket, Failure> {
        let Some(ty) = read_sys(iface, "type") else {
            return Err(Failure::Runtime(format!(
                "--can {iface}: no such network interface (CAN interfaces here: {}); a USB \
                 CAN adapter not plugged in, or a HAT's overlay not loaded? For a virtual bus: \
                 sudo modprobe vcan && sudo ip link add dev vcan0 type vcan && sudo ip link set \
                 up vcan0",
                can_interfaces()
            )));
        };
        if ty.parse::<u32>().ok() != Some(ARPHRD_CAN) {
            return Err(Failure::Runtime(format!(
                "--can {iface}: not a CAN interface (link type {ty}; CAN interfaces here: {})",
                can_interfaces()
            )));
        }
        let flags = read_sys(iface, "flags")
            .and_then(|f| u32::from_str_radix(f.trim_start_matches("0x"), 16).ok())
            .unwrap_or(IFF_UP);
        if flags & IFF_UP == 0 {
            return Err(Failure::Runtime(format!(
                "--can {iface}: the interface is down; bring it up at the gimbal's 1 Mbit/s: \
                 sudo ip link set {iface} up type can bitrate 1000000 (a vcan: sudo ip link set \
                 {iface} up)"
            )));
        }
        let socket = CanSocket::open(iface)
            .map_err(|e| Failure::Runtime(format!("--can {iface}: cannot open: {e}")))?;
        socket
            .set_nonblocking(true)
            .map_err(|e| Failure::Runtime(format!("--can {iface}: {e}")))?;
        socket
            .set_error_filter_accept_all()
            .map_err(|e| Failure::Runtime(format!("--can {iface}: {e}")))?;
        Ok(socket)
    }

    impl BusFault for socketcan::Error {
        fn describe(&self) -> String {
            use socketcan::CanError as E;
            match self {
                socketcan::Error::Can(E::BusOff) => "bus off: the controller left the bus after \
                     too many errors (check wiring, the two 120 ohm terminations and the 1 Mbit/s \
                     bitrate; `ip link set IFACE type can restart-ms 100` lets it rejoin)"
                    .into(),
                socketcan::Error::Can(E::NoAck) => {
                    "no ACK: no other node acknowledged (is the gimbal powered and on this bus?)"
                        .into()
                }
                socketcan::Error::Can(e) => format!("error frame: {e}"),
                socketcan::Error::Io(e) => match e.raw_os_error() {
                    Some(libc::ENOBUFS) => "transmit queue full (no node acknowledges the frames: \
                         is the gimbal powered and the bus terminated?)"
                        .into(),
                    Some(libc::ENETDOWN) => "the interface went down".into(),
                    Some(libc::ENODEV | libc::ENXIO) => {
                        "the interface went away (a USB CAN adapter unplugged?)".into()
                    }
                    _ => format!("I/O error: {e}"),
                },
            }
        }

        fn is_fatal(&self) -> bool {
            matches!(self, socketcan::Error::Io(e)
                if matches!(e.raw_os_error(), Some(libc::ENETDOWN | libc::ENODEV | libc::ENXIO | libc::EBADF)))
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        /// Each SocketCAN error in words, and whether it ends the session (the interface
        /// gone or its socket unusable).
        #[test]
        fn socketcan_errors_say_what_they_mean_and_which_end_the_session() {
            use socketcan::CanError as E;
            let io = |errno| socketcan::Error::Io(std::io::Error::from_raw_os_error(errno));
            for (e, starts, fatal) in [
                (socketcan::Error::Can(E::BusOff), "bus off: ", false),
                (socketcan::Error::Can(E::NoAck), "no ACK: ", false),
                (
                    socketcan::Error::Can(E::TransmitTimeout),
                    "error frame: ",
                    false,
                ),
                (io(libc::ENOBUFS), "transmit queue full ", false),
                (io(libc::ENETDOWN), "the interface went down", true),
                (io(libc::ENODEV), "the interface went away ", true),
                (io(libc::ENXIO), "the interface went away ", true),
                (io(libc::EBADF), "I/O error: ", true),
                (io(libc::EIO), "I/O error: ", false),
            ] {
                let said = e.describe();
                assert!(said.starts_with(starts), "{e:?}: {said}");
                assert_eq!(e.is_fatal(), fatal, "{e:?}");
            }
        }

        /// The interfaces of link type CAN, sorted, or "none": read again here from
        /// /sys/class/net, where `lo` (link type 772) always is and is never listed.
        #[test]
        fn the_can_interfaces_listed_are_those_of_link_type_can() {
            let mut can: Vec<String> = std::fs::read_dir("/sys/class/net")
                .unwrap()
                .map(|e| e.unwrap().file_name().into_string().unwrap())
                .filter(|n| {
                    std::fs::read_to_string(format!("/sys/class/net/{n}/type"))
                        .is_ok_and(|t| t.trim() == "280")
                })
                .collect();
            can.sort();
            let expected = if can.is_empty() {
                "none".to_owned()
            } else {
                can.join(", ")
            };
            let listed = can_interfaces();
            assert_eq!(listed, expected);
            assert!(!listed.split(", ").any(|n| n == "lo"), "{listed}");
        }
    }
}

#[cfg(test)]
impl BusFault for idu_gimbal::mock::MockError {
    fn describe(&self) -> String {
        format!("{}", embedded_can::Error::kind(self))
    }

    fn is_fatal(&self) -> bool {
        false
    }
}

/// A session on endpoint 0 of the core's mock bus, named `mock0`: the CAN path of the unit
/// tests here and in `send_monitor`.
#[cfg(test)]
pub fn mock_session<const N: usize>(
    bus: &idu_gimbal::mock::Bus<2, N>,
    mode: Mode,
) -> super::Session<CanTransport<idu_gimbal::mock::Endpoint<'_, 2, N>>> {
    super::Session::new(CanTransport::new(bus.endpoint(0).unwrap(), "mock0", mode))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::Session;
    use idu_gimbal::mock::{Bus, Endpoint, MockFrame};

    fn session(bus: &Bus<2, 64>) -> Session<CanTransport<Endpoint<'_, 2, 64>>> {
        mock_session(bus, Mode::Drive)
    }

    /// `n` frames of another device from endpoint 1.
    fn flood(other: &mut Endpoint<'_, 2, 64>, n: usize) {
        for i in 0..n {
            other
                .transmit(&MockFrame::standard(0x123, &[i as u8]).unwrap())
                .unwrap();
        }
    }

    /// A poll takes at most the link's receive bound (32) and says whether it emptied the
    /// bus; a pump polls on until one did.
    #[test]
    fn a_poll_says_whether_it_emptied_the_bus_and_a_pump_polls_until_one_did() {
        let bus: Bus<2, 64> = Bus::new(1);
        let mut s = session(&bus);
        let mut other = bus.endpoint(1).unwrap();
        let bound = u32::from(s.link.config().max_rx_per_poll.get());
        assert_eq!(bound, 32);
        let now = Instant::from_millis(0);
        flood(&mut other, 40);
        s.transport.poll(&mut s.link, now).unwrap();
        assert_eq!(s.link.stats().frames_received, 32);
        assert!(!s.transport.drained());
        s.transport.poll(&mut s.link, now).unwrap();
        assert_eq!(s.link.stats().frames_received, 40);
        assert!(s.transport.drained());
        // Exactly the bound, then nothing: the first poll cannot know it emptied the bus.
        flood(&mut other, 32);
        s.transport.poll(&mut s.link, now).unwrap();
        assert!(!s.transport.drained());
        s.transport.poll(&mut s.link, now).unwrap();
        assert!(s.transport.drained());
        assert_eq!(s.link.stats().frames_received, 72);
        // 60 in one pump.
        flood(&mut other, 60);
        s.pump(now).unwrap();
        assert_eq!(s.link.stats().frames_received, 132);
        assert!(s.transport.drained());
    }

    /// The same driver error twice: one kind, counted twice, said once with both.
    #[test]
    fn an_error_of_one_kind_is_counted_each_time() {
        let bus: Bus<2, 64> = Bus::new(2);
        let mut s = session(&bus);
        let now = Instant::from_millis(0);
        for _ in 0..2 {
            bus.inject_error(0, embedded_can::ErrorKind::Crc);
            s.transport.poll(&mut s.link, now).unwrap();
        }
        let kind = embedded_can::ErrorKind::Crc.to_string();
        assert_eq!(s.counters()[2], format!("bus errors 2  last: {kind}"));
        assert_eq!(s.take_notes(), [format!("mock0: {kind} (2 new, 2 in all)")]);
        assert!(s.take_notes().is_empty());
        // One more: new since the last note.
        bus.inject_error(0, embedded_can::ErrorKind::Crc);
        s.transport.poll(&mut s.link, now).unwrap();
        assert_eq!(s.take_notes(), [format!("mock0: {kind} (1 new, 3 in all)")]);
    }

    /// Past 64 kinds of driver error, the rest are counted together: none goes uncounted.
    #[test]
    fn errors_of_more_kinds_than_are_kept_apart_are_all_counted() {
        let bus: Bus<2, 64> = Bus::new(4);
        let mut s = session(&bus);
        for i in 0..70 {
            s.transport
                .log
                .borrow_mut()
                .fault(format!("kind {i}"), false);
        }
        s.transport.log.borrow_mut().fault("kind 3".into(), false);
        assert_eq!(s.counters()[2], "bus errors 71  last: kind 3");
        let notes = s.take_notes();
        assert_eq!(notes.len(), 65);
        assert_eq!(notes[3], "mock0: kind 3 (2 new, 2 in all)");
        assert_eq!(notes[63], "mock0: kind 63 (1 new, 1 in all)");
        assert_eq!(notes[64], "mock0: errors of other kinds (6 new, 6 in all)");
    }

    /// Something to send: queued on the link until the bus takes it.
    #[test]
    fn a_frame_waits_to_be_sent_until_the_bus_takes_it() {
        let bus: Bus<2, 64> = Bus::new(3);
        let mut s = session(&bus);
        let now = Instant::from_millis(0);
        assert!(!s.has_transmit());
        let center = idu_gimbal::wire::control::GimbalCommand::Recenter;
        s.link.send(center).unwrap();
        assert!(s.has_transmit());
        s.transport.poll(&mut s.link, now).unwrap();
        assert!(!s.has_transmit());
        assert_eq!(s.link.stats().frames_sent, 1);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn interface_names_are_checked_as_linux_takes_them() {
        for name in ["can0", "vcan0", "slcan0", "a", "fifteen-bytes-0"] {
            assert!(check_name(name).is_ok(), "{name}");
        }
        for name in [
            "",
            "sixteen-bytes-00",
            "can0/x",
            "can 0",
            "can\t0",
            "can:0",
            ".",
            "..",
        ] {
            let Err(Failure::Usage(e)) = check_name(name) else {
                panic!("{name:?} taken");
            };
            assert!(
                e.starts_with(&format!("--can {name:?}: not an interface name")),
                "{e}"
            );
        }
    }
}
