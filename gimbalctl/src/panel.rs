//! `gimbalctl control (--tcp HOST:PORT | --can IFACE | --serial PATH[:BAUD])`: an
//! interactive terminal panel.
//!
//! Every byte or frame goes through the library's link and the port for the transport (a
//! [`Session`]: `SerialPort` for the serial server and the UART, `CanPort<C>` for CAN):
//! commands are queued on the link, the arrow keys drive its rate hold, and the panel shows
//! its latest postback, state and counters (bus errors on CAN, bytes that held no frame on
//! the serial paths).
//!
//! # How an arrow key holds a rate
//!
//! Terminals report key presses (and the key-repeat of a held key) but never a release.
//! Each arrow event calls [`Link::set_rate`](idu_gimbal::link::Link::set_rate): the first
//! starts a rate hold (the link sends the rate command at once and repeats it every 50 ms),
//! each key-repeat event refreshes it. When the key is released the repeat events stop,
//! and the core's dead-man ends the hold 250 ms after the last one with a single zero-rate
//! command. So the gimbal moves while the key is held and stops within 250 ms of its
//! release, with no release event needed. (A terminal's first repeat comes after its
//! repeat delay, often 250-600 ms, during which the hold may lapse once: the gimbal stops
//! briefly at the start of a long press unless the repeat delay is shorter than 250 ms.)

use std::io::IsTerminal;
use std::time::{Duration, Instant as StdInstant};

use idu_gimbal::link::{Event, Link, Medium};
use idu_gimbal::wire::control::{Command, GimbalCommand, Photo, Rate, Video, Zoom};
use idu_gimbal::Instant;
use ratatui::crossterm::event::{
    self, Event as TermEvent, KeyCode, KeyEvent, KeyEventKind, KeyModifiers,
};
use ratatui::crossterm::{cursor, execute, terminal};
use ratatui::layout::{Constraint, Layout};
use ratatui::text::Line;
use ratatui::widgets::{Block, Paragraph};
use ratatui::Terminal;

use crate::error::Failure;
use crate::spec;
use crate::transport::{clock, Job, Mode, Session, Target, Transport};

/// How long the loop waits for a key before looking at the socket and the link again.
const TICK: Duration = Duration::from_millis(10);
/// How often the panel is redrawn when nothing happens (the postback's age moves).
const REDRAW: Duration = Duration::from_millis(100);
/// How long `q` waits for its zero rate (and anything queued before it) to be written.
const QUIT_FLUSH: Duration = Duration::from_secs(1);

/// Puts the terminal back however the panel ends.
struct TerminalGuard;

impl TerminalGuard {
    fn enter() -> Result<Self, Failure> {
        terminal::enable_raw_mode().map_err(|e| Failure::io("cannot set up the terminal", e))?;
        let guard = TerminalGuard;
        execute!(
            std::io::stdout(),
            terminal::EnterAlternateScreen,
            cursor::Hide
        )
        .map_err(|e| Failure::io("cannot set up the terminal", e))?;
        Ok(guard)
    }
}

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        let _ = execute!(
            std::io::stdout(),
            cursor::Show,
            terminal::LeaveAlternateScreen
        );
        let _ = terminal::disable_raw_mode();
    }
}

/// What the panel shows besides the link's own state.
struct Panel {
    target: String,
    speed: f32,
    /// The rate held (for the panel; the link owns the hold).
    held: Option<Rate>,
    recording: bool,
    last_sent: String,
    last_event: String,
    key_events: u64,
}

/// What a key asks of the panel's loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Next {
    /// Go on.
    Go,
    /// Leave (`q`, Ctrl-C): a zero rate first.
    Quit,
}

impl Panel {
    fn new(target: String, speed: f32) -> Self {
        Panel {
            target,
            speed,
            held: None,
            recording: false,
            last_sent: "nothing yet".into(),
            last_event: "none".into(),
            key_events: 0,
        }
    }

    /// A link event, as the panel says it.
    fn event(&mut self, ev: Event) {
        match ev {
            Event::Postback | Event::TargetUnreachable { .. } => {}
            Event::LinkUp => self.last_event = "link up".into(),
            Event::LinkDown => self.last_event = "link down".into(),
            Event::RateHoldExpired => {
                self.held = None;
                self.last_event = "rate hold ended (dead-man): zero rate sent".into();
                self.last_sent = "rate 0 0".into();
            }
            Event::AimNotReached => self.last_event = "aim not reached".into(),
        }
    }

    /// A key pressed or repeated (never a release) at `t`: the rate it holds on `link` or
    /// the command it queues there, and what the panel says of it.
    fn key<M: Medium>(&mut self, link: &mut Link<8, 8, M>, key: KeyEvent, t: Instant) -> Next {
        self.key_events += 1;
        let speed = self.speed;
        let rate = |yaw: f32, pitch: f32| Rate::new(yaw, pitch).ok();
        let mut send: Option<Command> = None;
        let mut hold: Option<Rate> = None;
        match key.code {
            KeyCode::Char('q') => return Next::Quit,
            KeyCode::Char('c') if key.modifiers.contains(KeyModifiers::CONTROL) => {
                return Next::Quit
            }
            KeyCode::Up => hold = rate(0.0, speed),
            KeyCode::Down => hold = rate(0.0, -speed),
            KeyCode::Left => hold = rate(-speed, 0.0),
            KeyCode::Right => hold = rate(speed, 0.0),
            KeyCode::Char('c') => send = Some(GimbalCommand::Recenter.into()),
            KeyCode::Char('d') => send = Some(GimbalCommand::LookDown.into()),
            KeyCode::Char('+') | KeyCode::Char('=') => {
                send = Some(GimbalCommand::Zoom(Zoom::Double).into())
            }
            KeyCode::Char('-') => send = Some(GimbalCommand::Zoom(Zoom::Half).into()),
            KeyCode::Char('p') => send = Some(GimbalCommand::Photo(Photo::Single).into()),
            KeyCode::Char('r') => {
                let v = if self.recording {
                    Video::Stop
                } else {
                    Video::Start
                };
                send = Some(GimbalCommand::Video(v).into());
            }
            KeyCode::Char('f') => send = Some(GimbalCommand::NoseFollowing.into()),
            _ => {}
        }
        if let Some(r) = hold {
            match link.set_rate(r, t) {
                Ok(()) => {
                    if self.held != Some(r) {
                        self.last_sent = spec::command_line(&GimbalCommand::Rate(r).into());
                    }
                    self.held = Some(r);
                }
                Err(_) => self.last_event = "queue full: rate not taken".into(),
            }
        }
        if let Some(cmd) = send {
            match link.send(cmd) {
                Ok(()) => {
                    if cmd == Command::from(GimbalCommand::Video(Video::Start)) {
                        self.recording = true;
                    } else if cmd == Command::from(GimbalCommand::Video(Video::Stop)) {
                        self.recording = false;
                    }
                    if cmd.is_pointing() {
                        self.held = None;
                    }
                    self.last_sent = spec::command_line(&cmd);
                }
                Err(_) => self.last_event = "queue full: command not sent".into(),
            }
        }
        Next::Go
    }
}

fn centi(v: i64) -> String {
    let sign = if v < 0 { "-" } else { "" };
    let a = v.unsigned_abs();
    format!("{sign}{}.{:02}", a / 100, a % 100)
}

fn draw<T: Transport>(
    frame: &mut ratatui::Frame<'_>,
    session: &Session<T>,
    panel: &Panel,
    now: Instant,
) {
    let link = &session.link;
    let link_state = match (link.is_link_up(), link.stats().postbacks) {
        (true, _) => "up",
        (false, 0) => "waiting for the first postback",
        (false, _) => "DOWN (no postback for 1.5 s)",
    };
    let mut gimbal = Vec::new();
    match link.latest_postback(now) {
        Some((pb, age)) => {
            let mode = match pb.mode.name() {
                Some(name) => name.to_owned(),
                None => format!("unknown({})", pb.mode.code()),
            };
            let model = pb.gimbal_type.model_name().unwrap_or("unknown");
            gimbal.push(Line::raw(format!(
                "pitch   {:>8} deg   heading {:>7} deg   motor {:>8} deg",
                centi(pb.pitch.into()),
                centi(pb.heading.into()),
                centi(pb.motor_heading.into())
            )));
            gimbal.push(Line::raw(format!(
                "mode    {mode:<16} tracking {:<3}   gimbal {} ({model})",
                if pb.tracking { "yes" } else { "no" },
                pb.gimbal_type.code()
            )));
            gimbal.push(Line::raw(format!(
                "age     {age:>5} ms         link {link_state}"
            )));
        }
        None => {
            gimbal.push(Line::raw("no postback yet"));
            gimbal.push(Line::raw(""));
            gimbal.push(Line::raw(format!("link {link_state}")));
        }
    }
    let hold = match panel.held {
        Some(r) if link.is_rate_holding() => format!(
            "yaw {} pitch {} deg/s (held while the key repeats)",
            r.yaw_dps(),
            r.pitch_dps()
        ),
        _ => "none".to_owned(),
    };
    let commands = vec![
        Line::raw(format!("rate hold  {hold}")),
        Line::raw(format!(
            "recording  {}   speed {} deg/s   key events {}",
            if panel.recording { "yes" } else { "no" },
            panel.speed,
            panel.key_events
        )),
        Line::raw(format!("last sent  {}", panel.last_sent)),
        Line::raw(format!("last event {}", panel.last_event)),
    ];
    let counters: Vec<Line> = session.counters().into_iter().map(Line::raw).collect();
    let keys = vec![
        Line::raw("arrows rate hold (stops 250 ms after the last key event)"),
        Line::raw("c centre  d look down  +/- zoom  p photo  r record  f follow  q quit"),
    ];
    let [a, b, c, d] = Layout::vertical([
        Constraint::Length(5),
        Constraint::Length(6),
        Constraint::Length(5),
        Constraint::Length(4),
    ])
    .areas(frame.area());
    let title = format!(" gimbalctl control {} ", panel.target);
    frame.render_widget(
        Paragraph::new(gimbal).block(Block::bordered().title(title)),
        a,
    );
    frame.render_widget(
        Paragraph::new(commands).block(Block::bordered().title(" commands ")),
        b,
    );
    frame.render_widget(
        Paragraph::new(counters).block(Block::bordered().title(" counters ")),
        c,
    );
    frame.render_widget(
        Paragraph::new(keys).block(Block::bordered().title(" keys ")),
        d,
    );
}

/// `gimbalctl control (--tcp HOST:PORT | --can IFACE | --serial PATH[:BAUD]) [--speed DEG_S]`.
pub fn run(target: &Target, speed: f32) -> Result<(), Failure> {
    if !(1.0..=100.0).contains(&speed) {
        return Err(Failure::Usage(format!(
            "--speed {speed}: out of range [1, 100] deg/s"
        )));
    }
    if !std::io::stdin().is_terminal() {
        return Err(Failure::Usage(
            "control: stdin is not a terminal; control is interactive (in scripts use send and monitor)"
                .into(),
        ));
    }
    if !std::io::stdout().is_terminal() {
        return Err(Failure::Usage(
            "control: stdout is not a terminal; control is interactive (in scripts use send and monitor)"
                .into(),
        ));
    }
    target.run(Mode::Drive, Panelled { speed })
}

struct Panelled {
    speed: f32,
}

impl Job for Panelled {
    type Out = ();

    fn run<T: Transport>(self, session: Session<T>) -> Result<(), Failure> {
        panel(session, self.speed)
    }
}

/// The panel over an open session.
fn panel<T: Transport>(mut session: Session<T>, speed: f32) -> Result<(), Failure> {
    let now = clock(StdInstant::now());
    let mut panel = Panel::new(session.transport.name().to_owned(), speed);

    let guard = TerminalGuard::enter()?;
    let backend = ratatui::backend::CrosstermBackend::new(std::io::stdout());
    let mut term = Terminal::new(backend).map_err(|e| Failure::io("terminal", e))?;
    let mut drawn = StdInstant::now() - REDRAW;
    let result = (|| -> Result<(), Failure> {
        loop {
            let t = now();
            session.pump(t)?;
            let mut changed = false;
            while let Some(ev) = session.link.next_event() {
                panel.event(ev);
                changed = true;
            }
            if changed || drawn.elapsed() >= REDRAW {
                term.draw(|f| draw(f, &session, &panel, now()))
                    .map_err(|e| Failure::io("terminal", e))?;
                drawn = StdInstant::now();
            }
            if !event::poll(TICK).map_err(|e| Failure::io("terminal", e))? {
                continue;
            }
            // Every key waiting, before the next write.
            loop {
                let TermEvent::Key(key) = event::read().map_err(|e| Failure::io("terminal", e))?
                else {
                    if !event::poll(Duration::ZERO).map_err(|e| Failure::io("terminal", e))? {
                        break;
                    }
                    continue;
                };
                if key.kind != KeyEventKind::Release {
                    let t = now();
                    if panel.key(&mut session.link, key, t) == Next::Quit {
                        return quit(&mut session, now);
                    }
                    session.pump(t)?;
                }
                if !event::poll(Duration::ZERO).map_err(|e| Failure::io("terminal", e))? {
                    break;
                }
            }
            term.draw(|f| draw(f, &session, &panel, now()))
                .map_err(|e| Failure::io("terminal", e))?;
            drawn = StdInstant::now();
        }
    })();
    drop(term);
    drop(guard);
    if result.is_ok() {
        session.finish();
    }
    result
}

/// `q`: a zero rate (through the link: the end of the hold, or a zero-rate command when
/// none is held, queued as soon as the queue has room), written before leaving.
fn quit<T: Transport>(session: &mut Session<T>, now: impl Fn() -> Instant) -> Result<(), Failure> {
    // Ending a hold queues the link's own zero rate, which is never refused.
    let mut zero_queued = session.link.is_rate_holding();
    session.link.stop_rate();
    let deadline = StdInstant::now() + QUIT_FLUSH;
    loop {
        if !zero_queued {
            zero_queued = session.link.send(GimbalCommand::Rate(Rate::ZERO)).is_ok();
        }
        session.pump(now())?;
        if zero_queued && !session.has_transmit() {
            break;
        }
        if StdInstant::now() >= deadline {
            return Err(Failure::Runtime(format!(
                "cannot send the zero rate to {} within {} ms",
                session.transport.name(),
                QUIT_FLUSH.as_millis()
            )));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
