//! Network, serial and bus defaults, the connector pinout, and CAN hardware-filter helpers.
//!
//! Everything here is a fact from chapter I of the vendor document (V-1.1, 2019-09-18) or
//! from the project's notes on it, given as constants so that firmware and host tools do
//! not copy numbers by hand. Each item cites its section.
//!
//! # Hardware filters
//!
//! A flight controller only needs the gimbal's postback; a (simulated) gimbal only needs
//! the control, vehicle and text frames. [`accepted_ids`] lists them exactly, for
//! list-mode filters (a bxcan 32-bit filter bank in list mode holds two extended IDs).
//! [`mask_filter`] gives the tightest single 29-bit id/mask pair for mask-mode banks:
//!
//! | role | ids | mask-filter id | mask | ids passed | extra ids passed |
//! |---|---|---|---|---|---|
//! | [`Role::FlightController`] | `0x030F0001` | `0x030F0001` | `0x1FFFFFFF` | 1 | 0 |
//! | [`Role::Gimbal`] | `0x00000F01`, `0x0000FF13`, `0x0000FF15`, `0x0000FF16`, `0x02008201`, `0x02008202` | `0x00000200` | `0x1DFF02E8` | 4096 | 4090 |
//!
//! The gimbal's single mask leaves 12 bits free, so it passes 4096 IDs, 4090 of which the
//! protocol does not use ([`GIMBAL_MASK_EXTRA_IDS`]); none of those 4090 is the postback
//! or any other protocol ID, so software still has to drop only foreign traffic. Use
//! list mode (three banks) for an exact gimbal filter.
//!
//! ```
//! use idu_gimbal::interface::{accepted_ids, mask_filter, mask_accepts, Role};
//! use idu_gimbal::wire::ids;
//!
//! // A flight controller: pass the postback, and nothing else.
//! let (id, mask) = mask_filter(Role::FlightController);
//! assert_eq!((id, mask), (0x030F_0001, 0x1FFF_FFFF));
//! assert_eq!(accepted_ids(Role::FlightController), &[ids::POSTBACK]);
//! assert!(mask_accepts(id, mask, ids::POSTBACK));
//! assert!(!mask_accepts(id, mask, ids::CONTROL));
//!
//! // A gimbal: one id/mask pair that passes all six IDs it receives.
//! let (id, mask) = mask_filter(Role::Gimbal);
//! assert_eq!((id, mask), (0x0000_0200, 0x1DFF_02E8));
//! assert!(accepted_ids(Role::Gimbal).iter().all(|&rx| mask_accepts(id, mask, rx)));
//! assert!(!mask_accepts(id, mask, ids::POSTBACK));
//! ```
//!
//! # Connector
//!
//! ```
//! use idu_gimbal::interface::{Signal, CONNECTOR_PINS};
//! let can_h = CONNECTOR_PINS.iter().find(|p| p.signal == Signal::CanHigh);
//! assert_eq!(can_h.map(|p| p.number), Some(2));
//! ```

use core::net::Ipv4Addr;

use crate::wire::ids;

/// The camera's IP address on the gimbal's RJ45 port, for its RTSP video streams
/// (section 1.2; the same address appears in the example of section 1.3).
pub const CAMERA_IP: Ipv4Addr = Ipv4Addr::new(192, 168, 42, 108);

/// The serial server's IP address on the gimbal's RJ45 port (section 1.2). It bridges the
/// gimbal's UART to TCP port [`SERIAL_SERVER_PORT`]; the frames on it are described in
/// chapter III.
pub const SERIAL_SERVER_IP: Ipv4Addr = Ipv4Addr::new(192, 168, 42, 200);

/// The serial server's TCP port (section 1.2, "Port Number: 2000").
pub const SERIAL_SERVER_PORT: u16 = 2000;

/// The RTSP port of every video stream (section 1.3).
pub const RTSP_PORT: u16 = 554;

/// The gimbal's UART baud rate (section 1.2, "Baud rate: 115200").
pub const UART_BAUD: u32 = 115_200;

/// UART data bits. The document gives only the baud rate; the project's notes on it
/// (`docs/protocol-notes.md`, "TCP / serial frame") fix the format as 8N1.
pub const UART_DATA_BITS: u8 = 8;

/// UART parity: none (8N1; see [`UART_DATA_BITS`]).
pub const UART_PARITY: Parity = Parity::None;

/// UART stop bits: one (8N1; see [`UART_DATA_BITS`]).
pub const UART_STOP_BITS: u8 = 1;

/// UART parity.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Parity {
    /// No parity bit.
    None,
    /// Even parity.
    Even,
    /// Odd parity.
    Odd,
}

/// The CAN bitrate, 1 Mbit/s (section 1.2 "CAN (1M/S)" and chapter II "CAN baud rate: 1 M/S").
pub const CAN_BITRATE: u32 = 1_000_000;

/// Every frame of the protocol uses a 29-bit extended identifier (chapter II, "Use extended
/// frame ID").
pub const CAN_EXTENDED_IDS: bool = true;

/// Every frame of the protocol carries 8 data bytes (chapter II, "Message length =8").
pub const CAN_DLC: u8 = 8;

/// Which end of the bus a device is: decides which IDs its hardware filters must pass.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Role {
    /// A flight controller (or any host) driving the gimbal: receives the postback only.
    FlightController,
    /// The gimbal, or a simulation of it: receives control, vehicle (GPS, altitude,
    /// attitude) and text frames.
    Gimbal,
}

/// The IDs a device in `role` must receive: [`ids::FROM_GIMBAL`] for a flight controller,
/// [`ids::TO_GIMBAL`] for a gimbal. Use them for exact (list-mode) hardware filters.
pub const fn accepted_ids(role: Role) -> &'static [u32] {
    match role {
        Role::FlightController => &ids::FROM_GIMBAL,
        Role::Gimbal => &ids::TO_GIMBAL,
    }
}

/// The tightest single 29-bit `(id, mask)` pair that passes every ID of
/// [`accepted_ids`]`(role)`, for mask-mode filter banks such as bxcan's.
///
/// A frame with identifier `x` passes when `x & mask == id & mask` (see [`mask_accepts`]).
/// The mask has a 1 in every bit on which all accepted IDs agree, and `id` is their common
/// value there (0 elsewhere). For [`Role::FlightController`] this is exact; for
/// [`Role::Gimbal`] it also passes [`GIMBAL_MASK_EXTRA_IDS`] IDs the protocol does not use
/// (see the [module docs](self)).
///
/// ```
/// use idu_gimbal::interface::{mask_filter, Role};
/// assert_eq!(mask_filter(Role::Gimbal), (0x0000_0200, 0x1DFF_02E8));
/// ```
pub const fn mask_filter(role: Role) -> (u32, u32) {
    tightest_mask(accepted_ids(role))
}

/// Whether a frame with identifier `candidate` passes the mask filter `(id, mask)`.
pub const fn mask_accepts(id: u32, mask: u32, candidate: u32) -> bool {
    candidate & mask == id & mask
}

/// How many IDs that the gimbal does not receive pass [`mask_filter`]`(Role::Gimbal)`:
/// its mask leaves 12 of the 29 bits free, so it passes 2^12 = 4096 IDs, of which 6 are
/// the ones the gimbal receives. None of the 4090 is an ID the protocol uses.
pub const GIMBAL_MASK_EXTRA_IDS: u32 = 4090;

/// How many IDs that a flight controller does not receive pass
/// [`mask_filter`]`(Role::FlightController)`: none, since it receives a single ID.
pub const FLIGHT_CONTROLLER_MASK_EXTRA_IDS: u32 = 0;

/// The tightest id/mask pair over a set of 29-bit IDs: fixed where they all agree, free
/// where any two differ.
const fn tightest_mask(list: &[u32]) -> (u32, u32) {
    let mut all_ones = ids::EXTENDED_MAX; // bits set in every ID
    let mut any_ones = 0u32; // bits set in some ID
    let mut rest = list;
    while let [first, tail @ ..] = rest {
        all_ones &= *first;
        any_ones |= *first;
        rest = tail;
    }
    let mask = !(all_ones ^ any_ones) & ids::EXTENDED_MAX;
    (all_ones & mask, mask)
}

/// What a connector pin carries.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Signal {
    /// CAN low.
    CanLow,
    /// CAN high.
    CanHigh,
    /// Not used (printed as `/` in the document).
    Unused,
    /// The gimbal's serial receive line: connect the other device's TX here.
    UsartRx,
    /// The gimbal's serial transmit line: connect the other device's RX here.
    UsartTx,
    /// Ground.
    Ground,
}

/// One pin of the gimbal's SATA 7-pin connector.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pin {
    /// The pin number, 1 to 7.
    pub number: u8,
    /// The pin's name as the document prints it (typo corrected, see [`CONNECTOR_PINS`]).
    pub name: &'static str,
    /// What the pin carries.
    pub signal: Signal,
}

/// The gimbal's SATA 7P CAN/serial connector (section 1.1), pins 1 to 7 in order.
///
/// | pin | name | signal |
/// |---|---|---|
/// | 1 | CAN L | CAN low |
/// | 2 | CAN H | CAN high |
/// | 3 | / | unused |
/// | 4 | / | unused |
/// | 5 | USART RX | gimbal's serial receive |
/// | 6 | USART TX | gimbal's serial transmit |
/// | 7 | GND | ground |
///
/// The document prints pin 7 as "DRND", a typo for GND, and the CAN pins as "CAN L-" and
/// "CAN H+". It does not say from whose side RX and TX are named; they are taken here to
/// be the gimbal's (cross them: your TX to pin 5, your RX to pin 6). If no serial data
/// arrives, swap them.
pub const CONNECTOR_PINS: [Pin; 7] = [
    Pin {
        number: 1,
        name: "CAN L",
        signal: Signal::CanLow,
    },
    Pin {
        number: 2,
        name: "CAN H",
        signal: Signal::CanHigh,
    },
    Pin {
        number: 3,
        name: "/",
        signal: Signal::Unused,
    },
    Pin {
        number: 4,
        name: "/",
        signal: Signal::Unused,
    },
    Pin {
        number: 5,
        name: "USART RX",
        signal: Signal::UsartRx,
    },
    Pin {
        number: 6,
        name: "USART TX",
        signal: Signal::UsartTx,
    },
    Pin {
        number: 7,
        name: "GND",
        signal: Signal::Ground,
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn network_and_bus_defaults_are_the_documented_values() {
        assert_eq!(CAMERA_IP.octets(), [192, 168, 42, 108]);
        assert_eq!(SERIAL_SERVER_IP.octets(), [192, 168, 42, 200]);
        assert_eq!(SERIAL_SERVER_PORT, 2000);
        assert_eq!(RTSP_PORT, 554);
        assert_eq!(UART_BAUD, 115_200);
        assert_eq!(
            (UART_DATA_BITS, UART_PARITY, UART_STOP_BITS),
            (8, Parity::None, 1)
        );
        assert_eq!(CAN_BITRATE, 1_000_000);
        const { assert!(CAN_EXTENDED_IDS) };
        assert_eq!(CAN_DLC, 8);
    }

    #[test]
    fn connector_pinout() {
        let table: Vec<(u8, &str, Signal)> = CONNECTOR_PINS
            .iter()
            .map(|p| (p.number, p.name, p.signal))
            .collect();
        assert_eq!(
            table,
            [
                (1, "CAN L", Signal::CanLow),
                (2, "CAN H", Signal::CanHigh),
                (3, "/", Signal::Unused),
                (4, "/", Signal::Unused),
                (5, "USART RX", Signal::UsartRx),
                (6, "USART TX", Signal::UsartTx),
                (7, "GND", Signal::Ground),
            ]
        );
    }

    #[test]
    fn accepted_ids_are_the_wire_id_lists() {
        assert_eq!(accepted_ids(Role::FlightController), &[ids::POSTBACK]);
        assert_eq!(accepted_ids(Role::FlightController), &ids::FROM_GIMBAL);
        assert_eq!(
            accepted_ids(Role::Gimbal),
            &[
                ids::CONTROL,
                ids::ATTITUDE,
                ids::GPS,
                ids::ALTITUDE,
                ids::TEXT,
                ids::TEXT_END
            ]
        );
        assert_eq!(accepted_ids(Role::Gimbal), &ids::TO_GIMBAL);
    }

    #[test]
    fn mask_filters_are_the_documented_values() {
        assert_eq!(
            mask_filter(Role::FlightController),
            (0x030F_0001, 0x1FFF_FFFF)
        );
        assert_eq!(mask_filter(Role::Gimbal), (0x0000_0200, 0x1DFF_02E8));
    }

    /// Every ID a role receives passes its filter; every other protocol ID is rejected.
    #[test]
    fn mask_filters_pass_exactly_the_right_protocol_ids() {
        for role in [Role::FlightController, Role::Gimbal] {
            let (id, mask) = mask_filter(role);
            assert!(id <= ids::EXTENDED_MAX && mask <= ids::EXTENDED_MAX);
            assert_eq!(id & !mask, 0, "id has bits outside the mask");
            for rx in ids::ALL {
                let wanted = accepted_ids(role).contains(&rx);
                assert_eq!(
                    mask_accepts(id, mask, rx),
                    wanted,
                    "{role:?}: id {rx:#010x} wanted={wanted}"
                );
            }
        }
        let (id, mask) = mask_filter(Role::FlightController);
        assert!(!mask_accepts(id, mask, ids::CONTROL));
        let (id, mask) = mask_filter(Role::Gimbal);
        assert!(!mask_accepts(id, mask, ids::POSTBACK));
    }

    /// The mask is the tightest: clearing any further bit of it would be needed by no
    /// accepted ID, and every bit left free is one on which two accepted IDs differ.
    #[test]
    fn mask_filters_are_tightest() {
        for role in [Role::FlightController, Role::Gimbal] {
            let (_, mask) = mask_filter(role);
            let list = accepted_ids(role);
            for bit in 0..29 {
                let b = 1u32 << bit;
                let differ = list.iter().any(|x| x & b != list[0] & b);
                assert_eq!(mask & b == 0, differ, "{role:?} bit {bit}");
            }
        }
    }

    /// Enumerates every ID a single mask passes (over its free bits) and counts the ones
    /// the role does not receive; asserts exactly which they are not (no protocol ID).
    #[test]
    fn extra_ids_passed_by_the_single_mask() {
        for (role, documented) in [
            (Role::FlightController, FLIGHT_CONTROLLER_MASK_EXTRA_IDS),
            (Role::Gimbal, GIMBAL_MASK_EXTRA_IDS),
        ] {
            let (id, mask) = mask_filter(role);
            let free = !mask & ids::EXTENDED_MAX;
            // Enumerate all subsets of the free bits.
            let mut passed = Vec::new();
            let mut sub = 0u32;
            loop {
                passed.push(id | sub);
                if sub == free {
                    break;
                }
                sub = (sub.wrapping_sub(free)) & free;
            }
            assert_eq!(passed.len(), 1usize << free.count_ones());
            assert!(passed.iter().all(|&x| mask_accepts(id, mask, x)));
            let extra: Vec<u32> = passed
                .iter()
                .copied()
                .filter(|x| !accepted_ids(role).contains(x))
                .collect();
            assert_eq!(extra.len() as u32, documented, "{role:?}");
            assert!(extra.iter().all(|x| !ids::ALL.contains(x)), "{role:?}");
            for rx in accepted_ids(role) {
                assert!(passed.contains(rx));
            }
        }
        // Concrete foreign IDs the gimbal's single mask lets through, and some it does not.
        let (id, mask) = mask_filter(Role::Gimbal);
        assert!(mask_accepts(id, mask, 0x0000_FF17));
        assert!(mask_accepts(id, mask, 0x0200_0200));
        assert!(!mask_accepts(id, mask, 0x0000_0F09)); // bit 3 set: all six have it clear
        assert!(!mask_accepts(id, mask, 0x0000_FD13)); // bit 9 clear: all six have it set
    }

    #[test]
    fn brute_force_low_ids_agree_with_enumeration() {
        // All 2^16 IDs below 0x10000 (where the vehicle and control IDs live): the
        // gimbal's filter passes exactly those with the mask's fixed bits.
        let (id, mask) = mask_filter(Role::Gimbal);
        let n = (0u32..0x1_0000)
            .filter(|&x| mask_accepts(id, mask, x))
            .count();
        // Free bits below bit 16: 0xFD17 has 11 set bits.
        assert_eq!(n, 1 << 11);
    }
}
