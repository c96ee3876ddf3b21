//! Frames in, bytes out: serialized MAVLink 2 frames waiting for the transport, whole
//! frames only.

use heapless::Deque;
use mavio::protocol::{Frame, V2};
use mavio::Message;

use super::MAX_FRAME_LEN;

/// Why a message was not queued for sending.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum OutboxError {
    /// `mavio` could not encode it (a message this bridge builds wrongly: a bug).
    Encode,
    /// No room for the whole frame: the transport is not taking bytes fast enough.
    Full,
}

/// Serialized frames waiting for the transport, `N` bytes in all; whole frames only.
#[derive(Clone, Debug)]
pub struct Outbox<const N: usize> {
    bytes: Deque<u8, N>,
    sequence: u8,
}

impl<const N: usize> Default for Outbox<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Outbox<N> {
    /// An empty outbox; the first frame gets sequence number 0.
    pub const fn new() -> Self {
        Outbox {
            bytes: Deque::new(),
            sequence: 0,
        }
    }

    /// Queues `message` from `(system, component)` as one MAVLink 2 frame: all of it or,
    /// when it does not fit, nothing.
    pub fn push(
        &mut self,
        system: u8,
        component: u8,
        message: &dyn Message,
    ) -> Result<(), OutboxError> {
        let frame = Frame::builder()
            .version(V2)
            .sequence(self.sequence)
            .system_id(system)
            .component_id(component)
            .message(message)
            .map_err(|_| OutboxError::Encode)?
            .build();
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = frame.serialize(&mut buf).map_err(|_| OutboxError::Encode)?;
        if N - self.bytes.len() < n {
            return Err(OutboxError::Full);
        }
        for &b in buf.get(..n).unwrap_or(&[]) {
            // Room for all n was checked above.
            let _ = self.bytes.push_back(b);
        }
        self.sequence = self.sequence.wrapping_add(1);
        Ok(())
    }

    /// The bytes to write next (a prefix of what waits); empty when nothing waits.
    pub fn bytes(&self) -> &[u8] {
        self.bytes.as_slices().0
    }

    /// `n` bytes of [`Outbox::bytes`] were written.
    pub fn written(&mut self, n: usize) {
        for _ in 0..n {
            if self.bytes.pop_front().is_none() {
                break;
            }
        }
    }

    /// Bytes waiting.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// Whether nothing waits.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
}
