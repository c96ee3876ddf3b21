//! The byte-stream transports: the serial server over TCP and the gimbal's UART on a serial
//! port, both through the library's `SerialPort` over a non-blocking [`StreamPort`].

use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use idu_gimbal::link::{Config, LinkStats, Serial};
use idu_gimbal::port::{Port, PortError, SerialPort, Uart};
use idu_gimbal::wire::serial::StreamStats;
use idu_gimbal::{Instant, Link};

use super::{Mode, SerialSpec, Transport, GIMBAL_BAUD};
use crate::error::Failure;

/// A non-blocking byte stream: a TCP connection or a serial port, for the library's
/// [`SerialPort`] (as its [`Uart`]) and for `mavlink --autopilot-serial`.
///
/// Reads and writes never wait: nothing to read or no room is `Ok(0)`. Every error is the
/// end of the stream, already worded for the user: the server closed the connection, the
/// serial port went away.
pub struct StreamPort {
    io: Io,
    name: String,
    /// The most bytes one read takes (see [`Mode::Monitor`]).
    read_cap: usize,
}

enum Io {
    Tcp(TcpStream),
    Tty(Box<dyn serialport::SerialPort>),
}

/// Why a stream ended, in words for stderr.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ended(pub String);

impl StreamPort {
    /// Connects to the serial server (3 s timeout) and makes the socket non-blocking.
    pub fn tcp(target: &str) -> Result<StreamPort, Failure> {
        let stream = crate::tcp::connect(target)?;
        stream
            .set_nonblocking(true)
            .map_err(|e| Failure::io(target, e))?;
        Ok(StreamPort {
            io: Io::Tcp(stream),
            name: target.to_owned(),
            read_cap: usize::MAX,
        })
    }

    /// Opens a serial port at `spec.baud` 8N1, no flow control, exclusively (a second
    /// program on the same port is refused), and drops whatever arrived before.
    /// `arg` names the option in messages (`--serial`, `--autopilot-serial`).
    pub fn serial(spec: &SerialSpec, arg: &str) -> Result<StreamPort, Failure> {
        let path = &spec.path;
        let port = serialport::new(path, spec.baud)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::ZERO)
            .open()
            .map_err(|e| open_error(arg, path, &e))?;
        let _ = port.clear(serialport::ClearBuffer::Input);
        Ok(StreamPort {
            io: Io::Tty(port),
            name: path.clone(),
            read_cap: usize::MAX,
        })
    }

    fn is_tcp(&self) -> bool {
        matches!(self.io, Io::Tcp(_))
    }

    /// Reads what waits, at most `buf.len()` (and the read cap); `Ok(0)` when nothing does.
    pub fn read_now(&mut self, buf: &mut [u8]) -> Result<usize, Ended> {
        let cap = buf.len().min(self.read_cap);
        let buf = &mut buf[..cap];
        loop {
            let r = match &mut self.io {
                Io::Tcp(s) => s.read(buf),
                Io::Tty(p) => p.read(buf),
            };
            return match r {
                Ok(0) if buf.is_empty() => Ok(0),
                Ok(0) => Err(self.ended(None)),
                Ok(n) => Ok(n),
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => Ok(0),
                Err(e) => Err(self.ended(Some(e))),
            };
        }
    }

    /// Writes what the port takes now; `Ok(0)` when it takes nothing.
    pub fn write_now(&mut self, bytes: &[u8]) -> Result<usize, Ended> {
        if bytes.is_empty() {
            return Ok(0);
        }
        loop {
            let r = match &mut self.io {
                Io::Tcp(s) => s.write(bytes),
                Io::Tty(p) => p.write(bytes),
            };
            return match r {
                Ok(0) if self.is_tcp() => Err(self.ended(None)),
                Ok(n) => Ok(n),
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => Ok(0),
                Err(e) => Err(self.ended(Some(e))),
            };
        }
    }

    /// The words for the end of the stream.
    fn ended(&self, e: Option<std::io::Error>) -> Ended {
        let name = &self.name;
        Ended(match (&self.io, e) {
            (Io::Tcp(_), None) => format!("{name} closed the connection"),
            (Io::Tcp(_), Some(e)) => format!("connection to {name} lost: {e}"),
            (Io::Tty(_), e) => {
                let why = e.map_or_else(|| "end of file".to_owned(), |e| e.to_string());
                format!(
                    "{name}: the serial port went away ({why}): was the USB adapter unplugged \
                     or the other end closed? (gimbalctl stops rather than wait for it)"
                )
            }
        })
    }

    /// Closes the port without losing what was written: TCP sends FIN and waits briefly
    /// for the server (see [`crate::tcp::close_gently`]); a tty drains its output.
    pub fn close(self) {
        match self.io {
            Io::Tcp(s) => {
                let _ = s.set_nonblocking(false);
                crate::tcp::close_gently(s);
            }
            Io::Tty(mut p) => {
                let _ = p.flush();
            }
        }
    }
}

impl Uart for StreamPort {
    type ReadError = Ended;
    type WriteError = Ended;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Ended> {
        self.read_now(buf)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<usize, Ended> {
        self.write_now(bytes)
    }
}

/// Opening a serial port failed: the usual causes in words.
fn open_error(arg: &str, path: &str, e: &serialport::Error) -> Failure {
    use serialport::ErrorKind as K;
    let what = match e.kind {
        K::Io(ErrorKind::NotFound) => format!(
            "no such device (is the adapter plugged in? serial ports are usually \
             /dev/ttyUSB*, /dev/ttyACM*, /dev/ttyAMA*, /dev/serial/by-id/*): {}",
            e.description
        ),
        K::Io(ErrorKind::PermissionDenied) => {
            format!("permission denied: {}{}", owner_hint(path), e.description)
        }
        K::NoDevice => format!("busy: another program has it open ({})", e.description),
        _ if e.description.contains("Inappropriate ioctl")
            || e.description.contains("Not a typewriter") =>
        {
            "not a serial port (not a tty)".to_owned()
        }
        _ => e.description.clone(),
    };
    Failure::Runtime(format!("{arg} {path}: cannot open: {what}"))
}

/// "add yourself to group G" when the device's group can be named.
#[cfg(unix)]
fn owner_hint(path: &str) -> String {
    use std::os::unix::fs::MetadataExt;
    let Ok(meta) = std::fs::metadata(path) else {
        return String::new();
    };
    let gid = meta.gid();
    let group = std::fs::read_to_string("/etc/group")
        .ok()
        .and_then(|groups| {
            groups.lines().find_map(|l| {
                let mut f = l.split(':');
                let name = f.next()?;
                let id = f.nth(1)?.parse::<u32>().ok()?;
                (id == gid).then(|| name.to_owned())
            })
        });
    match group {
        Some(g) => format!(
            "the device belongs to group {g}: add yourself to it (sudo usermod -aG {g} $USER, \
             then log in again) or run as root; "
        ),
        None => format!("the device belongs to group id {gid}; "),
    }
}

#[cfg(not(unix))]
fn owner_hint(_path: &str) -> String {
    String::new()
}

/// A serial port's reads in [`Mode::Monitor`]: at most one postback (27 bytes) each.
const MONITOR_READ: usize = 27;

/// The library's `SerialPort` over a [`StreamPort`]: the serial server or the UART.
pub struct StreamTransport {
    port: SerialPort<StreamPort>,
    name: String,
    /// The baud rate, for the hint on garbage (a TCP stream has none).
    baud: Option<u32>,
    /// Stream counters at the last note.
    noted: StreamStats,
    /// The link's timing for the mode opened in.
    config: Config,
    /// The most bytes one poll reads.
    per_poll: u32,
    /// Whether the last poll read fewer bytes than its bound.
    drained: bool,
}

impl StreamTransport {
    /// The serial server (or `gimbalctl sim`) at `target`.
    pub fn tcp(target: &str, mode: Mode) -> Result<StreamTransport, Failure> {
        Ok(Self::new(StreamPort::tcp(target)?, None, mode))
    }

    /// The gimbal's UART.
    pub fn serial(spec: &SerialSpec, mode: Mode) -> Result<StreamTransport, Failure> {
        Ok(Self::new(
            StreamPort::serial(spec, "--serial")?,
            Some(spec.baud),
            mode,
        ))
    }

    /// A transport over an open port; `baud` for the wrong-baud hint.
    pub fn new(mut port: StreamPort, baud: Option<u32>, mode: Mode) -> StreamTransport {
        // The library's port reads 32 bytes at a time, `max_rx_per_poll` times.
        let chunk = match mode {
            Mode::Drive => 32,
            Mode::Monitor => {
                port.read_cap = MONITOR_READ;
                MONITOR_READ as u32
            }
        };
        let name = port.name.clone();
        // In `monitor`, one read a poll: at most one postback.
        let config = mode.config(1);
        StreamTransport {
            port: SerialPort::new(port),
            name,
            baud,
            noted: StreamStats::default(),
            config,
            per_poll: u32::from(config.max_rx_per_poll.get()) * chunk,
            drained: true,
        }
    }

    /// Bytes received that held no frame (skipped, or in frames with a bad CRC or bad
    /// fixed bytes).
    fn garbage(s: &StreamStats) -> u64 {
        u64::from(s.skipped_bytes) + 27 * u64::from(s.crc_errors) + 24 * u64::from(s.invalid_frames)
    }

    fn baud_hint(&self) -> String {
        match self.baud {
            Some(b) if b != GIMBAL_BAUD => format!(
                ": wrong baud rate? this port runs at {b}, the gimbal's UART at {GIMBAL_BAUD} 8N1"
            ),
            Some(_) => {
                ": wrong baud rate (the gimbal's UART runs at 115200 8N1), or noise on the line?"
                    .to_owned()
            }
            None => String::new(),
        }
    }
}

impl Transport for StreamTransport {
    type Medium = Serial;

    fn name(&self) -> &str {
        &self.name
    }

    fn config(&self) -> Config {
        self.config
    }

    fn poll(&mut self, link: &mut Link<8, 8, Serial>, now: Instant) -> Result<(), Failure> {
        let before = self.port.stats().bytes_received;
        let polled = self.port.poll(link, now);
        let read = self.port.stats().bytes_received.wrapping_sub(before);
        self.drained = read < self.per_poll;
        match polled {
            Ok(()) => Ok(()),
            Err(PortError::Read(Ended(why)) | PortError::Write(Ended(why))) => {
                Err(Failure::Runtime(why))
            }
        }
    }

    fn drained(&self) -> bool {
        self.drained
    }

    fn has_transmit(&self, link: &Link<8, 8, Serial>) -> bool {
        self.port.stream().has_transmit(link)
    }

    fn send_text(_link: &mut Link<8, 8, Serial>, _text: &[u8]) -> Result<(), String> {
        Err("the serial link carries no text (CAN only)".into())
    }

    fn counters(&self, link: &LinkStats) -> [String; 3] {
        let s = self.port.stats();
        let garbage = Self::garbage(&s.stream);
        [
            format!(
                "postbacks {}  crc errors {}  skipped bytes {}",
                link.postbacks, s.stream.crc_errors, s.stream.skipped_bytes
            ),
            format!(
                "frames sent {}  bytes sent {}  bytes received {}  queue full {}",
                s.bytes_sent / 24,
                s.bytes_sent,
                s.bytes_received,
                link.queue_full
            ),
            if garbage > 0 && link.postbacks == 0 {
                // Fits the 80-column panel.
                match self.baud {
                    Some(b) if b != GIMBAL_BAUD => format!(
                        "no frame in {garbage} bytes: wrong baud rate? ({b} here; the gimbal: {GIMBAL_BAUD})"
                    ),
                    Some(_) => format!(
                        "no frame in {garbage} bytes: wrong baud rate (the gimbal: 115200 8N1)?"
                    ),
                    None => format!("no frame in {garbage} bytes"),
                }
            } else {
                String::new()
            },
        ]
    }

    fn take_notes(&mut self, _link: &LinkStats) -> Vec<String> {
        let s = self.port.stats().stream;
        let new = Self::garbage(&s).saturating_sub(Self::garbage(&self.noted));
        if new == 0 {
            return Vec::new();
        }
        let crc = s.crc_errors.wrapping_sub(self.noted.crc_errors);
        self.noted = s;
        vec![format!(
            "{new} bytes from {} held no valid frame ({crc} bad CRCs; {} postbacks so far){}",
            self.name,
            s.postbacks,
            self.baud_hint()
        )]
    }

    fn take_frames(&mut self) -> Vec<super::Seen> {
        Vec::new()
    }

    fn finish(self) {
        self.port.release().close();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::Session;
    use idu_gimbal::wire::control::{GimbalCommand, Pitch};
    use std::net::{TcpListener, TcpStream};
    use std::sync::mpsc;

    /// A connected pair on loopback: our port and the server's end.
    fn pair() -> (StreamPort, TcpStream) {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let port = StreamPort::tcp(&addr).unwrap();
        let (server, _) = listener.accept().unwrap();
        (port, server)
    }

    /// Waits until `n` bytes wait in `port`'s receive queue (loopback's delivery may be
    /// deferred past the server's write).
    fn wait_waiting(port: &StreamPort, n: usize) {
        let Io::Tcp(stream) = &port.io else {
            unreachable!("a TCP port")
        };
        let mut peek = vec![0; n];
        let deadline = std::time::Instant::now() + Duration::from_secs(5);
        while stream.peek(&mut peek).map_or(true, |got| got < n) {
            assert!(std::time::Instant::now() < deadline, "the bytes never came");
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// An empty buffer reads nothing and is not the end of the stream, even with bytes
    /// waiting (a read of 0 bytes into a non-empty one is the end).
    #[test]
    fn an_empty_read_is_not_the_end() {
        let (mut port, mut server) = pair();
        assert_eq!(port.read_now(&mut [0; 8]), Ok(0), "nothing sent yet");
        server.write_all(b"abc").unwrap();
        wait_waiting(&port, 3);
        assert_eq!(port.read_now(&mut []), Ok(0));
        let mut buf = [0; 8];
        assert_eq!(port.read_now(&mut buf), Ok(3));
        assert_eq!(&buf[..3], b"abc");
        drop(server);
        // Nothing to read until the server's FIN comes (its delivery may be deferred too).
        let deadline = std::time::Instant::now() + Duration::from_secs(5);
        let ended = loop {
            match port.read_now(&mut [0; 8]) {
                Ok(0) => {
                    assert!(std::time::Instant::now() < deadline, "never ended");
                    std::thread::sleep(Duration::from_millis(1));
                }
                other => break other,
            }
        };
        let name = port.name.clone();
        assert_eq!(ended, Err(Ended(format!("{name} closed the connection"))));
    }

    /// A write that finds no room takes nothing (the server not reading); one after the
    /// server has gone ends the stream, saying so.
    #[test]
    fn a_full_connection_takes_nothing_and_a_gone_one_ends() {
        let (mut port, server) = pair();
        let chunk = [0x55; 65_536];
        let deadline = std::time::Instant::now() + Duration::from_secs(10);
        // The kernel's buffers hold a few megabytes at most.
        while port.write_now(&chunk).expect("room or none, not the end") > 0 {
            assert!(std::time::Instant::now() < deadline, "never full");
        }
        assert_eq!(port.write_now(&chunk), Ok(0), "still full");
        // Unread data: the server's close resets the connection.
        drop(server);
        let ended = loop {
            match port.write_now(&chunk) {
                Ok(_) => {
                    assert!(std::time::Instant::now() < deadline, "never ended");
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => break e,
            }
        };
        let lost = format!("connection to {} lost: ", port.name);
        assert!(ended.0.starts_with(&lost), "{ended:?}");
    }

    /// Opening errors in words: the usual causes named, anything else as the driver said.
    #[test]
    fn open_errors_say_the_likely_cause() {
        use serialport::{Error, ErrorKind as K};
        let said = |kind, description: &str| match open_error(
            "--serial",
            "/dev/ttyX",
            &Error::new(kind, description),
        ) {
            Failure::Runtime(m) => m,
            other => panic!("{other:?}"),
        };
        let prefix = "--serial /dev/ttyX: cannot open: ";
        assert_eq!(
            said(K::Io(ErrorKind::NotFound), "No such file or directory"),
            format!(
                "{prefix}no such device (is the adapter plugged in? serial ports are usually \
                 /dev/ttyUSB*, /dev/ttyACM*, /dev/ttyAMA*, /dev/serial/by-id/*): No such file \
                 or directory"
            )
        );
        // No such file: no group to name.
        assert_eq!(
            said(K::Io(ErrorKind::PermissionDenied), "Permission denied"),
            format!("{prefix}permission denied: Permission denied")
        );
        assert_eq!(
            said(K::NoDevice, "Device or resource busy"),
            format!("{prefix}busy: another program has it open (Device or resource busy)")
        );
        for not_a_tty in ["Inappropriate ioctl for device", "Not a typewriter"] {
            assert_eq!(
                said(K::Unknown, not_a_tty),
                format!("{prefix}not a serial port (not a tty)")
            );
        }
        assert_eq!(
            said(K::InvalidInput, "Invalid baud rate"),
            format!("{prefix}Invalid baud rate")
        );
    }

    /// The group a device belongs to, named as coreutils' `stat` names a file's group (a
    /// file the test creates: its group is the test's, or a setgid directory's).
    #[cfg(unix)]
    #[test]
    fn the_owner_hint_names_the_device_s_group() {
        let path = std::env::temp_dir().join(format!("gimbalctl-owner-{}", std::process::id()));
        std::fs::write(&path, b"").unwrap();
        let hint = owner_hint(path.to_str().unwrap());
        let stat = |format: &str| {
            let out = std::process::Command::new("stat")
                .args(["-c", format])
                .arg(&path)
                .output()
                .unwrap();
            assert!(out.status.success(), "stat -c {format}");
            String::from_utf8(out.stdout).unwrap().trim().to_owned()
        };
        let (name, gid) = (stat("%G"), stat("%g"));
        std::fs::remove_file(&path).unwrap();
        let expected = if name == "UNKNOWN" {
            format!("the device belongs to group id {gid}; ")
        } else {
            format!(
                "the device belongs to group {name}: add yourself to it (sudo usermod -aG \
                 {name} $USER, then log in again) or run as root; "
            )
        };
        assert_eq!(hint, expected);
        assert_eq!(owner_hint("/nonexistent/tty"), "");
    }

    /// Bytes that held no frame: the skipped, and whole frames that failed (a postback's
    /// 27 for a bad CRC, a control frame's 24 for bad fixed bytes).
    #[test]
    fn garbage_counts_bytes() {
        let s = StreamStats {
            skipped_bytes: 5,
            crc_errors: 2,
            invalid_frames: 3,
            ..StreamStats::default()
        };
        assert_eq!(StreamTransport::garbage(&s), 5 + 2 * 27 + 3 * 24);
        let most = StreamStats {
            skipped_bytes: u32::MAX,
            crc_errors: u32::MAX,
            invalid_frames: u32::MAX,
            ..StreamStats::default()
        };
        assert_eq!(StreamTransport::garbage(&most), 52 * u64::from(u32::MAX));
    }

    /// The wrong-baud hint: the port's rate when it is not the gimbal's, noise otherwise,
    /// nothing on TCP.
    #[test]
    fn the_baud_hint_names_the_rates() {
        let hint = |baud| StreamTransport::new(pair().0, baud, Mode::Drive).baud_hint();
        assert_eq!(
            hint(Some(9600)),
            ": wrong baud rate? this port runs at 9600, the gimbal's UART at 115200 8N1"
        );
        assert_eq!(
            hint(Some(115_200)),
            ": wrong baud rate (the gimbal's UART runs at 115200 8N1), or noise on the line?"
        );
        assert_eq!(hint(None), "");
    }

    /// A poll says whether it emptied the stream: not when it read its bound (more may
    /// wait), so a pump polls again.
    #[test]
    fn a_poll_says_whether_it_emptied_the_stream() {
        let (port, mut server) = pair();
        let mut t = StreamTransport::new(port, None, Mode::Drive);
        let mut link = Link::new(t.config());
        let now = Instant::from_millis(0);
        // The library's port reads 32 bytes at a time, the link's bound times.
        let per_poll = 32 * usize::from(t.config().max_rx_per_poll.get());
        assert_eq!(t.per_poll as usize, per_poll);
        for (waiting, polls) in [(per_poll + 10, [false, true]), (per_poll, [false, true])] {
            let before = t.port.stats().bytes_received as usize;
            server.write_all(&vec![0; waiting]).unwrap();
            wait_waiting(t.port.uart(), waiting);
            for (i, drained) in polls.into_iter().enumerate() {
                t.poll(&mut link, now).unwrap();
                assert_eq!(t.drained(), drained, "{waiting} bytes, poll {i}");
            }
            let read = t.port.stats().bytes_received as usize - before;
            assert_eq!(read, waiting);
        }
    }

    /// The panel's lines: what came and went, and bytes with no frame in them said with
    /// the likely cause until a postback comes.
    #[test]
    fn the_counters_say_what_came_and_the_likely_cause() {
        let now = Instant::from_millis(0);
        for (baud, cause) in [
            (
                Some(9600),
                "no frame in 10 bytes: wrong baud rate? (9600 here; the gimbal: 115200)",
            ),
            (
                Some(115_200),
                "no frame in 10 bytes: wrong baud rate (the gimbal: 115200 8N1)?",
            ),
            (None, "no frame in 10 bytes"),
        ] {
            let (port, mut server) = pair();
            let mut t = StreamTransport::new(port, baud, Mode::Drive);
            let mut link = Link::new(t.config());
            t.poll(&mut link, now).unwrap();
            assert_eq!(t.counters(&link.stats())[2], "", "nothing received yet");
            server.write_all(&[0; 10]).unwrap();
            wait_waiting(t.port.uart(), 10);
            t.poll(&mut link, now).unwrap();
            let stats = link.stats();
            assert_eq!(
                t.counters(&stats),
                [
                    "postbacks 0  crc errors 0  skipped bytes 10".to_owned(),
                    "frames sent 0  bytes sent 0  bytes received 10  queue full 0".to_owned(),
                    cause.to_owned(),
                ]
            );
            let one = LinkStats {
                postbacks: 1,
                ..stats
            };
            assert_eq!(t.counters(&one)[2], "", "a postback came");
        }
    }

    /// A session's end closes the connection gently: the server, which has written
    /// postbacks the session never read, gets the command and then the end of the stream,
    /// not a reset (which a plain close of a socket holding unread data sends).
    #[test]
    fn a_session_s_finish_closes_gently() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let (sent, wait_sent) = mpsc::channel();
        let server = std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            wait_sent.recv().unwrap();
            s.write_all(&[0x55; 512]).unwrap();
            let mut got = Vec::new();
            s.read_to_end(&mut got).map(|_| got)
        });
        let mut session = Session::new(StreamTransport::tcp(&addr, Mode::Drive).unwrap());
        session
            .link
            .send(GimbalCommand::Pitch(Pitch::new(-30.0).unwrap()))
            .unwrap();
        assert!(session.has_transmit(), "queued");
        assert_eq!(
            session.send_text(b"hi"),
            Err("the serial link carries no text (CAN only)".to_owned())
        );
        session.pump(Instant::from_millis(0)).unwrap();
        assert!(!session.has_transmit(), "the frame is written");
        sent.send(()).unwrap();
        wait_waiting(session.transport.port.uart(), 512);
        session.finish();
        let got = server
            .join()
            .unwrap()
            .expect("the end of the stream, not a reset");
        // One 24-byte serial control frame (the protocol notes' EB 90 0A header).
        assert_eq!((got.len(), &got[..3]), (24, &[0xEB, 0x90, 0x0A][..]));
    }
}
