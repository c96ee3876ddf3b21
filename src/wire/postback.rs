//! The postback: the gimbal's status message (section 2.2), every 500 ms.
//!
//! On CAN it arrives as four 8-byte frames on ID `0x030F0001` (32 bytes: 27 of message and
//! 5 of zero padding). On the serial/TCP byte stream the document does not show it; this
//! crate takes it to be the same 27 bytes without the CAN padding, recognised by header,
//! length byte and CRC.
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 2 | header `EB 90` |
//! | 2 | 1 | length, `0x0C` (informational: it does not match the field count) |
//! | 3 | 9 | zero |
//! | 12 | 2 | CMD+DID `21 FE` |
//! | 14 | 1 | C_ID, `0x0F` |
//! | 15 | 1 | Data_id, `0x01` |
//! | 16 | 1 | gimbal type |
//! | 17 | 1 | tracking flag |
//! | 18 | 1 | control mode |
//! | 19 | 2 | pitch, 0.01°, i16, [-11000, 6000] |
//! | 21 | 2 | heading, 0.01°, u16, [0, 36000] |
//! | 23 | 2 | heading motor, 0.01°, i16, [-17000, 17000] ([-32500, 32500] on the 3.5× model) |
//! | 25 | 2 | CRC-16/MODBUS over bytes 0..=24, low byte first |
//! | 27 | 5 | zero padding (CAN form only) |
//!
//! [`Packet`] is a zero-copy view over either form; [`Postback`] is the decoded value.
//! Only the header and the CRC decide whether a message is good: the length byte, CMD+DID
//! and C_ID are exposed but not enforced, and unknown gimbal types, control modes and
//! Data_id values decode as `Unknown(n)`.
//!
//! # Panics
//! Nothing here panics: [`Packet::new`] checks the length once and every accessor reads
//! within it.
//!
//! ```
//! use idu_gimbal::wire::postback::{ControlMode, GimbalType, Postback};
//! let status = Postback {
//!     pitch: -4500,
//!     heading: 9000,
//!     ..Postback::default()
//! };
//! let frames = status.to_can_frames();
//! assert_eq!(&frames[0][..3], &[0xEB, 0x90, 0x0C]);
//! let back = Postback::parse(frames.as_flattened())?;
//! assert_eq!(back, status);
//! assert_eq!(back.pitch_deg(), -45.0);
//! # Ok::<(), idu_gimbal::wire::postback::PostbackError>(())
//! ```

use core::fmt;

use super::{crc, ids};

mod field {
    use core::ops::Range;
    pub const HEADER: Range<usize> = 0..2;
    pub const LENGTH: usize = 2;
    pub const RESERVED: Range<usize> = 3..12;
    pub const CMD_DID: Range<usize> = 12..14;
    pub const C_ID: usize = 14;
    pub const DATA_ID: usize = 15;
    pub const GIMBAL_TYPE: usize = 16;
    pub const TRACKING: usize = 17;
    pub const MODE: usize = 18;
    pub const PITCH: Range<usize> = 19..21;
    pub const HEADING: Range<usize> = 21..23;
    pub const MOTOR: Range<usize> = 23..25;
    pub const CRC: Range<usize> = 25..27;
    /// What the CRC covers.
    pub const CHECKED: Range<usize> = 0..25;
}

/// CAN ID of the postback frames.
pub const ID: u32 = ids::POSTBACK;
/// The message header, `EB 90`.
pub const HEADER: [u8; 2] = [0xEB, 0x90];
/// The length byte the gimbal sends (informational).
pub const LENGTH_BYTE: u8 = 0x0C;
/// CMD+DID bytes of the postback.
pub const CMD_DID: [u8; 2] = [0x21, 0xFE];
/// C_ID (equipment ID) of the gimbal.
pub const C_ID: u8 = 0x0F;
/// Length of the message proper (the serial/TCP stream form).
pub const MESSAGE_LEN: usize = 27;
/// Length of the CAN form: four frames of 8 bytes.
pub const CAN_LEN: usize = 32;
/// Number of CAN frames in one message.
pub const FRAMES: usize = 4;

/// Why bytes are not a good postback.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PostbackError {
    /// Fewer than [`MESSAGE_LEN`] bytes.
    Truncated {
        /// The length given.
        len: usize,
    },
    /// The first two bytes are not `EB 90`.
    BadHeader {
        /// The bytes found.
        found: [u8; 2],
    },
    /// The CRC does not match the message.
    BadCrc {
        /// The CRC computed over bytes 0..=24.
        computed: u16,
        /// The CRC carried in bytes 25..=26.
        received: u16,
    },
}

impl fmt::Display for PostbackError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PostbackError::Truncated { len } => {
                write!(
                    f,
                    "postback of {len} bytes is truncated: it needs {MESSAGE_LEN}"
                )
            }
            PostbackError::BadHeader { found: [a, b] } => {
                write!(f, "postback header is {a:02X} {b:02X}, expected EB 90")
            }
            PostbackError::BadCrc { computed, received } => {
                write!(
                    f,
                    "postback CRC is {received:#06X}, computed {computed:#06X}"
                )
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for PostbackError {}

enum_with_unknown! {
    /// Gimbal model as reported in the postback (Note 1 of section 2.2).
    #[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
    #[cfg_attr(feature = "defmt", derive(defmt::Format))]
    pub enum GimbalType {
        /// 1: X30 / X30GT.
        #[default]
        X30 = 1,
        /// 2: X30T.
        X30T = 2,
        /// 3: 3.5× zoom.
        Zoom3_5x = 3,
        /// 4: 3.5× dual light.
        DualLight3_5x = 4,
        /// 5: laser ranging.
        LaserRanging = 5,
        /// 6: A2000.
        A2000 = 6,
        /// 7: 30× dual light.
        DualLight30x = 7,
    }
}

impl GimbalType {
    /// The model's name as the document gives it, or `None` for an unknown code.
    pub const fn model_name(self) -> Option<&'static str> {
        match self {
            GimbalType::X30 => Some("X30/X30GT"),
            GimbalType::X30T => Some("X30T"),
            GimbalType::Zoom3_5x => Some("3.5x"),
            GimbalType::DualLight3_5x => Some("3.5x dual light"),
            GimbalType::LaserRanging => Some("laser ranging"),
            GimbalType::A2000 => Some("A2000"),
            GimbalType::DualLight30x => Some("30x dual light"),
            GimbalType::Unknown(_) => None,
        }
    }

    /// The yaw motor's travel either side of the nose, in 0.01°: the postback's
    /// `Motor_psi` scope, ±170.00°, or ±325.00° on the 3.5× models (section 2.2). An
    /// unknown model is taken to have the common ±170.00°.
    pub const fn motor_yaw_limit_cdeg(self) -> i16 {
        match self {
            GimbalType::Zoom3_5x | GimbalType::DualLight3_5x => 32_500,
            _ => 17_000,
        }
    }
}

enum_with_unknown! {
    /// Control mode as reported in the postback (Note 2 of section 2.2).
    #[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
    #[cfg_attr(feature = "defmt", derive(defmt::Format))]
    pub enum ControlMode {
        /// 1: full lock (controllable speed).
        FullLock = 1,
        /// 2: heading follow.
        #[default]
        HeadingFollow = 2,
        /// 3: lock (controllable angle).
        Lock = 3,
    }
}

impl ControlMode {
    /// A stable snake_case name (`full_lock`, `heading_follow`, `lock`), or `None` for an
    /// unknown code.
    pub const fn name(self) -> Option<&'static str> {
        match self {
            ControlMode::FullLock => Some("full_lock"),
            ControlMode::HeadingFollow => Some("heading_follow"),
            ControlMode::Lock => Some("lock"),
            ControlMode::Unknown(_) => None,
        }
    }
}

enum_with_unknown! {
    /// What the postback's Data_id says the message carries; another Data_id (newer
    /// firmware) is decoded at the same offsets.
    #[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
    #[cfg_attr(feature = "defmt", derive(defmt::Format))]
    pub enum DataId {
        /// 1: gimbal type, tracking, mode and attitude (the only one the document defines).
        #[default]
        Attitude = 1,
    }
}

/// A zero-copy view over a postback in either form (27 or 32 bytes, or longer).
#[derive(Clone, Copy, Debug)]
pub struct Packet<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Packet<T> {
    /// Wraps `buffer`, checking that it holds at least [`MESSAGE_LEN`] bytes. Header and CRC
    /// are not checked here: see [`Packet::check`].
    pub fn new(buffer: T) -> Result<Self, PostbackError> {
        let len = buffer.as_ref().len();
        if len < MESSAGE_LEN {
            Err(PostbackError::Truncated { len })
        } else {
            Ok(Packet { buffer })
        }
    }

    /// Gives back the buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    fn byte(&self, at: usize) -> u8 {
        self.buffer.as_ref().get(at).copied().unwrap_or(0)
    }

    fn pair(&self, at: core::ops::Range<usize>) -> [u8; 2] {
        self.buffer
            .as_ref()
            .get(at)
            .and_then(|s| s.try_into().ok())
            .unwrap_or([0; 2])
    }

    /// Checks the header and the CRC.
    pub fn check(&self) -> Result<(), PostbackError> {
        let header = self.pair(field::HEADER);
        if header != HEADER {
            return Err(PostbackError::BadHeader { found: header });
        }
        let computed = self.compute_crc();
        let received = self.crc();
        if computed != received {
            return Err(PostbackError::BadCrc { computed, received });
        }
        Ok(())
    }

    /// The length byte (informational).
    pub fn length(&self) -> u8 {
        self.byte(field::LENGTH)
    }

    /// Whether bytes 3..=11 are zero, as documented.
    pub fn reserved_is_zero(&self) -> bool {
        self.buffer
            .as_ref()
            .get(field::RESERVED)
            .is_some_and(|r| r.iter().all(|&b| b == 0))
    }

    /// CMD+DID, documented as `21 FE`.
    pub fn cmd_did(&self) -> [u8; 2] {
        self.pair(field::CMD_DID)
    }

    /// C_ID, documented as `0x0F`.
    pub fn c_id(&self) -> u8 {
        self.byte(field::C_ID)
    }

    /// Data_id.
    pub fn data_id(&self) -> DataId {
        DataId::from_code(self.byte(field::DATA_ID))
    }

    /// Gimbal type.
    pub fn gimbal_type(&self) -> GimbalType {
        GimbalType::from_code(self.byte(field::GIMBAL_TYPE))
    }

    /// The raw tracking flag byte (non-zero means tracking).
    pub fn tracking_flag(&self) -> u8 {
        self.byte(field::TRACKING)
    }

    /// Control mode.
    pub fn control_mode(&self) -> ControlMode {
        ControlMode::from_code(self.byte(field::MODE))
    }

    /// Pitch in 0.01°.
    pub fn pitch(&self) -> i16 {
        i16::from_le_bytes(self.pair(field::PITCH))
    }

    /// Heading in 0.01°.
    pub fn heading(&self) -> u16 {
        u16::from_le_bytes(self.pair(field::HEADING))
    }

    /// Heading motor angle in 0.01°.
    pub fn motor_heading(&self) -> i16 {
        i16::from_le_bytes(self.pair(field::MOTOR))
    }

    /// The CRC carried in the message.
    pub fn crc(&self) -> u16 {
        u16::from_le_bytes(self.pair(field::CRC))
    }

    /// The CRC of bytes 0..=24.
    pub fn compute_crc(&self) -> u16 {
        self.buffer
            .as_ref()
            .get(field::CHECKED)
            .map_or(0, crc::checksum)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Packet<T> {
    fn set_byte(&mut self, at: usize, value: u8) {
        if let Some(b) = self.buffer.as_mut().get_mut(at) {
            *b = value;
        }
    }

    fn set_pair(&mut self, at: core::ops::Range<usize>, value: [u8; 2]) {
        if let Some(b) = self.buffer.as_mut().get_mut(at) {
            b.copy_from_slice(&value);
        }
    }

    /// Writes the CRC of bytes 0..=24 into bytes 25..=26.
    pub fn fill_crc(&mut self) {
        let crc = self.compute_crc();
        self.set_pair(field::CRC, crc.to_le_bytes());
    }
}

/// A decoded postback.
///
/// Angles are kept in the wire's 0.01° units; the `*_deg` methods convert. The fields are
/// what the gimbal reported, not validated against the document's ranges: a gimbal that
/// reports a value outside them is still reporting it.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Postback {
    /// What the message carries.
    pub data_id: DataId,
    /// Gimbal model.
    pub gimbal_type: GimbalType,
    /// Whether the gimbal is tracking a target.
    pub tracking: bool,
    /// Control mode.
    pub mode: ControlMode,
    /// Pitch in 0.01°, [-11000, 6000] (down is negative).
    pub pitch: i16,
    /// Heading in 0.01°, [0, 36000].
    pub heading: u16,
    /// Heading motor angle in 0.01°, [-17000, 17000] ([-32500, 32500] on the 3.5× model).
    pub motor_heading: i16,
}

impl Default for Postback {
    /// An X30 in heading-follow mode, level, heading 0.
    fn default() -> Self {
        Postback {
            data_id: DataId::Attitude,
            gimbal_type: GimbalType::X30,
            tracking: false,
            mode: ControlMode::HeadingFollow,
            pitch: 0,
            heading: 0,
            motor_heading: 0,
        }
    }
}

/// The first 16 bytes of every postback the document describes: header, length byte,
/// nine zeros, CMD+DID, C_ID and Data_id 1.
const PREFIX: [u8; 16] = [
    0xEB,
    0x90,
    LENGTH_BYTE,
    0,
    0,
    0,
    0,
    0,
    0,
    0,
    0,
    0,
    0x21,
    0xFE,
    C_ID,
    0x01,
];

/// [`PREFIX`] as four little-endian words, so that comparing a message's first 16 bytes
/// with it is four word compares (a slice `==` would call `memcmp`).
const PREFIX_WORDS: [u32; 4] = words(&PREFIX);

const fn words(b: &[u8; 16]) -> [u32; 4] {
    let [a0, a1, a2, a3, b0, b1, b2, b3, c0, c1, c2, c3, d0, d1, d2, d3] = *b;
    [
        u32::from_le_bytes([a0, a1, a2, a3]),
        u32::from_le_bytes([b0, b1, b2, b3]),
        u32::from_le_bytes([c0, c1, c2, c3]),
        u32::from_le_bytes([d0, d1, d2, d3]),
    ]
}

/// The CRC state after [`PREFIX`], computed at compile time.
const PREFIX_CRC: u16 = crc::checksum_const(&PREFIX);

/// Decodes a message (either form), checking header and CRC: the fast path of the CAN
/// assembler. The 27 bytes are destructured once, so every field is a known offset and no
/// access is bounds-checked.
///
/// When the first 16 bytes are the documented constant prefix (four word compares), the
/// CRC continues from its precomputed state over the 9 bytes left instead of running over
/// all 25: the same CRC at a third of the cost. Any other prefix takes the full CRC.
#[inline(always)]
pub(crate) fn decode_checked(b: &[u8]) -> Option<Postback> {
    let message: &[u8; MESSAGE_LEN] = b.get(..MESSAGE_LEN)?.try_into().ok()?;
    let [w0, w1, w2, w3] = words(message.first_chunk()?);
    let [q0, q1, q2, q3] = PREFIX_WORDS;
    // Bitwise, not `==` on arrays: LLVM would turn that into a call to `memcmp`.
    let crc = if (w0 ^ q0) | (w1 ^ q1) | (w2 ^ q2) | (w3 ^ q3) == 0 {
        crc::update(PREFIX_CRC, message.get(PREFIX.len()..field::CHECKED.end)?)
    } else {
        if w0 as u16 != u16::from_le_bytes(HEADER) {
            return None;
        }
        crc::checksum(message.get(field::CHECKED)?)
    };
    // Fields are read only once the CRC holds: nothing to keep across the CRC loop.
    let [_, _, _, _, _, _, _, _, _, _, _, _, _, _, _, d, g, t, m, p0, p1, hd0, hd1, m0, m1, c0, c1] =
        *message;
    if crc != u16::from_le_bytes([c0, c1]) {
        return None;
    }
    Some(Postback {
        data_id: DataId::from_code(d),
        gimbal_type: GimbalType::from_code(g),
        tracking: t != 0,
        mode: ControlMode::from_code(m),
        pitch: i16::from_le_bytes([p0, p1]),
        heading: u16::from_le_bytes([hd0, hd1]),
        motor_heading: i16::from_le_bytes([m0, m1]),
    })
}

impl Postback {
    /// Decodes a postback from its 27-byte stream form or 32-byte CAN form, checking the
    /// header and the CRC.
    pub fn parse(bytes: &[u8]) -> Result<Self, PostbackError> {
        if let Some(p) = decode_checked(bytes) {
            return Ok(p);
        }
        // Not a good message: the view says why.
        let packet = Packet::new(bytes)?;
        packet.check()?;
        Ok(Self::from_packet(&packet))
    }

    /// Reads the fields of a packet whose header and CRC the caller has checked.
    pub fn from_packet<T: AsRef<[u8]>>(packet: &Packet<T>) -> Self {
        Postback {
            data_id: packet.data_id(),
            gimbal_type: packet.gimbal_type(),
            tracking: packet.tracking_flag() != 0,
            mode: packet.control_mode(),
            pitch: packet.pitch(),
            heading: packet.heading(),
            motor_heading: packet.motor_heading(),
        }
    }

    /// Writes a complete, valid message (header, length byte, zeros, CMD+DID, C_ID,
    /// fields and CRC) into the first 27 bytes of `packet`; bytes after them are untouched.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, packet: &mut Packet<T>) {
        packet.set_pair(field::HEADER, HEADER);
        packet.set_byte(field::LENGTH, LENGTH_BYTE);
        if let Some(r) = packet.buffer.as_mut().get_mut(field::RESERVED) {
            r.fill(0);
        }
        packet.set_pair(field::CMD_DID, CMD_DID);
        packet.set_byte(field::C_ID, C_ID);
        packet.set_byte(field::DATA_ID, self.data_id.code());
        packet.set_byte(field::GIMBAL_TYPE, self.gimbal_type.code());
        packet.set_byte(field::TRACKING, u8::from(self.tracking));
        packet.set_byte(field::MODE, self.mode.code());
        packet.set_pair(field::PITCH, self.pitch.to_le_bytes());
        packet.set_pair(field::HEADING, self.heading.to_le_bytes());
        packet.set_pair(field::MOTOR, self.motor_heading.to_le_bytes());
        packet.fill_crc();
    }

    /// The 27-byte stream form.
    pub fn to_stream_bytes(&self) -> [u8; MESSAGE_LEN] {
        let mut buf = [0u8; MESSAGE_LEN];
        if let Ok(mut p) = Packet::new(&mut buf[..]) {
            self.emit(&mut p);
        }
        buf
    }

    /// The 32-byte CAN form (27 bytes and 5 of zero padding).
    pub fn to_can_bytes(&self) -> [u8; CAN_LEN] {
        let mut buf = [0u8; CAN_LEN];
        if let Ok(mut p) = Packet::new(&mut buf[..]) {
            self.emit(&mut p);
        }
        buf
    }

    /// The four CAN frames' data, in order, each sent on [`ID`].
    pub fn to_can_frames(&self) -> [[u8; 8]; FRAMES] {
        let bytes = self.to_can_bytes();
        let mut frames = [[0u8; 8]; FRAMES];
        for (frame, chunk) in frames.iter_mut().zip(bytes.chunks_exact(8)) {
            frame.copy_from_slice(chunk);
        }
        frames
    }

    /// Pitch in degrees.
    pub fn pitch_deg(&self) -> f32 {
        f32::from(self.pitch) / 100.0
    }

    /// Heading in degrees.
    pub fn heading_deg(&self) -> f32 {
        f32::from(self.heading) / 100.0
    }

    /// Heading motor angle in degrees.
    pub fn motor_heading_deg(&self) -> f32 {
        f32::from(self.motor_heading) / 100.0
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::wire::crc::tests::crc_fly16;
    use proptest::prelude::*;

    /// A postback built by hand: X30T (2), tracking, lock (3), pitch -45.00° (0xEE6C),
    /// heading 90.00° (0x2328), motor -12.34° (0xFB2E). CRC computed independently with
    /// the document's nibble algorithm.
    pub(crate) fn sample() -> [u8; 32] {
        let mut b = [
            0xEB, 0x90, 0x0C, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x21, 0xFE, 0x0F, 0x01, 0x02, 0x01, 0x03,
            0x6C, 0xEE, 0x28, 0x23, 0x2E, 0xFB, 0, 0, 0, 0, 0, 0, 0,
        ];
        let crc = crc_fly16(&b[..25]);
        b[25] = crc as u8;
        b[26] = (crc >> 8) as u8;
        b
    }

    #[test]
    fn parses_hand_built_sample() {
        let p = Postback::parse(&sample()).unwrap();
        assert_eq!(p.data_id, DataId::Attitude);
        assert_eq!(p.gimbal_type, GimbalType::X30T);
        assert!(p.tracking);
        assert_eq!(p.mode, ControlMode::Lock);
        assert_eq!((p.pitch, p.heading, p.motor_heading), (-4500, 9000, -1234));
        assert_eq!(
            (p.pitch_deg(), p.heading_deg(), p.motor_heading_deg()),
            (-45.0, 90.0, -12.34)
        );
        // The stream form is the first 27 bytes.
        assert_eq!(Postback::parse(&sample()[..27]), Ok(p));
        // Emit gives back the same bytes in both forms.
        assert_eq!(p.to_can_bytes(), sample());
        assert_eq!(p.to_stream_bytes()[..], sample()[..27]);
        let bytes = sample();
        let view = Packet::new(&bytes[..]).unwrap();
        assert_eq!(
            (view.length(), view.cmd_did(), view.c_id()),
            (0x0C, [0x21, 0xFE], 0x0F)
        );
        assert!(view.reserved_is_zero());
        // The view's fields, and a postback read from it, are the sample's.
        assert_eq!(
            (view.data_id(), view.gimbal_type(), view.tracking_flag()),
            (DataId::Attitude, GimbalType::X30T, 1)
        );
        assert_eq!(Postback::from_packet(&view), p);
    }

    #[test]
    fn rejects_truncated_header_and_crc() {
        let s = sample();
        assert_eq!(
            Postback::parse(&s[..26]),
            Err(PostbackError::Truncated { len: 26 })
        );
        let mut bad = s;
        bad[1] = 0x91;
        assert_eq!(
            Postback::parse(&bad),
            Err(PostbackError::BadHeader {
                found: [0xEB, 0x91]
            })
        );
        let mut bad = s;
        bad[20] ^= 0x01;
        assert!(matches!(
            Postback::parse(&bad),
            Err(PostbackError::BadCrc { .. })
        ));
    }

    #[test]
    fn errors_say_what_was_wrong_and_what_was_expected() {
        let text = |e: PostbackError| e.to_string();
        assert_eq!(
            text(PostbackError::Truncated { len: 26 }),
            "postback of 26 bytes is truncated: it needs 27"
        );
        assert_eq!(
            text(PostbackError::BadHeader {
                found: [0xEB, 0x91]
            }),
            "postback header is EB 91, expected EB 90"
        );
        assert_eq!(
            text(PostbackError::BadCrc {
                computed: 0x1234,
                received: 0xABCD
            }),
            "postback CRC is 0xABCD, computed 0x1234"
        );
    }

    #[test]
    fn reserved_bytes_are_zero_only_when_all_nine_are() {
        let good = sample();
        assert!(Packet::new(&good[..]).unwrap().reserved_is_zero());
        for i in 3..=11 {
            let mut b = good;
            b[i] = 0x80;
            assert!(!Packet::new(&b[..]).unwrap().reserved_is_zero(), "byte {i}");
        }
    }

    /// The CRC covers bytes 0..=24 whatever they hold: a message whose first 16 bytes are not
    /// the documented prefix is checked over all of them, never over the prefix it lacks.
    /// Each replaced word shares no bit with the documented word it replaces (a masked
    /// compare would take it for the prefix).
    #[test]
    fn a_message_without_the_documented_prefix_is_checked_over_its_own_bytes() {
        let good = sample();
        let received = u16::from_le_bytes([good[25], good[26]]);

        // CMD+DID, C_ID and Data_id changed (21 FE 0F 01 -> DE 01 F0 FE), the CRC kept.
        let mut b = good;
        b[12..16].copy_from_slice(&[0xDE, 0x01, 0xF0, 0xFE]);
        let computed = crc_fly16(&b[..25]);
        assert_ne!(computed, received);
        assert_eq!(
            Postback::parse(&b),
            Err(PostbackError::BadCrc { computed, received })
        );
        assert_eq!(decode_checked(&b), None);
        // With its own CRC it is a message (Data_id 0xFE, the rest as sent).
        b[25..27].copy_from_slice(&computed.to_le_bytes());
        let expected = Postback {
            data_id: DataId::from_code(0xFE),
            ..Postback::parse(&good).unwrap()
        };
        assert_eq!(Postback::parse(&b), Ok(expected));
        assert_eq!(decode_checked(&b), Some(expected));

        // Header and length byte changed (EB 90 0C 00 -> 14 6F F3 FF): never a message,
        // with the old CRC or its own.
        let mut b = good;
        b[..4].copy_from_slice(&[0x14, 0x6F, 0xF3, 0xFF]);
        let bad_header = Err(PostbackError::BadHeader {
            found: [0x14, 0x6F],
        });
        assert_eq!(Postback::parse(&b), bad_header);
        assert_eq!(decode_checked(&b), None);
        let own = crc_fly16(&b[..25]).to_le_bytes();
        b[25..27].copy_from_slice(&own);
        assert_eq!(Postback::parse(&b), bad_header);
        assert_eq!(decode_checked(&b), None);
    }

    #[test]
    fn unknown_codes_survive() {
        let p = Postback {
            data_id: DataId::Unknown(0x02),
            gimbal_type: GimbalType::Unknown(0x42),
            mode: ControlMode::Unknown(9),
            ..Postback::default()
        };
        let back = Postback::parse(&p.to_can_bytes()).unwrap();
        assert_eq!(back, p);
        assert_eq!(back.gimbal_type.model_name(), None);
        assert_eq!(back.mode.name(), None);
        for code in 1..=7 {
            assert!(GimbalType::from_code(code).model_name().is_some());
            assert_eq!(GimbalType::from_code(code).code(), code);
        }
        assert_eq!(ControlMode::from_code(1).name(), Some("full_lock"));
        assert_eq!(ControlMode::from_code(2).name(), Some("heading_follow"));
        assert_eq!(ControlMode::from_code(3).name(), Some("lock"));
    }

    #[test]
    fn every_single_and_double_bit_flip_is_rejected() {
        let good = sample();
        let bits = MESSAGE_LEN * 8;
        for i in 0..bits {
            let mut one = good;
            one[i / 8] ^= 1 << (i % 8);
            assert!(Postback::parse(&one[..MESSAGE_LEN]).is_err(), "bit {i}");
            for j in (i + 1)..bits {
                let mut two = one;
                two[j / 8] ^= 1 << (j % 8);
                assert!(
                    Postback::parse(&two[..MESSAGE_LEN]).is_err(),
                    "bits {i} {j}"
                );
            }
        }
    }

    pub(crate) fn arb_postback() -> impl Strategy<Value = Postback> {
        (
            any::<u8>(),
            any::<u8>(),
            any::<bool>(),
            any::<u8>(),
            any::<i16>(),
            any::<u16>(),
            any::<i16>(),
        )
            .prop_map(
                |(d, g, tracking, m, pitch, heading, motor_heading)| Postback {
                    data_id: DataId::from_code(d),
                    gimbal_type: GimbalType::from_code(g),
                    tracking,
                    mode: ControlMode::from_code(m),
                    pitch,
                    heading,
                    motor_heading,
                },
            )
    }

    proptest! {
        #[test]
        fn emit_parse_round_trip(p in arb_postback()) {
            let can = p.to_can_bytes();
            prop_assert_eq!(&can[27..], &[0u8; 5]);
            prop_assert_eq!(crc_fly16(&can[..25]).to_le_bytes(), [can[25], can[26]]);
            prop_assert_eq!(Postback::parse(&can), Ok(p));
            prop_assert_eq!(Postback::parse(&p.to_stream_bytes()), Ok(p));
        }

        /// The fast path (`decode_checked`, used by `parse` and the assembler) and the view's
        /// header and CRC check agree on any bytes, good or not.
        #[test]
        fn fast_path_agrees_with_parse(p in arb_postback(), documented: bool, flips in proptest::collection::vec(0usize..256, 0..3), len in 0usize..40) {
            // Half the messages carry the documented prefix (Data_id 1): the precomputed-CRC path.
            let p = if documented { Postback { data_id: DataId::Attitude, ..p } } else { p };
            let mut b = p.to_can_bytes().to_vec();
            for f in flips {
                b[f / 8] ^= 1 << (f % 8);
            }
            b.resize(len.max(20), 0x5A);
            let view = Packet::new(&b[..]).and_then(|v| v.check().map(|()| Postback::from_packet(&v)));
            prop_assert_eq!(decode_checked(&b), view.ok());
            prop_assert_eq!(Postback::parse(&b), view);
        }

        #[test]
        fn parse_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..40)) {
            let _ = Postback::parse(&bytes);
        }
    }
}
