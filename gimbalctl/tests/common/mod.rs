//! Helpers shared by the integration tests: run the built binary, to its end with a timeout
//! or in the background with its output collected; the checks most error tests make;
//! reference encodings written from the spec (independent of the library and the tool); and,
//! in [`mavlink`], MAVLink frames for the bridge's tests.

#![allow(dead_code)]

pub mod mavlink;

use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

pub const BIN: &str = env!("CARGO_BIN_EXE_gimbalctl");

/// Every run of the binary is killed after this long (no test may hang).
pub const TIMEOUT: Duration = Duration::from_secs(20);

/// What a finished run left behind.
#[derive(Debug)]
pub struct Out {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

impl Out {
    pub fn lines(&self) -> Vec<&str> {
        self.stdout.lines().collect()
    }

    /// Each stdout line parsed as JSON.
    pub fn json(&self) -> Vec<serde_json::Value> {
        self.stdout
            .lines()
            .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
            .collect()
    }
}

/// Waits for a child with a deadline, killing it if the deadline passes.
pub fn wait_with_timeout(child: &mut Child, timeout: Duration) -> Option<i32> {
    let deadline = Instant::now() + timeout;
    loop {
        match child.try_wait().expect("try_wait") {
            Some(status) => return Some(status.code().unwrap_or(-1)),
            None if Instant::now() >= deadline => {
                let _ = child.kill();
                let _ = child.wait();
                return None;
            }
            None => thread::sleep(Duration::from_millis(10)),
        }
    }
}

/// `gimbalctl ARGS`, ready to spawn: stdin closed, stdout and stderr piped (a caller may
/// change any of them first).
pub fn command(args: &[&str]) -> Command {
    let mut command = Command::new(BIN);
    command
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    command
}

/// Reads `r` to its end on a thread of its own (a child never blocks on a full pipe); the
/// text, once the thread is joined.
pub fn reader<R: Read + Send + 'static>(r: Option<R>) -> thread::JoinHandle<String> {
    thread::spawn(move || {
        let mut s = Vec::new();
        if let Some(mut r) = r {
            let _ = r.read_to_end(&mut s);
        }
        String::from_utf8_lossy(&s).into_owned()
    })
}

/// The lines of `r` on a channel as they come, read on a thread of its own to the end, also
/// once the receiver is gone (a child never blocks on a full pipe).
pub fn lines<R: Read + Send + 'static>(r: R) -> Receiver<String> {
    let (tx, rx) = mpsc::channel();
    thread::spawn(move || {
        for line in BufReader::new(r).lines() {
            let Ok(line) = line else { break };
            let _ = tx.send(line);
        }
    });
    rx
}

/// Runs the binary with `args` and `stdin`, within `timeout`.
pub fn run_timeout(args: &[&str], stdin: &[u8], timeout: Duration) -> Out {
    let mut child = command(args)
        .stdin(Stdio::piped())
        .spawn()
        .expect("spawn gimbalctl");
    let input = stdin.to_vec();
    let mut child_in = child.stdin.take();
    let writer = thread::spawn(move || {
        if let Some(w) = child_in.as_mut() {
            let _ = w.write_all(&input);
        }
        drop(child_in);
    });
    let out = reader(child.stdout.take());
    let err = reader(child.stderr.take());
    let code = wait_with_timeout(&mut child, timeout);
    let _ = writer.join();
    let out = Out {
        code: code.unwrap_or(-1),
        stdout: out.join().unwrap(),
        stderr: err.join().unwrap(),
    };
    assert!(code.is_some(), "gimbalctl {args:?} timed out: {out:?}");
    out
}

pub fn run(args: &[&str]) -> Out {
    run_timeout(args, b"", TIMEOUT)
}

pub fn run_stdin(args: &[&str], stdin: &[u8]) -> Out {
    run_timeout(args, stdin, TIMEOUT)
}

/// Runs, expecting success.
pub fn ok(args: &[&str]) -> Out {
    let out = run(args);
    assert_eq!(out.code, 0, "gimbalctl {args:?}: {out:?}");
    assert!(out.stderr.is_empty(), "gimbalctl {args:?}: {out:?}");
    out
}

/// Runs, expecting a usage error: exit 2, nothing on stdout, something on stderr.
#[track_caller]
pub fn usage_error(args: &[&str]) -> Out {
    let out = run(args);
    assert_eq!(out.code, 2, "gimbalctl {args:?}: {out:?}");
    assert!(out.stdout.is_empty(), "gimbalctl {args:?}: {out:?}");
    assert!(!out.stderr.is_empty(), "gimbalctl {args:?}: {out:?}");
    out
}

/// A [`usage_error`] whose stderr names each of `words` (the argument, its range).
#[track_caller]
pub fn usage_error_naming(args: &[&str], words: &[&str]) -> Out {
    let out = usage_error(args);
    assert_names(args, &out, words);
    out
}

/// Runs, expecting a runtime failure: exit 1, nothing on stdout, each of `words` on stderr.
#[track_caller]
pub fn failure_naming(args: &[&str], words: &[&str]) -> Out {
    let out = run(args);
    assert_eq!(out.code, 1, "gimbalctl {args:?}: {out:?}");
    assert!(out.stdout.is_empty(), "gimbalctl {args:?}: {out:?}");
    assert_names(args, &out, words);
    out
}

#[track_caller]
fn assert_names(args: &[&str], out: &Out, words: &[&str]) {
    for w in words {
        assert!(
            out.stderr.contains(w),
            "gimbalctl {args:?}: {w:?} not in {}",
            out.stderr
        );
    }
}

/// A loopback TCP port that nobody listens on, held for as long as this lives: bound and
/// never listening, so that a connection to it is refused (the kernel answers with a reset)
/// and no other test or process can take the port in the meantime, as one could a port
/// bound and freed.
pub struct ClosedPort {
    socket: socket2::Socket,
}

impl ClosedPort {
    /// The port's number.
    pub fn port(&self) -> u16 {
        self.socket
            .local_addr()
            .unwrap()
            .as_socket()
            .unwrap()
            .port()
    }
}

/// A [`ClosedPort`] on 127.0.0.1.
pub fn closed_port() -> ClosedPort {
    use socket2::{Domain, Socket, Type};
    let socket = Socket::new(Domain::IPV4, Type::STREAM, None).unwrap();
    let any: std::net::SocketAddr = "127.0.0.1:0".parse().unwrap();
    socket.bind(&any.into()).unwrap();
    ClosedPort { socket }
}

/// CRC-16/MODBUS, bit by bit, from its definition (reflected 0xA001, init 0xFFFF, no
/// final xor). A reference for the tests only.
pub fn crc16_modbus(data: &[u8]) -> u16 {
    let mut crc = 0xFFFFu16;
    for &b in data {
        crc ^= u16::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xA001
            } else {
                crc >> 1
            };
        }
    }
    crc
}

pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

pub fn unhex(s: &str) -> Vec<u8> {
    assert!(s.len().is_multiple_of(2), "{s}");
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
        .collect()
}

/// the protocol notes' 24-byte serial/TCP frame around 8 CAN data bytes: `EB 90 0A`, nine `00`,
/// `40 88`, the data, CRC-16/MODBUS over bytes 0..=21, low byte first.
pub fn tcp_frame(can_data: &[u8]) -> Vec<u8> {
    assert_eq!(can_data.len(), 8);
    let mut f = vec![0xEB, 0x90, 0x0A];
    f.extend([0u8; 9]);
    f.extend([0x40, 0x88]);
    f.extend_from_slice(can_data);
    let crc = crc16_modbus(&f);
    f.extend(crc.to_le_bytes());
    f
}

/// A postback message per the protocol notes' table: 27 bytes (the stream form).
pub fn postback(
    gimbal_type: u8,
    tracking: u8,
    mode: u8,
    pitch: i16,
    heading: u16,
    motor: i16,
) -> Vec<u8> {
    let mut m = vec![0xEB, 0x90, 0x0C];
    m.extend([0u8; 9]);
    m.extend([0x21, 0xFE, 0x0F, 0x01, gimbal_type, tracking, mode]);
    m.extend(pitch.to_le_bytes());
    m.extend(heading.to_le_bytes());
    m.extend(motor.to_le_bytes());
    let crc = crc16_modbus(&m);
    m.extend(crc.to_le_bytes());
    assert_eq!(m.len(), 27);
    m
}

/// The postback as four CAN frames' data (32 bytes: 27 + 5 of zero padding).
pub fn postback_frames(msg: &[u8]) -> Vec<Vec<u8>> {
    let mut padded = msg.to_vec();
    padded.resize(32, 0);
    padded.chunks(8).map(<[u8]>::to_vec).collect()
}

/// A sibling of `std::process::Child` that is killed when dropped.
pub struct Guard(pub Child);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `v` with every number as an f64, so that `45` and `45.0` compare equal (the tool writes
/// whole values without a fraction).
pub fn norm(v: &serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Number(n) => serde_json::json!(n.as_f64().unwrap()),
        Value::Array(a) => Value::Array(a.iter().map(norm).collect()),
        Value::Object(o) => Value::Object(o.iter().map(|(k, v)| (k.clone(), norm(v))).collect()),
        other => other.clone(),
    }
}

/// Asserts two JSON values are equal up to number representation.
#[track_caller]
pub fn assert_json_eq(got: &serde_json::Value, expected: &serde_json::Value) {
    assert_eq!(norm(got), norm(expected));
}

/// A child's stderr, line by line, each line with when it arrived (read on a thread of its
/// own, as it comes).
pub struct Log {
    lines: Arc<Mutex<Vec<(Instant, String)>>>,
    since: Instant,
    reader: thread::JoinHandle<()>,
}

impl Log {
    pub fn collect<R: Read + Send + 'static>(r: R) -> Log {
        let lines: Arc<Mutex<Vec<(Instant, String)>>> = Arc::default();
        let l = lines.clone();
        let since = Instant::now();
        let reader = thread::spawn(move || {
            for line in BufReader::new(r).lines() {
                let Ok(line) = line else { break };
                l.lock().unwrap().push((Instant::now(), line));
            }
        });
        Log {
            lines,
            since,
            reader,
        }
    }

    /// The lines so far, each ended by a newline.
    pub fn text(&self) -> String {
        text(&self.lines)
    }

    /// Whether a line so far ends with `suffix`.
    pub fn has(&self, suffix: &str) -> bool {
        self.lines
            .lock()
            .unwrap()
            .iter()
            .any(|(_, l)| l.ends_with(suffix))
    }

    /// Polls for a line ending with `suffix` that arrived at `after` or later; when it
    /// arrived. Panics with the log after `timeout`.
    #[track_caller]
    pub fn wait_after(&self, suffix: &str, after: Instant, timeout: Duration) -> Instant {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some((t, _)) = self
                .lines
                .lock()
                .unwrap()
                .iter()
                .find(|(t, l)| *t >= after && l.ends_with(suffix))
            {
                return *t;
            }
            assert!(
                Instant::now() < deadline,
                "never logged {suffix:?}:\n{}",
                self.text()
            );
            thread::sleep(Duration::from_millis(5));
        }
    }

    /// [`Log::wait_after`] for any line since the log began.
    #[track_caller]
    pub fn wait(&self, suffix: &str, timeout: Duration) -> Instant {
        self.wait_after(suffix, self.since, timeout)
    }

    /// All of it, once the stream has ended (the child gone).
    pub fn finish(self) -> String {
        let Log { lines, reader, .. } = self;
        reader.join().expect("the log's reader");
        text(&lines)
    }
}

fn text(lines: &Mutex<Vec<(Instant, String)>>) -> String {
    let lines = lines.lock().unwrap();
    lines.iter().map(|(_, l)| format!("{l}\n")).collect()
}

/// Starts `gimbalctl ARGS` in the background (stdin closed, killed when the guard drops): the
/// guard, all of its stdout once it ends, its stderr as it comes.
pub fn spawn(args: &[&str]) -> (Guard, thread::JoinHandle<String>, Log) {
    let mut child = command(args).spawn().expect("spawn gimbalctl");
    let stdout = reader(child.stdout.take());
    let stderr = Log::collect(child.stderr.take().unwrap());
    (Guard(child), stdout, stderr)
}

/// Starts `gimbalctl ARGS` in the background (stdin closed, killed when the guard drops) and
/// waits up to `within` for its first stdout line, which must start with `says` (where it
/// listens, say): the guard, that line, its stderr. The rest of stdout is drained.
pub fn start(args: &[&str], says: &str, within: Duration) -> (Guard, String, Log) {
    start_command(command(args), says, within)
}

/// [`start`] for a command built by the caller (gimbalctl run through a shell, say), its
/// stdout and stderr piped.
pub fn start_command(mut command: Command, says: &str, within: Duration) -> (Guard, String, Log) {
    let mut child = command.spawn().expect("spawn gimbalctl");
    let stdout = lines(child.stdout.take().unwrap());
    let stderr = Log::collect(child.stderr.take().unwrap());
    let guard = Guard(child);
    let first = stdout
        .recv_timeout(within)
        .unwrap_or_else(|e| panic!("{command:?} said nothing ({e}): {}", stderr.text()));
    assert!(first.starts_with(says), "{first}");
    (guard, first, stderr)
}

/// `gimbalctl sim --listen 127.0.0.1:0 EXTRA`, given `within` to say where it listens: the
/// guard, that address, its log.
pub fn start_sim_logged(extra: &[&str], within: Duration) -> (Guard, String, Log) {
    let mut args = vec!["sim", "--listen", "127.0.0.1:0"];
    args.extend_from_slice(extra);
    let (guard, first, log) = start(&args, "gimbalctl sim: listening on 127.0.0.1:", within);
    let addr = first.rsplit(' ').next().expect("an address").to_owned();
    (guard, addr, log)
}

/// Starts `gimbalctl sim` on an ephemeral port; returns the guard and its address.
pub fn start_sim(extra: &[&str]) -> (Guard, String) {
    let (guard, addr, _log) = start_sim_logged(extra, Duration::from_secs(10));
    (guard, addr)
}

/// `gimbalctl sim --pty` for 60 s at most: the guard, the slave's path, the sim's log. The
/// path is awaited for as long (until the sim would end anyway).
pub fn start_pty_sim() -> (Guard, String, Log) {
    let (guard, first, log) = start(
        &["sim", "--pty", "--exit-after-ms", "60000"],
        "gimbalctl sim: serial port at /dev/",
        Duration::from_secs(60),
    );
    let path = first.rsplit(' ').next().expect("a path").to_owned();
    (guard, path, log)
}

/// Takes the whole 27-byte postbacks off the front of `buf` (what a raw client of the sim
/// received), each checked: its header and the reference CRC.
#[track_caller]
pub fn take_postbacks(buf: &mut Vec<u8>) -> Vec<Vec<u8>> {
    let mut got = Vec::new();
    while buf.len() >= 27 {
        let msg: Vec<u8> = buf.drain(..27).collect();
        assert_eq!(&msg[..3], &[0xEB, 0x90, 0x0C], "{msg:02X?}");
        let crc = crc16_modbus(&msg[..25]).to_le_bytes();
        assert_eq!(&msg[25..], &crc, "{msg:02X?}");
        got.push(msg);
    }
    got
}

/// A postback's pitch, in 0.01 deg.
pub fn postback_pitch(msg: &[u8]) -> i16 {
    i16::from_le_bytes([msg[19], msg[20]])
}

/// A pseudo-terminal made by a test: its master side (the test's end of the line) and the
/// slave's path (gimbalctl's `--serial PATH`). Close-on-exec, so that no child process keeps
/// the line open: dropping it is the other end going away (a USB adapter pulled).
#[cfg(unix)]
pub struct TestPty {
    master: nix::pty::PtyMaster,
    pub path: String,
}

#[cfg(unix)]
impl TestPty {
    pub fn new() -> TestPty {
        use nix::fcntl::OFlag;
        use nix::sys::termios;
        use std::os::unix::fs::OpenOptionsExt;
        let master = nix::pty::posix_openpt(
            OFlag::O_RDWR | OFlag::O_NOCTTY | OFlag::O_NONBLOCK | OFlag::O_CLOEXEC,
        )
        .expect("posix_openpt");
        nix::pty::grantpt(&master).unwrap();
        nix::pty::unlockpt(&master).unwrap();
        let path = nix::pty::ptsname_r(&master).unwrap();
        // Raw, as a UART: set once through the slave, which is then closed.
        let slave = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(libc::O_NOCTTY)
            .open(&path)
            .unwrap();
        let mut raw = termios::tcgetattr(&slave).unwrap();
        termios::cfmakeraw(&mut raw);
        termios::tcsetattr(&slave, termios::SetArg::TCSANOW, &raw).unwrap();
        drop(slave);
        TestPty { master, path }
    }

    /// Writes all of `bytes` (waiting while the line is full, 2 s at most); `false` when no
    /// one has the slave open (the bytes are lost, as on a line with no listener).
    pub fn write(&mut self, bytes: &[u8]) -> bool {
        let deadline = Instant::now() + Duration::from_secs(2);
        let mut rest = bytes;
        while !rest.is_empty() {
            match Write::write(&mut self.master, rest) {
                Ok(n) => rest = &rest[n..],
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    assert!(Instant::now() < deadline, "the pty stays full");
                    thread::sleep(Duration::from_millis(1));
                }
                Err(_) => return false,
            }
        }
        true
    }

    /// What arrives within `wait`.
    pub fn read_for(&mut self, wait: Duration) -> Vec<u8> {
        let deadline = Instant::now() + wait;
        let mut got = Vec::new();
        let mut buf = [0u8; 4096];
        while Instant::now() < deadline {
            match Read::read(&mut self.master, &mut buf) {
                Ok(n) if n > 0 => got.extend_from_slice(&buf[..n]),
                _ => thread::sleep(Duration::from_millis(2)),
            }
        }
        got
    }

    /// Whether a process has the slave side open (the master reads EIO while none does).
    pub fn is_open(&mut self) -> bool {
        match Read::read(&mut self.master, &mut []) {
            Err(e) => e.raw_os_error() != Some(libc::EIO),
            Ok(_) => true,
        }
    }
}
