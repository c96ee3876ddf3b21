//! `send` and `monitor` over any transport (`--tcp`, `--can`, `--serial`: see
//! [`crate::transport`]), and how a frame is printed.

use std::io::Write;
use std::num::NonZeroU64;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use idu_gimbal::link::text::TextAssembler;
use idu_gimbal::wire::control::{Command, DualLightCommand, GimbalCommand, Rate};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::VehicleFrame;

use crate::decode;
use crate::error::Failure;
use crate::json::Obj;
use crate::spec::{self, Message, Spec};
use crate::transport::{clock, Job, Mode, Seen, Session, Target, Transport};

/// `monitor` warns after this long without a postback (three missed 500 ms periods).
pub const SILENCE_WARNING: Duration = Duration::from_millis(1500);

/// The control commands of a spec, or a usage error for vehicle and text commands, which
/// have no serial/TCP frame.
pub fn control_commands(spec: &Spec) -> Result<Vec<Command>, Failure> {
    match spec.build()? {
        Message::Control(cmds) => Ok(cmds),
        Message::Vehicle(_) | Message::Text(_) => Err(no_stream_frame(spec)),
    }
}

/// The usage error for a vehicle or text command asked of a serial/TCP transport.
fn no_stream_frame(spec: &Spec) -> Failure {
    Failure::Usage(format!(
        "{}: only control commands have a serial/TCP frame (--tcp, --serial); \
         vehicle and text frames exist only on CAN (--can)",
        spec.name()
    ))
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

/// How long `send` waits for its frames to be taken by the port or bus.
const SEND_TIMEOUT: Duration = Duration::from_secs(3);

/// `gimbalctl send (--tcp HOST:PORT | --can IFACE | --serial PATH[:BAUD]) [--repeat-ms MS
/// --for-ms MS] COMMAND ARGS...`.
pub fn send(
    target: &Target,
    spec: &Spec,
    repeat: Option<(NonZeroU64, u64)>,
) -> Result<(), Failure> {
    let job = SendJob::new(spec, repeat)?;
    if !target.carries_vehicle() && !matches!(job.message, Message::Control(_)) {
        // Vehicle and text frames exist only on CAN: a usage error before connecting.
        return Err(no_stream_frame(spec));
    }
    target.run(Mode::Drive, job)
}

struct SendJob {
    message: Message,
    text: Option<String>,
    repeat: Option<(NonZeroU64, u64)>,
}

impl SendJob {
    /// `spec`'s message, checked, and its text for the link's text queue.
    fn new(spec: &Spec, repeat: Option<(NonZeroU64, u64)>) -> Result<SendJob, Failure> {
        Ok(SendJob {
            message: spec.build()?,
            text: match spec {
                Spec::Text { text } => Some(text.clone()),
                _ => None,
            },
            repeat,
        })
    }
}

impl Job for SendJob {
    type Out = ();

    fn run<T: Transport>(self, mut s: Session<T>) -> Result<(), Failure> {
        let now = clock(Instant::now());
        let frames = self.message.frames().len() as u64;
        let mut want = u64::from(s.link.stats().frames_sent) + frames;
        queue(&mut s, &self.message, self.text.as_deref(), now())?;
        flush(&mut s, want, now)?;
        if let Some((every_ms, for_ms)) = self.repeat {
            let start = Instant::now();
            let every = Duration::from_millis(every_ms.get());
            let total = Duration::from_millis(for_ms);
            let mut next = start + every;
            while next <= start + total {
                // Polled while waiting: postbacks arriving are read, not left to pile up.
                while Instant::now() < next {
                    s.pump(now())?;
                    std::thread::sleep(Duration::from_millis(1).min(next - Instant::now()));
                }
                queue(&mut s, &self.message, self.text.as_deref(), now())?;
                want += frames;
                flush(&mut s, want, now)?;
                next += every;
            }
            if let Message::Control(cmds) = &self.message {
                for zero in cmds.iter().filter_map(zero_rate) {
                    queue(&mut s, &Message::Control(vec![zero]), None, now())?;
                    want += 1;
                }
                flush(&mut s, want, now)?;
            }
        }
        s.finish();
        Ok(())
    }
}

/// Hands a message to the library: commands to the queue, vehicle values to the push
/// (CAN), a text to the text queue (CAN).
fn queue<T: Transport>(
    s: &mut Session<T>,
    message: &Message,
    text: Option<&str>,
    now: idu_gimbal::Instant,
) -> Result<(), Failure> {
    match message {
        Message::Control(cmds) => {
            for cmd in cmds {
                s.link.send(*cmd).map_err(|_| {
                    Failure::Runtime(format!(
                        "cannot send to {}: the transmit queue is full",
                        s.transport.name()
                    ))
                })?;
            }
        }
        Message::Vehicle(VehicleFrame::Gps(g)) => s.link.set_gps(*g, now),
        Message::Vehicle(VehicleFrame::Altitude(a)) => s.link.set_altitude(*a, now),
        Message::Vehicle(VehicleFrame::Attitude(a)) => s.link.set_attitude(*a, now),
        Message::Text(_) => s
            .send_text(text.unwrap_or_default().as_bytes())
            .map_err(|e| {
                Failure::Runtime(format!(
                    "cannot send the text to {}: {e}",
                    s.transport.name()
                ))
            })?,
    }
    Ok(())
}

/// Polls until `want` frames in all were taken by the port or bus, and nothing of them
/// waits to be written.
fn flush<T: Transport>(
    s: &mut Session<T>,
    want: u64,
    now: impl Fn() -> idu_gimbal::Instant,
) -> Result<(), Failure> {
    let deadline = Instant::now() + SEND_TIMEOUT;
    loop {
        s.pump(now())?;
        if u64::from(s.link.stats().frames_sent) >= want && !s.has_transmit() {
            return Ok(());
        }
        if Instant::now() >= deadline {
            let mut why = format!(
                "cannot send to {}: not taken within {} s",
                s.transport.name(),
                SEND_TIMEOUT.as_secs()
            );
            for note in s.take_notes() {
                why.push_str("; ");
                why.push_str(&note);
            }
            return Err(Failure::Runtime(why));
        }
        std::thread::sleep(Duration::from_millis(1));
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

/// How often `monitor` tells of new faults (bus errors, bytes that held no frame).
const NOTE_EVERY: Duration = Duration::from_secs(1);

/// `gimbalctl monitor (--tcp HOST:PORT | --can IFACE | --serial PATH[:BAUD]) [--json]
/// [--count N]`.
pub fn monitor(target: &Target, json: bool, count: Option<u64>) -> Result<(), Failure> {
    if count == Some(0) {
        return Ok(());
    }
    target.run(Mode::Monitor, MonitorJob { json, count })
}

struct MonitorJob {
    json: bool,
    count: Option<u64>,
}

impl Job for MonitorJob {
    type Out = ();

    fn run<T: Transport>(self, s: Session<T>) -> Result<(), Failure> {
        let stdout = std::io::stdout();
        let mut out = stdout.lock();
        watch(
            s,
            self.json,
            self.count,
            &mut out,
            &mut std::io::stderr(),
            None,
        )
    }
}

/// `monitor`'s loop over any session, writing what it sees to `out` and its warnings (the
/// transport's notes, silence) to `warn`, as `eprintln!` would: a warning that cannot be
/// written is not a reason to stop watching. `until`, for tests, ends it after that long
/// (Ok). Each postback is printed once: a monitor session completes at most one per poll.
pub fn watch<T: Transport>(
    mut s: Session<T>,
    json: bool,
    count: Option<u64>,
    out: &mut impl Write,
    warn: &mut impl Write,
    until: Option<Duration>,
) -> Result<(), Failure> {
    let start = Instant::now();
    let now = clock(start);
    let mut seen = 0u64;
    let mut postbacks = s.link.stats().postbacks;
    // The last postback (or the start), and when to warn about silence next.
    let mut last = Instant::now();
    let mut warn_at = last + SILENCE_WARNING;
    let mut notes_at = last + NOTE_EVERY;
    let mut texts: TextAssembler<TEXT_CAPACITY> = TextAssembler::new();
    let mut line = Vec::with_capacity(512);
    loop {
        if until.is_some_and(|u| start.elapsed() >= u) {
            return Ok(());
        }
        let t = now();
        if let Err(e) = s.poll(t) {
            return Err(match e {
                Failure::Runtime(why) => {
                    Failure::Runtime(format!("{why} (after {seen} postback(s))"))
                }
                other => other,
            });
        }
        line.clear();
        let ts = now_timestamp();
        for frame in s.transport.take_frames() {
            if !frame.is(ids::POSTBACK) {
                describe_frame(&mut line, &frame, &mut texts, json.then_some(ts.as_bytes()));
            }
        }
        let mut done = false;
        if s.link.stats().postbacks != postbacks {
            postbacks = s.link.stats().postbacks;
            if let Some((pb, _age)) = s.link.latest_postback(t) {
                last = Instant::now();
                warn_at = last + SILENCE_WARNING;
                if json {
                    let id = T::IS_CAN.then_some(ids::POSTBACK);
                    decode::write_postback(&mut line, Some(ts.as_bytes()), id, &pb);
                } else {
                    line.extend_from_slice(readable(&pb).as_bytes());
                    line.push(b'\n');
                }
                seen += 1;
                done = count.is_some_and(|c| seen >= c);
            }
        }
        if !line.is_empty() {
            out.write_all(&line)
                .and_then(|()| out.flush())
                .map_err(Failure::stdout)?;
        }
        if done {
            s.finish();
            return Ok(());
        }
        let clock_now = Instant::now();
        if clock_now >= notes_at {
            for note in s.take_notes() {
                let _ = writeln!(warn, "gimbalctl: warning: {note}");
            }
            notes_at = clock_now + NOTE_EVERY;
        }
        if clock_now >= warn_at {
            let _ = writeln!(
                warn,
                "gimbalctl: warning: no postback from {} for {:.1} s",
                s.transport.name(),
                (clock_now - last).as_secs_f64()
            );
            warn_at += SILENCE_WARNING;
        }
        if s.transport.drained() {
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

/// The longest text `monitor` assembles from CAN text frames.
const TEXT_CAPACITY: usize = 256;

/// A CAN frame other than a postback, as a line: its class (control, vehicle, text,
/// foreign), its ID, and what it says. With `json` (the receive time), as a JSON object.
pub fn describe_frame(
    out: &mut Vec<u8>,
    f: &Seen,
    texts: &mut TextAssembler<TEXT_CAPACITY>,
    json: Option<&[u8]>,
) {
    let id = f.raw_id();
    let hex: String = f.data.iter().map(|b| format!("{b:02X}")).collect();
    let protocol = !f.remote && matches!(f.id, embedded_can::Id::Extended(_));
    let malformed = |out: &mut Vec<u8>, class: &str, why: &str| match json {
        Some(t) => {
            let mut o = Obj::start(out, "malformed", Some(t), Some(id));
            o.str("class", class).str("data", &hex).str("error", why);
            o.end();
        }
        None => out.extend_from_slice(
            format!(
                "{class:<8} {}  {}: {why}\n",
                f.id_text(),
                length_and_data(f, &hex)
            )
            .as_bytes(),
        ),
    };
    match id {
        ids::CONTROL if protocol => match Command::decode(&f.data) {
            Ok(cmd) => match json {
                Some(t) => decode::write_command(out, Some(t), Some(id), &cmd),
                None => out.extend_from_slice(
                    format!("control  {}  {}\n", f.id_text(), spec::command_line(&cmd)).as_bytes(),
                ),
            },
            Err(e) => malformed(out, "control", &e.to_string()),
        },
        ids::GPS | ids::ALTITUDE | ids::ATTITUDE if protocol => {
            match VehicleFrame::decode(id, &f.data) {
                Ok(v) => match json {
                    Some(t) => decode::write_vehicle(out, Some(t), Some(id), &v),
                    None => out.extend_from_slice(
                        format!("vehicle  {}  {}\n", f.id_text(), vehicle_text(&v)).as_bytes(),
                    ),
                },
                Err(e) => malformed(out, "vehicle", &e.to_string()),
            }
        }
        ids::TEXT | ids::TEXT_END if protocol => match texts.feed(id, &f.data) {
            Ok(Some(text)) => match json {
                Some(t) => {
                    let mut o = Obj::start(out, "text", Some(t), Some(id));
                    o.str("text", text);
                    o.end();
                }
                None => out
                    .extend_from_slice(format!("text     {}  {text:?}\n", f.id_text()).as_bytes()),
            },
            Ok(None) => {
                if json.is_none() {
                    out.extend_from_slice(
                        format!("text     {}  (part) {hex}\n", f.id_text()).as_bytes(),
                    );
                }
            }
            Err(e) => malformed(out, "text", &e.to_string()),
        },
        _ => match json {
            Some(t) => {
                let mut o = Obj::start(out, "foreign", Some(t), Some(id));
                o.bool("extended", matches!(f.id, embedded_can::Id::Extended(_)))
                    .bool("remote", f.remote)
                    .int("dlc", f.dlc as i64)
                    .str("data", &hex);
                o.end();
            }
            None => out.extend_from_slice(
                format!(
                    "foreign  {}  {}{}\n",
                    f.id_text(),
                    if f.remote { "remote " } else { "" },
                    length_and_data(f, &hex)
                )
                .as_bytes(),
            ),
        },
    }
}

/// `[DLC]` and the data in hex after a space, as candump writes them; a remote frame, or a
/// data frame of no bytes, has the length alone.
fn length_and_data(f: &Seen, hex: &str) -> String {
    if hex.is_empty() {
        format!("[{}]", f.dlc)
    } else {
        format!("[{}] {hex}", f.dlc)
    }
}

/// A vehicle frame in words, with exact decimals of its wire values.
fn vehicle_text(v: &VehicleFrame) -> String {
    let fixed = |v: i64, d: u32| {
        let mut b = Vec::new();
        crate::json::push_fixed(&mut b, v, d);
        String::from_utf8(b).unwrap_or_default()
    };
    match v {
        VehicleFrame::Gps(g) => format!(
            "gps {} {}",
            fixed(g.lat_e7().into(), 7),
            fixed(g.lon_e7().into(), 7)
        ),
        VehicleFrame::Altitude(a) => format!("altitude {} m", fixed(a.cm().into(), 2)),
        VehicleFrame::Attitude(a) => format!(
            "attitude pitch {} roll {} heading {} deg",
            fixed(a.pitch_centideg().into(), 2),
            fixed(a.roll_centideg().into(), 2),
            fixed(a.heading_centideg().into(), 2)
        ),
    }
}

/// `send` and `monitor` over the library's `CanPort<C>` on the core's in-memory CAN bus: the
/// same session code `--can` runs over a SocketCAN socket.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::can::mock_session;
    use embedded_can::{nb::Can, ExtendedId, Frame as _};
    use idu_gimbal::mock::{Bus, MockFrame};
    use idu_gimbal::sim::{SimConfig, Simulator};
    use idu_gimbal::wire::text;

    /// The seconds a silence warning on `mock0` says, or `None` for any other line.
    fn silence_secs(line: &str) -> Option<f64> {
        let rest = line.strip_prefix("gimbalctl: warning: no postback from mock0 for ")?;
        Some(rest.strip_suffix(" s").unwrap().parse().unwrap())
    }

    fn spec(args: &[&str]) -> Spec {
        use clap::Parser;
        #[derive(Parser)]
        struct One {
            #[command(subcommand)]
            spec: Spec,
        }
        let mut argv = vec!["one"];
        argv.extend_from_slice(args);
        One::try_parse_from(argv).expect("a command").spec
    }

    /// What `gimbalctl send --can` puts on the bus for `args`, as `ID#DATA`.
    fn sent_on_can(args: &[&str], repeat: Option<(NonZeroU64, u64)>) -> Vec<String> {
        sent_on(&Bus::new(1), args, repeat)
    }

    /// What `gimbalctl send --can` puts on `bus` for `args`, as `ID#DATA`.
    fn sent_on(bus: &Bus<2, 64>, args: &[&str], repeat: Option<(NonZeroU64, u64)>) -> Vec<String> {
        let mut gimbal = bus.endpoint(1).unwrap();
        let session = mock_session(bus, Mode::Drive);
        let job = SendJob::new(&spec(args), repeat).unwrap();
        job.run(session).expect("sent");
        let mut frames = Vec::new();
        while let Ok(f) = gimbal.receive() {
            let hex: String = f.data().iter().map(|b| format!("{b:02X}")).collect();
            frames.push(format!("{:08X}#{hex}", f.raw_id()));
        }
        frames
    }

    #[test]
    fn send_on_can_puts_each_message_on_the_bus() {
        // The same frames `encode` prints (and the README's examples).
        assert_eq!(
            sent_on_can(&["pitch", "-45"], None),
            ["00000F01#0F08023EFE000000"]
        );
        assert_eq!(
            sent_on_can(&["look-at", "0", "0", "1000", "0", "0.009", "0"], None),
            ["00000F01#0F08018403000000", "00000F01#0F08023FFE000000"]
        );
        // Vehicle and text frames, which only CAN carries, through the link's push and
        // text queue, as computed by hand: latitude and longitude in 1e-7 degrees
        // (473977420, 85455940) as little-endian i32; pitch, roll and heading in 0.01°
        // (100, -200, 3000) as little-endian i16, i16, u16; the text in 8-byte chunks, the
        // last on its own ID and padded with zeros (`tests/encode.rs`'s golden vector).
        assert_eq!(
            sent_on_can(&["gps", "47.397742", "8.545594"], None),
            ["0000FF15#4C52401C44F41705"]
        );
        assert_eq!(
            sent_on_can(&["attitude", "1", "-2", "30"], None),
            ["0000FF13#640038FFB80B0000"]
        );
        assert_eq!(
            sent_on_can(&["text", "HELLO, GIMBAL"], None),
            ["02008201#48454C4C4F2C2047", "02008202#494D42414C000000"]
        );
    }

    #[test]
    fn send_on_can_holds_a_rate_then_sends_zero_rate() {
        let frames = sent_on_can(&["rate", "10", "0"], NonZeroU64::new(50).zip(Some(300)));
        let (last, held) = frames.split_last().unwrap();
        assert_eq!(last, "00000F01#0F04000000000000");
        // The first, then a repeat at 50, 100, … 300 ms: a count of passes, not of time.
        assert_eq!(held.len(), 7, "{frames:?}");
        assert!(held.iter().all(|f| f == "00000F01#0F04E80300000000"));
    }

    #[test]
    fn send_on_can_repeats_a_message_of_two_frames_whole() {
        let frames = sent_on_can(
            &["look-at", "0", "0", "1000", "0", "0.009", "0"],
            NonZeroU64::new(50).zip(Some(100)),
        );
        // The first, then a repeat at 50 and 100 ms; no zero rate (not a rate command).
        let look_at = ["00000F01#0F08018403000000", "00000F01#0F08023FFE000000"];
        assert_eq!(frames, [look_at, look_at, look_at].concat());
    }

    /// A bus whose transmitter fails half its calls (seeded, so the same calls each run):
    /// `send` polls on until every frame of a six-frame text is on the bus, each once and
    /// in order, as on a bus without faults.
    #[test]
    fn send_on_can_retries_until_the_bus_takes_every_frame() {
        let text = ["text", "THE QUICK BROWN FOX JUMPS OVER THE LAZY DOG"];
        let clean = sent_on_can(&text, None);
        assert_eq!(clean.len(), 6, "{clean:?}");
        let faulty = Bus::new(7).with_faults(idu_gimbal::mock::Faults {
            tx_error: 0.5,
            ..idu_gimbal::mock::Faults::NONE
        });
        assert_eq!(sent_on(&faulty, &text, None), clean);
        assert!(faulty.stats().injected_errors >= 3, "{:?}", faulty.stats());
    }

    /// A writer that keeps, with what is written, when each line was ended (from `start`).
    struct Stamped {
        start: Instant,
        text: String,
        ended: Vec<Duration>,
    }

    impl Write for Stamped {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.text.push_str(std::str::from_utf8(buf).unwrap());
            let at = self.start.elapsed();
            self.ended
                .extend(buf.iter().filter(|&&b| b == b'\n').map(|_| at));
            Ok(buf.len())
        }

        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// A silent bus whose receiver fails half its calls, one error waiting at the start:
    /// the errors' notes first at the first second, then at most once a second (in 2.5 s,
    /// two batches of at most a line for each of the three kinds), the silence warned of
    /// after 1.5 s and not again before 3 s. Only earliest times are asserted; the counts
    /// need one pass of the loop between 1.5 s and the end at 2.5 s, a second's margin.
    #[test]
    fn monitor_says_notes_each_second_and_silence_each_1_5_s() {
        let bus: Bus<2, 64> = Bus::new(6).with_faults(idu_gimbal::mock::Faults {
            rx_error: 0.5,
            ..idu_gimbal::mock::Faults::NONE
        });
        let session = mock_session(&bus, Mode::Monitor);
        // And one error waiting at the start: counted by the first poll, said at 1 s.
        bus.inject_error(0, embedded_can::ErrorKind::Crc);
        let mut warn = Stamped {
            start: Instant::now(),
            text: String::new(),
            ended: Vec::new(),
        };
        let mut out = Vec::new();
        watch(
            session,
            false,
            None,
            &mut out,
            &mut warn,
            Some(Duration::from_millis(2500)),
        )
        .unwrap();
        assert!(out.is_empty());
        type Lines<'a> = Vec<(&'a str, Duration)>;
        let (silence, notes): (Lines, Lines) = warn
            .text
            .lines()
            .zip(warn.ended)
            .partition(|(l, _)| silence_secs(l).is_some());
        assert_eq!(silence.len(), 1, "{}", warn.text);
        assert!(silence_secs(silence[0].0) >= Some(1.5), "{:?}", silence[0]);
        assert!(silence[0].1 >= SILENCE_WARNING, "{:?}", silence[0]);
        assert!((1..=6).contains(&notes.len()), "{}", warn.text);
        assert!(notes[0].1 >= NOTE_EVERY, "{:?}", notes[0]);
        for (line, _) in &notes {
            assert!(
                line.starts_with("gimbalctl: warning: mock0: ") && line.ends_with(" in all)"),
                "{line}"
            );
        }
    }

    /// Puts on the bus, from endpoint 1: another controller's command, the flight
    /// controller's attitude, a text, a foreign standard frame, remote frames on the control,
    /// GPS and text IDs, a control and an attitude frame too short, then the simulated gimbal's
    /// postbacks.
    fn traffic(bus: &Bus<2, 64>) -> idu_gimbal::mock::Endpoint<'_, 2, 64> {
        let mut other = bus.endpoint(1).unwrap();
        let mut put = |f: MockFrame| other.transmit(&f).unwrap();
        let ext = |id, data: &[u8]| MockFrame::extended(id, data).unwrap();
        let control = spec(&["pitch", "-45"]).build().unwrap().frames();
        put(ext(control[0].id, &control[0].data));
        let att = spec(&["attitude", "0", "0", "30.05"])
            .build()
            .unwrap()
            .frames();
        put(ext(att[0].id, &att[0].data));
        for f in text::chunks(b"HELLO, GIMBAL").unwrap() {
            put(ext(f.id, &f.data));
        }
        put(MockFrame::standard(0x123, &[1, 2, 3]).unwrap());
        // Remote frames on three of the protocol's IDs: requests, not its frames.
        let remote = |id, dlc| MockFrame::new_remote(ExtendedId::new(id).unwrap(), dlc).unwrap();
        put(remote(ids::CONTROL, 8));
        put(remote(ids::GPS, 0));
        put(remote(ids::TEXT, 8));
        // A control frame of no bytes and an attitude frame of two: malformed.
        put(ext(ids::CONTROL, &[]));
        put(ext(ids::ATTITUDE, &[1, 2]));
        let mut sim: Simulator =
            Simulator::new(SimConfig::default(), idu_gimbal::Instant::from_millis(0));
        for ms in [500, 1000] {
            sim.poll(idu_gimbal::Instant::from_millis(ms)).unwrap();
            while let Some(f) = sim.pop_frame() {
                put(ext(f.id, &f.data));
            }
        }
        other
    }

    #[test]
    fn monitor_on_can_shows_postbacks_and_every_other_frame() {
        let bus: Bus<2, 64> = Bus::new(2);
        let session = mock_session(&bus, Mode::Monitor);
        let _other = traffic(&bus);
        let (mut out, mut warn) = (Vec::new(), Vec::new());
        watch(
            session,
            false,
            Some(2),
            &mut out,
            &mut warn,
            Some(Duration::from_secs(5)),
        )
        .unwrap();
        // A postback puts the silence warning 1.5 s after it: any said here (none, unless
        // the test stalls that long) says at least that much.
        for line in String::from_utf8(warn).unwrap().lines() {
            if let Some(secs) = silence_secs(line) {
                assert!(secs >= 1.5, "{line}");
            }
        }
        let out = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = out.lines().collect();
        let postback = "pitch 0.00 deg  heading 0.00 deg  motor 0.00 deg  mode heading_follow  \
                        tracking no  gimbal 1 (X30/X30GT)";
        assert_eq!(
            lines,
            [
                "control  00000F01  pitch -45",
                "vehicle  0000FF13  attitude pitch 0 roll 0 heading 30.05 deg",
                "text     02008201  (part) 48454C4C4F2C2047",
                "text     02008202  \"HELLO, GIMBAL\"",
                "foreign  123  [3] 010203",
                "foreign  00000F01  remote [8]",
                "foreign  0000FF15  remote [0]",
                "foreign  02008201  remote [8]",
                "control  00000F01  [0]: control frame must be 8 bytes, got 0",
                "vehicle  0000FF13  [2] 0102: vehicle frame has 2 bytes, expected 8",
                postback,
                postback,
            ],
            "{out}"
        );
    }

    #[test]
    fn monitor_on_can_writes_json_as_decode_does() {
        let bus: Bus<2, 64> = Bus::new(3);
        let session = mock_session(&bus, Mode::Monitor);
        let _other = traffic(&bus);
        let mut out = Vec::new();
        watch(
            session,
            true,
            Some(1),
            &mut out,
            &mut std::io::sink(),
            Some(Duration::from_secs(5)),
        )
        .unwrap();
        let objects: Vec<serde_json::Value> = String::from_utf8(out)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let kinds: Vec<&str> = objects
            .iter()
            .map(|o| o["type"].as_str().unwrap())
            .collect();
        assert_eq!(
            kinds,
            [
                "command",
                "attitude",
                "text",
                "foreign",
                "foreign",
                "foreign",
                "foreign",
                "malformed",
                "malformed",
                "postback"
            ]
        );
        assert_eq!(objects[0]["command"], "pitch");
        assert_eq!(objects[2]["text"], "HELLO, GIMBAL");
        assert_eq!(objects[3]["id"], 0x123);
        assert_eq!(objects[3]["extended"], false);
        assert_eq!(
            (
                &objects[3]["remote"],
                &objects[3]["dlc"],
                &objects[3]["data"]
            ),
            (&false.into(), &3.into(), &"010203".into())
        );
        assert_eq!(objects[4]["id"], 0x0000_0F01);
        assert_eq!(
            (&objects[4]["extended"], &objects[4]["remote"]),
            (&true.into(), &true.into())
        );
        assert_eq!(
            (&objects[4]["dlc"], &objects[4]["data"]),
            (&8.into(), &"".into())
        );
        assert_eq!(
            (&objects[7]["class"], &objects[7]["data"]),
            (&"control".into(), &"".into())
        );
        assert_eq!(objects[9]["id"], 0x030F_0001);
        assert_eq!(objects[9]["gimbal_model"], "X30/X30GT");
        assert!(objects.iter().all(|o| o["t"].as_f64().unwrap() > 1.6e9));
    }

    #[test]
    fn bus_errors_are_counted_and_told_once() {
        let bus: Bus<2, 64> = Bus::new(4);
        let mut s = mock_session(&bus, Mode::Drive);
        let _other = traffic(&bus);
        bus.inject_error(0, embedded_can::ErrorKind::Acknowledge);
        let t = idu_gimbal::Instant::from_millis(0);
        s.pump(t).unwrap();
        assert_eq!(s.link.stats().postbacks, 2);
        let counters = s.counters();
        assert!(
            counters[2].starts_with("bus errors 1  last: "),
            "{counters:?}"
        );
        let notes = s.take_notes();
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].starts_with("mock0: ") && notes[0].ends_with("(1 new, 1 in all)"));
        assert!(s.take_notes().is_empty());
        // A monitor-less session records no frames.
        assert!(s.transport.take_frames().is_empty());
    }

    #[test]
    fn postbacks_lost_on_the_bus_are_told_once_as_they_grow() {
        // A simulated gimbal's postback with one byte of its second frame flipped (a CRC
        // error), then a good one: the link counts the first, and the notes say it once.
        let bus: Bus<2, 64> = Bus::new(5);
        let mut s = mock_session(&bus, Mode::Drive);
        let mut other = bus.endpoint(1).unwrap();
        let mut sim: Simulator =
            Simulator::new(SimConfig::default(), idu_gimbal::Instant::from_millis(0));
        let mut frames = Vec::new();
        for ms in [500, 1000] {
            sim.poll(idu_gimbal::Instant::from_millis(ms)).unwrap();
            while let Some(f) = sim.pop_frame() {
                frames.push(f);
            }
        }
        assert_eq!(frames.len(), 8);
        frames[1].data[3] ^= 0x40;
        for f in &frames {
            other
                .transmit(&MockFrame::extended(f.id, &f.data).unwrap())
                .unwrap();
        }
        s.pump(idu_gimbal::Instant::from_millis(0)).unwrap();
        assert_eq!(
            (s.link.stats().postbacks, s.link.stats().crc_errors),
            (1, 1)
        );
        let notes = s.take_notes();
        assert_eq!(
            notes,
            [
                "mock0: postbacks lost: 1 with a bad CRC, 0 cut short (a frame missing or late), \
              0 restarted by a new header, 0 postback-ID frames not 8 bytes; postbacks so far: 1"
            ]
        );
        assert!(s.take_notes().is_empty());
    }
}
