//! `gimbalctl control` in a real terminal: tmux runs it in a detached 80x24 session (no tty
//! needed) against `gimbalctl sim`; the test types keys with `tmux send-keys`, reads the
//! pane with `tmux capture-pane`, and watches the simulated gimbal from two independent
//! places: a raw TCP client parsing the sim's 27-byte postbacks (checked with the reference
//! CRC), and the sim's log of the commands it received, time-stamped as they arrive.
//!
//! Every wait polls for the expected state with a generous deadline; tmux runs on a
//! private socket that is killed (with everything in it) when the test ends, pass or fail.

mod common;

use common::*;
use std::io::Read;
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

/// A tmux server of our own; killed with its sessions (and their processes) on drop.
struct Tmux {
    socket: String,
}

impl Tmux {
    fn new() -> Self {
        let ok = Command::new("tmux")
            .arg("-V")
            .output()
            .is_ok_and(|o| o.status.success());
        assert!(
            ok,
            "tmux is needed for this test (scripts/test.sh installs it)"
        );
        // One server per test: tests run in parallel threads of one process.
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        Tmux {
            socket: format!("gimbalctl-test-{}-{n}", std::process::id()),
        }
    }

    fn run(&self, args: &[&str]) -> std::process::Output {
        Command::new("tmux")
            .arg("-L")
            .arg(&self.socket)
            .args(args)
            .stdin(Stdio::null())
            .output()
            .expect("run tmux")
    }

    fn pane(&self) -> String {
        String::from_utf8_lossy(&self.run(&["capture-pane", "-p", "-t", "ctl"]).stdout).into_owned()
    }

    fn keys(&self, keys: &[&str]) {
        let mut args = vec!["send-keys", "-t", "ctl"];
        args.extend_from_slice(keys);
        let out = self.run(&args);
        assert!(out.status.success(), "send-keys: {out:?}");
    }

    fn alive(&self) -> bool {
        self.run(&["has-session", "-t", "ctl"]).status.success()
    }

    /// Waits up to 10 s for the panel with the link up; the pane.
    fn wait_link_up(&self) -> String {
        self.wait_pane("the link up", Duration::from_secs(10), |p| {
            p.contains("link up") && p.contains("pitch") && p.contains("q quit")
        })
    }

    /// Holds `key` for `hold`: a key event every 50 ms, as a terminal's key-repeat sends
    /// them. When the hold started, and when its last key was sent.
    fn hold(&self, key: &str, hold: Duration) -> (Instant, Instant) {
        let started = Instant::now();
        let mut last_key = started;
        while started.elapsed() < hold {
            self.keys(&[key]);
            last_key = Instant::now();
            thread::sleep(Duration::from_millis(50));
        }
        (started, last_key)
    }

    /// Polls the pane until `pred` holds, or panics with the pane after `timeout`.
    fn wait_pane(&self, what: &str, timeout: Duration, pred: impl Fn(&str) -> bool) -> String {
        let deadline = Instant::now() + timeout;
        loop {
            let pane = self.pane();
            if pred(&pane) {
                return pane;
            }
            assert!(
                Instant::now() < deadline,
                "pane never showed {what}:\n{pane}"
            );
            thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.run(&["kill-server"]);
    }
}

/// The sim's postbacks' pitch (0.01 deg), each with when it arrived.
type Pitches = Arc<Mutex<Vec<(Instant, i16)>>>;

/// A raw client recording the pitch of every postback the sim sends.
fn observe(addr: &str) -> Pitches {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let pitches: Pitches = Arc::default();
    let p = pitches.clone();
    thread::spawn(move || {
        let mut buf = Vec::new();
        let mut chunk = [0u8; 512];
        while let Ok(n) = s.read(&mut chunk) {
            if n == 0 {
                break;
            }
            buf.extend_from_slice(&chunk[..n]);
            for msg in take_postbacks(&mut buf) {
                p.lock()
                    .unwrap()
                    .push((Instant::now(), postback_pitch(&msg)));
            }
        }
    });
    pitches
}

/// Waits for two postbacks arriving after `after` with the same pitch: the gimbal stands
/// still (the sim sends one every 500 ms).
fn wait_still(pitches: &Pitches, after: Instant) -> i16 {
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let seen: Vec<i16> = pitches
            .lock()
            .unwrap()
            .iter()
            .filter(|(t, _)| *t >= after)
            .map(|(_, p)| *p)
            .collect();
        if let Some(w) = seen.windows(2).find(|w| w[0] == w[1]) {
            return w[0];
        }
        assert!(
            Instant::now() < deadline,
            "the gimbal never stood still: {seen:?}"
        );
        thread::sleep(Duration::from_millis(20));
    }
}

/// Runs `control ARGS` in a detached 80x24 tmux session; the file its exit status goes to.
/// The terminal's state after it goes to the same path with `.term`: its line settings
/// (`stty -a`), and tmux's alternate-screen and cursor-visible flags.
fn control_in_tmux(tmux: &Tmux, args: &str, name: &str) -> std::path::PathBuf {
    let rc = std::env::temp_dir().join(format!("gimbalctl-{name}-{}.rc", std::process::id()));
    let _ = std::fs::remove_file(&rc);
    let term = rc.with_extension("term");
    let _ = std::fs::remove_file(&term);
    let cmd = format!(
        "'{BIN}' control {args}; echo $? > '{}'; {{ stty -a; tmux display-message -p \
         'alternate #{{alternate_on}} cursor #{{cursor_flag}}'; }} > '{}' 2>&1",
        rc.display(),
        term.display()
    );
    let out = tmux.run(&[
        "new-session",
        "-d",
        "-x",
        "80",
        "-y",
        "24",
        "-s",
        "ctl",
        &cmd,
    ]);
    assert!(out.status.success(), "tmux new-session: {out:?}");
    rc
}

/// The postback's age the panel shows (ms), if it shows one.
fn postback_age(pane: &str) -> Option<u32> {
    let line = pane.lines().find(|l| l.contains("│age "))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Waits for the panel to exit; its exit status.
fn exit_status(tmux: &Tmux, rc: &std::path::Path) -> String {
    let deadline = Instant::now() + Duration::from_secs(10);
    while tmux.alive() {
        assert!(
            Instant::now() < deadline,
            "control did not exit: {}",
            tmux.pane()
        );
        thread::sleep(Duration::from_millis(50));
    }
    let code = std::fs::read_to_string(rc).unwrap_or_default();
    let _ = std::fs::remove_file(rc);
    code.trim().to_owned()
}

/// After the panel exited: the terminal as it found it (line editing and echo back, the
/// main screen, the cursor shown).
fn assert_terminal_restored(rc: &std::path::Path) {
    let term = rc.with_extension("term");
    let state = std::fs::read_to_string(&term).unwrap_or_default();
    let _ = std::fs::remove_file(&term);
    let words: Vec<&str> = state.split_whitespace().collect();
    for flag in ["icanon", "echo"] {
        assert!(
            words.contains(&flag) && !words.contains(&format!("-{flag}").as_str()),
            "{flag}: {state}"
        );
    }
    assert!(state.contains("alternate 0 cursor 1"), "{state}");
}

#[test]
fn control_moves_the_simulated_gimbal_and_stops_it() {
    // Up to 60 s to say where it listens: as long as it runs.
    let (_sim, addr, log) =
        start_sim_logged(&["--exit-after-ms", "60000"], Duration::from_secs(60));
    let pitches = observe(&addr);
    let tmux = Tmux::new();
    let rc = control_in_tmux(&tmux, &format!("--tcp {addr}"), "control");

    // The panel, within 80x24: the postback, the link up, the keys.
    let pane = tmux.wait_link_up();
    assert!(pane.lines().count() <= 24, "{pane}");
    assert!(pane.lines().all(|l| l.chars().count() <= 80), "{pane}");
    let p0 = wait_still(&pitches, Instant::now());

    // The terminal resized (an event that is not a key): the panel is drawn again at the
    // new width, and goes on without a key (the postback's age moves: the sim sends one
    // every 500 ms, the panel is drawn every 100 ms).
    let out = tmux.run(&["resize-window", "-t", "ctl", "-x", "100", "-y", "30"]);
    assert!(out.status.success(), "resize-window: {out:?}");
    let pane = tmux.wait_pane("the panel 100 columns wide", Duration::from_secs(5), |p| {
        p.lines().next().is_some_and(|l| l.chars().count() == 100)
    });
    let before = postback_age(&pane);
    assert!(before.is_some(), "{pane}");
    tmux.wait_pane("the postback's age moving", Duration::from_secs(5), |p| {
        postback_age(p) != before
    });

    // Up held for 1.5 s.
    let (started, last_key) = tmux.hold("Up", Duration::from_millis(1500));
    let first_rate = log.wait_after(": rate 0 20", started, Duration::from_secs(5));
    assert!(
        first_rate <= last_key,
        "the hold started only after the last key"
    );
    // Released: the core's dead-man sends one zero rate 250 ms after the last key event.
    // Bound: 250 ms, plus control's 10 ms loop and the sim's 5 ms tick, plus margin for a
    // loaded 2-core machine; a hold that did not stop would never log it.
    let stopped = log.wait_after(": rate 0 0", last_key, Duration::from_secs(5));
    let after = stopped.duration_since(last_key);
    assert!(
        after <= Duration::from_millis(1000),
        "stopped {after:?} after the last key"
    );
    // The gimbal moved up (20 deg/s for about 1.5 s; a hold that lapsed between key
    // events would move 5 deg per event at most) and then stood still.
    let p1 = wait_still(&pitches, stopped + Duration::from_millis(100));
    assert!(p1 - p0 >= 1500, "pitch {p0} -> {p1} (0.01 deg)");
    // The panel shows where it stopped.
    let sign = if p1 < 0 { "-" } else { "" };
    let abs = p1.unsigned_abs();
    let shown = format!("{sign}{}.{:02} deg", abs / 100, abs % 100);
    tmux.wait_pane(&shown, Duration::from_secs(5), |p| p.contains(&shown));

    // c: centre; d: look down; then q: a zero rate first, and exit 0.
    let t = Instant::now();
    tmux.keys(&["c"]);
    log.wait_after(": center", t, Duration::from_secs(5));
    let t = Instant::now();
    tmux.keys(&["d"]);
    log.wait_after(": look-down", t, Duration::from_secs(5));
    let t = Instant::now();
    tmux.keys(&["q"]);
    let zero = log.wait_after(": rate 0 0", t, Duration::from_secs(5));
    let gone = log.wait_after(" disconnected", t, Duration::from_secs(5));
    assert!(zero <= gone);
    assert_eq!(exit_status(&tmux, &rc), "0");
    assert_terminal_restored(&rc);
}

#[test]
fn control_needs_a_terminal_and_valid_arguments() {
    // stdin a pipe: usage error before any connection is tried.
    usage_error_naming(
        &["control", "--tcp", "127.0.0.1:1"],
        &["stdin is not a terminal"],
    );
    usage_error_naming(
        &["control", "--tcp", "127.0.0.1:1", "--speed", "0"],
        &["--speed", "[1, 100]"],
    );
    usage_error_naming(
        &["control", "--tcp", "127.0.0.1:1", "--speed", "-5"],
        &["[1, 100]"],
    );
    usage_error_naming(&["control", "--tcp", "host:99999"], &["--tcp"]);
    usage_error_naming(&["control"], &["--tcp"]);
}

/// A server that is not there: exit 1 before the panel is drawn, stderr naming it.
#[test]
fn control_without_a_server_is_a_runtime_failure() {
    let closed = closed_port();
    let port = closed.port();
    let tmux = Tmux::new();
    let err = std::env::temp_dir().join(format!(
        "gimbalctl-control-refused-{}.err",
        std::process::id()
    ));
    let rc = control_in_tmux(
        &tmux,
        &format!("--tcp 127.0.0.1:{port} 2> '{}'", err.display()),
        "control-refused",
    );
    let deadline = Instant::now() + Duration::from_secs(10);
    while !rc.exists() || std::fs::read_to_string(&rc).unwrap_or_default().is_empty() {
        assert!(
            Instant::now() < deadline,
            "control did not exit: {}",
            tmux.pane()
        );
        thread::sleep(Duration::from_millis(20));
    }
    let code = std::fs::read_to_string(&rc).unwrap();
    let stderr = std::fs::read_to_string(&err).unwrap_or_default();
    let _ = std::fs::remove_file(&rc);
    let _ = std::fs::remove_file(&err);
    assert_eq!(code.trim(), "1", "{stderr}");
    assert!(stderr.contains(&format!("127.0.0.1:{port}")), "{stderr}");
}

/// The panel on the gimbal's UART (`--serial`, the simulated gimbal on a pty): the same
/// keys, the same rate hold and dead-man, through the library's `SerialLink` and `SerialPort`.
#[test]
fn control_drives_the_gimbal_over_its_uart() {
    let (_sim, path, log) = start_pty_sim();
    let tmux = Tmux::new();
    let rc = control_in_tmux(&tmux, &format!("--serial {path}"), "serial");
    let pane = tmux.wait_link_up();
    assert!(pane.contains(&format!("control {path}")), "{pane}");
    let (started, last_key) = tmux.hold("Up", Duration::from_millis(600));
    log.wait_after(": rate 0 20", started, Duration::from_secs(5));
    let stopped = log.wait_after(": rate 0 0", last_key, Duration::from_secs(5));
    assert!(stopped.duration_since(last_key) <= Duration::from_millis(1000));
    let t = Instant::now();
    tmux.keys(&["c"]);
    log.wait_after(": center", t, Duration::from_secs(5));
    tmux.keys(&["q"]);
    assert_eq!(exit_status(&tmux, &rc), "0");
    assert_terminal_restored(&rc);
}

/// Bytes that hold no frame (a wrong baud rate): counted on the panel, with the likely
/// cause; the panel goes on, and `q` still leaves with exit 0.
#[test]
fn control_shows_garbage_on_the_line() {
    let mut pty = TestPty::new();
    let tmux = Tmux::new();
    let rc = control_in_tmux(&tmux, &format!("--serial {}:57600", pty.path), "garbage");
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        // 0x55 never starts a frame.
        pty.write(&[0x55; 100]);
        let pane = tmux.pane();
        if pane.contains("no frame in") {
            assert!(pane.contains("wrong baud rate"), "{pane}");
            assert!(pane.contains("57600"), "{pane}");
            assert!(pane.contains("waiting for the first postback"), "{pane}");
            break;
        }
        assert!(Instant::now() < deadline, "the panel never said: {pane}");
        thread::sleep(Duration::from_millis(100));
    }
    tmux.keys(&["q"]);
    assert_eq!(exit_status(&tmux, &rc), "0");
    assert_terminal_restored(&rc);
}
