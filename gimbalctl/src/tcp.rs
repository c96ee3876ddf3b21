//! The TCP helpers every TCP use shares (the serial server's client, the simulator's
//! server, the MAVLink bridge's addresses): resolving, connecting, closing gently.

use std::io::Read;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use idu_gimbal::interface::SERIAL_SERVER_PORT;

use crate::error::Failure;

/// How long `send` and `monitor` wait for the connection.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(3);
/// How long a write may block before the server is taken to be gone.
const WRITE_TIMEOUT: Duration = Duration::from_secs(3);

/// What a `HOST` with no port means for an option: the serial server's port (2000) for
/// the serial server's addresses (`--tcp`, the simulator's `--listen`), nothing for a
/// MAVLink address, whose port differs between autopilots and ground stations.
#[derive(Clone, Copy, Debug)]
pub enum DefaultPort {
    /// A missing port is [`SERIAL_SERVER_PORT`].
    SerialServer,
    /// A missing port is a usage error.
    None,
}

/// Checks the form of `target`, the value of `option`: `HOST:PORT`, `[v6]:PORT`, or with
/// [`DefaultPort::SerialServer`] a `HOST` or bare IPv6 address alone. Returns it with its
/// port, ready to resolve; a usage error names the option and the form. Nothing is looked
/// up, so every argument can be checked before a slow or failing name lookup.
pub fn address(option: &str, target: &str, default: DefaultPort) -> Result<String, Failure> {
    if target.parse::<SocketAddr>().is_ok() {
        return Ok(target.to_owned());
    }
    let form = match default {
        DefaultPort::SerialServer => "HOST:PORT or HOST (port 2000)",
        DefaultPort::None => "HOST:PORT",
    };
    let usage = || {
        Failure::Usage(format!(
            "{option} {target:?}: expected {form} with PORT in [0, 65535]"
        ))
    };
    match (target.rsplit_once(':'), default) {
        // A bare IPv6 address has colons but no port.
        (Some((host, _)), DefaultPort::SerialServer)
            if host.contains(':') && !host.starts_with('[') =>
        {
            Ok(format!("[{target}]:{SERIAL_SERVER_PORT}"))
        }
        (Some((host, port)), _) => {
            if host.is_empty() || host.contains(':') && !host.starts_with('[') {
                return Err(usage());
            }
            port.parse::<u16>().map_err(|_| usage())?;
            Ok(target.to_owned())
        }
        (None, DefaultPort::SerialServer) if !target.is_empty() => {
            Ok(format!("{target}:{SERIAL_SERVER_PORT}"))
        }
        (None, _) => Err(usage()),
    }
}

/// Looks up an [`address`]'s form of `target` (a runtime failure when the name has no
/// address).
pub fn resolve(
    option: &str,
    target: &str,
    default: DefaultPort,
) -> Result<Vec<SocketAddr>, Failure> {
    let with_port = address(option, target, default)?;
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
    for addr in resolve("--tcp", target, DefaultPort::SerialServer)? {
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;
    use std::net::TcpListener;

    fn usage(option: &str, target: &str, default: DefaultPort) -> bool {
        matches!(address(option, target, default), Err(Failure::Usage(_)))
    }

    /// The forms each option takes, the serial server's port added where a host is alone
    /// (a bare IPv6 address in brackets), and every other form refused.
    #[test]
    fn addresses_take_their_forms_and_refuse_the_rest() {
        let serial = DefaultPort::SerialServer;
        for (target, with_port) in [
            ("127.0.0.1:2001", "127.0.0.1:2001"),
            ("[::1]:2001", "[::1]:2001"),
            ("gimbal.local:2001", "gimbal.local:2001"),
            ("gimbal.local", "gimbal.local:2000"),
            ("::1", "[::1]:2000"),
            ("fe80::1", "[fe80::1]:2000"),
        ] {
            assert_eq!(address("--tcp", target, serial).unwrap(), with_port);
        }
        for target in [
            "",
            ":2000",
            "gimbal.local:",
            "gimbal.local:65536",
            "[::1]",
            "[::1]:x",
        ] {
            assert!(usage("--tcp", target, serial), "{target:?}");
        }
        let mavlink = DefaultPort::None;
        for target in ["127.0.0.1:14550", "[::1]:14550", "localhost:14550"] {
            assert_eq!(address("--to", target, mavlink).unwrap(), target);
        }
        // "localhost" alone: below, with its message.
        for target in ["", "::1", "a:b:14550", ":14550", "localhost:-1"] {
            assert!(usage("--to", target, mavlink), "{target:?}");
        }
        let Err(Failure::Usage(e)) = address("--to", "localhost", mavlink) else {
            panic!("a usage error");
        };
        assert_eq!(
            e,
            "--to \"localhost\": expected HOST:PORT with PORT in [0, 65535]"
        );
    }

    /// Closing gently: what we sent reaches a server that had written to us unread (a
    /// plain close would reset the connection, and the server lose it), and a server
    /// that never closes keeps us no longer than the grace period.
    #[test]
    fn a_gentle_close_loses_nothing_and_waits_a_bounded_time() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        let server = std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            // Postbacks the client never reads.
            s.write_all(&[0x55; 4096]).unwrap();
            std::thread::sleep(Duration::from_millis(50));
            let mut got = Vec::new();
            let read = s.read_to_end(&mut got).map(|_| got);
            // Open after the client's FIN: the client waits out its grace, no longer.
            std::thread::sleep(Duration::from_secs(1));
            read
        });
        let mut client = TcpStream::connect(addr).unwrap();
        client.write_all(b"frame").unwrap();
        std::thread::sleep(Duration::from_millis(20));
        let started = Instant::now();
        close_gently(client);
        let waited = started.elapsed();
        // The grace period, plus the scheduler's slack on a loaded machine.
        assert!(
            waited >= CLOSE_GRACE && waited < Duration::from_secs(1),
            "{waited:?}"
        );
        assert_eq!(server.join().unwrap().unwrap(), b"frame");
    }
}
