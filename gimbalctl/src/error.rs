//! How a run fails, and the exit status that goes with it.

use std::fmt;
use std::io;

/// A failed run.
#[derive(Debug)]
pub enum Failure {
    /// Bad usage or a value out of range: exit status 2.
    Usage(String),
    /// A runtime failure (I/O, connection): exit status 1.
    Runtime(String),
    /// The reader of our stdout went away (`gimbalctl decode log | head`): stop quietly.
    BrokenPipe,
}

impl Failure {
    /// A runtime failure from an I/O error, with what we were doing.
    pub fn io(context: impl fmt::Display, e: io::Error) -> Self {
        if e.kind() == io::ErrorKind::BrokenPipe {
            Failure::BrokenPipe
        } else {
            Failure::Runtime(format!("{context}: {e}"))
        }
    }

    /// An error writing to stdout.
    pub fn stdout(e: io::Error) -> Self {
        Failure::io("cannot write to stdout", e)
    }
}
