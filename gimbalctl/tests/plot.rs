//! `gimbalctl plot`: a generated 60 s flight log with known faults, drawn, then read back
//! from the SVG: series present (by colour), axis ranges (from the tick labels), and the
//! fault markers at the injected times (pixels mapped back to seconds through the tick
//! labels). Plus a golden picture, reviewed by eye and committed.
//!
//! The log is built here from the spec (the protocol notes' frame layouts, through the reference
//! helpers in `common`), not with the tool or the library.

mod common;

use common::*;
use std::collections::BTreeMap;

const T0: f64 = 1_700_000_000.0;

/// Injected faults and events, seconds from the start.
const CRC_AT: f64 = 20.25;
const LOST_AT: f64 = 30.25;
const GAP: (f64, f64) = (40.0, 45.0);
const TRACKING: (f64, f64) = (50.0, 55.0);
const LOCK_FROM: f64 = 25.0;
const END: f64 = 60.0;

/// The reported pitch (deg): level, then to -30 after the command at 5 s, then up at the
/// commanded 5 deg/s from 10 s to 12 s.
fn pitch_at(t: f64) -> f64 {
    if t < 5.0 {
        0.0
    } else if t < 8.0 {
        -10.0 * (t - 5.0)
    } else if t < 10.0 {
        -30.0
    } else if t < 12.0 {
        -30.0 + 5.0 * (t - 10.0)
    } else {
        -20.0
    }
}

/// The reported heading (deg): 0, then to 90 after the command at 20 s.
fn heading_at(t: f64) -> f64 {
    (30.0 * (t - 20.0)).clamp(0.0, 90.0)
}

fn vehicle_heading_at(t: f64) -> f64 {
    30.0 + 0.5 * t
}

fn line(out: &mut String, t: f64, id: u32, data: &[u8]) {
    out.push_str(&format!("({:.6}) can0 {id:08X}#{}\n", T0 + t, hex(data)));
}

/// The log, and how many postbacks in it are whole and valid.
fn flight_log() -> (String, usize) {
    let mut events: Vec<(f64, u32, Vec<u8>)> = Vec::new();
    // Attitude every 200 ms: pitch, roll, heading in 0.01 deg, i16 LE (heading in
    // [-180, 180)).
    for k in 0..(END / 0.2) as i32 {
        let t = f64::from(k) * 0.2 + 0.1;
        let h = (vehicle_heading_at(t) * 100.0).round() as i16;
        let mut d = vec![0u8; 8];
        d[4..6].copy_from_slice(&h.to_le_bytes());
        events.push((t, 0x0000_FF13, d));
    }
    // Control frames: pitch -30 at 5 s; a rate hold (yaw 0, pitch 5 deg/s, every 50 ms)
    // from 10 s to 12 s then zero; heading 90 at 20 s.
    let pitch_cmd = |deg: i16| {
        let [lo, hi] = (deg * 10).to_le_bytes();
        vec![0x0F, 0x08, 0x02, lo, hi, 0, 0, 0]
    };
    events.push((5.0, 0xF01, pitch_cmd(-30)));
    for k in 0..40 {
        let [lo, hi] = 500i16.to_le_bytes();
        events.push((
            10.0 + f64::from(k) * 0.05,
            0xF01,
            vec![0x0F, 0x04, 0, 0, lo, hi, 0, 0],
        ));
    }
    events.push((12.0, 0xF01, vec![0x0F, 0x04, 0, 0, 0, 0, 0, 0]));
    let [lo, hi] = 900u16.to_le_bytes();
    events.push((20.0, 0xF01, vec![0x0F, 0x08, 0x01, lo, hi, 0, 0, 0]));
    // Postbacks every 500 ms (four frames 1 ms apart), none in the gap.
    let mut valid = 0;
    for k in 0..(END / 0.5) as i32 {
        let t = f64::from(k) * 0.5 + 0.25;
        if t > GAP.0 && t < GAP.1 {
            continue;
        }
        let pitch = (pitch_at(t) * 100.0).round() as i16;
        let heading = (heading_at(t) * 100.0).round() as u16;
        let motor = ((heading_at(t) - vehicle_heading_at(t)) * 100.0).round() as i16;
        let mode = if t >= LOCK_FROM { 3 } else { 2 };
        let tracking = u8::from(t >= TRACKING.0 && t < TRACKING.1);
        let msg = postback(1, tracking, mode, pitch, heading, motor);
        let mut frames = postback_frames(&msg);
        if (t - CRC_AT).abs() < 1e-9 {
            frames[3][1] ^= 0xFF; // byte 25: the CRC's low byte
        } else if (t - LOST_AT).abs() < 1e-9 {
            frames.remove(2);
        } else {
            valid += 1;
        }
        let n = frames.len();
        for (i, f) in frames.into_iter().enumerate() {
            let i = if n == 3 && i == 2 { 3 } else { i };
            events.push((t + i as f64 * 0.001, 0x030F_0001, f));
        }
    }
    events.sort_by(|a, b| a.0.total_cmp(&b.0));
    // The log starts at 0 s, with a frame of another device.
    let mut out = String::new();
    line(&mut out, 0.0, 0x18FF_0000, &[0; 8]);
    for (t, id, d) in &events {
        line(&mut out, *t, *id, d);
    }
    // The log ends at 60 s, with a frame of another device.
    line(&mut out, END, 0x18FF_0000, &[0; 8]);
    (out, valid)
}

/// An attribute of an SVG element's text.
fn attr<'a>(el: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let at = el.find(&key)? + key.len();
    let end = el[at..].find('"')?;
    Some(&el[at..at + end])
}

fn num(el: &str, name: &str) -> f64 {
    attr(el, name)
        .unwrap_or_else(|| panic!("no {name} in {el}"))
        .parse()
        .unwrap()
}

/// The SVG's elements of one tag, as their text.
fn elements<'a>(svg: &'a str, tag: &str) -> Vec<&'a str> {
    let open = format!("<{tag} ");
    svg.match_indices(&open)
        .map(|(i, _)| {
            let end = svg[i..].find('>').unwrap();
            &svg[i..i + end + 1]
        })
        .collect()
}

/// Text elements: (x, y, text).
fn texts(svg: &str) -> Vec<(f64, f64, String)> {
    svg.match_indices("<text ")
        .map(|(i, _)| {
            let head_end = i + svg[i..].find('>').unwrap();
            let body_end = head_end + svg[head_end..].find("</text>").unwrap();
            let head = &svg[i..=head_end];
            (
                num(head, "x"),
                num(head, "y"),
                svg[head_end + 1..body_end]
                    .trim()
                    .replace("&gt;", ">")
                    .replace("&lt;", "<")
                    .replace("&amp;", "&"),
            )
        })
        .collect()
}

/// A linear map from pixels to values, fitted on two tick labels far apart.
fn fit(ticks: &[(f64, f64)]) -> impl Fn(f64) -> f64 {
    let (p0, v0) = ticks[0];
    let (p1, v1) = ticks[ticks.len() - 1];
    assert!((p1 - p0).abs() > 100.0, "ticks too close: {ticks:?}");
    move |p| v0 + (p - p0) * (v1 - v0) / (p1 - p0)
}

struct Panels {
    /// Panel tops (pixels), from the captions.
    tops: Vec<f64>,
}

impl Panels {
    fn of(texts: &[(f64, f64, String)]) -> Self {
        let caption = |c: &str| {
            texts
                .iter()
                .find(|t| t.2 == c)
                .unwrap_or_else(|| panic!("no caption {c}"))
                .1
        };
        let tops = vec![
            caption("pitch (deg)"),
            caption("heading (deg)"),
            caption("rates (deg/s)"),
            caption("mode, tracking, faults"),
            f64::INFINITY,
        ];
        assert!(tops.windows(2).all(|w| w[0] < w[1]), "{tops:?}");
        Panels { tops }
    }

    fn index(&self, y: f64) -> usize {
        self.tops
            .windows(2)
            .position(|w| y >= w[0] && y < w[1])
            .unwrap_or(99)
    }
}

/// x-axis tick labels (pixel x, value) of panel `p`: numbers under the plot, centred.
fn x_ticks(texts: &[(f64, f64, String)], panels: &Panels, p: usize) -> Vec<(f64, f64)> {
    let mut ticks: Vec<(f64, f64)> = texts
        .iter()
        .filter(|t| panels.index(t.1) == p)
        .filter_map(|t| Some((t.0, t.2.parse::<f64>().ok()?, t.1)))
        .fold(
            BTreeMap::<i64, Vec<(f64, f64)>>::new(),
            |mut rows, (x, v, y)| {
                rows.entry(y.round() as i64).or_default().push((x, v));
                rows
            },
        )
        .into_values()
        .max_by_key(Vec::len)
        .unwrap_or_default();
    ticks.sort_by(|a, b| a.0.total_cmp(&b.0));
    ticks
}

/// y-axis tick labels (pixel y, value) of panel `p`: numbers left of the plot.
fn y_ticks(texts: &[(f64, f64, String)], panels: &Panels, p: usize) -> Vec<(f64, f64)> {
    let mut ticks: Vec<(f64, f64)> = texts
        .iter()
        .filter(|t| panels.index(t.1) == p && t.0 < 100.0)
        .filter_map(|t| Some((t.1, t.2.parse::<f64>().ok()?)))
        .collect();
    ticks.sort_by(|a, b| a.0.total_cmp(&b.0));
    ticks
}

/// Polylines of a stroke colour: their points.
fn polylines(svg: &str, color: &str) -> Vec<Vec<(f64, f64)>> {
    elements(svg, "polyline")
        .into_iter()
        .filter(|e| attr(e, "stroke") == Some(color))
        .map(|e| {
            attr(e, "points")
                .unwrap()
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect()
        })
        .collect()
}

fn render(log: &str) -> (Out, String) {
    // A file of each call's own: the tests of this file run at once, in one process.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    let path = dir.join(format!("plot-{}-{call}.svg", std::process::id()));
    let _ = std::fs::remove_file(&path);
    let out = run_stdin(&["plot", "-", "-o", path.to_str().unwrap()], log.as_bytes());
    let svg = std::fs::read_to_string(&path).unwrap_or_default();
    let _ = std::fs::remove_file(&path);
    (out, svg)
}

/// The picture of `log`, which `plot` drew with exit 0 and a summary ending `summary`.
fn rendered(log: &str, summary: &str) -> String {
    let (out, svg) = render(log);
    assert_eq!(out.code, 0, "{out:?}");
    assert!(out.stdout.ends_with(summary), "{}", out.stdout);
    svg
}

#[test]
fn plot_of_a_flight_log_has_its_series_axes_and_faults() {
    let (log, valid) = flight_log();
    let (out, svg) = render(&log);
    assert_eq!(out.code, 0, "{out:?}");
    assert!(out.stderr.is_empty(), "{out:?}");
    // 300 attitude frames (one per 200 ms over 60 s); 43 commands (pitch, 40 rates, the
    // zero rate, heading).
    assert!(
        out.stdout.ends_with(&format!(
            ": 60.0 s, {valid} postbacks, 43 commands, 300 attitude frames, 1 link gaps, 1 CRC errors, 1 lost frames\n"
        )),
        "{}",
        out.stdout
    );
    assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(200)]);

    let texts = texts(&svg);
    let panels = Panels::of(&texts);
    for label in [
        "pitch (reported)",
        "pitch (commanded)",
        "heading (reported)",
        "motor heading (reported)",
        "vehicle heading (attitude)",
        "heading (commanded)",
        "yaw rate (from postbacks)",
        "pitch rate (from postbacks)",
        "yaw rate (commanded)",
        "pitch rate (commanded)",
        "link gap > 1.5 s",
        "tracking",
        "control mode",
        "CRC error",
        "lost frames",
    ] {
        assert!(texts.iter().any(|t| t.2 == label), "legend has no {label}");
    }

    // Series, by colour, each in its panel.
    for (color, panel) in [
        ("#1F77B4", 0), // pitch
        ("#2CA02C", 1), // heading
        ("#9467BD", 1), // motor heading
        ("#8C564B", 1), // vehicle heading
        ("#1F77B5", 2), // pitch rate (postbacks)
        ("#2CA02D", 2), // yaw rate (postbacks)
        ("#17BECF", 2), // pitch rate (commanded)
        ("#BCBD22", 2), // yaw rate (commanded)
        ("#7F7F7F", 3), // mode
    ] {
        let lines = polylines(&svg, color);
        let long = lines
            .iter()
            .find(|l| l.len() > 2)
            .unwrap_or_else(|| panic!("no series in {color}"));
        assert!(
            long.iter().all(|p| panels.index(p.1) == panel),
            "{color} outside panel {panel}"
        );
    }

    // The time axis of every panel: 0 to 60 s.
    for p in 0..4 {
        let ticks = x_ticks(&texts, &panels, p);
        assert!(ticks.len() >= 4, "panel {p}: {ticks:?}");
        assert!(
            ticks[0].1 >= 0.0 && ticks[0].1 <= 10.0,
            "panel {p}: {ticks:?}"
        );
        let last = ticks[ticks.len() - 1].1;
        assert!((50.0..=60.0).contains(&last), "panel {p}: {ticks:?}");
    }
    // The pitch axis covers -30 and 0, and not far beyond.
    let pitch_ticks = y_ticks(&texts, &panels, 0);
    let (lo, hi) = pitch_ticks
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), t| (a.min(t.1), b.max(t.1)));
    assert!(
        (-40.0..=-25.0).contains(&lo) && (0.0..=10.0).contains(&hi),
        "{pitch_ticks:?}"
    );

    // The reported pitch reaches -30 (y mapped through the pitch axis).
    let to_pitch = fit(&pitch_ticks);
    let pitch_line = &polylines(&svg, "#1F77B4")[0];
    let min_pitch = pitch_line
        .iter()
        .map(|p| to_pitch(p.1))
        .fold(f64::MAX, f64::min);
    assert!((min_pitch + 30.0).abs() < 1.0, "{min_pitch}");

    // Fault markers, at the injected times (x mapped through the status panel's axis).
    let to_t = fit(&x_ticks(&texts, &panels, 3));
    // How near a time read back from the drawing must be: four pixels of this axis (0.052 s
    // a pixel), for marks drawn at whole pixels and read through the tick labels' fit.
    let px = to_t(1.0) - to_t(0.0);
    assert!(px > 0.0 && px < 0.06, "{px} s a pixel");
    let near = 4.0 * px;
    let marks = |color: &str| -> Vec<f64> {
        polylines(&svg, color)
            .iter()
            // A marker spans the panel's height (a legend sample is 12 px).
            .filter(|l| l.len() == 2 && l[0].0 == l[1].0 && (l[1].1 - l[0].1).abs() > 50.0)
            .filter(|l| panels.index(l[0].1) == 3)
            .map(|l| to_t(l[0].0))
            .collect()
    };
    let crc = marks("#D62728");
    assert_eq!(crc.len(), 1, "{crc:?}");
    assert!((crc[0] - CRC_AT).abs() < near, "CRC marker at {crc:?}");
    let lost = marks("#FF7F0E");
    assert_eq!(lost.len(), 1, "{lost:?}");
    // The loss is seen when the next postback starts (within one period).
    assert!(
        lost[0] > LOST_AT - 0.1 && lost[0] < LOST_AT + 0.6,
        "lost marker at {lost:?}"
    );
    // The status panel's rectangles filled with `fill` that are `big` (not the legend's
    // sample), as (from, to) in s, of more than 0.5 s.
    let spans = |fill: &str, big: &dyn Fn(&str) -> bool| -> Vec<(f64, f64)> {
        elements(&svg, "rect")
            .into_iter()
            .filter(|e| attr(e, "fill") == Some(fill) && big(e))
            .filter(|e| panels.index(num(e, "y")) == 3)
            .map(|e| (to_t(num(e, "x")), to_t(num(e, "x") + num(e, "width"))))
            .filter(|g| g.1 - g.0 > 0.5)
            .collect()
    };
    // The link gap: from the last postback before 40 s to the first after 45 s. It spans
    // the panel's height (the legend sample is 10 px).
    let gaps = spans("#C7C7C7", &|e| num(e, "height") > 50.0);
    assert_eq!(gaps.len(), 1, "{gaps:?}");
    assert!(
        (gaps[0].0 - 39.75).abs() < near && (gaps[0].1 - 45.25).abs() < near,
        "{gaps:?}"
    );
    // Tracking: one band, 50 to 55 s (below the legend's 10 px sample, which sits in the
    // upper right).
    let bands = spans("#FFBB78", &|e| num(e, "width") > 25.0);
    assert_eq!(bands.len(), 1, "{bands:?}");
    assert!(
        (bands[0].0 - 50.25).abs() < near && (bands[0].1 - 55.25).abs() < near,
        "{bands:?}"
    );
}

/// The committed golden picture (`tests/data/plot-golden.svg`, reviewed by eye) is what the
/// tool draws for the generated log. `GIMBALCTL_BLESS=1` rewrites it after a deliberate
/// change (then look at it again).
#[test]
fn plot_matches_the_golden_picture() {
    let (log, _) = flight_log();
    let (out, svg) = render(&log);
    assert_eq!(out.code, 0, "{out:?}");
    let golden =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/plot-golden.svg");
    if std::env::var_os("GIMBALCTL_BLESS").is_some() {
        std::fs::write(&golden, &svg).unwrap();
        std::fs::write(golden.with_extension("log"), &log).unwrap();
    }
    let want = std::fs::read_to_string(&golden).expect("tests/data/plot-golden.svg");
    assert!(svg == want, "the plot differs from {}", golden.display());
    // The committed log is the generated one, for `gimbalctl plot` by hand.
    let log_file = std::fs::read_to_string(golden.with_extension("log")).unwrap();
    assert_eq!(log_file, log);
}

#[test]
fn plot_errors() {
    let (log, _) = flight_log();
    // PNG and unknown formats: exit 2 naming the valid extension, before reading input.
    for o in ["x.png", "x.pdf", "x"] {
        let out = run_stdin(&["plot", "-", "-o", o], log.as_bytes());
        assert_eq!(out.code, 2, "{out:?}");
        assert!(out.stdout.is_empty());
        assert!(
            out.stderr.contains(o) && out.stderr.contains(".svg"),
            "{}",
            out.stderr
        );
    }
    usage_error_naming(&["plot", "-"], &["--output"]);
    // A missing log and an empty one: runtime failures.
    failure_naming(
        &["plot", "/nonexistent/log", "-o", "/tmp/never.svg"],
        &["/nonexistent/log"],
    );
    let out = run_stdin(&["plot", "-o", "/tmp/never.svg"], b"garbage\n");
    assert_eq!(out.code, 1, "{out:?}");
    assert!(
        out.stdout.is_empty() && out.stderr.contains("nothing to plot"),
        "{out:?}"
    );
    // An unwritable output.
    let out = run_stdin(&["plot", "-o", "/nonexistent/dir/x.svg"], log.as_bytes());
    assert_eq!(out.code, 1, "{out:?}");
    assert!(
        out.stdout.is_empty() && out.stderr.contains("/nonexistent/dir/x.svg"),
        "{out:?}"
    );
}

/// A log of attitude frames only (no postback, no command) is drawn: the panels with
/// nothing in them over their default ranges, each with its margin (8% of the span):
/// pitch -90 to 30 deg (-99.6 to 39.6), rates -10 to 10 deg/s (-11.6 to 11.6).
#[test]
fn a_log_of_attitude_frames_only_is_drawn() {
    let mut log = String::new();
    for k in 0..50 {
        let t = f64::from(k) * 0.2;
        let mut d = vec![0u8; 8];
        d[4..6].copy_from_slice(&(3000i16 + 10 * k as i16).to_le_bytes());
        line(&mut log, t, 0x0000_FF13, &d);
    }
    let svg = rendered(&log, ": 9.8 s, 0 postbacks, 0 commands, 50 attitude frames, 0 link gaps, 0 CRC errors, 0 lost frames\n");
    let texts = texts(&svg);
    let panels = Panels::of(&texts);
    for (panel, lo, hi, (from, to)) in [
        (0, -90.0, 30.0, (-99.6, 39.6)),
        (2, -10.0, 10.0, (-11.6, 11.6)),
    ] {
        let values: Vec<f64> = y_ticks(&texts, &panels, panel)
            .iter()
            .map(|t| t.1)
            .collect();
        let (min, max) = (
            values[0].min(values[values.len() - 1]),
            values[0].max(values[values.len() - 1]),
        );
        // The ticks lie on the axis and reach within a tick step (a quarter of the
        // default span at most) of its default ends.
        let step = (hi - lo) / 4.0;
        assert!(
            values.iter().all(|v| (from..=to).contains(v)),
            "panel {panel}: {values:?}"
        );
        assert!(
            min <= lo + step && max >= hi - step,
            "panel {panel}: {values:?}"
        );
    }
    // The vehicle heading (30 to 34.9 deg) is drawn in the heading panel, and no
    // reported pitch anywhere.
    let vehicle = polylines(&svg, "#8C564B");
    let long: Vec<_> = vehicle.iter().filter(|l| l.len() > 2).collect();
    assert_eq!(long.len(), 1, "{vehicle:?}");
    assert!(long[0].iter().all(|p| panels.index(p.1) == 1), "{long:?}");
    assert!(polylines(&svg, "#1F77B4").is_empty());
    // Only what is drawn is in a legend.
    for label in [
        "pitch (reported)",
        "pitch (commanded)",
        "heading (reported)",
        "heading (commanded)",
        "yaw rate (commanded)",
        "CRC error",
    ] {
        assert!(!texts.iter().any(|t| t.2 == label), "legend has {label}");
    }
    assert!(texts.iter().any(|t| t.2 == "vehicle heading (attitude)"));
}

/// A log whose one postback has all its frames at one timestamp: no time passes, and the
/// time axis is 0 to 1 s.
#[test]
fn a_log_without_time_passing_is_drawn_over_one_second() {
    let mut log = String::new();
    for f in postback_frames(&postback(1, 0, 2, -1000, 4500, 0)) {
        line(&mut log, 0.0, 0x030F_0001, &f);
    }
    let svg = rendered(&log, ": 0.0 s, 1 postbacks, 0 commands, 0 attitude frames, 0 link gaps, 0 CRC errors, 0 lost frames\n");
    let texts = texts(&svg);
    let panels = Panels::of(&texts);
    for panel in 0..4 {
        let values: Vec<f64> = x_ticks(&texts, &panels, panel)
            .iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(values.first(), Some(&0.0), "panel {panel}: {values:?}");
        let last = values[values.len() - 1];
        assert!((0.75..=1.0).contains(&last), "panel {panel}: {values:?}");
    }
}

#[test]
fn timestamps_that_are_not_finite_times_are_counted_not_drawn() {
    // A candump timestamp of 309 digits or more parses to infinity: the time axis went to
    // infinity and the plot never finished. Each such line keeps the time before it. (The
    // log reader takes only digits[.digits]: no "inf", "nan" or sign reaches the plot.)
    let (log, _) = flight_log();
    let mut lines: Vec<String> = log.lines().map(str::to_owned).collect();
    let n = lines.len();
    for (at, ts) in [
        (n / 3, "9".repeat(309)),
        (n / 2, format!("{}.5", "1".repeat(400))),
        (2 * n / 3, "9".repeat(309)),
    ] {
        let (_, rest) = lines[at].split_once(')').unwrap();
        lines[at] = format!("({ts}){rest}");
    }
    let (out, svg) = render(&(lines.join("\n") + "\n"));
    assert_eq!(out.code, 0, "{out:?}");
    assert!(svg.contains("<svg"), "an SVG written");
    assert!(
        out.stdout
            .contains("3 lines with a timestamp that is not a finite time"),
        "{}",
        out.stdout
    );
    // The rest of the log's time is its own: the flight's END seconds.
    let secs: f64 = out
        .stdout
        .split(": ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    // The first and last lines are untouched: exactly END, as printed (to 0.1 s).
    assert_eq!(secs, END, "{}", out.stdout);
}

/// A serial capture (no timestamps): estimated time, 0.5 s per postback; a CRC error and
/// line noise marked where they were.
#[test]
fn plot_of_a_stream_capture() {
    let mut cap = Vec::new();
    for k in 0..20i16 {
        let mut pb = postback(1, 0, 2, -100 * k, 0, 0);
        if k == 10 {
            pb[25] ^= 0xFF;
        }
        cap.extend(pb);
        if k == 15 {
            cap.extend(b"\x00\x13line noise");
        }
        if k == 4 {
            let [lo, hi] = (-300i16).to_le_bytes();
            cap.extend(tcp_frame(&[0x0F, 0x08, 0x02, lo, hi, 0, 0, 0]));
        }
    }
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    let path = dir.join(format!("plot-stream-{}.svg", std::process::id()));
    let out = run_stdin(&["plot", "--stream", "-o", path.to_str().unwrap()], &cap);
    let svg = std::fs::read_to_string(&path).unwrap_or_default();
    let _ = std::fs::remove_file(&path);
    assert_eq!(out.code, 0, "{out:?}");
    assert!(
        out.stdout.ends_with(": 9.5 s (estimated), 19 postbacks, 1 commands, 0 attitude frames, 0 link gaps, 1 CRC errors, 1 lost frames\n"),
        "{}",
        out.stdout
    );
    assert!(
        svg.contains("estimated"),
        "the axis says the time is estimated"
    );
    let texts = texts(&svg);
    let panels = Panels::of(&texts);
    let to_t = fit(&x_ticks(&texts, &panels, 3));
    // Fault markers of `color` in the status panel, at their times.
    let marks = |color: &str| -> Vec<f64> {
        polylines(&svg, color)
            .iter()
            .filter(|l| l.len() == 2 && (l[1].1 - l[0].1).abs() > 50.0)
            .filter(|l| panels.index(l[0].1) == 3)
            .map(|l| to_t(l[0].0))
            .collect()
    };
    let crc = marks("#D62728");
    // Ten good postbacks before it: 5.0 s.
    assert_eq!(crc.len(), 1, "{crc:?}");
    assert!((crc[0] - 5.0).abs() < 0.1, "{crc:?}");
    // The noise after the 16th good postback (the 17th sent): 7.5 s.
    let lost = marks("#FF7F0E");
    assert_eq!(lost.len(), 1, "{lost:?}");
    assert!((lost[0] - 7.5).abs() < 0.1, "{lost:?}");
}
