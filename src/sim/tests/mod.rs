//! The simulator's own tests, by concern, and the helpers they share.

use super::*;
use crate::wire::control::{Focus, Heading, ImageOffset, ImagePoint, Pitch, ZoomRatio};

mod commands;
mod invariants;
mod motion;
mod postbacks;
mod tracking;

fn t(ms: u32) -> Instant {
    Instant::from_millis(ms)
}

fn send<const TX: usize>(sim: &mut Simulator<TX>, c: impl Into<Command>, at: Instant) {
    let f = c.into().to_frame();
    sim.receive(f.id, &f.data, at).unwrap();
}

/// Points the gimbal: a pitch, then a heading, both commanded at `at`.
fn point<const TX: usize>(sim: &mut Simulator<TX>, pitch: f32, heading: f32, at: Instant) {
    send(sim, GimbalCommand::Pitch(Pitch::new(pitch).unwrap()), at);
    send(
        sim,
        GimbalCommand::Heading(Heading::new(heading).unwrap()),
        at,
    );
}

fn attitude<const TX: usize>(sim: &mut Simulator<TX>, heading: f32, at: Instant) {
    let f = VehicleFrame::from(Attitude::new(0.0, 0.0, heading).unwrap()).to_frame();
    sim.receive(f.id, &f.data, at).unwrap();
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-3
}

/// Pops the four frames of one postback and parses them.
fn pop_postback<const TX: usize>(sim: &mut Simulator<TX>) -> Postback {
    let mut bytes = [0u8; 32];
    for chunk in bytes.chunks_exact_mut(8) {
        let f = sim.pop_frame().unwrap();
        assert_eq!(f.id, ids::POSTBACK);
        chunk.copy_from_slice(&f.data);
    }
    Postback::parse(&bytes).unwrap()
}
