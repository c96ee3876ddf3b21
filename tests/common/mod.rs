//! What the port tests over the simulated gimbal share (`tests/driver_sim.rs` on the
//! in-memory CAN bus, `tests/serial.rs` on the in-memory serial line).

use idu_gimbal::link::Medium;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::{Event, Instant, Link};

/// Takes every event the link raised by `now_ms`, with its time, and each postback it
/// delivered fresh (age 0) as the event came.
pub fn take_events<const Q: usize, const T: usize, M: Medium>(
    gimbal: &mut Link<Q, T, M>,
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
