//! The camera's settings: the parameters of its camera definition file (see
//! [`definition`](super::definition)), read and set with the extended parameter protocol
//! (`PARAM_EXT_REQUEST_LIST`, `PARAM_EXT_REQUEST_READ`, `PARAM_EXT_SET` →
//! `PARAM_EXT_VALUE`, `PARAM_EXT_ACK`).
//!
//! Each is a `uint8` whose value the gimbal cannot report, so the value is the one last
//! set (the definition's default until then), and each setting is sent to the gimbal as
//! its command when set:
//!
//! | parameter | values | command |
//! |---|---|---|
//! | `CAM_FOCUS` | 0 stop, 1 focus +, 2 focus −, 3 auto | 0x0F 0x13 (3, 1, 2, 4) |
//! | `IR_PALETTE` (dual light) | 0..=14, the document's palette codes | 0x1F 0x02 |
//! | `IR_EZOOM` (dual light) | 0 stop, 1 zoom in, 2 zoom out | 0x1F 0x12 (3, 1, 2) |
//!
//! Values travel as the parameter protocol's byte-wise encoding: the value's bytes,
//! little-endian, at the start of the 128-byte `param_value`, the rest zero, as both clients
//! encode and decode them (`QGCCameraIO.cc`:136-211, 257-305 at HTRamsey/qgroundcontrol
//! c15cc32; `param_value.cpp`:196-262, 527-560 at mavlink/MAVSDK 158e339). QGroundControl
//! reads them all with `PARAM_EXT_REQUEST_LIST` (`VehicleCameraControl.cc`:1188-1211),
//! MAVSDK one by one with `PARAM_EXT_REQUEST_READ` by name (`camera_impl.cpp`:2169-2235).
//!
//! A set with an unknown name, another type or a value outside the parameter's options is
//! answered `PARAM_ACK_VALUE_UNSUPPORTED` with the value kept; a set the gimbal's queue has
//! no room for, `PARAM_ACK_FAILED`. A value is read by its type's width (a `uint8`: the
//! first byte), whatever follows it. `MAV_CMD_RESET_CAMERA_SETTINGS` sets every parameter
//! back to its default. A read of an unknown name or index is not answered
//! (the protocol has no error reply for a read; the client times out).

use idu_gimbal::wire::control::{
    Command as GimbalCmd, DualLightCommand, ElectronicZoom, Focus, GimbalCommand, Palette,
};
use mavio::dialects::common::enums::{MavParamExtType, MavResult, ParamAck};
use mavio::dialects::common::messages::{ParamExtAck, ParamExtValue};

use crate::codec::param_ext::{self, ParamSet};
use crate::framing::MAX_FRAME_LEN;
use crate::tx::{name, Tx};
use idu_gimbal::link::{Link, Medium};

/// A parameter of the definition.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Parameter {
    /// Its name (`param_id`).
    pub name: &'static str,
    /// Only on a camera with a thermal sensor (the dual light).
    pub thermal: bool,
    /// The largest value; values are 0..=max.
    pub max: u8,
    /// The value until one is set.
    pub default: u8,
}

/// Every parameter, in index order (the thermal ones after the others).
pub const PARAMETERS: [Parameter; 3] = [
    Parameter {
        name: "CAM_FOCUS",
        thermal: false,
        max: 3,
        default: 0,
    },
    Parameter {
        name: "IR_PALETTE",
        thermal: true,
        max: 14,
        default: 0,
    },
    Parameter {
        name: "IR_EZOOM",
        thermal: true,
        max: 2,
        default: 0,
    },
];

/// The camera's parameters and their values.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Settings {
    /// How many of [`PARAMETERS`] this camera has (the first ones).
    count: usize,
    values: [u8; PARAMETERS.len()],
    /// Values still to send after a list request, one bit per index.
    listing: u8,
}

const _: () = assert!(
    PARAMETERS.len() <= 8,
    "`listing` holds one bit per parameter"
);

/// The parameters of a camera with or without a thermal sensor: a prefix of
/// [`PARAMETERS`], whose thermal ones come last (a test holds it).
pub(crate) fn parameters(thermal: bool) -> &'static [Parameter] {
    let count = PARAMETERS.iter().filter(|p| thermal || !p.thermal).count();
    PARAMETERS.get(..count).unwrap_or(&[])
}

/// A `uint8` value in a `param_value` field: its byte first, the rest zero.
fn value_field(v: u8) -> [u8; 128] {
    let mut field = [0u8; 128];
    field[0] = v;
    field
}

/// A `param_id` field as text: up to the first NUL, all 16 bytes when there is none.
fn id_text(id: &[u8; 16]) -> &[u8] {
    let len = id.iter().position(|&b| b == 0).unwrap_or(id.len());
    id.get(..len).unwrap_or(id)
}

impl Settings {
    pub(crate) fn new(thermal: bool) -> Self {
        let mut values = [0; PARAMETERS.len()];
        for (v, p) in values.iter_mut().zip(PARAMETERS.iter()) {
            *v = p.default;
        }
        Settings {
            count: parameters(thermal).len(),
            values,
            listing: 0,
        }
    }

    fn index_of(&self, id: &[u8; 16]) -> Option<usize> {
        let text = id_text(id);
        PARAMETERS
            .iter()
            .take(self.count)
            .position(|p| p.name.as_bytes() == text)
    }

    /// The value of parameter `i`.
    pub(crate) fn value(&self, i: usize) -> Option<u8> {
        (i < self.count)
            .then(|| self.values.get(i).copied())
            .flatten()
    }

    /// `PARAM_EXT_REQUEST_LIST`: every value, as the outbox makes room.
    pub(crate) fn list(&mut self) {
        self.listing = super::low_bits(self.count);
    }

    /// `PARAM_EXT_REQUEST_READ`: by index when `index` ≥ 0, else by name; whether it names
    /// one of the parameters.
    pub(crate) fn read(&mut self, id: &[u8; 16], index: i16, component: u8, tx: &mut Tx<'_>) {
        let i = match usize::try_from(index) {
            // One past the parameters names none: `send_value` sends nothing for it.
            Ok(i) => Some(i),
            Err(_) => self.index_of(id),
        };
        if let Some(i) = i {
            self.send_value(i, component, tx);
        }
    }

    pub(crate) fn pending(&self) -> bool {
        self.listing != 0
    }

    /// Values a list request still owes, as far as the outbox has room.
    pub(crate) fn send_pending(&mut self, component: u8, tx: &mut Tx<'_>) {
        for i in 0..self.count {
            let bit = 1u8 << i;
            if self.listing & bit == 0 {
                continue;
            }
            if tx.out.room() < MAX_FRAME_LEN {
                return;
            }
            self.send_value(i, component, tx);
            self.listing &= !bit;
        }
    }

    fn send_value(&self, i: usize, component: u8, tx: &mut Tx<'_>) {
        let (Some(p), Some(v)) = (PARAMETERS.get(i), self.value(i)) else {
            return;
        };
        let m = ParamExtValue {
            param_id: name(p.name),
            param_value: value_field(v),
            param_type: MavParamExtType::Uint8,
            // Below PARAMETERS.len(): the casts are exact.
            param_count: self.count as u16,
            param_index: i as u16,
        };
        tx.out.send(component, &m);
    }

    /// `PARAM_EXT_SET`: the setting sent to the gimbal, and the `PARAM_EXT_ACK`.
    pub(crate) fn set<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        set: &ParamSet,
        component: u8,
        tx: &mut Tx<'_>,
    ) {
        let result = self.apply(gimbal, set);
        // The value in effect and its type, accepted or not: QGroundControl shows what the
        // ACK says (QGCCameraIO::handleParamAck). An unknown name is echoed, its type as
        // sent, known to the dialect or not.
        let (param_value, param_type) =
            match self.index_of(&set.param_id).and_then(|i| self.value(i)) {
                Some(v) => (value_field(v), MavParamExtType::Uint8 as u8),
                None => (set.param_value, set.param_type),
            };
        tx.out
            .send_encoded::<ParamExtAck>(component, param_ext::ACK_LEN, |p| {
                param_ext::encode_ack(&set.param_id, &param_value, param_type, result as u8, p)
            });
    }

    fn apply<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        set: &ParamSet,
    ) -> ParamAck {
        let Some(i) = self.index_of(&set.param_id) else {
            return ParamAck::ValueUnsupported;
        };
        // A `uint8` is its first byte: the value is read by its type's width. What follows
        // is not looked at: QGroundControl 5.0 sends there what its stack buffer held
        // (`QGCCameraIO.cc` `_sendParameter`), and rejecting it bounced every change.
        let [v, ..] = set.param_value;
        let Some(p) = PARAMETERS.get(i) else {
            return ParamAck::ValueUnsupported;
        };
        // Any other type, known to the dialect or not, is not this parameter's.
        if set.param_type != MavParamExtType::Uint8 as u8 || v > p.max {
            return ParamAck::ValueUnsupported;
        }
        self.put(gimbal, i, v)
    }

    /// `MAV_CMD_RESET_CAMERA_SETTINGS`: every parameter back to its default, each sent to
    /// the gimbal. `TEMPORARILY_REJECTED`, nothing sent, when the gimbal's queue has no room
    /// for them all: the client may try again.
    pub(crate) fn reset<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
    ) -> MavResult {
        // Each parameter is one command.
        if gimbal.command_room() < self.count {
            return MavResult::TemporarilyRejected;
        }
        for (i, p) in PARAMETERS.iter().enumerate().take(self.count) {
            match self.put(gimbal, i, p.default) {
                ParamAck::Accepted => {}
                _ => return MavResult::TemporarilyRejected,
            }
        }
        MavResult::Accepted
    }

    /// Sends parameter `i`'s setting `v` (within its range) to the gimbal and keeps it.
    fn put<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        i: usize,
        v: u8,
    ) -> ParamAck {
        let (Some(p), Some(slot)) = (PARAMETERS.get(i), self.values.get_mut(i)) else {
            return ParamAck::ValueUnsupported;
        };
        let command: Option<GimbalCmd> = match p.name {
            "CAM_FOCUS" => Some(
                GimbalCommand::Focus(match v {
                    1 => Focus::Plus,
                    2 => Focus::Minus,
                    3 => Focus::Auto,
                    _ => Focus::Stop,
                })
                .into(),
            ),
            "IR_PALETTE" => Palette::from_code(v).map(|p| DualLightCommand::Palette(p).into()),
            "IR_EZOOM" => Some(
                DualLightCommand::ElectronicZoom(match v {
                    1 => ElectronicZoom::In,
                    2 => ElectronicZoom::Out,
                    _ => ElectronicZoom::Stop,
                })
                .into(),
            ),
            _ => None,
        };
        let Some(command) = command else {
            return ParamAck::ValueUnsupported;
        };
        if gimbal.send(command).is_err() {
            return ParamAck::Failed;
        }
        *slot = v;
        ParamAck::Accepted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thermal_parameters_come_last() {
        let first_thermal = PARAMETERS.iter().position(|p| p.thermal).unwrap();
        assert!(PARAMETERS[first_thermal..].iter().all(|p| p.thermal));
        assert_eq!(parameters(false).len(), first_thermal);
        assert_eq!(parameters(true).len(), PARAMETERS.len());
    }

    #[test]
    fn a_camera_without_thermal_has_no_thermal_values() {
        let visible = Settings::new(false);
        let count = parameters(false).len();
        assert_eq!(
            visible.value(count - 1),
            Some(PARAMETERS[count - 1].default)
        );
        assert_eq!(visible.value(count), None);
        assert_eq!(
            Settings::new(true).value(count),
            Some(PARAMETERS[count].default)
        );
    }

    #[test]
    fn low_bits_masks_the_first_n() {
        let masks: Vec<u8> = (0..=9).map(crate::camera::low_bits).collect();
        assert_eq!(masks, [0, 1, 3, 7, 15, 31, 63, 127, 255, 255]);
    }
}
