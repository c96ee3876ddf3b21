//! The panel's keys, events, drawing and quitting, over the core's mock bus.

use super::*;
use crate::transport::can::{mock_session, CanTransport};
use embedded_can::nb::Can;
use embedded_can::Frame as _;
use idu_gimbal::mock::{Bus, Endpoint, MockFrame};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::{ControlMode, GimbalType, Postback};
use ratatui::backend::TestBackend;

type MockSession<'a> = Session<CanTransport<Endpoint<'a, 2, 64>>>;

fn press(code: KeyCode) -> KeyEvent {
    KeyEvent::new(code, KeyModifiers::NONE)
}

/// A panel at `speed` deg/s over a session on endpoint 0 of `bus`, and the gimbal's end
/// of the bus.
fn on(bus: &Bus<2, 64>, speed: f32) -> (MockSession<'_>, Endpoint<'_, 2, 64>, Panel) {
    let session = mock_session(bus, Mode::Drive);
    let gimbal = bus.endpoint(1).unwrap();
    (session, gimbal, Panel::new("mock0".into(), speed))
}

/// The commands on the bus since the last look, as `send` names them.
fn sent(gimbal: &mut Endpoint<'_, 2, 64>) -> Vec<String> {
    let mut out = Vec::new();
    while let Ok(f) = gimbal.receive() {
        assert_eq!(f.raw_id(), ids::CONTROL);
        let cmd = Command::decode(f.data()).expect("a control frame");
        out.push(spec::command_line(&cmd));
    }
    out
}

/// The panel drawn on an 80x24 terminal, a line a row, trailing blanks cut.
fn screen(s: &MockSession<'_>, panel: &Panel, now: Instant) -> Vec<String> {
    let mut term = Terminal::new(TestBackend::new(80, 24)).unwrap();
    term.draw(|f| draw(f, s, panel, now)).unwrap();
    let buf = term.backend().buffer();
    (0..24)
        .map(|y| {
            let row: String = (0..80).map(|x| buf[(x, y)].symbol()).collect();
            row.trim_end().to_owned()
        })
        .collect()
}

/// The gimbal's postback, put on the bus as its four frames.
fn postback(gimbal: &mut Endpoint<'_, 2, 64>, pb: &Postback) {
    for data in pb.to_can_frames() {
        gimbal
            .transmit(&MockFrame::extended(ids::POSTBACK, &data).unwrap())
            .unwrap();
    }
}

#[test]
fn hundredths_are_written_with_their_sign() {
    for (v, text) in [
        (0, "0.00"),
        (5, "0.05"),
        (-5, "-0.05"),
        (-4512, "-45.12"),
        (17000, "170.00"),
        (-32768, "-327.68"),
    ] {
        assert_eq!(centi(v), text, "{v}");
    }
}

/// The arrows hold a rate at the panel's speed (up and right positive); a key-repeat
/// refreshes the hold and queues nothing.
#[test]
fn arrows_hold_a_rate_at_the_panel_speed() {
    let bus: Bus<2, 64> = Bus::new(1);
    let (mut s, mut gimbal, mut panel) = on(&bus, 12.5);
    let mut t = Instant::from_millis(0);
    for (key, rate) in [
        (KeyCode::Up, "rate 0 12.5"),
        (KeyCode::Down, "rate 0 -12.5"),
        (KeyCode::Left, "rate -12.5 0"),
        (KeyCode::Right, "rate 12.5 0"),
    ] {
        assert_eq!(panel.key(&mut s.link, press(key), t), Next::Go);
        s.pump(t).unwrap();
        assert_eq!(sent(&mut gimbal), [rate], "{key:?}");
        assert_eq!(panel.last_sent, rate);
        assert!(s.link.is_rate_holding());
        // The terminal's key-repeat 30 ms later: the same hold, nothing new sent.
        t = t.add_millis(30);
        assert_eq!(panel.key(&mut s.link, press(key), t), Next::Go);
        s.pump(t).unwrap();
        assert_eq!(sent(&mut gimbal), Vec::<String>::new(), "{key:?} repeated");
        t = t.add_millis(30);
    }
    assert_eq!(panel.key_events, 8);
    assert_eq!(panel.held, Some(Rate::new(12.5, 0.0).unwrap()));
}

/// Each command key queues its command; `r` starts and then stops recording; a
/// pointing command ends the rate held; other keys are counted and send nothing.
#[test]
fn keys_send_their_commands() {
    let bus: Bus<2, 64> = Bus::new(2);
    let (mut s, mut gimbal, mut panel) = on(&bus, 20.0);
    let t = Instant::from_millis(0);
    for (key, command, recording) in [
        ('p', "photo single", false),
        ('r', "record start", true),
        ('+', "zoom double", true),
        ('=', "zoom double", true),
        ('-', "zoom half", true),
        ('r', "record stop", false),
        ('f', "follow", false),
        ('d', "look-down", false),
        ('c', "center", false),
    ] {
        assert_eq!(
            panel.key(&mut s.link, press(KeyCode::Char(key)), t),
            Next::Go
        );
        s.pump(t).unwrap();
        assert_eq!(sent(&mut gimbal), [command], "{key:?}");
        assert_eq!(panel.last_sent, command);
        assert_eq!(panel.recording, recording, "{key:?}");
    }
    for key in [press(KeyCode::Char('x')), press(KeyCode::Esc)] {
        assert_eq!(panel.key(&mut s.link, key, t), Next::Go);
    }
    s.pump(t).unwrap();
    assert!(sent(&mut gimbal).is_empty());
    assert_eq!(panel.key_events, 11);
    // A rate held, then a photo (not pointing: the hold goes on), then look-down (a
    // pointing command: the hold ends).
    panel.key(&mut s.link, press(KeyCode::Up), t);
    panel.key(&mut s.link, press(KeyCode::Char('p')), t);
    assert_eq!(panel.held, Some(Rate::new(0.0, 20.0).unwrap()));
    panel.key(&mut s.link, press(KeyCode::Char('d')), t);
    assert_eq!(panel.held, None);
    s.pump(t).unwrap();
    assert_eq!(
        sent(&mut gimbal),
        ["rate 0 20", "photo single", "look-down"]
    );
}

/// `q` and Ctrl-C leave, sending nothing themselves (`quit` sends the zero rate);
/// a `c` with Ctrl is not the centre key.
#[test]
fn q_and_ctrl_c_leave() {
    let bus: Bus<2, 64> = Bus::new(3);
    let (mut s, mut gimbal, mut panel) = on(&bus, 20.0);
    let t = Instant::from_millis(0);
    let ctrl_c = KeyEvent::new(KeyCode::Char('c'), KeyModifiers::CONTROL);
    for key in [press(KeyCode::Char('q')), ctrl_c] {
        assert_eq!(panel.key(&mut s.link, key, t), Next::Quit, "{key:?}");
    }
    s.pump(t).unwrap();
    assert!(sent(&mut gimbal).is_empty());
    assert_eq!(panel.last_sent, "nothing yet");
}

/// A full queue refuses the key's command or rate, and the panel says so.
#[test]
fn a_full_queue_is_said() {
    let bus: Bus<2, 64> = Bus::new(4);
    let mut s = mock_session(&bus, Mode::Drive);
    let mut panel = Panel::new("mock0".into(), 20.0);
    let t = Instant::from_millis(0);
    // Eight photos fill the link's queue of eight (nothing is pumped).
    for _ in 0..8 {
        panel.key(&mut s.link, press(KeyCode::Char('p')), t);
    }
    assert_eq!(panel.last_event, "none");
    panel.key(&mut s.link, press(KeyCode::Char('r')), t);
    assert_eq!(panel.last_event, "queue full: command not sent");
    assert!(!panel.recording);
    assert_eq!(panel.last_sent, "photo single");
    panel.key(&mut s.link, press(KeyCode::Up), t);
    assert_eq!(panel.last_event, "queue full: rate not taken");
    assert_eq!(panel.held, None);
    assert!(!s.link.is_rate_holding());
}

/// What each link event makes the panel say.
#[test]
fn link_events_are_said() {
    let mut panel = Panel::new("mock0".into(), 20.0);
    panel.held = Rate::new(0.0, 20.0).ok();
    panel.last_sent = "rate 0 20".into();
    for (ev, said) in [
        (Event::LinkUp, "link up"),
        (Event::LinkDown, "link down"),
        (Event::AimNotReached, "aim not reached"),
    ] {
        panel.event(ev);
        assert_eq!(panel.last_event, said);
    }
    // A postback is shown by the gimbal lines, not said.
    panel.event(Event::Postback);
    assert_eq!(panel.last_event, "aim not reached");
    assert_eq!(panel.held, Rate::new(0.0, 20.0).ok());
    panel.event(Event::RateHoldExpired);
    assert_eq!(
        panel.last_event,
        "rate hold ended (dead-man): zero rate sent"
    );
    assert_eq!(panel.last_sent, "rate 0 0");
    assert_eq!(panel.held, None);
}

/// The panel on 80 columns: before any postback, with one (its values as the gimbal
/// gave them, an unknown mode and model by their codes), a rate held, and the link
/// down after 1.5 s without one.
#[test]
fn the_panel_shows_the_gimbal_the_commands_and_the_counters() {
    let bus: Bus<2, 64> = Bus::new(5);
    let (mut s, mut gimbal, mut panel) = on(&bus, 20.0);
    let t0 = Instant::from_millis(1000);
    let before = screen(&s, &panel, t0);
    let keys = [
        "┌ keys ────────────────────────────────────────────────────────────────────────┐",
        "│arrows rate hold (stops 250 ms after the last key event)                      │",
        "│c centre  d look down  +/- zoom  p photo  r record  f follow  q quit          │",
        "└──────────────────────────────────────────────────────────────────────────────┘",
    ];
    assert_eq!(
        before[..16],
        [
            "┌ gimbalctl control mock0 ─────────────────────────────────────────────────────┐",
            "│no postback yet                                                               │",
            "│                                                                              │",
            "│link waiting for the first postback                                           │",
            "└──────────────────────────────────────────────────────────────────────────────┘",
            "┌ commands ────────────────────────────────────────────────────────────────────┐",
            "│rate hold  none                                                               │",
            "│recording  no   speed 20 deg/s   key events 0                                 │",
            "│last sent  nothing yet                                                        │",
            "│last event none                                                               │",
            "└──────────────────────────────────────────────────────────────────────────────┘",
            "┌ counters ────────────────────────────────────────────────────────────────────┐",
            format!("│{:<78}│", s.counters()[0]).as_str(),
            format!("│{:<78}│", s.counters()[1]).as_str(),
            format!("│{:<78}│", s.counters()[2]).as_str(),
            "└──────────────────────────────────────────────────────────────────────────────┘",
        ]
    );
    assert_eq!(before[16..20], keys);
    assert!(before[20..].iter().all(String::is_empty));

    let pb = Postback {
        gimbal_type: GimbalType::Unknown(9),
        tracking: true,
        mode: ControlMode::Unknown(7),
        pitch: -4512,
        heading: 35999,
        motor_heading: -5,
        ..Postback::default()
    };
    postback(&mut gimbal, &pb);
    s.pump(t0).unwrap();
    while let Some(ev) = s.link.next_event() {
        panel.event(ev);
    }
    panel.key(&mut s.link, press(KeyCode::Up), t0);
    let shown = screen(&s, &panel, t0.add_millis(120));
    assert_eq!(
        shown[..10],
        [
            "┌ gimbalctl control mock0 ─────────────────────────────────────────────────────┐",
            "│pitch     -45.12 deg   heading  359.99 deg   motor    -0.05 deg               │",
            "│mode    unknown(7)       tracking yes   gimbal 9 (unknown)                    │",
            "│age       120 ms         link up                                              │",
            "└──────────────────────────────────────────────────────────────────────────────┘",
            "┌ commands ────────────────────────────────────────────────────────────────────┐",
            "│rate hold  yaw 0 pitch 20 deg/s (held while the key repeats)                  │",
            "│recording  no   speed 20 deg/s   key events 1                                 │",
            "│last sent  rate 0 20                                                          │",
            "│last event link up                                                            │",
        ]
    );
    // A known model and mode by name.
    let pb = Postback {
        mode: ControlMode::FullLock,
        ..Postback::default()
    };
    postback(&mut gimbal, &pb);
    s.pump(t0.add_millis(500)).unwrap();
    let shown = screen(&s, &panel, t0.add_millis(500));
    assert_eq!(
        shown[2],
        "│mode    full_lock        tracking no    gimbal 1 (X30/X30GT)                  │"
    );
    // No postback for 1.5 s: the link goes down. The hold has ended too, and is not
    // shown as held even before the panel has taken the link's events.
    let late = t0.add_millis(2100);
    s.pump(late).unwrap();
    assert!(!s.link.is_rate_holding());
    assert!(panel.held.is_some());
    let shown = screen(&s, &panel, late);
    assert_eq!(
        shown[3],
        "│age      1600 ms         link DOWN (no postback for 1.5 s)                    │"
    );
    assert_eq!(
        shown[6],
        "│rate hold  none                                                               │"
    );
    while let Some(ev) = s.link.next_event() {
        panel.event(ev);
    }
    let shown = screen(&s, &panel, late);
    assert_eq!(
        shown[9],
        "│last event rate hold ended (dead-man): zero rate sent                         │"
    );
}

/// `q` with a rate held ends the hold (the link's zero rate) and with none sends a
/// zero rate; either is on the bus before `quit` returns.
#[test]
fn quit_sends_a_zero_rate_first() {
    let now = || Instant::from_millis(0);
    for (key, first) in [(KeyCode::Up, "rate 0 20"), (KeyCode::Char('c'), "center")] {
        let bus: Bus<2, 64> = Bus::new(6);
        let (mut s, mut gimbal, mut panel) = on(&bus, 20.0);
        panel.key(&mut s.link, press(key), now());
        quit(&mut s, now).unwrap();
        assert!(!s.link.is_rate_holding());
        assert!(!s.has_transmit());
        assert_eq!(sent(&mut gimbal), [first, "rate 0 0"], "{key:?}");
    }
}

/// With the queue full, `q` queues its zero rate as soon as the queue has room and waits
/// for it to be sent; a bus that takes nothing for a second is a runtime failure naming it.
#[test]
fn quit_waits_a_second_for_the_bus() {
    let now = || Instant::from_millis(0);
    let bus: Bus<2, 64> = Bus::new(7);
    let (mut s, mut gimbal, mut panel) = on(&bus, 20.0);
    for _ in 0..8 {
        panel.key(&mut s.link, press(KeyCode::Char('p')), now());
    }
    quit(&mut s, now).unwrap();
    let mut after_photos = vec!["photo single"; 8];
    after_photos.push("rate 0 0");
    assert_eq!(sent(&mut gimbal), after_photos);

    // One mailbox, never delivered: the first frame fills it and the zero rate waits.
    bus.set_auto_deliver(false);
    assert!(bus.set_mailboxes(0, 1));
    panel.key(&mut s.link, press(KeyCode::Char('c')), now());
    let started = StdInstant::now();
    let Err(Failure::Runtime(e)) = quit(&mut s, now) else {
        panic!("quit over a bus that takes nothing");
    };
    assert_eq!(e, "cannot send the zero rate to mock0 within 1000 ms");
    assert!(started.elapsed() >= QUIT_FLUSH);
    assert!(s.has_transmit());
}
