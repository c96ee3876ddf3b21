//! `gimbalctl`: the host tool for bench work with IDU camera gimbals.
//!
//! Exit status: 0 success; 2 bad usage or a value out of range (stderr names the argument
//! and its valid range, stdout stays empty); 1 runtime failure (I/O, connection).

use std::io::Write;
use std::net::Ipv4Addr;
use std::num::{NonZeroU16, NonZeroU64, NonZeroUsize};
use std::process::ExitCode;

use clap::builder::TypedValueParser as _;
use clap::{Parser, Subcommand};
use idu_gimbal::wire::serial;

/// A stderr line that never panics: `std`'s `eprintln!` panics when stderr is gone (a pipe
/// whose reader exited, as in `gimbalctl sim 2>&1 | head`); a line nobody can read is
/// dropped and the run goes on. Defined before the modules, it is the one they use.
macro_rules! eprintln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

mod counts;
mod decode;
mod error;
mod json;
mod mavlink;
mod panel;
mod plot;
mod rtsp;
mod send_monitor;
mod sim;
mod spec;
mod tcp;
mod transport;

use error::Failure;
use spec::Spec;
use transport::{GimbalArgs, SerialSpec, Target, AUTOPILOT_BAUD};

/// Host tool for IDU camera gimbals: encode and decode CAN frames, send commands and monitor
/// postbacks over the serial server (TCP), SocketCAN or the gimbal's UART, simulate a gimbal.
#[derive(Parser, Debug)]
#[command(name = "gimbalctl", version, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Top,
}

#[derive(Subcommand, Debug)]
enum Top {
    /// Print a command's CAN frames (ID#DATA, cansend syntax), or its 24-byte serial/TCP frame with --tcp
    Encode {
        /// Print the 24-byte serial/TCP frame as 48 hex digits (control commands only)
        #[arg(long, global = true)]
        tcp: bool,
        #[command(subcommand)]
        command: Spec,
    },
    /// Decode CAN logs (candump -L, cansend or candump screen form) or a serial/TCP capture to JSON lines
    Decode {
        /// Read raw bytes of a serial/TCP capture instead of a CAN log
        #[arg(long)]
        stream: bool,
        /// End with a {"type":"stats",...} line of counters
        #[arg(long)]
        stats: bool,
        /// The log; stdin when absent or "-"
        #[arg(value_name = "FILE|-")]
        file: Option<String>,
    },
    /// Draw one picture of a log: angles, commands, rates, mode, tracking, link gaps, CRC errors, lost frames
    Plot {
        /// Read raw bytes of a serial/TCP capture instead of a CAN log
        #[arg(long)]
        stream: bool,
        /// The picture to write; .svg (PNG would need system fonts)
        #[arg(short = 'o', long = "output", value_name = "FILE.svg")]
        output: String,
        /// The log; stdin when absent or "-"
        #[arg(value_name = "LOG|-")]
        file: Option<String>,
    },
    /// Send a command to the gimbal: over the serial server or the UART (control commands), or CAN (any)
    Send {
        #[command(flatten)]
        gimbal: GimbalArgs,
        /// Repeat the frame every MS milliseconds (a rate hold), then send zero rate
        #[arg(
            long,
            value_name = "MS",
            requires = "for_ms",
            global = true,
            value_parser = clap::value_parser!(u64).range(1..).try_map(NonZeroU64::try_from)
        )]
        repeat_ms: Option<NonZeroU64>,
        /// How long to repeat, milliseconds
        #[arg(long, value_name = "MS", requires = "repeat_ms", global = true)]
        for_ms: Option<u64>,
        #[command(subcommand)]
        command: Spec,
    },
    /// Print the gimbal's postbacks (on CAN also every other frame: control, vehicle, text, foreign)
    Monitor {
        #[command(flatten)]
        gimbal: GimbalArgs,
        /// One JSON object per postback, as decode writes them
        #[arg(long)]
        json: bool,
        /// Exit after N postbacks
        #[arg(long, value_name = "N")]
        count: Option<u64>,
    },
    /// Interactive terminal panel: the latest postback, link state and counters; keys move the gimbal
    Control {
        #[command(flatten)]
        gimbal: GimbalArgs,
        /// Rate of the arrow keys' rate hold, deg/s, 1..=100
        #[arg(
            long,
            value_name = "DEG_S",
            default_value_t = 20.0,
            allow_negative_numbers = true
        )]
        speed: f32,
    },
    /// Run a simulated gimbal on TCP (the serial server's byte stream) or on a pseudo-terminal (its UART)
    Sim {
        /// Address to listen on (port 0: any free port; the first stdout line says which)
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:2000")]
        listen: String,
        /// Serve on a new pseudo-terminal instead, as the gimbal's UART (the first stdout line gives the path to open with --serial)
        #[arg(long, conflicts_with_all = ["listen", "max_clients"])]
        pty: bool,
        /// Exit after MS milliseconds (for scripted tests)
        #[arg(long, value_name = "MS")]
        exit_after_ms: Option<u64>,
        /// Clients served at once, 1..=65535; more are turned away
        #[arg(
            long,
            value_name = "N",
            default_value = "8",
            value_parser = clap::value_parser!(u16).range(1..).try_map(NonZeroU16::try_from)
        )]
        max_clients: NonZeroU16,
    },
    /// Bridge MAVLink 2 (UDP or a serial port) to a gimbal: a MAVLink gimbal device (154) and camera (100)
    Mavlink {
        /// The gimbal is the in-process simulated gimbal (on an in-memory CAN link)
        #[arg(long, group = "gimbal")]
        sim: bool,
        #[command(flatten)]
        gimbal: GimbalArgs,
        /// UDP address to listen on (port 0: any free port; the first stdout line says which)
        #[arg(long, value_name = "HOST:PORT", default_value = "127.0.0.1:14560")]
        listen: String,
        /// Also send to this UDP peer (repeatable); peers heard from are always sent to
        #[arg(long, value_name = "HOST:PORT")]
        to: Vec<String>,
        /// The autopilot on a serial port instead of UDP (a TELEM port): PATH, or PATH:BAUD (921600 8N1 when BAUD is omitted)
        #[arg(long, value_name = "PATH[:BAUD]", conflicts_with_all = ["listen", "to"])]
        autopilot_serial: Option<String>,
        /// MAVLink system id (default: the autopilot's, from its heartbeat)
        #[arg(long, value_name = "1-255", value_parser = clap::value_parser!(u8).range(1..))]
        system_id: Option<u8>,
        /// Camera family: its streams, and with dual-light the thermal stream and settings (a2000, x3, argus, dual-light or f10)
        #[arg(long, value_name = "FAMILY", default_value = "x3")]
        camera: String,
        /// The main camera's horizontal and vertical field of view at 1× zoom, degrees, each more than 0 and less than 180 (default unknown: no source gives it for any family)
        #[arg(long, value_name = "HFOV,VFOV")]
        camera_fov: Option<String>,
        /// The video streams' resolution in pixels, each 1-65535 (default unknown)
        #[arg(long, value_name = "WIDTHxHEIGHT")]
        camera_resolution: Option<String>,
        /// Sign MAVLink 2 with the key MAVProxy's `signing setup` and QGroundControl derive from this passphrase (its SHA-256): only frames signed with it are acted on
        #[arg(long, value_name = "TEXT", conflicts_with = "signing_key_file")]
        signing_passphrase: Option<String>,
        /// Sign MAVLink 2 with the 32-byte key in this file, as 64 hex digits
        #[arg(long, value_name = "PATH")]
        signing_key_file: Option<String>,
        /// With --sim: what the simulated gimbal holds in lock while the vehicle turns, its north heading (the default) or its motor angle (the vendor document does not say)
        #[arg(long, value_name = "WHAT", value_enum)]
        sim_lock_holds: Option<mavlink::SimLock>,
        /// Exit after MS milliseconds (for scripted tests)
        #[arg(long, value_name = "MS")]
        exit_after_ms: Option<u64>,
    },
    /// Print the RTSP address of a camera's video stream
    Rtsp {
        /// a2000, x3, argus, dual-light or f10
        family: String,
        /// main, aux1, aux2 or infrared, as the family has them
        stream: String,
        /// Camera IP address (default 192.168.42.108)
        #[arg(long, value_name = "IP")]
        ip: Option<Ipv4Addr>,
        /// User name (default admin; with --password)
        #[arg(long, value_name = "U", requires = "password")]
        user: Option<String>,
        /// Password (default admin; with --user)
        #[arg(long, value_name = "P", requires = "user")]
        password: Option<String>,
    },
}

/// Writes `text` to stdout in one go.
fn print(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(Failure::stdout)
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

/// `gimbalctl encode [--tcp] COMMAND ARGS...`.
fn encode(spec: &Spec, tcp: bool) -> Result<(), Failure> {
    let mut text = String::new();
    if tcp {
        for cmd in send_monitor::control_commands(spec)? {
            text.push_str(&hex(&serial::control_frame(&cmd.encode())));
            text.push('\n');
        }
    } else {
        for frame in spec.build()?.frames() {
            text.push_str(&format!("{:08X}#{}\n", frame.id, hex(&frame.data)));
        }
    }
    print(&text)
}

fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Top::Encode { tcp, command } => encode(&command, tcp),
        Top::Decode {
            stream,
            stats,
            file,
        } => decode::run(file.as_deref(), stream, stats),
        Top::Plot {
            stream,
            output,
            file,
        } => plot::run(file.as_deref(), stream, &output),
        Top::Send {
            gimbal,
            repeat_ms,
            for_ms,
            command,
        } => send_monitor::send(
            &Target::from_args(&gimbal)?,
            &command,
            repeat_ms.zip(for_ms),
        ),
        Top::Monitor {
            gimbal,
            json,
            count,
        } => send_monitor::monitor(&Target::from_args(&gimbal)?, json, count),
        Top::Control { gimbal, speed } => {
            let target = Target::from_args(&gimbal)?;
            panel::run(&target, speed)
        }
        Top::Sim {
            listen,
            pty,
            exit_after_ms,
            max_clients,
        } => {
            if pty {
                sim::run_pty(exit_after_ms)
            } else {
                sim::run(&listen, exit_after_ms, NonZeroUsize::from(max_clients))
            }
        }
        Top::Mavlink {
            sim,
            gimbal,
            listen,
            to,
            autopilot_serial,
            system_id,
            camera,
            camera_fov,
            camera_resolution,
            signing_passphrase,
            signing_key_file,
            sim_lock_holds,
            exit_after_ms,
        } => {
            let target = if sim {
                None
            } else {
                // clap's `requires` counts `--sim` present by its default (false).
                if sim_lock_holds.is_some() {
                    return Err(Failure::Usage(
                        "--sim-lock-holds: only with --sim (it sets the simulated gimbal)".into(),
                    ));
                }
                Some(Target::from_args(&gimbal)?)
            };
            let serial = autopilot_serial
                .as_deref()
                .map(|s| SerialSpec::parse("--autopilot-serial", s, AUTOPILOT_BAUD))
                .transpose()?;
            mavlink::run(&mavlink::Options {
                gimbal: target
                    .as_ref()
                    .map_or(mavlink::Gimbal::Sim, mavlink::Gimbal::Target),
                autopilot: match &serial {
                    Some(spec) => mavlink::Autopilot::Serial(spec),
                    None => mavlink::Autopilot::Udp {
                        listen: &listen,
                        to: &to,
                    },
                },
                system_id,
                camera: &camera,
                camera_fov: camera_fov.as_deref(),
                camera_resolution: camera_resolution.as_deref(),
                signing: match (&signing_passphrase, &signing_key_file) {
                    (Some(p), _) => Some(mavlink::SigningKey::Passphrase(p)),
                    (None, Some(path)) => Some(mavlink::SigningKey::File(path)),
                    (None, None) => None,
                },
                sim_lock_holds: sim_lock_holds.unwrap_or(mavlink::SimLock::North),
                exit_after_ms,
            })
        }
        Top::Rtsp {
            family,
            stream,
            ip,
            user,
            password,
        } => {
            let creds = user.as_deref().zip(password.as_deref());
            let url = rtsp::address(&family, &stream, ip, creds)?;
            print(&format!("{url}\n"))
        }
    }
}

fn main() -> ExitCode {
    // clap prints its own usage errors to stderr and exits 2 (help and version: 0).
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Usage(msg)) => {
            eprintln!("gimbalctl: error: {msg}");
            ExitCode::from(2)
        }
        Err(Failure::Runtime(msg)) => {
            eprintln!("gimbalctl: error: {msg}");
            ExitCode::from(1)
        }
        Err(Failure::BrokenPipe) => ExitCode::SUCCESS,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_is_consistent() {
        Cli::command().debug_assert();
    }
}
