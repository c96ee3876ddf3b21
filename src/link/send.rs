//! Commands and text into the transmit queue.

use super::*;
use crate::wire::control::DualLightCommand;

impl<const Q: usize, const T: usize, M: Medium> Link<Q, T, M> {
    /// How many commands [`Link::send`] takes now: the free control-frame slots, out of
    /// `Q`. A caller with several commands that only make sense together (a zoom of several
    /// steps) checks it first and sends all or none.
    #[inline]
    pub fn command_room(&self) -> usize {
        self.tx.control_free()
    }

    /// Queues a command. A pointing command (see [`Command::is_pointing`]) ends a rate hold
    /// (without a zero-rate command: it is the gimbal's new instruction), an aim or a
    /// point-at, except start tracking, to which an aim or a point-at yields until the
    /// tracker lets go (see [`AimState::yielded_to_tracker`]); stop tracking gives the
    /// gimbal back to it. A full queue hands the command back and ends nothing.
    pub fn send(&mut self, command: impl Into<Command>) -> Result<(), QueueFull<Command>> {
        let command = command.into();
        if self
            .tx
            .push_control(command.encode(), &mut self.quiet)
            .is_err()
        {
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
            return Err(QueueFull(command));
        }
        if let Steering::Aim(_) | Steering::Point(_) = self.steering {
            self.aim_commanded(command);
        } else if command.is_pointing() {
            self.steering = Steering::Manual;
            // A zero-rate frame still waiting would arrive after this command and undo it.
            self.tx.cancel_zero_rate();
        }
        Ok(())
    }

    /// A command went out while an aim or a point-at is held: start tracking makes it yield
    /// to the tracker rather than end (the setpoint stream that keeps giving the same aim
    /// must not take the gimbal back from it), stop tracking gives the gimbal back to it,
    /// any other pointing command ends it. Out of line: the common path, nothing held,
    /// pays one test of the steering for it.
    #[inline(never)]
    fn aim_commanded(&mut self, command: Command) {
        let hold = match &mut self.steering {
            Steering::Aim(h) => h,
            Steering::Point(p) => &mut p.hold,
            Steering::Manual | Steering::Rate(_) => return,
        };
        match command {
            Command::Gimbal(GimbalCommand::StartTracking(_))
            | Command::DualLight(DualLightCommand::StartTracking(_)) => hold.suspend(),
            Command::Gimbal(GimbalCommand::StopTracking)
            | Command::DualLight(DualLightCommand::StopTracking) => {
                hold.resume();
                return;
            }
            c if c.is_pointing() => self.steering = Steering::Manual,
            _ => return,
        }
        // A zero-rate frame still waiting would arrive after this command and undo it.
        self.tx.cancel_zero_rate();
    }
}

impl<const Q: usize, const T: usize> Link<Q, T, Can> {
    /// Queues a text message, all of it or nothing.
    ///
    /// Only CAN carries text: a [`SerialLink`] has no such method, and a CAN link built
    /// without text slots (`T` = 0) has nothing to queue it in: calling this on either does
    /// not build.
    ///
    /// ```compile_fail
    /// use idu_gimbal::link::{Config, Link};
    /// let mut no_text: Link<8, 0> = Link::new(Config::default());
    /// let _ = no_text.send_text(b"hello");
    /// ```
    ///
    /// ```compile_fail
    /// use idu_gimbal::link::{Config, SerialLink};
    /// let mut serial: SerialLink = SerialLink::new(Config::default());
    /// let _ = serial.send_text(b"hello");
    /// ```
    pub fn send_text(&mut self, text: &[u8]) -> Result<(), TextQueueError> {
        const {
            assert!(
                T > 0,
                "this link has no text slots (T = 0): its transport carries no text"
            )
        };
        let frames = wire_text::chunks(text).map_err(TextQueueError::Invalid)?;
        let free = self.tx.text_free();
        let slots = frames.map(|f| queue::TextSlot {
            data: f.data,
            last: f.id == ids::TEXT_END,
        });
        self.tx
            .push_text(slots, &mut self.quiet)
            .map_err(|needed| {
                self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
                TextQueueError::NoRoom { needed, free }
            })?;
        Ok(())
    }
}
