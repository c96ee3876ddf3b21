//! Sending: the outbox every frame the bridge and its camera send goes through, with a
//! full outbox counted, and the small helpers both use to build messages.

use idu_gimbal::wire::postback::GimbalType;
use mavio::dialects::common::enums::MavResult;
use mavio::dialects::common::messages::CommandAck;
use mavio::mavspec::rust::spec::MessageSpecStatic;
use mavio::Message;

use crate::capture::Vantage;
use crate::framing::Outbox;

/// Bytes of serialized frames the bridge holds for the transport.
pub const OUTBOX_LEN: usize = 1024;

/// Where every frame the bridge and its camera send goes: the outbox, the system ID they
/// send as, and a count of the frames a full outbox refused.
pub(crate) struct Sender {
    pub(crate) outbox: Outbox<OUTBOX_LEN>,
    pub(crate) system_id: u8,
    /// Frames a full outbox refused.
    pub(crate) outbox_full: u32,
}

impl Sender {
    /// Sending into `outbox` as `system_id`.
    pub(crate) fn new(outbox: Outbox<OUTBOX_LEN>, system_id: u8) -> Self {
        Sender {
            outbox,
            system_id,
            outbox_full: 0,
        }
    }

    /// Queues `message` from `component`; a full outbox is counted. (The bridge sends as
    /// two components, within the outbox's [`crate::framing::COMPONENTS`]: never refused
    /// for that.)
    pub(crate) fn send(&mut self, component: u8, message: &dyn Message) {
        let pushed = self.outbox.push(self.system_id, component, message);
        if pushed.is_err() {
            bump(&mut self.outbox_full);
        }
    }

    /// Queues message `M` from `component`, its `len`-byte payload written in place by its
    /// codec ([`crate::codec`]); a full outbox is counted. Whether it was queued.
    pub(crate) fn send_encoded<M: MessageSpecStatic>(
        &mut self,
        component: u8,
        len: usize,
        encode: impl FnOnce(&mut [u8]),
    ) -> bool {
        let pushed = self.outbox.push_with(
            self.system_id,
            component,
            M::message_id(),
            M::crc_extra(),
            len,
            encode,
        );
        if pushed.is_err() {
            bump(&mut self.outbox_full);
        }
        pushed.is_ok()
    }

    /// Queues `me`'s `COMMAND_ACK` of `command` with `result` to `to`: the one way ACKs go
    /// out. Out of line: several callers, one copy of the codec.
    #[inline(never)]
    pub(crate) fn ack(&mut self, me: u8, command: u16, result: MavResult, to: (u8, u8)) {
        self.send_encoded::<CommandAck>(me, crate::codec::command_ack::LEN, |p| {
            crate::codec::command_ack::encode(command, result, to, p)
        });
    }

    /// Bytes the outbox has room for.
    pub(crate) fn room(&self) -> usize {
        self.outbox.room()
    }
}

/// What the camera is given to send with: the bridge's sender, and what it reports from the
/// bridge's state.
pub(crate) struct Tx<'a> {
    pub(crate) out: &'a mut Sender,
    /// The vehicle's position and the camera's attitude now, for captures.
    pub(crate) vantage: Vantage,
    /// The gimbal type from the latest postback.
    pub(crate) gimbal_type: Option<GimbalType>,
}

/// A message's id.
pub(crate) fn id_of<M: MessageSpecStatic>() -> u32 {
    M::spec().id()
}

pub(crate) fn bump(counter: &mut u32) {
    *counter = counter.wrapping_add(1);
}

/// A name in a fixed MAVLink char field, zero-padded.
pub(crate) fn name<const N: usize>(s: &str) -> [u8; N] {
    let mut out = [0u8; N];
    for (dst, src) in out.iter_mut().zip(s.bytes()) {
        *dst = src;
    }
    out
}
