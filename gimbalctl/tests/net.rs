//! `send`, `monitor` and `sim` on loopback, with ephemeral ports and timeouts on every
//! socket and child process.

mod common;

use common::*;
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::process::{Command, Stdio};
use std::thread;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

fn connect(addr: &str) -> TcpStream {
    let s = TcpStream::connect_timeout(&addr.parse().unwrap(), Duration::from_secs(3)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    s.set_write_timeout(Some(Duration::from_secs(5))).unwrap();
    s
}

fn unix_now() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}

#[test]
fn end_to_end_send_pitch_and_monitor_it() {
    let (_sim, addr) = start_sim(&["--exit-after-ms", "8000"]);
    let sent_at = unix_now();
    let out = ok(&["send", "--tcp", &addr, "pitch", "-30"]);
    assert!(out.stdout.is_empty());
    let out = run_timeout(
        &["monitor", "--tcp", &addr, "--json", "--count", "6"],
        b"",
        Duration::from_secs(7),
    );
    assert_eq!(out.code, 0, "{out:?}");
    let msgs = out.json();
    assert_eq!(msgs.len(), 6);
    let reached = msgs
        .iter()
        .find(|m| (m["pitch_deg"].as_f64().unwrap() + 30.0).abs() <= 0.05)
        .unwrap_or_else(|| panic!("pitch never reached -30: {msgs:?}"));
    let t = reached["t"].as_f64().unwrap();
    assert!(t - sent_at <= 3.0, "reached -30 after {} s", t - sent_at);
    for m in &msgs {
        assert_eq!(m["type"], "postback");
        assert_eq!(m["id"], serde_json::Value::Null);
    }
    // Readable form.
    let out = run_timeout(
        &["monitor", "--tcp", &addr, "--count", "1"],
        b"",
        Duration::from_secs(5),
    );
    assert_eq!(out.code, 0, "{out:?}");
    assert!(out.stdout.contains("pitch -30.00 deg"), "{}", out.stdout);
}

/// Reads 27-byte postbacks from a raw client until `n` arrived; checks each with the
/// reference CRC.
fn read_postbacks(s: &mut TcpStream, n: usize) -> Vec<Vec<u8>> {
    let mut got = Vec::new();
    let mut buf = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(5);
    while got.len() < n {
        assert!(Instant::now() < deadline, "only {} postbacks", got.len());
        let mut chunk = [0u8; 256];
        let k = s.read(&mut chunk).expect("postbacks keep coming");
        assert!(k > 0, "sim closed the connection");
        buf.extend_from_slice(&chunk[..k]);
        got.extend(take_postbacks(&mut buf));
    }
    got
}

#[test]
fn sim_serves_several_clients_tolerates_garbage_and_bounds_clients() {
    let (_sim, addr, log) = start_sim_logged(
        &["--exit-after-ms", "8000", "--max-clients", "2"],
        Duration::from_secs(10),
    );
    let mut a = connect(&addr);
    let mut b = connect(&addr);
    // Give the sim a tick to take both before the third one comes.
    thread::sleep(Duration::from_millis(100));
    let mut c = connect(&addr);
    let mut one = [0u8; 1];
    assert_eq!(
        c.read(&mut one).unwrap_or(0),
        0,
        "a third client is turned away"
    );

    // Garbage, a frame with a bad CRC, then a good pitch frame split in two writes.
    let mut bad = tcp_frame(&unhex("0F0802D4FE000000"));
    bad[23] ^= 0xFF;
    a.write_all(b"\x00\xFFnot a frame\xEB\x90\x0A\x01").unwrap();
    a.write_all(&bad).unwrap();
    let good = tcp_frame(&unhex("0F0802D4FE000000"));
    a.write_all(&good[..7]).unwrap();
    thread::sleep(Duration::from_millis(20));
    a.write_all(&good[7..]).unwrap();

    // Both clients get postbacks and see the pitch move to -30. (Their period is the
    // simulator's, tested on its own clock: here a stalled machine may bunch two.) What b
    // holds already is read first, so that what it reads is sent from now on.
    drain(&mut b);
    let start = Instant::now();
    let first = read_postbacks(&mut b, 2);
    read_postbacks(&mut a, 1);
    let mut seen = first.iter().map(|m| postback_pitch(m)).collect::<Vec<_>>();
    while !seen.contains(&-3000) {
        assert!(start.elapsed() < Duration::from_secs(4), "pitch: {seen:?}");
        seen.extend(read_postbacks(&mut b, 1).iter().map(|m| postback_pitch(m)));
    }
    // What was no frame is said, with its counts, in a line or over a few (as the reads
    // came): every byte before the good frame skipped (the garbage's 17 and the bad
    // frame's 24, rescanned), the bad CRC, and the candidate the garbage's `EB 90` began,
    // whose fixed bytes were wrong.
    let deadline = Instant::now() + Duration::from_secs(2);
    while no_frame(&log.text()) != (41, 1, 1) && Instant::now() < deadline {
        thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(no_frame(&log.text()), (41, 1, 1), "{}", log.text());
    // A client leaving frees a slot, once the sim has seen it go.
    let gone = a.local_addr().expect("a's address");
    drop(a);
    let deadline = Instant::now() + Duration::from_secs(5);
    while !log.text().lines().any(|l| {
        l.contains(&format!("sim: {gone} disconnected"))
            || l.contains(&format!("sim: {gone}: ")) && l.contains("(os error ")
            || l.contains(&format!("dropping {gone}"))
    }) {
        assert!(
            Instant::now() < deadline,
            "a never seen gone:\n{}",
            log.text()
        );
        thread::sleep(Duration::from_millis(5));
    }
    let mut d = connect(&addr);
    read_postbacks(&mut d, 1);
}

/// Reads, without waiting, what `s` holds.
fn drain(s: &mut TcpStream) {
    s.set_nonblocking(true).expect("non-blocking");
    let mut chunk = [0u8; 256];
    while matches!(s.read(&mut chunk), Ok(k) if k > 0) {}
    s.set_nonblocking(false).expect("blocking");
}

/// The counts of the sim's "sent what is no frame: N bytes skipped, N frames with a bad
/// CRC, N with wrong fixed bytes" lines, summed.
fn no_frame(log: &str) -> (u64, u64, u64) {
    let mut sum = (0, 0, 0);
    for line in log.lines() {
        let Some(rest) = line.split("sent what is no frame: ").nth(1) else {
            continue;
        };
        let n: Vec<u64> = rest
            .split(", ")
            .filter_map(|part| part.split(' ').next()?.parse().ok())
            .collect();
        if let [skipped, crc, invalid] = n[..] {
            sum = (sum.0 + skipped, sum.1 + crc, sum.2 + invalid);
        }
    }
    sum
}

/// Each command logged once, not each repeat (a rate hold sends one every 50 ms); a
/// client whose connection is reset dropped with the error said.
#[test]
fn sim_logs_each_command_once_and_says_a_reset() {
    let (_sim, addr, log) = start_sim_logged(&["--exit-after-ms", "8000"], Duration::from_secs(10));
    let mut a = connect(&addr);
    let peer = a.local_addr().unwrap();
    // Pitch -30 three times in one write, then -20 (-200 = FF38), then -30 again.
    let minus_30 = tcp_frame(&unhex("0F0802D4FE000000"));
    a.write_all(&minus_30.repeat(3)).unwrap();
    a.write_all(&tcp_frame(&unhex("0F080238FF000000"))).unwrap();
    a.write_all(&minus_30).unwrap();
    let logged = |log: &Log| -> Vec<String> {
        let prefix = format!("gimbalctl sim: {peer}: pitch ");
        log.text()
            .lines()
            .filter_map(|l| l.strip_prefix(&prefix).map(str::to_owned))
            .collect()
    };
    let deadline = Instant::now() + Duration::from_secs(5);
    while logged(&log).len() < 3 {
        assert!(Instant::now() < deadline, "{}", log.text());
        thread::sleep(Duration::from_millis(5));
    }
    // A tick for any line more to come.
    thread::sleep(Duration::from_millis(50));
    assert_eq!(logged(&log), ["-30", "-20", "-30"], "{}", log.text());
    // Closed while holding a postback unread: the kernel resets the connection.
    a.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    assert!(a.peek(&mut [0; 1]).unwrap() > 0, "a postback");
    drop(a);
    log.wait(
        &format!("gimbalctl sim: {peer}: Connection reset by peer (os error 104)"),
        Duration::from_secs(5),
    );
    assert!(!log.has(&format!("{peer} disconnected")), "{}", log.text());
}

/// Out of file descriptors, the sim keeps serving the clients it has and says why it takes
/// no more, at most once a second (the failure comes back at every tick).
#[test]
fn sim_out_of_descriptors_keeps_serving_and_says_so_once_a_second() {
    // stdin, stdout, stderr and the listener leave four of eight descriptors for clients.
    let mut sh = Command::new("sh");
    sh.args(["-c", "ulimit -n 8 && exec \"$0\" \"$@\"", BIN])
        .args(["sim", "--listen", "127.0.0.1:0", "--exit-after-ms", "2500"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let (mut sim, first, log) = start_command(
        sh,
        "gimbalctl sim: listening on 127.0.0.1:",
        Duration::from_secs(10),
    );
    let addr = first.rsplit(' ').next().unwrap().to_owned();
    let mut clients: Vec<TcpStream> = (0..6).map(|_| connect(&addr)).collect();
    log.wait(
        "accept failed: Too many open files (os error 24)",
        Duration::from_secs(5),
    );
    // Four, unless the process holds more descriptors than the three and its listener.
    let text = log.text();
    let served = text.matches(" connected\n").count();
    assert!((1..6).contains(&served), "{text}");
    // Those taken, the first in line, are served: each gets a postback.
    for c in &mut clients[..served] {
        read_postbacks(c, 1);
    }
    assert_eq!(
        wait_with_timeout(&mut sim.0, Duration::from_secs(10)),
        Some(0)
    );
    let text = log.text();
    assert_eq!(text.matches(" connected\n").count(), served, "{text}");
    let failures: Vec<&str> = text
        .lines()
        .filter(|l| l.contains("accept failed"))
        .collect();
    // 2.5 s: three lines at the most (about 400 failures at one a tick).
    assert!((1..=3).contains(&failures.len()), "{text}");
    let said = "gimbalctl sim: accept failed: Too many open files (os error 24)";
    assert_eq!(failures[0], said);
    for later in &failures[1..] {
        let count = later
            .strip_prefix(&format!("{said} ("))
            .and_then(|rest| rest.strip_suffix(" since the last line)"))
            .and_then(|n| {
                n.strip_suffix(" more failures")
                    .or(n.strip_suffix(" more failure"))
            })
            .and_then(|n| n.parse::<u32>().ok());
        assert!(count.is_some_and(|n| n >= 1), "{later}");
    }
}

#[test]
fn sim_exits_after_the_given_time() {
    let start = Instant::now();
    let mut child = command(&["sim", "--listen", "127.0.0.1:0", "--exit-after-ms", "300"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let code = wait_with_timeout(&mut child, Duration::from_secs(10));
    assert_eq!(code, Some(0));
    assert!(start.elapsed() >= Duration::from_millis(300));
}

/// Accepts one connection and returns everything the client sent until it closed.
fn capture(listener: TcpListener) -> thread::JoinHandle<Vec<u8>> {
    thread::spawn(move || {
        listener.set_nonblocking(false).unwrap();
        let (mut s, _) = listener.accept().unwrap();
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        let mut all = Vec::new();
        let _ = s.read_to_end(&mut all);
        all
    })
}

fn frames_of(bytes: &[u8]) -> Vec<String> {
    assert_eq!(bytes.len() % 24, 0, "{bytes:02X?}");
    bytes.chunks(24).map(hex).collect()
}

#[test]
fn send_writes_the_24_byte_frames() {
    let cases: &[(&[&str], &[&str])] = &[
        (&["pitch", "-30"], &["0F0802D4FE000000"]),
        (&["look-down"], &["0F07000000000000"]),
        (
            &["look-at", "0", "0", "1000", "0", "0.009", "0"],
            &["0F08018403000000", "0F08023FFE000000"],
        ),
    ];
    for (cmd, data) in cases {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let got = capture(listener);
        let mut args = vec!["send", "--tcp", &addr];
        args.extend_from_slice(cmd);
        ok(&args);
        let expected: Vec<String> = data.iter().map(|d| hex(&tcp_frame(&unhex(d)))).collect();
        assert_eq!(frames_of(&got.join().unwrap()), expected, "{cmd:?}");
    }
}

#[test]
fn send_holds_a_rate_then_sends_zero_rate() {
    for (cmd, data, zero) in [
        (["rate", "10", "0"], "0F04E80300000000", "0F04000000000000"),
        (
            ["ir-rate", "0", "-5"],
            "1F0400000CFE0000",
            "1F04000000000000",
        ),
    ] {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let got = capture(listener);
        let start = Instant::now();
        let mut args = vec![
            "send",
            "--tcp",
            &addr,
            "--repeat-ms",
            "50",
            "--for-ms",
            "300",
        ];
        args.extend_from_slice(&cmd);
        ok(&args);
        let took = start.elapsed();
        assert!(took >= Duration::from_millis(300), "{took:?}");
        let frames = frames_of(&got.join().unwrap());
        let rate = hex(&tcp_frame(&unhex(data)));
        let (last, held) = frames.split_last().unwrap();
        assert_eq!(*last, hex(&tcp_frame(&unhex(zero))), "{cmd:?}");
        // The first, then one a repeat at 50, 100, … 300 ms: a count of passes, not of
        // time, whatever the load (`SendJob::run`).
        assert_eq!(held.len(), 7, "{} frames", held.len());
        assert!(held.iter().all(|f| *f == rate), "{held:?}");
    }
    // The options may also follow the command.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let got = capture(listener);
    ok(&[
        "send",
        "--tcp",
        &addr,
        "rate",
        "10",
        "0",
        "--repeat-ms",
        "50",
        "--for-ms",
        "100",
    ]);
    let frames = frames_of(&got.join().unwrap());
    // The first, repeats at 50 and 100 ms, the zero rate.
    assert_eq!(frames.len(), 4, "{frames:?}");
}

#[test]
fn monitor_warns_when_postbacks_stop_and_fails_when_the_server_goes() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let server = thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        // Silence for 3 s, twice the monitor's 1.5 s before it warns (a stalled monitor
        // wakes late), then one postback split across two writes, after garbage.
        thread::sleep(Duration::from_millis(3000));
        let msg = postback(6, 1, 3, -3000, 18000, -150);
        s.write_all(b"\x01\x02\x03").unwrap();
        s.write_all(&msg[..5]).unwrap();
        thread::sleep(Duration::from_millis(20));
        s.write_all(&msg[5..]).unwrap();
        // Then one more and close, before the client's count of 3.
        s.write_all(&msg).unwrap();
        thread::sleep(Duration::from_millis(100));
    });
    let out = run_timeout(
        &["monitor", "--tcp", &addr, "--count", "3"],
        b"",
        Duration::from_secs(10),
    );
    server.join().unwrap();
    assert_eq!(out.code, 1, "{out:?}");
    assert!(out.stderr.contains("no postback"), "{}", out.stderr);
    assert!(out.stderr.contains("closed"), "{}", out.stderr);
    let lines = out.lines();
    assert_eq!(lines.len(), 2, "{}", out.stdout);
    assert_eq!(
        lines[0],
        "pitch -30.00 deg  heading 180.00 deg  motor -1.50 deg  mode lock  tracking yes  gimbal 6 (A2000)"
    );

    // --json --count 1 ends with the first one.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let server = thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        s.write_all(&postback(9, 0, 8, 1, 2, 3)).unwrap();
        thread::sleep(Duration::from_millis(500));
    });
    let out = run_timeout(
        &["monitor", "--tcp", &addr, "--json", "--count", "1"],
        b"",
        Duration::from_secs(10),
    );
    server.join().unwrap();
    assert_eq!(out.code, 0, "{out:?}");
    let m = &out.json()[0];
    assert_json_eq(
        &serde_json::json!([
            m["gimbal_type"],
            m["gimbal_model"],
            m["mode"],
            m["mode_name"],
            m["pitch_deg"],
            m["heading_deg"],
            m["motor_heading_deg"]
        ]),
        &serde_json::json!([9, null, 8, null, 0.01, 0.02, 0.03]),
    );
    assert!(m["t"].as_f64().unwrap() > 1.6e9);
}
