//! What the driver tests over the simulated gimbal share (`tests/driver_sim.rs` on the
//! in-memory CAN bus, `tests/serial.rs` on the in-memory serial line).

use idu_gimbal::wire::postback::Postback;
use idu_gimbal::{Event, GimbalControl, Instant};

/// Takes every event the gimbal raised by `now_ms`, with its time, and each postback it
/// delivered fresh (age 0) as the event came.
pub fn take_events<G: GimbalControl>(
    gimbal: &mut G,
    now_ms: u32,
    delivered: &mut Vec<Postback>,
    events: &mut Vec<(u32, Event)>,
) {
    let now = Instant::from_millis(now_ms);
    while let Some(e) = gimbal.next_event() {
        if e == Event::Postback {
            if let Some((p, 0)) = gimbal.latest_postback(now) {
                delivered.push(p);
            }
        }
        events.push((now_ms, e));
    }
}
