//! `COMMAND_ACK` (77), sent: 3 bytes, and the `progress`, `result_param2`, `target_system`
//! and `target_component` extensions (10 in all). The command is its raw `u16`, so that a
//! command `mavio`'s dialect does not know (a newer common.xml's, another dialect's) is
//! answered too: `mavio`'s `CommandAck` can only carry a `MavCmd` it knows.

use mavio::dialects::common::enums::MavResult;

use super::put;

/// The full payload's length.
pub const LEN: usize = 10;

mod field {
    pub const COMMAND: usize = 0;
    pub const RESULT: usize = 2;
    pub const PROGRESS: usize = 3;
    pub const RESULT_PARAM2: usize = 4;
    pub const TARGET_SYSTEM: usize = 8;
    pub const TARGET_COMPONENT: usize = 9;
}

/// Writes the ACK of `command` with `result` to `to` into `p`, zeroed, its full length
/// ([`LEN`]; nothing is written into a slice of another length). Progress and
/// `result_param2` are 0: no command here reports progress.
pub fn encode(command: u16, result: MavResult, to: (u8, u8), p: &mut [u8]) {
    let Ok(p) = <&mut [u8; LEN]>::try_from(p) else {
        return;
    };
    put(p, field::COMMAND, command.to_le_bytes());
    put(p, field::RESULT, [result as u8]);
    put(p, field::PROGRESS, [0]);
    put(p, field::RESULT_PARAM2, 0i32.to_le_bytes());
    put(p, field::TARGET_SYSTEM, [to.0]);
    put(p, field::TARGET_COMPONENT, [to.1]);
}
