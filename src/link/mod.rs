//! The stateful link: reassembly, queues and schedules, with no I/O.

pub mod postback;
pub mod text;
