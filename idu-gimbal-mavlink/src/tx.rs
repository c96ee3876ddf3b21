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

/// What the camera is given to send with: the outbox, and what it reports from the
/// bridge's state.
pub(crate) struct Tx<'a> {
    pub(crate) out: &'a mut Outbox<OUTBOX_LEN>,
    pub(crate) system_id: u8,
    pub(crate) outbox_full: &'a mut u32,
    /// The vehicle's position and the camera's attitude now, for captures.
    pub(crate) vantage: Vantage,
    /// The gimbal type from the latest postback.
    pub(crate) gimbal_type: Option<GimbalType>,
}

/// Queues `message` from `(system_id, component)`; a full outbox is counted in `full`.
/// The one way every frame the bridge sends goes out.
pub(crate) fn push_counted(
    out: &mut Outbox<OUTBOX_LEN>,
    system_id: u8,
    full: &mut u32,
    component: u8,
    message: &dyn Message,
) {
    if out.push(system_id, component, message).is_err() {
        bump(full);
    }
}

/// [`push_counted`] for message `M`, its `len`-byte payload written in place by its codec
/// ([`crate::codec`]).
pub(crate) fn push_encoded<M: MessageSpecStatic>(
    out: &mut Outbox<OUTBOX_LEN>,
    system_id: u8,
    full: &mut u32,
    component: u8,
    len: usize,
    encode: impl FnOnce(&mut [u8]),
) {
    if out
        .push_with(
            system_id,
            component,
            M::message_id(),
            M::crc_extra(),
            len,
            encode,
        )
        .is_err()
    {
        bump(full);
    }
}

/// Queues `me`'s `COMMAND_ACK` of `command` with `result` to `to`: the one way ACKs go out.
/// Out of line: three callers, one copy of the codec.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn push_ack(
    out: &mut Outbox<OUTBOX_LEN>,
    system_id: u8,
    full: &mut u32,
    me: u8,
    command: u16,
    result: MavResult,
    to: (u8, u8),
) {
    push_encoded::<CommandAck>(
        out,
        system_id,
        full,
        me,
        crate::codec::command_ack::LEN,
        |p| crate::codec::command_ack::encode(command, result, to, p),
    );
}

impl Tx<'_> {
    /// Queues `me`'s ACK of `command` to `to`.
    pub(crate) fn ack(&mut self, me: u8, command: u16, result: MavResult, to: (u8, u8)) {
        push_ack(
            self.out,
            self.system_id,
            self.outbox_full,
            me,
            command,
            result,
            to,
        );
    }

    /// Queues `message` from `component`; a full outbox is counted.
    pub(crate) fn send(&mut self, component: u8, message: &dyn Message) {
        push_counted(
            self.out,
            self.system_id,
            self.outbox_full,
            component,
            message,
        );
    }

    /// Queues message `M` from `component`, its `len`-byte payload written by its codec.
    pub(crate) fn send_encoded<M: MessageSpecStatic>(
        &mut self,
        component: u8,
        len: usize,
        encode: impl FnOnce(&mut [u8]),
    ) {
        push_encoded::<M>(
            self.out,
            self.system_id,
            self.outbox_full,
            component,
            len,
            encode,
        );
    }

    /// Bytes the outbox has room for.
    pub(crate) fn room(&self) -> usize {
        self.out.room()
    }
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
