//! `gimbalctl decode`: the three log forms, corruption, loss and foreign frames, `--stats`
//! counts and `--stream`. Postbacks are built in the test from the protocol notes' table with a
//! reference CRC.

mod common;

use common::*;
use serde_json::{json, Value};

/// Candump `-L` lines for one postback's four frames, 1 ms apart from `t`.
fn log_frames(t: f64, frames: &[Vec<u8>], skip: Option<usize>) -> Vec<String> {
    frames
        .iter()
        .enumerate()
        .filter(|(i, _)| Some(*i) != skip)
        .map(|(i, f)| format!("({:.6}) can0 030F0001#{}", t + i as f64 * 0.001, hex(f)))
        .collect()
}

fn pb(pitch: i16, heading: u16, motor: i16) -> Vec<Vec<u8>> {
    postback_frames(&postback(1, 0, 2, pitch, heading, motor))
}

fn postback_json(t: Value, pitch: f64, heading: f64, motor: f64) -> Value {
    json!({
        "type": "postback", "t": t, "id": 0x030F0001,
        "gimbal_type": 1, "gimbal_model": "X30/X30GT", "tracking": false,
        "mode": 2, "mode_name": "heading_follow",
        "pitch_deg": pitch, "heading_deg": heading, "motor_heading_deg": motor,
    })
}

fn stats(out: &Out) -> Value {
    let all = out.json();
    let last = all.last().expect("a stats line").clone();
    assert_eq!(last["type"], "stats");
    last
}

fn decode_log(lines: &[String], extra: &[&str]) -> Out {
    let mut text = lines.join("\n");
    text.push('\n');
    let mut args = vec!["decode"];
    args.extend_from_slice(extra);
    let out = run_stdin(&args, text.as_bytes());
    assert_eq!(out.code, 0, "{out:?}");
    out
}

#[test]
fn corruption_loss_and_foreign_frames() {
    let t0 = 1_700_000_000.0;
    let mut log = Vec::new();
    // A: good.
    log.extend(log_frames(t0, &pb(-3000, 9000, -77), None));
    log.push(format!(
        "({:.6}) can0 18FF0001#0102030405060708",
        t0 + 0.004
    ));
    // B: one bit flipped in its second frame: a CRC error.
    let mut b = pb(1000, 100, 0);
    b[1][3] ^= 0x10;
    log.extend(log_frames(t0 + 0.5, &b, None));
    // C: third frame lost: incomplete.
    log.extend(log_frames(t0 + 1.0, &pb(2000, 200, 0), Some(2)));
    // D: good, with frames of other devices (extended and standard IDs) in between.
    let d = log_frames(t0 + 1.5, &pb(-4567, 35999, 17000), None);
    log.push(d[0].clone());
    log.push(format!(
        "({:.6}) can0 18FF0001#0102030405060708",
        t0 + 1.5005
    ));
    log.push(format!("({:.6}) can0 123#00", t0 + 1.5006));
    log.extend(d[1..].iter().cloned());
    // E: header frame lost: its other three frames are orphans (incomplete).
    log.extend(log_frames(t0 + 2.0, &pb(0, 0, 0), Some(0)));
    // F: good.
    log.extend(log_frames(t0 + 2.5, &pb(-10000, 0, -17000), None));
    // A control command, then a bad line and a blank one.
    log.push(format!("({:.6}) can0 00000F01#0F08023EFE000000", t0 + 2.6));
    log.push("this is not a CAN frame".to_owned());
    log.push(String::new());
    // G: cut off by the end of the log.
    log.extend(log_frames(t0 + 3.0, &pb(0, 0, 0), None).into_iter().take(2));

    let out = decode_log(&log, &["--stats"]);
    let msgs = out.json();
    assert_eq!(msgs.len(), 5, "{}", out.stdout);
    assert_json_eq(
        &msgs[0],
        &postback_json(json!(1_700_000_000.003), -30.0, 90.0, -0.77),
    );
    assert_json_eq(
        &msgs[1],
        &postback_json(json!(1_700_000_001.503), -45.67, 359.99, 170.0),
    );
    assert_json_eq(
        &msgs[2],
        &postback_json(json!(1_700_000_002.503), -100.0, 0.0, -170.0),
    );
    assert_json_eq(
        &msgs[3],
        &json!({"type": "command", "t": 1_700_000_002.6, "id": 3841, "peripheral": "gimbal",
               "command": "pitch", "args": [-45]}),
    );
    assert_json_eq(
        &msgs[4],
        &json!({"type": "stats", "lines": log.len(), "frames": 28, "messages": 4,
               "crc_errors": 1, "incomplete": 3, "malformed_lines": 1, "foreign_frames": 3}),
    );
    // Without --stats, the same messages and no stats line.
    let plain = decode_log(&log, &[]);
    assert_eq!(plain.json(), msgs[..4].to_vec());
}

#[test]
fn the_three_forms_decode_alike() {
    let frames = pb(-3000, 4500, 12);
    let cmd = unhex("0F08023EFE000000");
    let candump_l: Vec<String> = log_frames(100.25, &frames, None)
        .into_iter()
        .chain([format!("(100.300000) vcan0 00000F01#{}", hex(&cmd))])
        .collect();
    let cansend: Vec<String> = frames
        .iter()
        .chain([&cmd])
        .map(|f| format!("030F0001#{}", hex(f)))
        .map(|l| {
            if l.contains("#0F08") {
                l.replace("030F0001", "00000F01")
            } else {
                l
            }
        })
        .collect();
    let spaced = |f: &[u8]| {
        f.iter()
            .map(|b| format!("{b:02X}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let screen: Vec<String> = frames
        .iter()
        .map(|f| format!("  can0  030F0001   [8]  {}", spaced(f)))
        .chain([format!("  can0  00000F01   [8]  {}", spaced(&cmd))])
        .collect();
    let screen_ts: Vec<String> = screen
        .iter()
        .map(|l| format!(" (000.000120) {l}"))
        .collect();

    let expected_pb = postback_json(Value::Null, -30.0, 45.0, 0.12);
    let expected_cmd = json!({"type": "command", "t": null, "id": 3841,
        "peripheral": "gimbal", "command": "pitch", "args": [-45]});
    for (name, log) in [("cansend", &cansend), ("screen", &screen)] {
        let out = decode_log(log, &["--stats"]);
        let msgs = out.json();
        assert_json_eq(&msgs[0], &expected_pb);
        assert_json_eq(&msgs[1], &expected_cmd);
        assert_eq!(msgs[2]["frames"], 5, "{name}");
        assert_eq!(msgs[2]["messages"], 2, "{name}");
    }
    let msgs = decode_log(&candump_l, &[]).json();
    assert_eq!(msgs[0]["t"], json!(100.253));
    assert_eq!(msgs[1]["t"], json!(100.3));
    assert_eq!(msgs[0]["pitch_deg"], json!(-30));
    // Screen form with a relative timestamp: "000.000120" is written as the JSON number
    // 0.00012.
    let out = decode_log(&screen_ts, &[]);
    assert!(out.stdout.contains("\"t\":0.000120,"), "{}", out.stdout);
    assert_eq!(out.json()[1]["t"], json!(0.00012));
    // CRLF line ends, tabs and a last line without a newline.
    let mut crlf = cansend.join("\r\n").replace("030F0001#", "\t030F0001#");
    crlf.push_str("\r\n");
    let out = run_stdin(&["decode"], crlf.trim_end().as_bytes());
    assert_json_eq(&json!(out.json()), &json!([expected_pb, expected_cmd]));
}

#[test]
fn unknown_codes_survive_decoding() {
    let frames = postback_frames(&postback(9, 1, 7, 6000, 36000, -32500));
    let lines: Vec<String> = frames
        .iter()
        .map(|f| format!("030F0001#{}", hex(f)))
        .collect();
    let msgs = decode_log(&lines, &[]).json();
    assert_json_eq(
        &json!(msgs),
        &json!([{
            "type": "postback", "t": null, "id": 0x030F0001,
            "gimbal_type": 9, "gimbal_model": null, "tracking": true,
            "mode": 7, "mode_name": null,
            "pitch_deg": 60, "heading_deg": 360, "motor_heading_deg": -325,
        }]),
    );
    // The documented names.
    for (code, model) in [(2, "X30T"), (6, "A2000"), (7, "30x dual light")] {
        let frames = postback_frames(&postback(code, 0, 1, 0, 0, 0));
        let lines: Vec<String> = frames
            .iter()
            .map(|f| format!("030F0001#{}", hex(f)))
            .collect();
        let m = &decode_log(&lines, &[]).json()[0];
        assert_eq!(m["gimbal_model"], model);
        assert_eq!(m["mode_name"], "full_lock");
    }
}

#[test]
fn bad_frames_on_protocol_ids_are_malformed_not_fatal() {
    let mut lines: Vec<String> = [
        // Pitch 3276.7 deg: out of range.
        "00000F01#0F0802FF7F000000",
        // Unknown command.
        "00000F01#0F99000000000000",
        // Wrong length.
        "00000F01#0F07",
        "0000FF16#01020304",
        "030F0001#EB90",
        // Altitude with non-zero padding.
        "0000FF16#0100000000000001",
        // Non-ASCII text byte.
        "02008202#C300000000000000",
        // Fine.
        "00000F01#0F07000000000000",
        // Remote and CAN FD frames, an error frame.
        "00000F01#R",
        "00000F01##0112233",
        "20000004#0000000000000000",
        // Not frames.
        "00000F01#0F0",
        "0F01#0F07000000000000",
        "(1700000000.1 can0 00000F01#0F07000000000000",
    ]
    .map(str::to_owned)
    .to_vec();
    // And a line too long to keep (malformed, whatever it holds).
    lines.push(format!("00000F01#0F07{}", "0".repeat(5000)));
    let out = decode_log(&lines, &["--stats"]);
    let msgs = out.json();
    assert_eq!(msgs.len(), 2, "{}", out.stdout);
    assert_eq!(msgs[0]["command"], "look-down");
    assert_json_eq(
        &msgs[1],
        &json!({"type": "stats", "lines": 15, "frames": 11, "messages": 1, "crc_errors": 0,
               "incomplete": 0, "malformed_lines": 11, "foreign_frames": 3}),
    );
}

#[test]
fn texts_and_vehicle_frames_in_a_log() {
    let lines: Vec<String> = [
        "(1.000000) can0 02008201#48454C4C4F2C2047",
        "(1.001000) can0 0000FF15#A850401C80F41705",
        "(1.002000) can0 02008202#494D42414C000000",
        "(1.003000) can0 0000FF16#3930000000000000",
        "(1.004000) can0 0000FF13#960038FFD8DC0000",
        // A text whose end never comes.
        "(1.005000) can0 02008201#4142434445464748",
    ]
    .map(str::to_owned)
    .to_vec();
    let msgs = decode_log(&lines, &["--stats"]).json();
    assert_json_eq(
        &json!(msgs),
        &json!([
            json!({"type": "gps", "t": 1.001, "id": 0xFF15, "lat_deg": 47.3977, "lon_deg": 8.5456}),
            json!({"type": "text", "t": 1.002, "id": 0x02008202, "text": "HELLO, GIMBAL"}),
            json!({"type": "altitude", "t": 1.003, "id": 0xFF16, "alt_m": 123.45}),
            json!({"type": "attitude", "t": 1.004, "id": 0xFF13, "pitch_deg": 1.5,
                   "roll_deg": -2, "heading_deg": -90}),
            json!({"type": "stats", "lines": 6, "frames": 6, "messages": 4, "crc_errors": 0,
                   "incomplete": 1, "malformed_lines": 0, "foreign_frames": 0}),
        ]),
    );
}

#[test]
fn frames_too_far_apart_are_not_one_message() {
    // Four frames 200 ms apart (the bound between frames of one message is 100 ms).
    let frames = pb(100, 100, 100);
    let lines: Vec<String> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            format!(
                "({}.{}00000) can0 030F0001#{}",
                10 + i / 5,
                (i * 2) % 10,
                hex(f)
            )
        })
        .collect();
    let msgs = decode_log(&lines, &["--stats"]).json();
    assert_eq!(msgs.len(), 1, "{msgs:?}");
    assert_eq!(msgs[0]["messages"], 0);
    assert_eq!(msgs[0]["incomplete"], 1);
    // Without timestamps there is no time to go by: the same frames make a message.
    let lines: Vec<String> = frames
        .iter()
        .map(|f| format!("030F0001#{}", hex(f)))
        .collect();
    assert_eq!(decode_log(&lines, &[]).json().len(), 1);
}

#[test]
fn stream_capture() {
    let mut bytes = b"garbage \xEB\x90 more garbage".to_vec();
    bytes.extend(tcp_frame(&unhex("0F08023EFE000000")));
    bytes.extend(postback(1, 0, 2, -3000, 9000, -77));
    // A postback with a bad CRC.
    let mut bad = postback(1, 0, 2, 1, 1, 1);
    bad[20] ^= 1;
    bytes.extend(bad);
    // A control frame with a good CRC but an unknown command.
    bytes.extend(tcp_frame(&unhex("0F99000000000000")));
    bytes.extend(tcp_frame(&unhex("1F020A0000000000")));
    // Cut off.
    bytes.extend(&tcp_frame(&unhex("0F07000000000000"))[..10]);
    let out = run_stdin(&["decode", "--stream", "--stats"], &bytes);
    assert_eq!(out.code, 0, "{out:?}");
    let msgs = out.json();
    assert_json_eq(
        &json!(msgs),
        &json!([
            json!({"type": "command", "t": null, "id": null, "peripheral": "gimbal",
                   "command": "pitch", "args": [-45]}),
            postback_json(Value::Null, -30.0, 90.0, -0.77)
                .as_object()
                .map(|o| {
                    let mut o = o.clone();
                    o.insert("id".into(), Value::Null);
                    Value::Object(o)
                })
                .unwrap(),
            json!({"type": "command", "t": null, "id": null, "peripheral": "dual_light",
                   "command": "palette", "args": ["ice-blue"]}),
            // Incomplete: the leading garbage (a run of bytes that held no frame) and the
            // frame cut off.
            json!({"type": "stats", "lines": 0, "frames": 5, "messages": 3, "crc_errors": 1,
                   "incomplete": 2, "malformed_lines": 1, "foreign_frames": 0}),
        ]),
    );
    // A control frame without its first byte: all 23 bytes skipped, one frame lost.
    let frame = tcp_frame(&unhex("0F07000000000000"));
    let out = run_stdin(&["decode", "--stream", "--stats"], &frame[1..]);
    assert_eq!(out.code, 0, "{out:?}");
    assert_json_eq(
        &json!(out.json()),
        &json!([
            json!({"type": "stats", "lines": 0, "frames": 0, "messages": 0,
                       "crc_errors": 0, "incomplete": 1, "malformed_lines": 0,
                       "foreign_frames": 0})
        ]),
    );
}

#[test]
fn what_could_not_be_decoded_is_said_without_the_stats_line_too() {
    let input = b"garbage\n00000F01#0F07000000000000\n";
    let out = run_stdin(&["decode"], input);
    assert_eq!(out.code, 0, "{out:?}");
    assert_eq!(out.json().len(), 1, "{out:?}");
    assert_eq!(
        out.stderr,
        "gimbalctl decode: warning: 0 CRC errors, 0 incomplete messages, 1 malformed line \
         (--stats counts them)\n"
    );
    // With the stats line, it is said there, and stderr stays empty.
    let out = run_stdin(&["decode", "--stats"], input);
    assert_eq!((out.code, out.stderr.as_str()), (0, ""), "{out:?}");
    assert_eq!(out.json()[1]["malformed_lines"], 1);
}

#[test]
fn files_and_stdin() {
    let dir = std::env::temp_dir().join(format!("gimbalctl-decode-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("log.txt");
    std::fs::write(&path, "00000F01#0F07000000000000\n").unwrap();
    let p = path.to_str().unwrap();
    let from_file = ok(&["decode", p]);
    let from_stdin = run_stdin(&["decode", "-"], b"00000F01#0F07000000000000\n");
    assert_eq!(from_file.stdout, from_stdin.stdout);
    assert_eq!(from_file.json()[0]["command"], "look-down");
    // Empty input: nothing, or just the stats.
    assert_eq!(run_stdin(&["decode"], b"").stdout, "");
    assert_eq!(
        run_stdin(&["decode", "--stats"], b"").json(),
        vec![
            json!({"type": "stats", "lines": 0, "frames": 0, "messages": 0, "crc_errors": 0,
                    "incomplete": 0, "malformed_lines": 0, "foreign_frames": 0})
        ]
    );
    // Binary junk is malformed lines, not a failure.
    let out = run_stdin(&["decode", "--stats"], b"\x00\xFF\xFE\n\x01\x02");
    assert_eq!(out.code, 0);
    assert_eq!(out.json()[0]["malformed_lines"], 2);
    // A directory cannot be read as a log: a runtime failure.
    let out = run(&["decode", dir.to_str().unwrap()]);
    assert_eq!(out.code, 1, "{out:?}");
    assert!(out.stdout.is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_long_log_streams_through() {
    // 40 000 lines (10 000 postbacks): output arrives in order, and nothing is lost
    // across the reader's block boundaries.
    let mut text = String::new();
    for i in 0..10_000i32 {
        let p = (i % 16000 - 10000) as i16;
        for f in pb(p, (i % 36000) as u16, 0) {
            text.push_str(&format!("030F0001#{}\n", hex(&f)));
        }
    }
    let out = run_stdin(&["decode", "--stats"], text.as_bytes());
    let lines = out.lines();
    assert_eq!(lines.len(), 10_001);
    for (i, l) in lines[..10_000].iter().enumerate() {
        let p = (i as i32 % 16000 - 10000) as f64 / 100.0;
        let v: Value = serde_json::from_str(l).unwrap();
        assert_eq!(v["pitch_deg"].as_f64(), Some(p), "{l}");
    }
    let s = stats(&out);
    assert_eq!(
        (s["lines"].as_u64(), s["messages"].as_u64()),
        (Some(40_000), Some(10_000))
    );
}
