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
