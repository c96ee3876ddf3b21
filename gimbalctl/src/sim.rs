//! `gimbalctl sim`: a simulated gimbal on TCP, speaking the serial server's byte stream, or
//! (`--pty`) on a pseudo-terminal, as the gimbal's UART.
//!
//! On a pty the gimbal is the library's [`SerialSimulator`] (the same `Simulator` in its
//! serial framing), served through the library's `SerialPort` contract on the pty's master
//! side; the slave side's path is the first stdout line, for `--serial PATH`. The sim keeps
//! no slave open itself, so the kernel tells it when a client opens and closes the port (a
//! hang-up on the master): postbacks go out only while a client has it open, and a client
//! that opens it later sees fresh postbacks, not a backlog.
//!
//! The gimbal is the library's [`Simulator`] (with `emit_can_frames: false`: its postbacks
//! go out in their 27-byte stream form). One thread, non-blocking sockets, a 5 ms tick: accept clients up to a bound (more are
//! turned away), read each client's bytes through its own `StreamParser` (garbage is
//! skipped, bad CRCs dropped), hand every control frame to the simulated gimbal, and send
//! every client the 27-byte postback whenever the gimbal has one due (every 500 ms). A
//! client that does not read its postbacks is dropped rather than allowed to stall the
//! others.

use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::num::NonZeroUsize;
use std::time::{Duration, Instant as StdInstant};

use idu_gimbal::sim::serial::SerialSimulator;
use idu_gimbal::sim::{SimConfig, Simulator};
use idu_gimbal::wire::control::Command;
use idu_gimbal::wire::ids;
use idu_gimbal::wire::serial::{StreamItem, StreamParser};
use idu_gimbal::Instant;

use crate::counts::{counted, grown};
use crate::error::Failure;
use crate::spec;
use crate::tcp::DefaultPort;

/// How often the loop runs.
const TICK: Duration = Duration::from_millis(5);
/// Reads per client per tick (4 KiB each).
const MAX_READS: usize = 16;
/// Reads of the pty per tick (24 bytes each, see `run_pty`).
#[cfg(unix)]
const PTY_READS: usize = 256;

struct Client {
    stream: TcpStream,
    peer: SocketAddr,
    parser: StreamParser,
    /// The last command logged for this client.
    last_logged: Option<[u8; 8]>,
    /// Its parser's faults as last said ([`NoFrame`]).
    no_frame: NoFrame,
}

/// What a client sent that was no frame, said as it grows: bytes skipped looking for a
/// header, frames whose CRC failed, frames whose fixed bytes were wrong.
#[derive(Default)]
struct NoFrame([u32; 3]);

impl NoFrame {
    /// The line to say for `parser`'s faults new since the last call, if any.
    fn note(&mut self, from: &str, parser: &StreamParser) -> Option<String> {
        let s = parser.stats();
        let [skipped, crc, invalid] = grown(
            [s.skipped_bytes, s.crc_errors, s.invalid_frames],
            &mut self.0,
        )?;
        Some(format!(
            "gimbalctl sim: {from}: sent what is no frame: {} skipped, {} with a bad CRC, {invalid} with wrong fixed bytes",
            counted(skipped.into(), "byte"),
            counted(crc.into(), "frame"),
        ))
    }
}

/// Failures to accept a waiting connection (out of descriptors, say), which come back at
/// every tick while it waits: said at most once a second, with how many came between.
#[derive(Default)]
struct AcceptFailures {
    said_at: Option<StdInstant>,
    unsaid: u64,
}

impl AcceptFailures {
    /// The line to say for the failure `e` at `now`, if one is due.
    fn note(&mut self, e: &std::io::Error, now: StdInstant) -> Option<String> {
        if self
            .said_at
            .is_some_and(|t| now.saturating_duration_since(t) < Duration::from_secs(1))
        {
            self.unsaid += 1;
            return None;
        }
        self.said_at = Some(now);
        Some(match std::mem::take(&mut self.unsaid) {
            0 => format!("gimbalctl sim: accept failed: {e}"),
            n => format!(
                "gimbalctl sim: accept failed: {e} ({} since the last line)",
                counted(n, "more failure")
            ),
        })
    }
}

/// `gimbalctl sim [--listen ADDR] [--exit-after-ms MS] [--max-clients N]`.
pub fn run(
    listen: &str,
    exit_after_ms: Option<u64>,
    max_clients: NonZeroUsize,
) -> Result<(), Failure> {
    let addrs = crate::tcp::resolve("--listen", listen, DefaultPort::SerialServer)?;
    let listener = TcpListener::bind(&addrs[..])
        .map_err(|e| Failure::Runtime(format!("cannot listen on {listen}: {e}")))?;
    listener
        .set_nonblocking(true)
        .map_err(|e| Failure::io("listener", e))?;
    let local = listener
        .local_addr()
        .map_err(|e| Failure::io("listener", e))?;
    {
        // The first line says where we are (useful with port 0); flushed at once for
        // scripts that wait for it.
        let mut out = std::io::stdout().lock();
        writeln!(out, "gimbalctl sim: listening on {local}")
            .and_then(|()| out.flush())
            .map_err(Failure::stdout)?;
    }
    let start = StdInstant::now();
    let now = || Instant::from_millis(start.elapsed().as_millis() as u32);
    let mut gimbal = Simulator::new(
        SimConfig {
            emit_can_frames: false,
            ..SimConfig::default()
        },
        now(),
    );
    let mut clients: Vec<Client> = Vec::new();
    let mut accept_failures = AcceptFailures::default();
    let mut buf = [0u8; 4096];
    loop {
        if time_is_up(start, exit_after_ms) {
            return Ok(());
        }
        // New clients.
        loop {
            match listener.accept() {
                Ok((stream, peer)) => {
                    if clients.len() >= max_clients.get() {
                        eprintln!(
                            "gimbalctl sim: refusing {peer}: {max_clients} clients already connected"
                        );
                        drop(stream);
                        continue;
                    }
                    if stream.set_nonblocking(true).is_err() {
                        continue;
                    }
                    let _ = stream.set_nodelay(true);
                    eprintln!("gimbalctl sim: {peer} connected");
                    clients.push(Client {
                        stream,
                        peer,
                        parser: StreamParser::new(),
                        last_logged: None,
                        no_frame: NoFrame::default(),
                    });
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => {
                    // Running out of descriptors and the like: report, keep serving.
                    if let Some(line) = accept_failures.note(&e, StdInstant::now()) {
                        eprintln!("{line}");
                    }
                    break;
                }
            }
        }
        // What the clients sent.
        // At most MAX_READS reads per client per tick, so that one client flooding the
        // server cannot starve the others or the postbacks.
        clients.retain_mut(|c| {
            for _ in 0..MAX_READS {
                match c.stream.read(&mut buf) {
                    Ok(0) => {
                        eprintln!("gimbalctl sim: {} disconnected", c.peer);
                        return false;
                    }
                    Ok(n) => {
                        for item in c.parser.feed(&buf[..n]) {
                            let StreamItem::Control(data) = item else {
                                continue;
                            };
                            match gimbal.receive(ids::CONTROL, &data, now()) {
                                // Log each command once, not every repeat of a rate hold.
                                Ok(()) if c.last_logged == Some(data) => {}
                                Ok(()) => {
                                    c.last_logged = Some(data);
                                    if let Ok(cmd) = Command::decode(&data) {
                                        let line = spec::command_line(&cmd);
                                        eprintln!("gimbalctl sim: {}: {line}", c.peer);
                                    }
                                }
                                Err(e) => eprintln!("gimbalctl sim: {}: rejected: {e}", c.peer),
                            }
                        }
                        if let Some(line) = c.no_frame.note(&c.peer.to_string(), &c.parser) {
                            eprintln!("{line}");
                        }
                    }
                    Err(e) if e.kind() == ErrorKind::WouldBlock => return true,
                    Err(e) if e.kind() == ErrorKind::Interrupted => {}
                    Err(e) => {
                        eprintln!("gimbalctl sim: {}: {e}", c.peer);
                        return false;
                    }
                }
            }
            true
        });
        // Postbacks to everyone.
        if let Some(pb) = gimbal.poll(now()) {
            let bytes = pb.to_stream_bytes();
            clients.retain_mut(|c| match c.stream.write(&bytes) {
                Ok(n) if n == bytes.len() => true,
                Ok(_) | Err(_) => {
                    eprintln!("gimbalctl sim: dropping {}: not reading", c.peer);
                    false
                }
            });
        }
        std::thread::sleep(TICK);
    }
}

/// Whether the `--exit-after` time since `start` is up; said on stderr when it is.
fn time_is_up(start: StdInstant, exit_after_ms: Option<u64>) -> bool {
    let Some(ms) = exit_after_ms else {
        return false;
    };
    let up = start.elapsed() >= Duration::from_millis(ms);
    if up {
        eprintln!("gimbalctl sim: exiting after {ms} ms");
    }
    up
}

/// `gimbalctl sim --pty [--exit-after-ms MS]`.
#[cfg(unix)]
pub fn run_pty(exit_after_ms: Option<u64>) -> Result<(), Failure> {
    use idu_gimbal::port::Uart;

    let (master, path) =
        open_pty().map_err(|e| Failure::Runtime(format!("cannot open a pseudo-terminal: {e}")))?;
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "gimbalctl sim: serial port at {path}")
            .and_then(|()| out.flush())
            .map_err(Failure::stdout)?;
    }
    let mut port = PtyMaster {
        pty: master,
        open: false,
    };
    let start = StdInstant::now();
    let now = || Instant::from_millis(start.elapsed().as_millis() as u32);
    let mut gimbal: SerialSimulator = SerialSimulator::new(SimConfig::default(), now());
    let mut last_logged: Option<Command> = None;
    let mut handled = 0u32;
    let mut no_frame = NoFrame::default();
    // One control frame is 24 bytes: a read of 24 completes at most one, so each command
    // is seen (and logged) as it arrives.
    let mut buf = [0u8; 24];
    loop {
        if time_is_up(start, exit_after_ms) {
            return Ok(());
        }
        let was_open = port.open;
        for _ in 0..PTY_READS {
            let n = port.read(&mut buf).unwrap_or(0);
            if n == 0 {
                break;
            }
            gimbal.receive(&buf[..n], now());
            if let Some(line) = no_frame.note(&path, gimbal.parser()) {
                eprintln!("{line}");
            }
            let stats = gimbal.sim().stats();
            let seen = stats.commands.wrapping_add(stats.rejected);
            if seen != handled {
                handled = seen;
                match gimbal.sim().state().last_command {
                    // Each command once, not every repeat of a rate hold.
                    Some(cmd) if last_logged != Some(cmd) => {
                        last_logged = Some(cmd);
                        eprintln!("gimbalctl sim: {path}: {}", spec::command_line(&cmd));
                    }
                    _ => {}
                }
            }
        }
        if port.open != was_open {
            if port.open {
                eprintln!("gimbalctl sim: {path} opened");
            } else {
                eprintln!("gimbalctl sim: {path} closed");
                last_logged = None;
            }
        }
        // Postbacks only while a client has the port open (none pile up for the next).
        if gimbal.poll(now()).is_some() && !port.open {
            let n = gimbal.transmit_bytes().len();
            gimbal.transmit_written(n);
        }
        loop {
            let bytes = gimbal.transmit_bytes();
            if bytes.is_empty() {
                break;
            }
            match port.write(bytes) {
                Ok(0) | Err(()) => break,
                Ok(n) => gimbal.transmit_written(n),
            }
        }
        std::thread::sleep(TICK);
    }
}

/// A new pseudo-terminal: its master side (non-blocking, close-on-exec) and its slave's
/// path. The slave is opened once to set it raw (8-bit clean, no echo, no line editing),
/// as a UART is, and closed again.
#[cfg(unix)]
fn open_pty() -> nix::Result<(nix::pty::PtyMaster, String)> {
    use nix::fcntl::OFlag;
    use nix::sys::termios;
    use std::os::unix::fs::OpenOptionsExt;

    let master = nix::pty::posix_openpt(
        OFlag::O_RDWR | OFlag::O_NOCTTY | OFlag::O_NONBLOCK | OFlag::O_CLOEXEC,
    )?;
    nix::pty::grantpt(&master)?;
    nix::pty::unlockpt(&master)?;
    let path = ptsname(&master)?;
    let slave = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(libc::O_NOCTTY)
        .open(&path)
        .map_err(|e| nix::Error::from_raw(e.raw_os_error().unwrap_or(libc::EIO)))?;
    let mut raw = termios::tcgetattr(&slave)?;
    termios::cfmakeraw(&mut raw);
    termios::tcsetattr(&slave, termios::SetArg::TCSANOW, &raw)?;
    drop(slave);
    Ok((master, path))
}

#[cfg(any(target_os = "linux", target_os = "android"))]
fn ptsname(master: &nix::pty::PtyMaster) -> nix::Result<String> {
    nix::pty::ptsname_r(master)
}

#[cfg(all(unix, not(any(target_os = "linux", target_os = "android"))))]
fn ptsname(master: &nix::pty::PtyMaster) -> nix::Result<String> {
    // SAFETY: ptsname's static buffer is copied at once, and the sim calls it from its one
    // thread only.
    unsafe { nix::pty::ptsname(master) }
}

/// `--pty` needs a Unix pseudo-terminal.
#[cfg(not(unix))]
pub fn run_pty(_exit_after_ms: Option<u64>) -> Result<(), Failure> {
    Err(Failure::Usage(
        "--pty: pseudo-terminals exist only on Unix; use --listen ADDR (TCP)".into(),
    ))
}

/// The pty's master side as the library's `SerialPort`: never blocks. While no client has
/// the slave open the master reads EIO (after any bytes the last client left): that reads
/// as nothing and is noted in `open`.
#[cfg(unix)]
struct PtyMaster {
    pty: nix::pty::PtyMaster,
    /// Whether a client has the slave side open (as of the last read).
    open: bool,
}

#[cfg(unix)]
impl idu_gimbal::port::Uart for PtyMaster {
    type ReadError = ();
    type WriteError = ();

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, ()> {
        match std::io::Read::read(&mut self.pty, buf) {
            Ok(0) => {
                self.open = false;
                Ok(0)
            }
            Ok(n) => {
                self.open = true;
                Ok(n)
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => {
                self.open = true;
                Ok(0)
            }
            Err(e) if e.kind() == ErrorKind::Interrupted => Ok(0),
            // EIO: no client.
            Err(_) => {
                self.open = false;
                Err(())
            }
        }
    }

    fn write(&mut self, bytes: &[u8]) -> Result<usize, ()> {
        match std::io::Write::write(&mut self.pty, bytes) {
            Ok(n) => Ok(n),
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted) => Ok(0),
            Err(_) => Err(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first failure is said, the next ones in the same second counted, and said with
    /// the next line a second or more after the last.
    #[test]
    fn accept_failures_are_said_once_a_second() {
        let e = std::io::Error::from_raw_os_error(24);
        let t0 = StdInstant::now();
        let at = |ms| t0 + Duration::from_millis(ms);
        let mut f = AcceptFailures::default();
        let said = "gimbalctl sim: accept failed: Too many open files (os error 24)";
        assert_eq!(f.note(&e, at(0)).as_deref(), Some(said));
        for ms in [5, 500, 999] {
            assert_eq!(f.note(&e, at(ms)), None, "{ms} ms");
        }
        assert_eq!(
            f.note(&e, at(1000)),
            Some(format!("{said} (3 more failures since the last line)"))
        );
        assert_eq!(f.note(&e, at(1500)), None);
        assert_eq!(
            f.note(&e, at(9000)),
            Some(format!("{said} (1 more failure since the last line)"))
        );
        assert_eq!(f.note(&e, at(10_000)).as_deref(), Some(said));
    }
}
