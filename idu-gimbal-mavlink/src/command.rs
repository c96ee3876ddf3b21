//! Commands as they arrive, `COMMAND_LONG` and `COMMAND_INT` alike: one type for both, so
//! every command is handled and acknowledged the same way whichever message carried it.
//!
//! common.xml: "COMMAND_INT ... is the same as COMMAND_LONG, except that x and y are
//! integers (latitude and longitude in 1e7 degrees for global frames) and the frame is
//! given". Newer ArduPilot sends location commands (ROI) as `COMMAND_INT`.

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
    /// The location: latitude and longitude in 1e-7° (`COMMAND_INT`'s x and y; a
    /// `COMMAND_LONG`'s param5 and param6 in degrees, scaled), `None` where not finite or
    /// not a latitude/longitude.
    pub lat_lon_e7: Option<(i32, i32)>,
    /// param7 / z: the altitude, metres, in [`Command::frame`].
    pub z: f32,
    /// The altitude's frame: `COMMAND_INT`'s, and `GLOBAL_RELATIVE_ALT` for a
    /// `COMMAND_LONG` (which has none: ArduPilot and PX4 both read its altitudes as
    /// relative to home).
    pub frame: MavFrame,
}

/// Degrees to 1e-7° when a valid latitude (`max` 90) or longitude (`max` 180).
fn e7(deg: f32, max: f64) -> Option<i32> {
    let d = f64::from(deg);
    // In range: |d·1e7| <= 1.8e9 < 2^31, so the cast is exact after rounding.
    (d.is_finite() && d.abs() <= max).then(|| libm::round(d * 1e7) as i32)
}

impl From<&CommandLong> for Command {
    fn from(c: &CommandLong) -> Self {
        Command {
            command: c.command,
            target: (c.target_system, c.target_component),
            params: [c.param1, c.param2, c.param3, c.param4],
            lat_lon_e7: e7(c.param5, 90.0).zip(e7(c.param6, 180.0)),
            z: c.param7,
            frame: MavFrame::GlobalRelativeAlt,
        }
    }
}

impl From<&CommandInt> for Command {
    fn from(c: &CommandInt) -> Self {
        let valid = (-900_000_000..=900_000_000).contains(&c.x)
            && (-1_800_000_000..=1_800_000_000).contains(&c.y);
        Command {
            command: c.command,
            target: (c.target_system, c.target_component),
            params: [c.param1, c.param2, c.param3, c.param4],
            lat_lon_e7: valid.then_some((c.x, c.y)),
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
