//! What the log says: the series, faults and link gaps gathered from `decode`'s records
//! in one pass (the trace is one more [`Sink`]).

use idu_gimbal::wire::control::{Command, GimbalCommand};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::VehicleFrame;

use super::{Series, GAP_S, MAX_GAPS, UNTIMED_PERIOD_S};
use crate::decode::{Record, Sink};
use crate::error::Failure;

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

    pub(super) fn finish(&mut self) {
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

#[cfg(test)]
mod tests {
    use super::*;

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

    /// Past `MAX_GAPS`, the two gaps with the least time between them become one: 2 s
    /// gaps every 10 s (8 s apart), but the twelfth closer to the eleventh.
    #[test]
    fn the_closest_gaps_merge() {
        // The time between gap 10 and 11, and any other gap moved closer to its forerunner.
        for (space, other) in [(0.5, Some((21, 0.75))), (1.5, None)] {
            let mut t = Trace::default();
            for i in 0..MAX_GAPS {
                let from = match (i, other) {
                    (11, _) => 102.0 + space,
                    (k, Some((j, s))) if k == j => k as f64 * 10.0 - 8.0 + s,
                    _ => i as f64 * 10.0,
                };
                t.add_gap(from, from + 2.0);
            }
            t.add_gap(5000.0, 5002.0);
            assert_eq!(t.gaps.len(), MAX_GAPS);
            assert_eq!(
                t.gaps[9..12],
                [(90.0, 92.0), (100.0, 104.0 + space), (120.0, 122.0)],
                "{space}"
            );
            assert_eq!(t.gaps.last(), Some(&(5000.0, 5002.0)));
        }
    }

    fn postback_at(t: &mut Trace, at: f64) {
        t.timed = true;
        t.postback(at, &Postback::default());
    }

    /// A link gap is a postback more than 1.5 s after the one before, or the first more
    /// than 1.5 s after the log began; exactly 1.5 s is none.
    #[test]
    fn a_gap_is_more_than_one_and_a_half_seconds() {
        let mut t = Trace::default();
        for at in [1.5, 3.0, 4.5] {
            postback_at(&mut t, at);
        }
        assert!(t.gaps.is_empty());
        postback_at(&mut t, 6.0625);
        assert_eq!(t.gaps, [(4.5, 6.0625)]);
        let mut t = Trace::default();
        postback_at(&mut t, 1.5625);
        assert_eq!(t.gaps, [(0.0, 1.5625)]);
        // The log going on without postbacks: a gap to its end, if more than 1.5 s.
        for (end, gaps) in [(3.0625, &[][..]), (3.125, &[(1.5625, 3.125)][..])] {
            let mut t = Trace::default();
            postback_at(&mut t, 1.0);
            postback_at(&mut t, 1.5625);
            t.end = end;
            t.finish();
            assert_eq!(t.gaps, gaps, "{end}");
        }
    }

    /// The commanded angles as crosses at their values (look-down at -90, centre at 0);
    /// the commanded rate as steps, back to zero 250 ms after a rate not repeated.
    #[test]
    fn commands_are_drawn_at_their_values() {
        use idu_gimbal::wire::control::{Heading, Photo, Pitch, Rate};
        let mut t = Trace::default();
        let g = |g: GimbalCommand| Command::from(g);
        for (at, cmd) in [
            (1.0, g(GimbalCommand::Pitch(Pitch::new(-30.0).unwrap()))),
            (2.0, g(GimbalCommand::LookDown)),
            (3.0, g(GimbalCommand::Recenter)),
            (4.0, g(GimbalCommand::Heading(Heading::new(90.0).unwrap()))),
            // A rate repeated 125 ms and then exactly 250 ms later (both within the
            // dead-man; times exact in binary), then not.
            (5.0, g(GimbalCommand::Rate(Rate::new(5.0, -2.0).unwrap()))),
            (5.125, g(GimbalCommand::Rate(Rate::new(5.0, -2.0).unwrap()))),
            (5.375, g(GimbalCommand::Rate(Rate::new(5.0, -2.0).unwrap()))),
            (7.0, g(GimbalCommand::Photo(Photo::Single))),
        ] {
            t.command(at, &cmd);
        }
        assert_eq!(t.commands, 8);
        assert_eq!(
            t.cmd_pitch.points(),
            [(1.0, -30.0), (2.0, -90.0), (3.0, 0.0)]
        );
        assert_eq!(t.cmd_heading.points(), [(4.0, 90.0)]);
        // 250 ms after the last.
        let stop = 5.625;
        assert_eq!(
            t.cmd_yaw_rate.points(),
            [(5.0, 5.0), (stop, 5.0), (stop, 0.0)]
        );
        assert_eq!(
            t.cmd_pitch_rate.points(),
            [(5.0, -2.0), (stop, -2.0), (stop, 0.0)]
        );
    }
}
