//! Helpers shared by the integration tests: run the built binary with a timeout, and
//! reference encodings written from the spec (independent of the library and the tool).

#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
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

fn reader<R: Read + Send + 'static>(r: Option<R>) -> thread::JoinHandle<String> {
    thread::spawn(move || {
        let mut s = Vec::new();
        if let Some(mut r) = r {
            let _ = r.read_to_end(&mut s);
        }
        String::from_utf8_lossy(&s).into_owned()
    })
}

/// Runs the binary with `args` and `stdin`, within `timeout`.
pub fn run_timeout(args: &[&str], stdin: &[u8], timeout: Duration) -> Out {
    let mut child = Command::new(BIN)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
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
pub fn usage_error(args: &[&str]) -> Out {
    let out = run(args);
    assert_eq!(out.code, 2, "gimbalctl {args:?}: {out:?}");
    assert!(out.stdout.is_empty(), "gimbalctl {args:?}: {out:?}");
    assert!(!out.stderr.is_empty(), "gimbalctl {args:?}: {out:?}");
    out
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

/// Starts `gimbalctl sim` on an ephemeral port; returns the guard and its address.
pub fn start_sim(extra: &[&str]) -> (Guard, String) {
    let mut args = vec!["sim", "--listen", "127.0.0.1:0"];
    args.extend_from_slice(extra);
    let mut child = Command::new(BIN)
        .args(&args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn sim");
    let stdout = child.stdout.take().unwrap();
    let guard = Guard(child);
    let (tx, rx) = mpsc::channel();
    thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            let _ = tx.send(line);
        }
    });
    let first = rx
        .recv_timeout(Duration::from_secs(10))
        .expect("sim said where it listens");
    let addr = first.rsplit(' ').next().expect("an address").to_owned();
    assert!(first.contains("listening on 127.0.0.1:"), "{first}");
    (guard, addr)
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
