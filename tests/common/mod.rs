//! What the port tests over the simulated gimbal share (`tests/driver_sim.rs` on the
//! in-memory CAN bus, `tests/serial.rs` on the in-memory serial line): the application's
//! side, a link and its port, polled on the test's clock.

use idu_gimbal::wire::control::GimbalCommand;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::{Event, Instant, Link, Port};

/// The application: a link, the port that carries it, the test's clock (ms) and what the
/// link raised. Each test's bench holds one beside the simulated gimbal.
pub struct Host<P: Port, const Q: usize, const T: usize> {
    pub link: Link<Q, T, P::Medium>,
    pub port: P,
    pub now: u32,
    /// Each postback the link delivered fresh (age 0) as its event came.
    pub delivered: Vec<Postback>,
    /// Every event the link raised, with its time.
    pub events: Vec<(u32, Event)>,
}

impl<P: Port, const Q: usize, const T: usize> Host<P, Q, T> {
    pub fn new(link: Link<Q, T, P::Medium>, port: P, start: u32) -> Self {
        Host {
            link,
            port,
            now: start,
            delivered: Vec::new(),
            events: Vec::new(),
        }
    }

    pub fn instant(&self) -> Instant {
        Instant::from_millis(self.now)
    }

    /// One poll of the port at the current time (its error ignored: the port counts it),
    /// then every event the link raised.
    pub fn poll(&mut self) {
        let now = self.instant();
        let _ = self.port.poll(&mut self.link, now);
        while let Some(e) = self.link.next_event() {
            if e == Event::Postback {
                if let Some((p, 0)) = self.link.latest_postback(now) {
                    self.delivered.push(p);
                }
            }
            self.events.push((self.now, e));
        }
    }

    /// Queues `command`; the test fails if the queue has no room.
    pub fn send(&mut self, command: GimbalCommand) {
        self.link.send(command).expect("room in the command queue");
    }

    /// The latest postback; the test fails if there is none.
    pub fn latest(&self) -> Postback {
        self.link
            .latest_postback(self.instant())
            .expect("a postback")
            .0
    }
}
