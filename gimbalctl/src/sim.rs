//! `gimbalctl sim`: a simulated gimbal on TCP, speaking the serial server's byte stream.
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
use std::time::{Duration, Instant as StdInstant};

use idu_gimbal::sim::{SimConfig, Simulator};
use idu_gimbal::wire::control::Command;
use idu_gimbal::wire::ids;
use idu_gimbal::wire::serial::{StreamItem, StreamParser};
use idu_gimbal::Instant;

use crate::command;
use crate::error::Failure;

/// How often the loop runs.
const TICK: Duration = Duration::from_millis(5);
/// Reads per client per tick (4 KiB each).
const MAX_READS: usize = 16;

struct Client {
    stream: TcpStream,
    peer: SocketAddr,
    parser: StreamParser,
    /// The last command logged for this client.
    last_logged: Option<[u8; 8]>,
}

/// `gimbalctl sim [--listen ADDR] [--exit-after-ms MS] [--max-clients N]`.
pub fn run(listen: &str, exit_after_ms: Option<u64>, max_clients: usize) -> Result<(), Failure> {
    let addrs = crate::net::resolve(listen)?;
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
    let mut buf = [0u8; 4096];
    loop {
        if exit_after_ms.is_some_and(|ms| start.elapsed() >= Duration::from_millis(ms)) {
            eprintln!(
                "gimbalctl sim: exiting after {} ms",
                exit_after_ms.unwrap_or(0)
            );
            return Ok(());
        }
        // New clients.
        loop {
            match listener.accept() {
                Ok((stream, peer)) => {
                    if clients.len() >= max_clients {
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
                    });
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => {
                    // Running out of descriptors and the like: report, keep serving.
                    eprintln!("gimbalctl sim: accept failed: {e}");
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
                                        let line = command::command_line(&cmd);
                                        eprintln!("gimbalctl sim: {}: {line}", c.peer);
                                    }
                                }
                                Err(e) => eprintln!("gimbalctl sim: {}: rejected: {e}", c.peer),
                            }
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
