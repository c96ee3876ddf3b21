//! `STATUSTEXT` (253), sent: 54 bytes (the text's 50, its severity, and the extensions `id`
//! and `chunk_seq`: a text that fits one message has id 0).

use mavio::dialects::common::messages::Statustext;

use super::put;

/// The full payload's length.
pub const LEN: usize = 54;

mod field {
    pub const SEVERITY: usize = 0;
    pub const TEXT: usize = 1;
    pub const ID: usize = 51;
    pub const CHUNK_SEQ: usize = 53;
}

/// Writes the message's payload into `p`, zeroed, its full length ([`LEN`]; nothing is
/// written into a slice of another length).
pub fn encode(m: &Statustext, p: &mut [u8]) {
    let Ok(p) = <&mut [u8; LEN]>::try_from(p) else {
        return;
    };
    put(p, field::SEVERITY, [m.severity as u8]);
    put(p, field::TEXT, m.text);
    put(p, field::ID, m.id.to_le_bytes());
    put(p, field::CHUNK_SEQ, [m.chunk_seq]);
}
