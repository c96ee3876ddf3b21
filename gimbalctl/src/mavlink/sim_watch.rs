//! What the simulated gimbal's camera does, said on stderr as it changes: tracking (the
//! box it started on, a lost target), focus, the thermal palette and zoom, calibration.
//! The gimbal reports none of these in its postback, so this is how a user (or a test
//! driving `gimbalctl mavlink --sim` as a ground station would) sees a command's effect
//! rather than only its ACK.

use idu_gimbal::sim::SimState;
use idu_gimbal::wire::control::{ElectronicZoom, Focus, Palette, TrackingBox};

/// The part of the state that is said.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
struct Seen {
    tracking: Option<TrackingBox>,
    targets_lost: u32,
    focusing: Option<Focus>,
    auto_focus: bool,
    palette: Option<Palette>,
    electronic_zooming: Option<ElectronicZoom>,
    calibrations: u32,
    calibrating: bool,
}

impl Seen {
    fn of(s: &SimState) -> Self {
        Seen {
            // The box as started: its centre moves as the gimbal turns toward it.
            tracking: s.tracking_box.filter(|_| s.tracking),
            targets_lost: s.targets_lost,
            focusing: s.focusing,
            auto_focus: s.auto_focus,
            palette: s.palette,
            electronic_zooming: s.electronic_zooming,
            calibrations: s.calibrations,
            calibrating: s.calibrating,
        }
    }
}

/// Compares the simulated gimbal's state with what was last said.
#[derive(Debug, Default)]
pub struct SimWatch {
    seen: Seen,
}

impl SimWatch {
    /// Lines (without the `gimbalctl mavlink: ` prefix) for what changed since the last
    /// call.
    pub fn changes(&mut self, state: &SimState) -> Vec<String> {
        let now = Seen::of(state);
        let was = std::mem::replace(&mut self.seen, now);
        let mut out = Vec::new();
        let said = |s: String| format!("simulated gimbal: {s}");
        match (was.tracking, now.tracking) {
            (None, Some(b)) => out.push(said(format!(
                "tracking a {}x{} box at ({}, {})",
                b.width(),
                b.height(),
                b.centre().x(),
                b.centre().y()
            ))),
            (Some(_), None) if now.targets_lost != was.targets_lost => {
                out.push(said("target lost".into()))
            }
            (Some(_), None) => out.push(said("tracking stopped".into())),
            _ => {}
        }
        if (now.focusing, now.auto_focus) != (was.focusing, was.auto_focus) {
            let focus = match (now.focusing, now.auto_focus) {
                (Some(Focus::Plus), _) => "focusing +",
                (Some(Focus::Minus), _) => "focusing -",
                (_, true) => "auto-focus",
                _ => "focus held",
            };
            out.push(said(focus.into()));
        }
        if now.palette != was.palette {
            if let Some(p) = now.palette {
                out.push(said(format!("palette {p}")));
            }
        }
        if now.electronic_zooming != was.electronic_zooming {
            let z = match now.electronic_zooming {
                Some(ElectronicZoom::In) => "thermal zooming in",
                Some(ElectronicZoom::Out) => "thermal zooming out",
                _ => "thermal zoom held",
            };
            out.push(said(z.into()));
        }
        if now.calibrations != was.calibrations && now.calibrating {
            out.push(said("calibrating".into()));
        } else if was.calibrating && !now.calibrating {
            out.push(said("calibration done".into()));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use idu_gimbal::sim::{SimConfig, Simulator};
    use idu_gimbal::wire::control::{Command, DualLightCommand, GimbalCommand, ImagePoint};
    use idu_gimbal::wire::ids;
    use idu_gimbal::Instant;

    fn send(sim: &mut Simulator, c: impl Into<Command>, ms: u32) {
        let data = c.into().encode();
        sim.receive(ids::CONTROL, &data, Instant::from_millis(ms))
            .unwrap();
    }

    #[test]
    fn each_change_is_said_once() {
        let mut sim: Simulator = Simulator::new(SimConfig::default(), Instant::from_millis(0));
        let mut w = SimWatch::default();
        assert!(w.changes(sim.state()).is_empty());
        let b = TrackingBox::from_raw(ImagePoint::new(4096, 4096).unwrap(), 16, 16);
        send(&mut sim, GimbalCommand::StartTracking(b), 1);
        assert_eq!(
            w.changes(sim.state()),
            ["simulated gimbal: tracking a 256x256 box at (4096, 4096)"]
        );
        assert!(w.changes(sim.state()).is_empty());
        send(&mut sim, DualLightCommand::Palette(Palette::IceBlue), 2);
        send(&mut sim, GimbalCommand::Focus(Focus::Plus), 3);
        assert_eq!(
            w.changes(sim.state()),
            [
                "simulated gimbal: focusing +",
                "simulated gimbal: palette ice-blue"
            ]
        );
        send(&mut sim, GimbalCommand::StopTracking, 4);
        assert_eq!(
            w.changes(sim.state()),
            ["simulated gimbal: tracking stopped"]
        );
    }

    /// Every other line, each once: a lost target, the focus's four states, the thermal
    /// zoom's three, a calibration started, restarted and done; nothing while nothing
    /// changes.
    #[test]
    fn the_other_changes_are_said_once_each() {
        let config = SimConfig {
            tracking_lost_ms: 1000,
            ..SimConfig::default()
        };
        let mut sim: Simulator = Simulator::new(config, Instant::from_millis(0));
        let mut w = SimWatch::default();
        let b = TrackingBox::from_raw(ImagePoint::new(4096, 4096).unwrap(), 16, 16);
        send(&mut sim, GimbalCommand::StartTracking(b), 1);
        assert_eq!(w.changes(sim.state()).len(), 1);
        sim.poll(Instant::from_millis(1002));
        assert_eq!(w.changes(sim.state()), ["simulated gimbal: target lost"]);

        let mut after = |sim: &mut Simulator, c: Command, ms: u32| {
            send(sim, c, ms);
            w.changes(sim.state())
        };
        let focus = |f| Command::from(GimbalCommand::Focus(f));
        let zoom = |z| Command::from(DualLightCommand::ElectronicZoom(z));
        let steps = [
            (focus(Focus::Minus), "focusing -"),
            (focus(Focus::Auto), "auto-focus"),
            (focus(Focus::Plus), "focusing +"),
            (focus(Focus::Stop), "focus held"),
            (zoom(ElectronicZoom::In), "thermal zooming in"),
            (zoom(ElectronicZoom::Out), "thermal zooming out"),
            (zoom(ElectronicZoom::Stop), "thermal zoom held"),
            (GimbalCommand::FastCalibration.into(), "calibrating"),
        ];
        let mut ms = 1100;
        for (command, line) in steps {
            ms += 10;
            assert_eq!(
                after(&mut sim, command, ms),
                [format!("simulated gimbal: {line}")]
            );
        }
        // Still calibrating: nothing new; a second calibration restarts it, and is said.
        sim.poll(Instant::from_millis(ms + 1000));
        assert!(w.changes(sim.state()).is_empty());
        send(&mut sim, GimbalCommand::FastCalibration, ms + 1000);
        assert_eq!(w.changes(sim.state()), ["simulated gimbal: calibrating"]);
        // Done CALIBRATION_MS after the last command, said once.
        let done = ms + 1000 + idu_gimbal::sim::CALIBRATION_MS;
        sim.poll(Instant::from_millis(done - 10));
        assert!(w.changes(sim.state()).is_empty());
        sim.poll(Instant::from_millis(done + 10));
        assert_eq!(
            w.changes(sim.state()),
            ["simulated gimbal: calibration done"]
        );
        assert!(w.changes(sim.state()).is_empty());
    }
}
