//! Commands as they arrive, `COMMAND_LONG` and `COMMAND_INT` alike: one type for both, so
//! every command is handled and acknowledged the same way whichever message carried it.
//!
//! common.xml: "COMMAND_INT ... is the same as COMMAND_LONG, except that x and y are
//! integers (latitude and longitude in 1e7 degrees for global frames) and the frame is
//! given". Newer ArduPilot sends location commands (ROI) as `COMMAND_INT`.

use crate::bridge::Period;
use mavio::dialects::common::enums::{MavCmd, MavFrame};
use mavio::dialects::common::messages::{CommandInt, CommandLong};

/// A command from either message.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Command {
    /// What to do.
    pub command: MavCmd,
    /// Addressed to (system, component); 0 is broadcast.
    pub target: (u8, u8),
    /// param1 to param4.
    pub params: [f32; 4],
    /// x and y: `COMMAND_INT`'s integers or `COMMAND_LONG`'s param5 and param6.
    pub xy: Xy,
    /// param7 / z: the altitude, metres, in [`Command::frame`].
    pub z: f32,
    /// The altitude's frame: `COMMAND_INT`'s, and `GLOBAL_RELATIVE_ALT` for a
    /// `COMMAND_LONG` (which has none: ArduPilot and PX4 both read its altitudes as
    /// relative to home).
    pub frame: MavFrame,
}

/// A command's x and y as its message carries them; read as a location only by the
/// commands that take one, so that the others never pay for the conversion.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Xy {
    /// `COMMAND_LONG`'s param5 and param6 (a latitude and longitude in degrees).
    Float(f32, f32),
    /// `COMMAND_INT`'s x and y (a latitude and longitude in 1e-7°).
    Int(i32, i32),
}

impl Xy {
    /// The latitude and longitude in degrees, when both are finite and in range
    /// ([−90, 90], [−180, 180]).
    pub fn lat_lon_deg(self) -> Option<(f64, f64)> {
        let (lat, lon) = match self {
            Xy::Float(lat, lon) => (f64::from(lat), f64::from(lon)),
            Xy::Int(x, y) => (f64::from(x) * 1e-7, f64::from(y) * 1e-7),
        };
        let ok = lat.is_finite() && lon.is_finite() && lat.abs() <= 90.0 && lon.abs() <= 180.0;
        ok.then_some((lat, lon))
    }
}

impl From<&CommandLong> for Command {
    fn from(c: &CommandLong) -> Self {
        Command {
            command: c.command,
            target: (c.target_system, c.target_component),
            params: [c.param1, c.param2, c.param3, c.param4],
            xy: Xy::Float(c.param5, c.param6),
            z: c.param7,
            frame: MavFrame::GlobalRelativeAlt,
        }
    }
}

impl From<&CommandInt> for Command {
    fn from(c: &CommandInt) -> Self {
        Command {
            command: c.command,
            target: (c.target_system, c.target_component),
            params: [c.param1, c.param2, c.param3, c.param4],
            xy: Xy::Int(c.x, c.y),
            z: c.z,
            frame: c.frame,
        }
    }
}

impl Command {
    /// Whether this is `MAV_CMD_REQUEST_MESSAGE` for message `id`.
    pub fn requests(&self, id: u32) -> bool {
        self.command == MavCmd::RequestMessage && self.params[0] == id as f32
    }
}

/// What `MAV_CMD_SET_MESSAGE_INTERVAL` asks of a message sent on a period (param2, µs;
/// common.xml: "-1: disable. 0: request default rate").
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Interval {
    /// −1: stop sending it.
    Stop,
    /// 0: the message's default.
    Default,
    /// Every this many milliseconds.
    Every(u32),
}

impl Interval {
    /// The interval `us` asks for; `None` below 1 ms or above a minute ([`Period`]'s range)
    /// or NaN.
    pub(crate) fn from_us(us: f32) -> Option<Self> {
        // 60,000,000 = 2^7 × 468,750: exact in an f32.
        const MAX_US: f32 = Period::MAX_MS as f32 * 1_000.0;
        if us == -1.0 {
            Some(Interval::Stop)
        } else if us == 0.0 {
            Some(Interval::Default)
        } else if (1_000.0..=MAX_US).contains(&us) {
            // In range: the cast is exact to the millisecond.
            Some(Interval::Every((us / 1_000.0) as u32))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_interval_is_stop_default_or_a_period_of_1_ms_to_a_minute() {
        assert_eq!(Interval::from_us(-1.0), Some(Interval::Stop));
        assert_eq!(Interval::from_us(0.0), Some(Interval::Default));
        assert_eq!(Interval::from_us(1_000.0), Some(Interval::Every(1)));
        assert_eq!(
            Interval::from_us(60_000_000.0),
            Some(Interval::Every(60_000))
        );
        for us in [-2.0, 999.0, 60_001_000.0, f32::NAN, f32::INFINITY] {
            assert_eq!(Interval::from_us(us), None, "{us}");
        }
        // Every interval taken is a period the configuration could hold.
        for us in [1_000.0, 1_500.0, 100_000.0, 60_000_000.0] {
            let Some(Interval::Every(ms)) = Interval::from_us(us) else {
                panic!("{us}")
            };
            assert_eq!(Period::from_millis(ms).map(Period::millis), Ok(ms));
        }
    }

    #[test]
    fn a_position_is_taken_only_when_both_are_finite_and_in_range() {
        assert_eq!(Xy::Float(45.0, 90.0).lat_lon_deg(), Some((45.0, 90.0)));
        assert_eq!(
            Xy::Int(-900_000_000, 1_800_000_000).lat_lon_deg(),
            Some((-90.0, 180.0))
        );
        for (lat, lon) in [
            (f32::NAN, 0.0),
            (0.0, f32::NAN),
            (f32::INFINITY, 0.0),
            (90.5, 0.0),
            (0.0, -180.5),
        ] {
            assert_eq!(Xy::Float(lat, lon).lat_lon_deg(), None, "{lat}, {lon}");
        }
    }
}
