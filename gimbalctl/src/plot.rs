//! `gimbalctl plot [--stream] [LOG|-] -o FILE.svg`: one picture of a log.
//!
//! Four panels on one time axis:
//!
//! 1. **pitch**: the reported pitch, and each commanded pitch (`pitch`, `look-down`,
//!    `center`) as a cross at its value;
//! 2. **heading**: the reported heading and motor heading, each commanded heading as a
//!    cross, and the vehicle heading when the log has attitude frames;
//! 3. **rates**: the commanded yaw and pitch rates (a step line, from rate commands) against
//!    the rates the postbacks show (the change of heading and pitch between two postbacks
//!    over the time between them);
//! 4. **status**: the control mode (a step line at full lock, heading follow or lock),
//!    tracking (a band), and the faults on the time axis: link gaps (no postback for more
//!    than 1.5 s; a grey span), CRC errors (red lines) and lost frames (orange lines).
//!
//! The log is decoded by `decode`'s decoders, the trace being one more sink of their
//! records, so the plot shows the postbacks, commands and faults `gimbalctl decode` finds.
//!
//! Time is the log's timestamps, in seconds from the first. A log without timestamps (the
//! `cansend` and screen forms, `--stream` captures) is drawn against estimated time: 0.5 s
//! per postback (the gimbal's period); link gaps cannot be seen in such a log.
//!
//! Memory is bounded whatever the log's length: every series is kept in at most
//! [`BUCKETS`] time buckets holding the first, minimum, maximum and last point of the
//! bucket (with their times); when a series needs more, neighbouring buckets merge in pairs and the bucket
//! width doubles. So a spike survives decimation (it is the max or min of its bucket), and a
//! long log costs the same as a short one. Fault markers are bucketed the same way (one
//! marker per bucket, however many faults fell in it), and at most [`MAX_GAPS`] link gaps
//! are kept (beyond that the closest neighbours merge into one span covering both).
//!
//! Only SVG is written: plotters' PNG path needs its bitmap backend and, for any text, a
//! font from the system (`ttf`, through fontconfig) or one compiled in, which a bare
//! machine does not have.

use std::fmt::Write as _;

use idu_gimbal::wire::control::{Command, GimbalCommand};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::VehicleFrame;
use plotters::prelude::*;

use crate::decode::{self, Record, Sink};
use crate::error::Failure;

/// Time buckets per series (each holds its first, min, max and last point: at most four
/// times as many points).
pub const BUCKETS: usize = 1024;
/// Link gaps kept.
pub const MAX_GAPS: usize = 256;
/// A link gap: no postback for longer than this (three missed 500 ms periods).
pub const GAP_S: f64 = 1.5;
/// Estimated time per postback in a log without timestamps.
const UNTIMED_PERIOD_S: f64 = 0.5;

/// The picture's size in pixels.
const WIDTH: u32 = 1280;
const HEIGHT: u32 = 1000;

// Series colours: the structure test finds series by them.
/// Reported pitch.
pub const C_PITCH: RGBColor = RGBColor(0x1F, 0x77, 0xB4);
/// Reported heading.
pub const C_HEADING: RGBColor = RGBColor(0x2C, 0xA0, 0x2C);
/// Reported motor heading.
pub const C_MOTOR: RGBColor = RGBColor(0x94, 0x67, 0xBD);
/// Vehicle heading (attitude frames).
pub const C_VEHICLE: RGBColor = RGBColor(0x8C, 0x56, 0x4B);
/// Commanded angles (crosses) and commanded rates (step lines).
pub const C_CMD: RGBColor = RGBColor(0x00, 0x00, 0x00);
/// Commanded pitch rate.
pub const C_CMD_PITCH_RATE: RGBColor = RGBColor(0x17, 0xBE, 0xCF);
/// Commanded yaw rate.
pub const C_CMD_YAW_RATE: RGBColor = RGBColor(0xBC, 0xBD, 0x22);
/// Reported pitch rate.
pub const C_PITCH_RATE: RGBColor = RGBColor(0x1F, 0x77, 0xB5);
/// Reported yaw rate.
pub const C_YAW_RATE: RGBColor = RGBColor(0x2C, 0xA0, 0x2D);
/// Control mode.
pub const C_MODE: RGBColor = RGBColor(0x7F, 0x7F, 0x7F);
/// Tracking band.
pub const C_TRACKING: RGBColor = RGBColor(0xFF, 0xBB, 0x78);
/// Link gap spans.
pub const C_GAP: RGBColor = RGBColor(0xC7, 0xC7, 0xC7);
/// CRC error markers.
pub const C_CRC: RGBColor = RGBColor(0xD6, 0x27, 0x28);
/// Lost frame markers.
pub const C_LOST: RGBColor = RGBColor(0xFF, 0x7F, 0x0E);

// ---------------------------------------------------------------------------------------
// Bounded series

#[derive(Clone, Copy, Debug)]
struct Bucket {
    key: i64,
    first: (f64, f64),
    min: (f64, f64),
    max: (f64, f64),
    last: (f64, f64),
}

/// A time series in at most [`BUCKETS`] min/max buckets (see the module docs).
#[derive(Debug)]
pub struct Series {
    width: f64,
    buckets: Vec<Bucket>,
    /// Points taken (before decimation).
    pub count: u64,
}

impl Default for Series {
    fn default() -> Self {
        Series {
            width: 0.05,
            buckets: Vec::new(),
            count: 0,
        }
    }
}

impl Series {
    /// Adds a point; times must not go backwards (a later point at an earlier time goes
    /// into the last bucket).
    pub fn push(&mut self, t: f64, v: f64) {
        if !t.is_finite() || !v.is_finite() {
            return;
        }
        self.count += 1;
        loop {
            let key = (t / self.width).floor() as i64;
            let len = self.buckets.len();
            match self.buckets.last_mut() {
                Some(b) if key <= b.key => {
                    if v < b.min.1 {
                        b.min = (t, v);
                    }
                    if v > b.max.1 {
                        b.max = (t, v);
                    }
                    b.last = (t, v);
                    return;
                }
                _ if len < BUCKETS => {
                    self.buckets.push(Bucket {
                        key,
                        first: (t, v),
                        min: (t, v),
                        max: (t, v),
                        last: (t, v),
                    });
                    return;
                }
                _ => self.halve(),
            }
        }
    }

    /// Doubles the bucket width, merging buckets that fall together.
    fn halve(&mut self) {
        self.width *= 2.0;
        let mut merged: Vec<Bucket> = Vec::with_capacity(BUCKETS);
        for b in self.buckets.drain(..) {
            let key = b.key.div_euclid(2);
            match merged.last_mut() {
                Some(m) if m.key == key => {
                    if b.min.1 < m.min.1 {
                        m.min = b.min;
                    }
                    if b.max.1 > m.max.1 {
                        m.max = b.max;
                    }
                    m.last = b.last;
                }
                _ => merged.push(Bucket { key, ..b }),
            }
        }
        self.buckets = merged;
    }

    /// The points to draw, in time order: each bucket's first point, its min and max, and
    /// its last point (so steps keep their shape and spikes survive).
    pub fn points(&self) -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = Vec::with_capacity(self.buckets.len() * 4);
        for b in &self.buckets {
            let (lo, hi) = if b.min.0 <= b.max.0 {
                (b.min, b.max)
            } else {
                (b.max, b.min)
            };
            for p in [b.first, lo, hi, b.last] {
                if out.last() != Some(&p) {
                    out.push(p);
                }
            }
        }
        out
    }

    /// Each bucket's time, for markers (one per bucket).
    pub fn times(&self) -> Vec<f64> {
        self.buckets.iter().map(|b| b.first.0).collect()
    }

    fn range(&self) -> Option<(f64, f64)> {
        let lo = self.buckets.iter().map(|b| b.min.1).reduce(f64::min)?;
        let hi = self.buckets.iter().map(|b| b.max.1).reduce(f64::max)?;
        Some((lo, hi))
    }

    fn is_empty(&self) -> bool {
        self.buckets.is_empty()
    }
}

// ---------------------------------------------------------------------------------------
// What the log says

/// Everything drawn, gathered in one pass.
#[derive(Default, Debug)]
pub struct Trace {
    pub pitch: Series,
    pub heading: Series,
    pub motor: Series,
    pub vehicle_heading: Series,
    pub cmd_pitch: Series,
    pub cmd_heading: Series,
    pub cmd_yaw_rate: Series,
    pub cmd_pitch_rate: Series,
    pub yaw_rate: Series,
    pub pitch_rate: Series,
    pub mode: Series,
    pub tracking: Series,
    pub crc: Series,
    pub lost: Series,
    /// Link gaps, (start, end) in seconds.
    pub gaps: Vec<(f64, f64)>,
    /// Whether times are the log's (else estimated).
    pub timed: bool,
    /// The last time seen.
    pub end: f64,
    /// The first timestamp, absolute.
    t0: Option<f64>,
    last_postback: Option<(f64, Postback)>,
    /// Postbacks seen (the clock of an untimed log).
    pub postbacks: u64,
    /// Commands seen.
    pub commands: u64,
    /// The rate commanded last (yaw, pitch), to draw steps.
    last_rate: Option<(f64, f64)>,
    /// When the last rate command came (a rate not repeated within 250 ms has stopped).
    last_rate_t: f64,
    /// Lines whose timestamp was not a finite time (kept at the time before them).
    pub bad_timestamps: u64,
}

impl Trace {
    /// The time of a line: its timestamp from the first, else the current time. `frame`:
    /// the line's own frame record (a line's messages read the same time again), which
    /// counts a bad timestamp.
    fn clock(&mut self, ts: Option<&[u8]>, frame: bool) -> f64 {
        let abs = ts
            .and_then(|t| std::str::from_utf8(t).ok())
            .and_then(|t| t.parse::<f64>().ok());
        // Only a finite time from the first: "inf", "nan", 309 digits or a span beyond
        // f64 would put the time axis at infinity, whose tick search never ends. Such a
        // line keeps the time where it was, and is counted.
        let since_first = abs.and_then(|abs| {
            let t = abs - *self.t0.get_or_insert(abs);
            (abs.is_finite() && t.is_finite()).then_some(t)
        });
        if abs.is_some() && since_first.is_none() {
            self.bad_timestamps += u64::from(frame);
            if self.t0.is_some_and(|t0| !t0.is_finite()) {
                self.t0 = None;
            }
        }
        if let Some(t) = since_first {
            self.timed = true;
            // A timestamp going backwards keeps the time where it was.
            self.end = self.end.max(t);
        } else if !self.timed {
            self.end = self.postbacks as f64 * UNTIMED_PERIOD_S;
        }
        self.end
    }

    fn add_gap(&mut self, from: f64, to: f64) {
        if self.gaps.len() == MAX_GAPS {
            // Merge the two neighbours with the smallest space between them.
            let i = (0..self.gaps.len() - 1)
                .min_by(|&a, &b| {
                    let da = self.gaps[a + 1].0 - self.gaps[a].1;
                    let db = self.gaps[b + 1].0 - self.gaps[b].1;
                    da.total_cmp(&db)
                })
                .unwrap_or(0);
            let next = self.gaps.remove(i + 1);
            self.gaps[i].1 = next.1;
        }
        self.gaps.push((from, to));
    }

    fn postback(&mut self, t: f64, pb: &Postback) {
        let pitch = f64::from(pb.pitch) / 100.0;
        let heading = f64::from(pb.heading) / 100.0;
        self.pitch.push(t, pitch);
        self.heading.push(t, heading);
        self.motor.push(t, f64::from(pb.motor_heading) / 100.0);
        self.mode.push(t, f64::from(pb.mode.code()));
        self.tracking.push(t, if pb.tracking { 1.0 } else { 0.0 });
        match self.last_postback {
            Some((t_prev, prev)) => {
                let dt = t - t_prev;
                if self.timed && dt > GAP_S {
                    self.add_gap(t_prev, t);
                }
                if dt > 0.0 {
                    let dp = (pitch - f64::from(prev.pitch) / 100.0) / dt;
                    // The heading change the short way round.
                    let dh = (heading - f64::from(prev.heading) / 100.0 + 540.0).rem_euclid(360.0)
                        - 180.0;
                    self.pitch_rate.push(t, dp);
                    self.yaw_rate.push(t, dh / dt);
                }
            }
            None => {
                if self.timed && t > GAP_S {
                    self.add_gap(0.0, t);
                }
            }
        }
        self.last_postback = Some((t, *pb));
        self.postbacks += 1;
    }

    fn command(&mut self, t: f64, cmd: &Command) {
        self.commands += 1;
        self.rate_expiry(t);
        let Command::Gimbal(g) = cmd else {
            return;
        };
        match g {
            GimbalCommand::Pitch(p) => self.cmd_pitch.push(t, f64::from(p.degrees())),
            GimbalCommand::Heading(h) => self.cmd_heading.push(t, f64::from(h.degrees())),
            GimbalCommand::LookDown => self.cmd_pitch.push(t, -90.0),
            GimbalCommand::Recenter => self.cmd_pitch.push(t, 0.0),
            GimbalCommand::Rate(r) => {
                let (y, p) = (f64::from(r.yaw_dps()), f64::from(r.pitch_dps()));
                self.set_rate(t, y, p);
                self.last_rate_t = t;
            }
            _ => {}
        }
    }

    /// Draws a step of the commanded rate at `t`.
    fn set_rate(&mut self, t: f64, yaw: f64, pitch: f64) {
        if self.last_rate != Some((yaw, pitch)) {
            if let Some((py, pp)) = self.last_rate {
                self.cmd_yaw_rate.push(t, py);
                self.cmd_pitch_rate.push(t, pp);
            }
            self.cmd_yaw_rate.push(t, yaw);
            self.cmd_pitch_rate.push(t, pitch);
            self.last_rate = Some((yaw, pitch));
        }
    }

    /// A rate not repeated within the gimbal's 250 ms dead-man is back to zero.
    fn rate_expiry(&mut self, now: f64) {
        if let Some((y, p)) = self.last_rate {
            if (y, p) != (0.0, 0.0) && now - self.last_rate_t > 0.25 {
                self.set_rate(self.last_rate_t + 0.25, 0.0, 0.0);
            }
        }
    }

    fn finish(&mut self) {
        if !self.timed {
            // One period after the last postback.
            self.end = self.postbacks as f64 * UNTIMED_PERIOD_S;
        }
        let end = self.end;
        self.rate_expiry(end);
        if let Some((y, p)) = self.last_rate {
            self.cmd_yaw_rate.push(end, y);
            self.cmd_pitch_rate.push(end, p);
        }
        if self.timed {
            if let Some((t, _)) = self.last_postback {
                if end - t > GAP_S {
                    self.add_gap(t, end);
                }
            }
        }
    }
}

/// The plot's side of the decoding: each record drawn at its time.
impl Sink for Trace {
    fn record(&mut self, record: Record<'_>) -> Result<(), Failure> {
        match record {
            // Every frame moves the clock, whether or not it completes a message.
            Record::Frame(at) => {
                self.clock(at.ts, true);
            }
            Record::Postback(at, pb) => {
                let t = self.clock(at.ts, false);
                self.postback(t, &pb);
            }
            Record::Command(at, cmd) => {
                let t = self.clock(at.ts, false);
                self.command(t, &cmd);
            }
            Record::Vehicle(at, VehicleFrame::Attitude(a)) => {
                let t = self.clock(at.ts, false);
                self.vehicle_heading
                    .push(t, f64::from(a.heading_deg()).rem_euclid(360.0));
            }
            Record::Vehicle(..) | Record::Text(..) => {}
            Record::CrcError(at) => {
                let t = self.clock(at.ts, false);
                self.crc.push(t, 1.0);
            }
            Record::Lost(at) => {
                let t = self.clock(at.ts, false);
                self.lost.push(t, 1.0);
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// Drawing

/// A y range around the series' values, with a margin, and `fallback` when all are empty.
fn y_range(series: &[&Series], fallback: (f64, f64)) -> std::ops::Range<f64> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in series {
        if let Some((a, b)) = s.range() {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    if !lo.is_finite() {
        (lo, hi) = fallback;
    }
    let pad = ((hi - lo) * 0.08).max(1.0);
    (lo - pad)..(hi + pad)
}

fn draw_err(e: impl std::fmt::Display) -> Failure {
    Failure::Runtime(format!("cannot draw the plot: {e}"))
}

type Chart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

fn line<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    s: &Series,
    color: RGBColor,
    label: &str,
) -> Result<(), Failure> {
    if s.is_empty() {
        return Ok(());
    }
    chart
        .draw_series(LineSeries::new(s.points(), color.stroke_width(2)))
        .map_err(draw_err)?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    Ok(())
}

fn crosses<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    s: &Series,
    color: RGBColor,
    label: &str,
) -> Result<(), Failure> {
    if s.is_empty() {
        return Ok(());
    }
    chart
        .draw_series(
            s.points()
                .into_iter()
                .map(|p| Cross::new(p, 5, color.stroke_width(2))),
        )
        .map_err(draw_err)?
        .label(label)
        .legend(move |(x, y)| Cross::new((x + 10, y), 5, color.stroke_width(2)));
    Ok(())
}

fn legend<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>) -> Result<(), Failure> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(draw_err)
}

fn build<'a, 'b: 'a>(
    area: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    caption: &str,
) -> Result<Chart<'a, 'b>, Failure> {
    ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 15))
        .margin(6)
        .margin_right(16)
        .x_label_area_size(32)
        .y_label_area_size(100)
        .build_cartesian_2d(x, y)
        .map_err(draw_err)
}

/// Draws the picture as SVG text.
pub fn render(trace: &Trace, title: &str) -> Result<String, Failure> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let root = root.titled(title, ("sans-serif", 20)).map_err(draw_err)?;
        let h = root.dim_in_pixel().1 as i32;
        let (a, rest) = root.split_vertically(h * 28 / 100);
        let (b, rest) = rest.split_vertically(h * 28 / 100);
        let (c, d) = rest.split_vertically(h * 22 / 100);
        let x_end = if trace.end > 0.0 { trace.end } else { 1.0 };
        let x = 0.0..x_end;
        let x_desc = if trace.timed {
            "time (s from the first timestamp)"
        } else {
            "time (s, estimated: no timestamps in the log, 0.5 s per postback)"
        };
        // 1. Pitch.
        let mut chart = build(
            &a,
            x.clone(),
            y_range(&[&trace.pitch, &trace.cmd_pitch], (-90.0, 30.0)),
            "pitch (deg)",
        )?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc("deg")
            .draw()
            .map_err(draw_err)?;
        line(&mut chart, &trace.pitch, C_PITCH, "pitch (reported)")?;
        crosses(&mut chart, &trace.cmd_pitch, C_CMD, "pitch (commanded)")?;
        legend(&mut chart)?;

        // 2. Heading.
        let mut chart = build(
            &b,
            x.clone(),
            y_range(
                &[
                    &trace.heading,
                    &trace.motor,
                    &trace.cmd_heading,
                    &trace.vehicle_heading,
                ],
                (0.0, 360.0),
            ),
            "heading (deg)",
        )?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc("deg")
            .draw()
            .map_err(draw_err)?;
        line(&mut chart, &trace.heading, C_HEADING, "heading (reported)")?;
        line(
            &mut chart,
            &trace.motor,
            C_MOTOR,
            "motor heading (reported)",
        )?;
        line(
            &mut chart,
            &trace.vehicle_heading,
            C_VEHICLE,
            "vehicle heading (attitude)",
        )?;
        crosses(&mut chart, &trace.cmd_heading, C_CMD, "heading (commanded)")?;
        legend(&mut chart)?;

        // 3. Rates.
        let mut chart = build(
            &c,
            x.clone(),
            y_range(
                &[
                    &trace.cmd_yaw_rate,
                    &trace.cmd_pitch_rate,
                    &trace.yaw_rate,
                    &trace.pitch_rate,
                ],
                (-10.0, 10.0),
            ),
            "rates (deg/s)",
        )?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc("deg/s")
            .draw()
            .map_err(draw_err)?;
        line(
            &mut chart,
            &trace.yaw_rate,
            C_YAW_RATE,
            "yaw rate (from postbacks)",
        )?;
        line(
            &mut chart,
            &trace.pitch_rate,
            C_PITCH_RATE,
            "pitch rate (from postbacks)",
        )?;
        line(
            &mut chart,
            &trace.cmd_yaw_rate,
            C_CMD_YAW_RATE,
            "yaw rate (commanded)",
        )?;
        line(
            &mut chart,
            &trace.cmd_pitch_rate,
            C_CMD_PITCH_RATE,
            "pitch rate (commanded)",
        )?;
        legend(&mut chart)?;

        // 4. Status: mode, tracking, faults.
        let mut chart = build(&d, x.clone(), -0.5..3.5, "mode, tracking, faults")?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_labels(4)
            .y_label_formatter(&|v| match v.round() as i64 {
                0 => "tracking".into(),
                1 => "full_lock".into(),
                2 => "heading_follow".into(),
                3 => "lock".into(),
                _ => String::new(),
            })
            .disable_y_mesh()
            .draw()
            .map_err(draw_err)?;
        chart
            .draw_series(trace.gaps.iter().map(|&(from, to)| {
                Rectangle::new([(from, -0.5), (to, 3.5)], C_GAP.mix(0.6).filled())
            }))
            .map_err(draw_err)?
            .label(format!("link gap > {GAP_S} s"))
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], C_GAP.filled()));
        // Tracking: a band over the spans where it is on.
        let spans = tracking_spans(&trace.tracking, trace.end);
        chart
            .draw_series(
                spans.iter().map(|&(from, to)| {
                    Rectangle::new([(from, -0.3), (to, 0.3)], C_TRACKING.filled())
                }),
            )
            .map_err(draw_err)?
            .label("tracking")
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], C_TRACKING.filled()));
        // Mode: a step line.
        let mode = trace.mode.points();
        let mut steps = Vec::with_capacity(mode.len() * 2);
        for (i, &(t, v)) in mode.iter().enumerate() {
            if i > 0 {
                steps.push((t, mode[i - 1].1));
            }
            steps.push((t, v));
        }
        if let Some(&(_, v)) = mode.last() {
            steps.push((trace.end, v));
        }
        if !steps.is_empty() {
            chart
                .draw_series(LineSeries::new(steps, C_MODE.stroke_width(3)))
                .map_err(draw_err)?
                .label("control mode")
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], C_MODE.stroke_width(3))
                });
        }
        for (s, color, label) in [
            (&trace.crc, C_CRC, "CRC error"),
            (&trace.lost, C_LOST, "lost frames"),
        ] {
            if s.is_empty() {
                continue;
            }
            chart
                .draw_series(
                    s.times().into_iter().map(|t| {
                        PathElement::new(vec![(t, -0.5), (t, 3.5)], color.stroke_width(2))
                    }),
                )
                .map_err(draw_err)?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(
                        vec![(x + 10, y - 6), (x + 10, y + 6)],
                        color.stroke_width(2),
                    )
                });
        }
        legend(&mut chart)?;
        root.present().map_err(draw_err)?;
    }
    Ok(svg)
}

/// The spans where tracking was on, from the tracking series (1 on, 0 off; decimated, a
/// span may start or end up to one bucket early or late).
fn tracking_spans(s: &Series, end: f64) -> Vec<(f64, f64)> {
    let mut spans = Vec::new();
    let mut start = None;
    for (t, v) in s.points() {
        match (start, v > 0.5) {
            (None, true) => start = Some(t),
            (Some(from), false) => {
                spans.push((from, t));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(from) = start {
        spans.push((from, end));
    }
    spans
}

/// What `-o` names, checked before any input is read.
fn check_output(path: &str) -> Result<(), Failure> {
    let ext = std::path::Path::new(path)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("svg") => Ok(()),
        Some("png") => Err(Failure::Usage(format!(
            "-o {path}: PNG is not supported (it needs system fonts to draw text); valid extensions: .svg"
        ))),
        _ => Err(Failure::Usage(format!(
            "-o {path}: unknown picture format; valid extensions: .svg"
        ))),
    }
}

/// `gimbalctl plot [--stream] [LOG|-] -o FILE.svg`.
pub fn run(file: Option<&str>, stream: bool, output: &str) -> Result<(), Failure> {
    check_output(output)?;
    let input = decode::open(file)?;
    let mut trace = Trace::default();
    decode::decode_into(input, stream, &mut trace)?;
    trace.finish();
    if trace.postbacks == 0 && trace.commands == 0 && trace.vehicle_heading.count == 0 {
        return Err(Failure::Runtime(format!(
            "{}: no postback, command or attitude frame: nothing to plot",
            file.unwrap_or("stdin")
        )));
    }
    let name = match file {
        None | Some("-") => "stdin",
        Some(path) => path,
    };
    let svg = render(&trace, &format!("gimbalctl plot: {name}"))?;
    std::fs::write(output, svg.as_bytes())
        .map_err(|e| Failure::Runtime(format!("cannot write {output}: {e}")))?;
    let mut summary = String::new();
    let _ = writeln!(
        summary,
        "{output}: {:.1} s{}, {} postbacks, {} commands, {} attitude frames, {} link gaps, {} CRC errors, {} lost frames",
        trace.end,
        if trace.timed { "" } else { " (estimated)" },
        trace.postbacks,
        trace.commands,
        trace.vehicle_heading.count,
        trace.gaps.len(),
        trace.crc.count,
        trace.lost.count,
    );
    if trace.bad_timestamps > 0 {
        let _ = writeln!(
            summary,
            "{output}: {} lines with a timestamp that is not a finite time, drawn at the time before them",
            trace.bad_timestamps
        );
    }
    crate::print(&summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_is_bounded_and_keeps_extremes() {
        let mut s = Series::default();
        for i in 0..1_000_000u32 {
            let t = f64::from(i) * 0.01;
            let v = if i == 777_777 { 500.0 } else { (t * 0.1).sin() };
            s.push(t, v);
        }
        assert!(s.buckets.len() <= BUCKETS);
        assert!(s.buckets.len() > BUCKETS / 2);
        let pts = s.points();
        assert!(pts.len() <= 4 * BUCKETS);
        assert!(pts.windows(2).all(|w| w[0].0 <= w[1].0));
        assert!(pts
            .iter()
            .any(|&(t, v)| v == 500.0 && (t - 7777.77).abs() < 1e-6));
        assert_eq!(s.count, 1_000_000);
    }

    #[test]
    fn gaps_are_bounded() {
        let mut t = Trace::default();
        for i in 0..10_000 {
            t.add_gap(f64::from(i) * 10.0, f64::from(i) * 10.0 + 2.0);
        }
        assert_eq!(t.gaps.len(), MAX_GAPS);
        assert_eq!(t.gaps[0].0, 0.0);
        assert_eq!(t.gaps.last().map(|g| g.1), Some(99_992.0));
        assert!(t.gaps.windows(2).all(|w| w[0].1 <= w[1].0));
    }

    #[test]
    fn png_and_other_extensions_are_refused() {
        assert!(check_output("a.svg").is_ok());
        assert!(check_output("A.SVG").is_ok());
        assert!(matches!(check_output("a.png"), Err(Failure::Usage(_))));
        assert!(matches!(check_output("a.pdf"), Err(Failure::Usage(_))));
        assert!(matches!(check_output("a"), Err(Failure::Usage(_))));
    }
}
