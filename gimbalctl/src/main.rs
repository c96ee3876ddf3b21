//! `gimbalctl`: the host tool for bench work with IDU camera gimbals.
//!
//! Exit status: 0 success; 2 bad usage or a value out of range (stderr names the argument
//! and its valid range, stdout stays empty); 1 runtime failure (I/O, connection).

use std::io::Write;
use std::net::Ipv4Addr;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use idu_gimbal::wire::serial;

mod command;
mod control;
mod decode;
mod error;
mod json;
mod mavlink;
mod net;
mod plot;
mod rtsp;
mod sim;

use command::Spec;
use error::Failure;

/// Host tool for IDU camera gimbals: encode and decode CAN frames, send commands through
/// the serial server, monitor postbacks, simulate a gimbal.
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
    /// Send a control command's frame to the serial server (or gimbalctl sim)
    Send {
        /// The serial server, HOST:PORT (port 2000 when omitted)
        #[arg(long, value_name = "HOST:PORT")]
        tcp: String,
        /// Repeat the frame every MS milliseconds (a rate hold), then send zero rate
        #[arg(
            long,
            value_name = "MS",
            requires = "for_ms",
            global = true,
            value_parser = clap::value_parser!(u64).range(1..)
        )]
        repeat_ms: Option<u64>,
        /// How long to repeat, milliseconds
        #[arg(long, value_name = "MS", requires = "repeat_ms", global = true)]
        for_ms: Option<u64>,
        #[command(subcommand)]
        command: Spec,
    },
    /// Print the postbacks arriving from the serial server (or gimbalctl sim)
    Monitor {
        /// The serial server, HOST:PORT (port 2000 when omitted)
        #[arg(long, value_name = "HOST:PORT")]
        tcp: String,
        /// One JSON object per postback, as decode writes them
        #[arg(long)]
        json: bool,
        /// Exit after N postbacks
        #[arg(long, value_name = "N")]
        count: Option<u64>,
    },
    /// Interactive terminal panel: the latest postback, link state and counters; keys move the gimbal
    Control {
        /// The serial server, HOST:PORT (port 2000 when omitted), or gimbalctl sim
        #[arg(long, value_name = "HOST:PORT")]
        tcp: String,
        /// Rate of the arrow keys' rate hold, deg/s, 1..=100
        #[arg(
            long,
            value_name = "DEG_S",
            default_value_t = 20.0,
            allow_negative_numbers = true
        )]
        speed: f32,
    },
    /// Run a simulated gimbal on TCP, speaking the serial server's byte stream
    Sim {
        /// Address to listen on (port 0: any free port; the first stdout line says which)
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:2000")]
        listen: String,
        /// Exit after MS milliseconds (for scripted tests)
        #[arg(long, value_name = "MS")]
        exit_after_ms: Option<u64>,
        /// Clients served at once; more are turned away
        #[arg(long, value_name = "N", default_value_t = 8)]
        max_clients: usize,
    },
    /// Bridge MAVLink 2 on UDP to a gimbal: a MAVLink gimbal device (154) and camera (100)
    #[command(group(clap::ArgGroup::new("gimbal").required(true).args(["sim", "tcp"])))]
    Mavlink {
        /// The gimbal is the in-process simulated gimbal (on an in-memory CAN link)
        #[arg(long)]
        sim: bool,
        /// The gimbal is behind the serial server (or gimbalctl sim), HOST:PORT
        #[arg(long, value_name = "HOST:PORT")]
        tcp: Option<String>,
        /// UDP address to listen on (port 0: any free port; the first stdout line says which)
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:14560")]
        listen: String,
        /// Also send to this UDP peer (repeatable); peers heard from are always sent to
        #[arg(long, value_name = "ADDR")]
        to: Vec<String>,
        /// MAVLink system id (default: the autopilot's, from its heartbeat)
        #[arg(long, value_name = "1-255", value_parser = clap::value_parser!(u8).range(1..))]
        system_id: Option<u8>,
        /// Camera family for the stream URI: a2000, x3, argus, dual-light or f10
        #[arg(long, value_name = "FAMILY", default_value = "x3")]
        camera: String,
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
        for cmd in net::control_commands(spec)? {
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
            tcp,
            repeat_ms,
            for_ms,
            command,
        } => net::send(&tcp, &command, repeat_ms.zip(for_ms)),
        Top::Monitor { tcp, json, count } => net::monitor(&tcp, json, count),
        Top::Control { tcp, speed } => control::run(&tcp, speed),
        Top::Sim {
            listen,
            exit_after_ms,
            max_clients,
        } => sim::run(&listen, exit_after_ms, max_clients),
        Top::Mavlink {
            sim: _,
            tcp,
            listen,
            to,
            system_id,
            camera,
            exit_after_ms,
        } => mavlink::run(&mavlink::Options {
            gimbal: tcp
                .as_deref()
                .map_or(mavlink::Gimbal::Sim, mavlink::Gimbal::Tcp),
            listen: &listen,
            to: &to,
            system_id,
            camera: &camera,
            exit_after_ms,
        }),
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
