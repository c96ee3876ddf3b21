//! `send` and `monitor`: talking to the serial server (or `gimbalctl sim`) over TCP.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use idu_gimbal::interface::SERIAL_SERVER_PORT;
use idu_gimbal::wire::control::{Command, DualLightCommand, GimbalCommand, Rate};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::serial::{self, StreamItem, StreamParser};

use crate::command::{Message, Spec};
use crate::decode;
use crate::error::Failure;

/// How long `send` and `monitor` wait for the connection.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(3);
/// How long a write may block before the server is taken to be gone.
const WRITE_TIMEOUT: Duration = Duration::from_secs(3);
/// `monitor` warns after this long without a postback (three missed 500 ms periods).
pub const SILENCE_WARNING: Duration = Duration::from_millis(1500);

/// `HOST:PORT`, `HOST` (port 2000, the serial server's) or `[v6]:PORT` to addresses.
pub fn resolve(target: &str) -> Result<Vec<SocketAddr>, Failure> {
    if let Ok(addr) = target.parse::<SocketAddr>() {
        return Ok(vec![addr]);
    }
    let with_port = match target.rsplit_once(':') {
        // A bare IPv6 address has colons but no port.
        Some((host, _)) if host.contains(':') && !host.starts_with('[') => {
            format!("[{target}]:{SERIAL_SERVER_PORT}")
        }
        Some((host, port)) => {
            if host.is_empty() || port.parse::<u16>().is_err() {
                return Err(Failure::Usage(format!(
                    "--tcp {target}: expected HOST:PORT with PORT in [0, 65535]"
                )));
            }
            target.to_owned()
        }
        None if target.is_empty() => {
            return Err(Failure::Usage("--tcp: expected HOST:PORT".into()));
        }
        None => format!("{target}:{SERIAL_SERVER_PORT}"),
    };
    let addrs: Vec<SocketAddr> = with_port
        .to_socket_addrs()
        .map_err(|e| Failure::Runtime(format!("cannot resolve {target}: {e}")))?
        .collect();
    if addrs.is_empty() {
        return Err(Failure::Runtime(format!("cannot resolve {target}")));
    }
    Ok(addrs)
}

/// Connects with [`CONNECT_TIMEOUT`], trying each address in turn.
pub fn connect(target: &str) -> Result<TcpStream, Failure> {
    let mut last = None;
    for addr in resolve(target)? {
        match TcpStream::connect_timeout(&addr, CONNECT_TIMEOUT) {
            Ok(s) => {
                let _ = s.set_nodelay(true);
                s.set_write_timeout(Some(WRITE_TIMEOUT))
                    .map_err(|e| Failure::io(target, e))?;
                return Ok(s);
            }
            Err(e) => last = Some(e),
        }
    }
    Err(match last {
        Some(e) => Failure::Runtime(format!("cannot connect to {target}: {e}")),
        None => Failure::Runtime(format!("cannot connect to {target}")),
    })
}

/// The control commands of a spec, or a usage error for vehicle and text commands, which
/// have no serial/TCP frame.
pub fn control_commands(spec: &Spec) -> Result<Vec<Command>, Failure> {
    match spec.build()? {
        Message::Control(cmds) => Ok(cmds),
        Message::Vehicle(_) | Message::Text(_) => Err(Failure::Usage(format!(
            "{}: only control commands have a serial/TCP frame (--tcp); \
             vehicle and text frames exist only on CAN",
            spec.name()
        ))),
    }
}

/// The zero rate on the same peripheral, for a rate command (the end of a rate hold).
fn zero_rate(cmd: &Command) -> Option<Command> {
    match cmd {
        Command::Gimbal(GimbalCommand::Rate(_)) => Some(GimbalCommand::Rate(Rate::ZERO).into()),
        Command::DualLight(DualLightCommand::Rate(_)) => {
            Some(DualLightCommand::Rate(Rate::ZERO).into())
        }
        _ => None,
    }
}

/// `gimbalctl send --tcp HOST:PORT [--repeat-ms MS --for-ms MS] COMMAND ARGS...`.
pub fn send(target: &str, spec: &Spec, repeat: Option<(u64, u64)>) -> Result<(), Failure> {
    let cmds = control_commands(spec)?;
    let frames: Vec<u8> = cmds
        .iter()
        .flat_map(|c| serial::control_frame(&c.encode()))
        .collect();
    let mut stream = connect(target)?;
    let mut write = |bytes: &[u8]| {
        stream
            .write_all(bytes)
            .map_err(|e| Failure::Runtime(format!("cannot send to {target}: {e}")))
    };
    write(&frames)?;
    if let Some((every_ms, for_ms)) = repeat {
        let start = Instant::now();
        // clap rejects 0; guard anyway so the loop always advances.
        let every = Duration::from_millis(every_ms.max(1));
        let total = Duration::from_millis(for_ms);
        let mut next = start + every;
        while next <= start + total {
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            }
            write(&frames)?;
            next += every;
        }
        let zero: Vec<u8> = cmds
            .iter()
            .filter_map(zero_rate)
            .flat_map(|c| serial::control_frame(&c.encode()))
            .collect();
        if !zero.is_empty() {
            write(&zero)?;
        }
    }
    stream
        .flush()
        .map_err(|e| Failure::Runtime(format!("cannot send to {target}: {e}")))?;
    close_gently(stream);
    Ok(())
}

/// How long `send` waits for the server to close its side after ours.
const CLOSE_GRACE: Duration = Duration::from_millis(250);

/// Ends the connection without risking our frames: the serial server streams postbacks to
/// every client, and closing a socket with unread data sends a reset, which can make the
/// server drop what it has not read yet. So: send FIN after the data, read (and discard)
/// until the server closes or a short grace period ends, then close.
pub fn close_gently(mut stream: TcpStream) {
    if stream.shutdown(std::net::Shutdown::Write).is_err() {
        return;
    }
    let deadline = Instant::now() + CLOSE_GRACE;
    let mut sink = [0u8; 1024];
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || stream.set_read_timeout(Some(left)).is_err() {
            return;
        }
        match stream.read(&mut sink) {
            Ok(0) | Err(_) => return,
            Ok(_) => {}
        }
    }
}

/// A postback as one readable line.
pub fn readable(pb: &Postback) -> String {
    // Centidegrees with exactly two decimals.
    let deg = |v: i64| {
        let sign = if v < 0 { "-" } else { "" };
        let a = v.unsigned_abs();
        format!("{sign}{}.{:02}", a / 100, a % 100)
    };
    let model = match pb.gimbal_type.model_name() {
        Some(name) => format!("{} ({name})", pb.gimbal_type.code()),
        None => format!("{} (unknown)", pb.gimbal_type.code()),
    };
    let mode = match pb.mode.name() {
        Some(name) => name.to_owned(),
        None => format!("unknown({})", pb.mode.code()),
    };
    format!(
        "pitch {} deg  heading {} deg  motor {} deg  mode {}  tracking {}  gimbal {}",
        deg(pb.pitch.into()),
        deg(pb.heading.into()),
        deg(pb.motor_heading.into()),
        mode,
        if pb.tracking { "yes" } else { "no" },
        model
    )
}

/// Unix time as a candump-style timestamp text (`1700000000.123456`).
fn now_timestamp() -> String {
    let d = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default();
    format!("{}.{:06}", d.as_secs(), d.subsec_micros())
}

/// `gimbalctl monitor --tcp HOST:PORT [--json] [--count N]`.
pub fn monitor(target: &str, json: bool, count: Option<u64>) -> Result<(), Failure> {
    if count == Some(0) {
        return Ok(());
    }
    let mut stream = connect(target)?;
    stream
        .set_read_timeout(Some(Duration::from_millis(100)))
        .map_err(|e| Failure::io(target, e))?;
    let stdout = std::io::stdout();
    let mut parser = StreamParser::new();
    let mut seen = 0u64;
    // The last postback (or the connection), and when to warn about silence next.
    let mut last = Instant::now();
    let mut warn_at = last + SILENCE_WARNING;
    let mut buf = [0u8; 4096];
    let mut line = Vec::with_capacity(512);
    loop {
        let n = match stream.read(&mut buf) {
            Ok(0) => {
                return Err(Failure::Runtime(format!(
                    "{target} closed the connection after {seen} postback(s)"
                )))
            }
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                ) =>
            {
                0
            }
            Err(e) => return Err(Failure::Runtime(format!("cannot read from {target}: {e}"))),
        };
        for item in parser.feed(&buf[..n]) {
            let StreamItem::Postback(pb) = item else {
                continue;
            };
            last = Instant::now();
            warn_at = last + SILENCE_WARNING;
            line.clear();
            if json {
                let ts = now_timestamp();
                decode::write_postback(&mut line, Some(ts.as_bytes()), None, &pb);
            } else {
                line.extend_from_slice(readable(&pb).as_bytes());
                line.push(b'\n');
            }
            let mut out = stdout.lock();
            out.write_all(&line)
                .and_then(|()| out.flush())
                .map_err(Failure::stdout)?;
            seen += 1;
            if count.is_some_and(|c| seen >= c) {
                return Ok(());
            }
        }
        let now = Instant::now();
        if now >= warn_at {
            eprintln!(
                "gimbalctl: warning: no postback from {target} for {:.1} s",
                (now - last).as_secs_f64()
            );
            warn_at += SILENCE_WARNING;
        }
    }
}
