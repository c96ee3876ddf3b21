extern crate std;

use super::*;
use idu_gimbal::mock::Faults;
use std::string::String;

/// The simulated gimbal's frames for 6 s (a postback every 500 ms), on `bus`: how many
/// it made and how many the bus did not take.
fn gimbal_frames(bus: &DemoBus) -> (u32, u32) {
    let mut rig = CanRig::new(bus, Instant::from_millis(0)).unwrap();
    for ms in (0..=6000).step_by(10) {
        rig.run_gimbal(Instant::from_millis(ms));
    }
    (rig.sim_stats().postbacks * 4, rig.sim_unsent)
}

/// A frame the bus refuses to the simulated gimbal is counted, none lost quietly; on a
/// bus without faults none is refused.
#[test]
fn the_gimbal_frames_the_bus_refuses_are_counted() {
    let refusing = DemoBus::new(1).with_faults(Faults {
        tx_error: 1.0,
        ..Faults::NONE
    });
    let (made, unsent) = gimbal_frames(&refusing);
    assert!(made >= 48, "{made}");
    assert_eq!(unsent, made);
    assert_eq!(gimbal_frames(&DemoBus::new(1)).1, 0);
}

/// Plays the script over `rig`: the failures it counts and its transcript.
fn play<R: Rig>(rig: R) -> (u32, String) {
    let mut out = String::new();
    let failures = Script::new(rig, &mut out, 0).play();
    (failures, out)
}

/// Plays the script over CAN against a gimbal set up by `config`.
fn play_against(config: SimConfig) -> (u32, String) {
    let bus = DemoBus::new(1);
    play(CanRig::with_gimbal(&bus, config, Instant::from_millis(0)).unwrap())
}

/// The `FAIL` lines of `transcript`.
fn failed(transcript: &str) -> std::vec::Vec<&str> {
    transcript
        .lines()
        .filter(|l| l.starts_with("  FAIL "))
        .collect()
}

/// The lines of `transcript` that judge a step (`ok` or `FAIL`), without the time an `ok`
/// line ends with.
fn verdicts(transcript: &str) -> std::vec::Vec<&str> {
    transcript
        .lines()
        .filter(|l| l.starts_with("  ok  ") || l.starts_with("  FAIL "))
        .map(|l| l.split(" (t=").next().unwrap_or(l))
        .collect()
}

/// The `ok` lines of a session that saw every step, in the script's order: `heading` the
/// heading step's, and the text's where the transport carries it.
fn every_step_seen(heading: &str, text: bool) -> std::vec::Vec<String> {
    let mut seen: std::vec::Vec<String> = [
        "postbacks arrive, link up",
        "pitch 0°, motor 0°",
        "pitch -45.00° reported",
        heading,
        "gimbal turned, then stopped after the dead-man",
        "zoom 10x",
        "one photo taken",
        "recording",
        "not recording",
    ]
    .iter()
    .map(|what| std::format!("  ok  {what}"))
    .collect();
    if text {
        seen.push("  ok  text received".into());
    }
    seen
}

/// Over CAN, against a gimbal that does what it is asked: every step is seen, in the
/// script's order, the text included; vehicle frames reach the gimbal.
#[test]
fn a_session_over_can_sees_every_step() {
    let bus = DemoBus::new(1);
    let (failures, out) = play(CanRig::new(&bus, Instant::from_millis(0)).unwrap());
    assert_eq!(failures, 0, "{out}");
    assert_eq!(
        verdicts(&out),
        every_step_seen("heading 90.00°, motor 60.00°", true),
        "{out}"
    );
    assert!(out.contains("> text message\n"), "{out}");
    assert!(out.starts_with(
        "idu-gimbal session: link and port <-> simulated gimbal over an in-memory CAN bus\n"
    ));
    said_in_time(&out);
    // What the counters say agrees with what was seen: a postback is four frames, and
    // every frame sent reached the gimbal: its vehicle frames, its commands and the
    // text's four (32 bytes, 8 a frame).
    let postbacks = telemetry_ms(&out).len();
    let summary = line_after(&out, "frames sent ");
    let (sent, received) = (number(summary, "sent "), number(summary, "received "));
    assert_eq!(received, 4 * postbacks, "{out}");
    assert_eq!(number(summary, "postbacks "), postbacks, "{out}");
    assert!(summary.ends_with("driver errors 0; gimbal frames the bus refused 0"));
    let gimbal = line_after(&out, "gimbal saw ");
    let (vehicle, commands) = (number(gimbal, "saw "), number(gimbal, "frames, "));
    assert!(vehicle > 0 && commands > 0, "{out}");
    assert_eq!(sent, vehicle + commands + 4, "{out}");
    assert!(out.ends_with("session passed\n"), "{out}");
}

/// Over the serial line: the same steps but the text, which it does not carry, and the
/// heading nose-referenced; no vehicle frame reaches the gimbal.
#[test]
fn a_session_over_serial_sees_every_step_it_carries() {
    let pipe = DemoPipe::new(1);
    let (failures, out) = play(SerialRig::new(&pipe, Instant::from_millis(0)).unwrap());
    assert_eq!(failures, 0, "{out}");
    assert_eq!(
        verdicts(&out),
        every_step_seen("heading 90.00°, motor 90.00°", false),
        "{out}"
    );
    assert!(
        out.contains("> text message: not carried by this transport\n"),
        "{out}"
    );
    said_in_time(&out);
    // A command is a 24-byte frame, a postback 27 bytes; the gimbal saw every command.
    let postbacks = telemetry_ms(&out).len();
    let summary = line_after(&out, "bytes sent ");
    let frames = number(summary, "frames sent ");
    assert_eq!(number(summary, "bytes sent "), 24 * frames, "{out}");
    assert_eq!(number(summary, "received "), 27 * postbacks, "{out}");
    assert_eq!(number(summary, "postbacks "), postbacks, "{out}");
    assert!(summary.ends_with("bytes skipped 0, CRC errors 0"), "{out}");
    let gimbal = line_after(&out, "gimbal saw ");
    assert_eq!(number(gimbal, "saw "), 0, "{out}");
    assert_eq!(number(gimbal, "frames, "), frames, "{out}");
    assert!(out.ends_with("session passed\n"), "{out}");
}

/// The line of `transcript` that begins with `start`.
fn line_after<'a>(transcript: &'a str, start: &str) -> &'a str {
    transcript
        .lines()
        .find(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("no line '{start}…' in {transcript}"))
}

/// The number after the first `label` in `line`.
fn number(line: &str, label: &str) -> usize {
    let (_, rest) = line.split_once(label).unwrap();
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().unwrap()
}

/// A `t=  S.MMM s` or `(t=S.MMM s)` time in `line`, in ms.
fn time_ms(line: &str) -> u64 {
    let (_, rest) = line.split_once("t=").unwrap();
    let (s, rest) = rest.trim_start().split_once('.').unwrap();
    let ms: String = rest.chars().take_while(char::is_ascii_digit).collect();
    assert_eq!(ms.len(), 3, "{line}");
    s.parse::<u64>().unwrap() * 1000 + ms.parse::<u64>().unwrap()
}

/// The telemetry lines' times, in ms.
fn telemetry_ms(transcript: &str) -> std::vec::Vec<u64> {
    transcript
        .lines()
        .filter(|l| l.starts_with("t="))
        .map(time_ms)
        .collect()
}

/// The transcript's times and telemetry: a postback every 500 ms from 501 ms (the gimbal's
/// first at 500 ms, received on the next tick), each with the link up; every `ok` of a
/// postback awaited said the tick after that postback's line; the hold said as it began,
/// and the link's events.
fn said_in_time(transcript: &str) {
    let times = telemetry_ms(transcript);
    assert!(times.len() >= 16, "{transcript}");
    for (i, t) in times.iter().enumerate() {
        assert_eq!(*t, 501 + 500 * i as u64, "{transcript}");
    }
    let mut last = None;
    for line in transcript.lines() {
        if line.starts_with("t=") {
            assert!(line.ends_with("  link up"), "{line}");
            assert!(
                line.contains("  pitch ") && line.contains("°  mode "),
                "{line}"
            );
            last = Some(time_ms(line));
        } else if line.starts_with("  ok  ") && line.contains("(t=") {
            assert_eq!(Some(time_ms(line) - 1), last, "{line}");
        }
    }
    assert!(transcript
        .contains("\n> rate hold: yaw 20°/s, refreshed every 20 ms for 1 s, then released\n"));
    assert!(transcript.contains("\nlink up\n"));
    assert!(transcript.contains("\nrate hold released: dead-man sent zero rate\n"));
}

/// The steps' checks hold on the postback they wait for and on none that misses it in
/// one field.
#[test]
fn each_check_needs_every_field_it_names() {
    let sim = Simulator::new(SimConfig::default(), Instant::from_millis(0));
    let state = sim.state();
    let at = |pitch, heading, motor_heading| Postback {
        pitch,
        heading,
        motor_heading,
        ..Postback::default()
    };
    for (north, motor) in [(true, 6000), (false, 9000)] {
        let steps = steps(north);
        let check = |name: &str| {
            steps
                .iter()
                .find_map(|s| match s {
                    Step::Expect(what, _, check) if what.starts_with(name) => Some(*check),
                    _ => None,
                })
                .unwrap()
        };
        let centred = check("pitch 0°");
        assert!(centred(&at(0, 4000, 0), state));
        assert!(!centred(&at(1, 4000, 0), state));
        assert!(!centred(&at(0, 4000, 1), state));
        let pitched = check("pitch -45");
        assert!(pitched(&at(-4500, 0, 0), state));
        assert!(!pitched(&at(-4499, 0, 0), state));
        let turned = check("heading 90");
        assert!(turned(&at(0, 9000, motor), state));
        assert!(!turned(&at(0, 9000, motor + 1), state));
        assert!(!turned(&at(0, 8999, motor), state));
    }
}

/// A rig whose text is refused and whose gimbal reports no vehicle frame: both said and
/// counted as failures, and nothing else.
struct Refusing<'a>(CanRig<'a>);

impl<'a> Rig for Refusing<'a> {
    const WIRE: &'static str = "a CAN bus that refuses text";
    type Medium = idu_gimbal::link::Can;
    type Port = CanPort<Endpoint<'a, 2, 32>>;
    fn port(&mut self) -> &mut Self::Port {
        self.0.port()
    }
    fn run_gimbal(&mut self, now: Instant) {
        self.0.run_gimbal(now);
    }
    fn send_text(_: &mut Link<8, 8>, text: &[u8]) -> Option<Result<(), TextQueueError>> {
        Some(Err(TextQueueError::NoRoom {
            needed: text.len().div_ceil(8),
            free: 0,
        }))
    }
    fn sim_state(&self) -> &SimState {
        self.0.sim_state()
    }
    fn sim_stats(&self) -> SimStats {
        SimStats {
            vehicle_frames: 0,
            ..self.0.sim_stats()
        }
    }
    fn summary(&self, link: &LinkStats, out: &mut dyn Write) {
        self.0.summary(link, out);
    }
}

#[test]
fn a_refused_text_and_missing_vehicle_frames_fail_the_session() {
    let bus = DemoBus::new(1);
    let (failures, out) = play(Refusing(
        CanRig::new(&bus, Instant::from_millis(0)).unwrap(),
    ));
    assert_eq!(failures, 2, "{out}");
    let fails = failed(&out);
    assert_eq!(fails.len(), 2, "{out}");
    assert!(fails[0].starts_with("  FAIL text not queued: "), "{out}");
    assert_eq!(
        fails[1], "  FAIL vehicle frames: 0 reached the gimbal",
        "{out}"
    );
    assert!(!out.contains("text received"), "{out}");
    assert!(out.ends_with("session FAILED\n"), "{out}");
}

/// A gimbal that does not do what it is asked fails exactly the steps that need it, each
/// said, and the session fails: one that never slews the two angle steps (re-centring
/// finds it at 0° already; a rate moves it as before), one that honours a rate for no time
/// the rate hold (it does not turn).
#[test]
fn a_gimbal_that_does_not_obey_fails_exactly_its_steps() {
    let cases: [(SimConfig, &[&str]); 2] = [
        (
            SimConfig {
                slew_dps: 0.0,
                ..SimConfig::default()
            },
            &[
                "  FAIL pitch -45.00° reported: not seen within 3000 ms",
                "  FAIL heading 90.00°, motor 60.00°: not seen within 3000 ms",
            ],
        ),
        (
            SimConfig {
                rate_timeout_ms: 0,
                ..SimConfig::default()
            },
            &["  FAIL rate hold: turned 0 cdeg, stopped: true"],
        ),
    ];
    for (config, fails) in cases {
        let (failures, out) = play_against(config);
        assert_eq!(failures as usize, fails.len(), "{out}");
        assert_eq!(failed(&out), fails, "{out}");
        // The CAN session judges ten steps.
        assert_eq!(verdicts(&out).len(), 10, "{out}");
        assert!(out.ends_with("session FAILED\n"), "{out}");
    }
}

/// The rate hold's judgement: more than 15° turned, and still at both looks with a zero
/// rate; each condition missed alone fails it.
#[test]
fn the_rate_hold_passes_only_a_turn_that_stopped() {
    let judge = |turned, looks, stopped| {
        let mut out = String::new();
        let ok = RATE_HOLD.verdict(&mut out, turned, looks, stopped);
        (ok, out)
    };
    let (ok, out) = judge(2000, Some((50.0, 50.0)), true);
    assert!(ok);
    assert_eq!(
        out,
        "  turned 20.00° during the hold\n  ok  gimbal turned, then stopped after the dead-man\n"
    );
    // 15° exactly is not more than 15°.
    assert!(!judge(1500, Some((50.0, 50.0)), true).0);
    assert!(judge(1501, Some((50.0, 50.0)), true).0);
    // Still moving at the second look, or with a rate, or never looked at.
    let (ok, out) = judge(2000, Some((50.0, 51.0)), true);
    assert!(!ok);
    assert!(
        out.ends_with("  FAIL rate hold: turned 2000 cdeg, stopped: false\n"),
        "{out}"
    );
    assert!(!judge(2000, Some((50.0, 50.0)), false).0);
    assert!(!judge(2000, None, true).0);
    // A turn the other way is no turn.
    assert!(!judge(-2000, Some((50.0, 50.0)), true).0);
}

/// Vehicle frames must reach the gimbal exactly when the transport carries them.
#[test]
fn vehicle_frames_reach_the_gimbal_exactly_when_carried() {
    let judge = |vehicle_frames, carried| {
        let stats = SimStats {
            vehicle_frames,
            commands: 7,
            ..SimStats::default()
        };
        let mut out = String::new();
        let ok = vehicle_frames_verdict(&mut out, &stats, carried);
        (ok, out)
    };
    assert_eq!(
        judge(3, true),
        (true, "gimbal saw 3 vehicle frames, 7 commands\n".into())
    );
    assert_eq!(
        judge(0, false),
        (true, "gimbal saw 0 vehicle frames, 7 commands\n".into())
    );
    assert_eq!(
        judge(0, true),
        (
            false,
            "gimbal saw 0 vehicle frames, 7 commands\n  FAIL vehicle frames: 0 reached the gimbal\n"
                .into()
        )
    );
    assert!(!judge(1, false).0);
}
