//! The three text forms a CAN log line comes in: candump `-L` (`(SECS.FRAC) IFACE ID#DATA`),
//! cansend's `ID#DATA`, and candump's default screen form (`IFACE ID [LEN] BYTES`, with or
//! without a leading `(timestamp)`). [`parse_line`] takes any of them; the `-L` form, which
//! nearly every line of a long log has, on a one-pass fast path.
//!
//! As can-utils writes them (`lib.c`, `lib.h`): a classic frame's length is one digit in
//! the screen form (`[8]`), or its raw DLC in hex with `-8` (`{F}`: 9 to F carry 8 bytes),
//! and an 8-byte frame's raw DLC follows its data as `_9` to `_F` in the compact form. CAN
//! FD frames have a two-digit length (`[08]`) or `##` in the compact form, CAN XL frames a
//! four-digit one (`[0064]`) or `VCIDPRIO#FLAGS:SDT:AF#DATA`: both are foreign to the
//! protocol, which is classic CAN.

use idu_gimbal::wire::ids;
use idu_gimbal::Instant;

/// Hex digit values; 0xFF for anything else.
const HEX: [u8; 256] = {
    let mut t = [0xFFu8; 256];
    let mut i = 0;
    while i < 10 {
        t[b'0' as usize + i] = i as u8;
        i += 1;
    }
    let mut i = 0;
    while i < 6 {
        t[b'a' as usize + i] = 10 + i as u8;
        t[b'A' as usize + i] = 10 + i as u8;
        i += 1;
    }
    t
};

fn hex_u32(s: &[u8]) -> Option<u32> {
    if s.is_empty() || s.len() > 8 {
        return None;
    }
    let mut v = 0u32;
    for &b in s {
        let d = HEX[b as usize];
        if d == 0xFF {
            return None;
        }
        v = (v << 4) | u32::from(d);
    }
    Some(v)
}

fn hex_byte(hi: u8, lo: u8) -> Option<u8> {
    let (h, l) = (HEX[hi as usize], HEX[lo as usize]);
    if h == 0xFF || l == 0xFF {
        None
    } else {
        Some((h << 4) | l)
    }
}

fn is_space(b: u8) -> bool {
    b == b' ' || b == b'\t' || b == b'\r'
}

fn trim(mut s: &[u8]) -> &[u8] {
    while let [first, rest @ ..] = s {
        if !is_space(*first) {
            break;
        }
        s = rest;
    }
    while let [rest @ .., last] = s {
        if !is_space(*last) {
            break;
        }
        s = rest;
    }
    s
}

/// Whitespace-separated tokens.
struct Tokens<'a>(&'a [u8]);

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    fn next(&mut self) -> Option<&'a [u8]> {
        let s = self.0;
        let start = s.iter().position(|&b| !is_space(b))?;
        let s = &s[start..];
        let end = s.iter().position(|&b| is_space(b)).unwrap_or(s.len());
        self.0 = &s[end..];
        Some(&s[..end])
    }
}

/// `digits[.digits]`: a timestamp that is a number.
fn is_number(s: &[u8]) -> bool {
    let int = s.iter().position(|&b| b == b'.').unwrap_or(s.len());
    let (i, f) = s.split_at(int);
    !i.is_empty()
        && i.iter().all(u8::is_ascii_digit)
        && (f.is_empty() || (f.len() > 1 && f[1..].iter().all(u8::is_ascii_digit)))
}

/// A log timestamp in seconds, as a wrapping millisecond tick for the assembler.
pub(super) fn timestamp_millis(ts: &[u8]) -> Instant {
    let mut secs = 0u64;
    let mut it = ts.iter();
    for &b in it.by_ref() {
        if b == b'.' {
            break;
        }
        secs = secs.wrapping_mul(10).wrapping_add(u64::from(b - b'0'));
    }
    let mut ms = 0u64;
    for _ in 0..3 {
        let d = it.next().map_or(0, |&b| u64::from(b - b'0'));
        ms = ms * 10 + d;
    }
    Instant::from_millis(secs.wrapping_mul(1000).wrapping_add(ms) as u32)
}

/// One log line.
#[derive(Debug, PartialEq, Eq)]
pub(super) enum Line<'a> {
    /// Empty or whitespace only: ignored.
    Blank,
    /// Not a CAN frame in any of the three forms.
    Malformed,
    /// A frame the protocol cannot own: standard ID, remote, CAN FD, CAN XL or error frame.
    Foreign,
    /// A classic data frame with an extended ID.
    Frame {
        /// The timestamp's text, when the line has a numeric one.
        ts: Option<&'a [u8]>,
        /// The 29-bit ID.
        id: u32,
        /// The data bytes (`len` of them are valid).
        data: [u8; 8],
        /// The DLC, 0..=8.
        len: usize,
    },
}

/// `ID#DATA` (cansend and candump `-L` form).
fn parse_frame_token<'a>(tok: &[u8], ts: Option<&'a [u8]>) -> Line<'a> {
    let Some(hash) = tok.iter().position(|&b| b == b'#') else {
        return Line::Malformed;
    };
    let (id_text, data_text) = (&tok[..hash], &tok[hash + 1..]);
    let Some(id) = hex_u32(id_text) else {
        return Line::Malformed;
    };
    match id_text.len() {
        3 => return Line::Foreign,
        5 if is_xl_header(data_text) => return Line::Foreign,
        8 => {}
        _ => return Line::Malformed,
    }
    if id > ids::EXTENDED_MAX {
        // Error frames carry flags above the 29 ID bits.
        return Line::Foreign;
    }
    match data_text.first() {
        Some(b'#') | Some(b'R') | Some(b'r') => return Line::Foreign,
        _ => {}
    }
    let mut data = [0u8; 8];
    let mut len = 0;
    let mut rest = data_text;
    loop {
        match rest {
            [] => break,
            [b'.', tail @ ..] => rest = tail,
            // An 8-byte frame's raw DLC, 9 to F: the data is all there.
            [b'_', dlc] if len == 8 && matches!(HEX[usize::from(*dlc)], 9..=15) => break,
            [hi, lo, tail @ ..] => {
                let Some(b) = hex_byte(*hi, *lo) else {
                    return Line::Malformed;
                };
                let Some(slot) = data.get_mut(len) else {
                    return Line::Malformed;
                };
                *slot = b;
                len += 1;
                rest = tail;
            }
            [_] => return Line::Malformed,
        }
    }
    Line::Frame { ts, id, data, len }
}

/// `FLAGS:SDT:AF#`, what follows a CAN XL frame's `VCIDPRIO#`: two, two and eight hex digits.
fn is_xl_header(s: &[u8]) -> bool {
    match s.get(..15) {
        Some([f0, f1, b':', t0, t1, b':', af @ .., b'#']) => {
            hex_u32(&[*f0, *f1, *t0, *t1]).is_some() && hex_u32(af).is_some()
        }
        _ => false,
    }
}

/// Parses a line in candump `-L` form, cansend form or candump's default screen form (with
/// or without a leading `(timestamp)`).
pub(super) fn parse_line(line: &[u8]) -> Line<'_> {
    match parse_candump_l(line) {
        Some(frame) => frame,
        None => parse_line_general(line),
    }
}

/// The fast path for the form nearly every line of a long log has: candump `-L`'s
/// `(SECS.FRAC) IFACE IIIIIIII#DDDD...`, with single spaces, an extended ID of at most 29
/// bits, whole bytes of data without `.` separators, and nothing after them. It gives
/// exactly what [`parse_line_general`] gives for such a line (a unit test compares the
/// two on many mutated lines), in one pass; anything else is `None`, for the general path.
fn parse_candump_l(line: &[u8]) -> Option<Line<'_>> {
    let rest = line.strip_prefix(b"(")?;
    // The timestamp: digits, optionally `.` and at least one more digit, then `) `.
    let int = rest.iter().take_while(|b| b.is_ascii_digit()).count();
    if int == 0 {
        return None;
    }
    let mut end = int;
    if rest.get(int) == Some(&b'.') {
        let frac = rest
            .get(int + 1..)?
            .iter()
            .take_while(|b| b.is_ascii_digit())
            .count();
        if frac == 0 {
            return None;
        }
        end = int + 1 + frac;
    }
    let (ts, rest) = rest.split_at_checked(end)?;
    let rest = rest.strip_prefix(b") ")?;
    // The interface: one token (no `#`, which would make it the frame token), one space.
    let iface = rest.iter().take_while(|&&b| b != b' ').count();
    let (iface, tok) = rest.split_at_checked(iface)?;
    let tok = tok.strip_prefix(b" ")?;
    if iface.is_empty() || iface.iter().any(|&b| b == b'#' || is_space(b)) {
        return None;
    }
    // `IIIIIIII#` then pairs of hex digits to the end of the line.
    let (id_text, data_text) = tok.split_at_checked(8)?;
    let data_text = data_text.strip_prefix(b"#")?;
    let mut id = 0u32;
    for &b in id_text {
        let d = HEX[usize::from(b)];
        if d == 0xFF {
            return None;
        }
        id = (id << 4) | u32::from(d);
    }
    if id > ids::EXTENDED_MAX || data_text.len() > 16 || data_text.len() % 2 != 0 {
        return None;
    }
    let mut data = [0u8; 8];
    for (slot, pair) in data.iter_mut().zip(data_text.chunks_exact(2)) {
        if let [hi, lo] = *pair {
            *slot = hex_byte(hi, lo)?;
        }
    }
    Some(Line::Frame {
        ts: Some(ts),
        id,
        data,
        len: data_text.len() / 2,
    })
}

/// [`parse_line`] for any line.
fn parse_line_general(line: &[u8]) -> Line<'_> {
    let mut rest = trim(line);
    if rest.is_empty() {
        return Line::Blank;
    }
    let mut ts = None;
    if rest[0] == b'(' {
        let Some(close) = rest.iter().position(|&b| b == b')') else {
            return Line::Malformed;
        };
        let inner = &rest[1..close];
        if is_number(inner) {
            ts = Some(inner);
        }
        rest = &rest[close + 1..];
    }
    let mut tokens = Tokens(rest);
    let Some(first) = tokens.next() else {
        return Line::Malformed;
    };
    if first.contains(&b'#') {
        return parse_frame_token(first, ts);
    }
    // `first` is the interface.
    let Some(second) = tokens.next() else {
        return Line::Malformed;
    };
    if second.contains(&b'#') {
        return parse_frame_token(second, ts);
    }
    // Screen form: `can0  030F0001   [8]  EB 90 ...`, possibly with `-x` flags
    // (`TX - -`) between the interface and the ID.
    let mut id_text = second;
    let mut len_text = None;
    for _ in 0..5 {
        let Some(tok) = tokens.next() else {
            return Line::Malformed;
        };
        if let [open, inner @ .., close] = tok {
            if !inner.is_empty() && matches!((open, close), (b'[', b']') | (b'{', b'}')) {
                len_text = Some((*open, inner));
                break;
            }
        }
        id_text = tok;
    }
    let Some(len_text) = len_text else {
        return Line::Malformed;
    };
    let Some(id) = hex_u32(id_text) else {
        return Line::Malformed;
    };
    let dlc = match len_text {
        (b'[', [d]) if d.is_ascii_digit() => Some(usize::from(d - b'0')),
        // `-8`: the raw DLC in hex; 9 to F carry 8 bytes.
        (b'{', [d]) => match HEX[usize::from(*d)] {
            0xFF => return Line::Malformed,
            raw => Some(usize::from(raw).min(8)),
        },
        // CAN FD (two digits) and CAN XL (four).
        (b'[', digits)
            if matches!(digits.len(), 2 | 4) && digits.iter().all(u8::is_ascii_digit) =>
        {
            None
        }
        _ => return Line::Malformed,
    };
    match id_text.len() {
        1..=3 => return Line::Foreign,
        8 => {}
        _ => return Line::Malformed,
    }
    let Some(dlc) = dlc.filter(|&d| d <= 8 && id <= ids::EXTENDED_MAX) else {
        return Line::Foreign;
    };
    let mut data = [0u8; 8];
    for slot in data.iter_mut().take(dlc) {
        match tokens.next() {
            Some([hi, lo]) => match hex_byte(*hi, *lo) {
                Some(b) => *slot = b,
                None => return Line::Malformed,
            },
            Some(b"remote") => return Line::Foreign,
            _ => return Line::Malformed,
        }
    }
    if dlc == 0 && tokens.next() == Some(b"remote") {
        return Line::Foreign;
    }
    Line::Frame {
        ts,
        id,
        data,
        len: dlc,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(ts: Option<&str>, id: u32, bytes: &[u8]) -> Line<'static> {
        let mut data = [0u8; 8];
        data[..bytes.len()].copy_from_slice(bytes);
        Line::Frame {
            ts: ts
                .map(|s| -> &'static [u8] { Box::leak(s.as_bytes().to_vec().into_boxed_slice()) }),
            id,
            data,
            len: bytes.len(),
        }
    }

    /// Asserts that each of `lines` parses as `expected`.
    fn each_parses_as(expected: &Line<'_>, lines: &[&[u8]]) {
        for line in lines {
            assert_eq!(
                &parse_line(line),
                expected,
                "{}",
                String::from_utf8_lossy(line)
            );
        }
    }

    #[test]
    fn three_forms() {
        let bytes = [0xEB, 0x90, 0x0C, 0, 0, 0, 0, 0];
        assert_eq!(
            parse_line(b"(1700000000.123456) can0 030F0001#EB900C0000000000"),
            frame(Some("1700000000.123456"), 0x030F0001, &bytes)
        );
        assert_eq!(
            parse_line(b"030F0001#EB900C0000000000\r"),
            frame(None, 0x030F0001, &bytes)
        );
        assert_eq!(
            parse_line(b"  can0  030F0001   [8]  EB 90 0C 00 00 00 00 00"),
            frame(None, 0x030F0001, &bytes)
        );
        assert_eq!(
            parse_line(
                b" (1700000000.5)  can0  030F0001   [8]  EB 90 0C 00 00 00 00 00  '........'"
            ),
            frame(Some("1700000000.5"), 0x030F0001, &bytes)
        );
        assert_eq!(
            parse_line(b"  can0  TX - -  030F0001   [8]  EB 90 0C 00 00 00 00 00"),
            frame(None, 0x030F0001, &bytes)
        );
        assert_eq!(
            parse_line(b"00000F01#0F07"),
            frame(None, 0xF01, &[0x0F, 0x07])
        );
        assert_eq!(
            parse_line(b"00000F01#0F.07"),
            frame(None, 0xF01, &[0x0F, 0x07])
        );
        assert_eq!(parse_line(b"00000F01#"), frame(None, 0xF01, &[]));
    }

    /// Hex digits in either case, in the ID and the data, in every form.
    #[test]
    fn hex_in_either_case() {
        let bytes = [0xAB, 0xCD, 0xEF, 0x0F, 0x9A, 0xBC, 0xDE, 0xF0];
        let expected = frame(None, 0x1ABCDEF0, &bytes);
        each_parses_as(
            &expected,
            &[
                b"1abcdef0#abcdef0f9abcdef0",
                b"1ABCDEF0#ABCDEF0F9ABCDEF0",
                b"1aBcDeF0#aBcDeF0f9AbCdEf0",
                b"  can0  1abcdef0   [8]  ab cd ef 0f 9a bc de f0",
                b"  can0  1ABCDEF0   [8]  AB CD EF 0F 9A BC DE F0",
            ],
        );
        let timestamped = frame(Some("1.5"), 0x1ABCDEF0, &bytes);
        assert_eq!(
            parse_line(b"(1.5) can0 1abcdef0#abcdef0f9abcdef0"),
            timestamped
        );
        assert_eq!(
            parse_line(b"(1.5) can0 1ABCDEF0#ABCDEF0F9ABCDEF0"),
            timestamped
        );
    }

    /// Every byte that is no hex digit (`:` and `g` sit next to the digits and the letters)
    /// makes the ID or the data malformed, in every form.
    #[test]
    fn no_other_byte_is_a_hex_digit() {
        for b in 0..=255u8 {
            if b.is_ascii_hexdigit() {
                continue;
            }
            let b = char::from(b);
            for line in [
                format!("0000{b}F01#0F07"),
                format!("00000F01#0{b}07"),
                format!("(1.5) can0 00000F0{b}#0F07"),
                format!("(1.5) can0 00000F01#0{b}07"),
                format!("  can0  00000F01   [2]  0F {b}7"),
                format!("  can0  00000F{b}1   [2]  0F 07"),
            ] {
                let line = line.as_bytes();
                if let Line::Frame { .. } = parse_line(line) {
                    panic!("{:?} parsed as a frame", String::from_utf8_lossy(line));
                }
            }
        }
    }

    /// A classic frame's raw DLC as can-utils writes it: after 8 bytes of data (`_9` to
    /// `_F`) in the compact form, in braces (`-8`) in the screen form, where 9 to F carry 8
    /// bytes.
    #[test]
    fn raw_dlc() {
        let eight = [1, 2, 3, 4, 5, 6, 7, 8];
        let f01 = |bytes: &[u8]| frame(None, 0xF01, bytes);
        assert_eq!(parse_line(b"00000F01#0102030405060708_9"), f01(&eight));
        assert_eq!(parse_line(b"00000F01#0102030405060708_f"), f01(&eight));
        assert_eq!(
            parse_line(b"(1.5) can0 00000F01#0102030405060708_E"),
            frame(Some("1.5"), 0xF01, &eight)
        );
        each_parses_as(
            &Line::Malformed,
            &[
                b"00000F01#0102030405060708_8",
                b"00000F01#0102030405060708_G",
                b"00000F01#0102030405060708_",
                b"00000F01#0102030405060708_EE",
                b"00000F01#01020304050607_E",
            ],
        );
        assert_eq!(
            parse_line(b"  can0  00000F01   {8}  01 02 03 04 05 06 07 08"),
            f01(&eight)
        );
        assert_eq!(
            parse_line(b"  can0  00000F01   {F}  01 02 03 04 05 06 07 08"),
            f01(&eight)
        );
        assert_eq!(parse_line(b"  can0  00000F01   {2}  01 02"), f01(&[1, 2]));
        // What follows the data is not read (candump `-a` writes it as ASCII).
        assert_eq!(
            parse_line(b"  can0  00000F01   [2]  01 02  remote"),
            f01(&[1, 2])
        );
        assert_eq!(parse_line(b"  can0  00000F01   {}  01 02"), Line::Malformed);
        assert_eq!(
            parse_line(b"  can0  00000F01   {x}  01 02 03 04 05 06 07 08"),
            Line::Malformed
        );
    }

    /// CAN FD and CAN XL frames, in both forms, are foreign: the protocol is classic CAN.
    /// A two-digit length is CAN FD's even when it is 8 or less.
    #[test]
    fn can_fd_and_xl_are_foreign() {
        each_parses_as(
            &Line::Foreign,
            &[
                b"  can0  00000F01  [08]  01 02 03 04 05 06 07 08",
                b"  can0  00000F01  [00]",
                b"  can0  00000F01  [64]  01 02",
                b"  can0  123  [12]  01 02 03 04 05 06 07 08 09 0A 0B 0C",
                b"  can0  123 [0064] (00|11:22:12345678) 01 02 03",
                b"  can0  00000F01  [0008]  01 02 03 04 05 06 07 08",
                b"00000F01##00102",
                b"45123#81:00:12345678#11223344.556677",
                b"(1.5) can0 45123#81:00:12345678#11",
                // Not CAN FD or XL, but not the protocol's either: a classic length past 8,
                // an error frame's flags above the ID bits, a remote request.
                b"  can0  00000F01  [9]  01 02 03 04 05 06 07 08 09",
                b"  can0  20000004  [8]  00 00 00 00 00 00 00 00",
                b"  can0  00000F01   [3]  remote request",
            ],
        );
        each_parses_as(
            &Line::Malformed,
            &[
                // Three digits is no length can-utils writes, nor a non-digit.
                b"  can0  00000F01  [008]  01 02 03 04 05 06 07 08",
                b"  can0  00000F01  [0x]  01",
                b"  can0  00000F01  [x]  01",
                // A token closed by `]` alone is no length: here the ID is then `0F`.
                b"  can0  00000F01  x1]  0F",
                // A CAN XL header that is not one.
                b"45123#81:00:1234567#11",
                b"45123#81-00:12345678#11",
                b"45123#8G:00:12345678#11",
                b"45123#81:00:12345678",
            ],
        );
    }

    #[test]
    fn foreign_and_malformed() {
        assert_eq!(parse_line(b""), Line::Blank);
        assert_eq!(parse_line(b"   \r"), Line::Blank);
        assert_eq!(parse_line(b"123#DEADBEEF"), Line::Foreign);
        assert_eq!(parse_line(b"00000F01#R"), Line::Foreign);
        assert_eq!(parse_line(b"00000F01##1112233"), Line::Foreign);
        assert_eq!(parse_line(b"20000004#0000000000000000"), Line::Foreign);
        assert_eq!(parse_line(b"  can0  123   [2]  01 02"), Line::Foreign);
        assert_eq!(
            parse_line(b"  can0  00000F01   [0]  remote request"),
            Line::Foreign
        );
        assert_eq!(parse_line(b"  can0  00000F01  [12]  01 02"), Line::Foreign);
        assert_eq!(parse_line(b"hello world"), Line::Malformed);
        assert_eq!(parse_line(b"00000F01#0F0"), Line::Malformed);
        assert_eq!(parse_line(b"00000F01#0F07XX"), Line::Malformed);
        assert_eq!(parse_line(b"00000F01#000000000000000000"), Line::Malformed);
        assert_eq!(parse_line(b"0F01#00"), Line::Malformed);
        assert_eq!(parse_line(b"(12.5 can0 00000F01#00"), Line::Malformed);
        assert_eq!(
            parse_line(b"  can0  00000F01   [8]  0F 07 00"),
            Line::Malformed
        );
        assert_eq!(parse_line(b"  can0  00000F01   [x]  0F"), Line::Malformed);
    }

    /// The fast path agrees with the general parser on every line it takes, and takes the
    /// canonical `-L` lines: checked on canonical lines and on many mutations of them
    /// (bytes replaced, inserted and deleted from an alphabet of the characters that
    /// matter), from a fixed-seed generator.
    #[test]
    fn fast_path_matches_general_parser() {
        let base: [&[u8]; 6] = [
            b"(1700000000.123456) can0 0000FF13#610F0CC63BCC0000",
            b"(1700000000.5) vcan12 00000F01#0F07",
            b"(0000000001.000001) can0 030F0001#",
            b"(17) can0 1FFFFFFF#0011223344556677",
            b"(1700000000.123456) can0 00000f01#0f08023efe000000",
            b"(1700000000.123456) any 20000000#00",
        ];
        let alphabet = b"0123456789abcdefABCDEF#.()[]{}_: \t\rRrxgG-";
        let mut seed = 0x2545_F491_4F6C_DD1Du64;
        let mut next = |n: usize| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % n as u64) as usize
        };
        let mut taken = 0;
        for line in base {
            let fast = parse_candump_l(line);
            assert_eq!(
                fast.is_some(),
                !line.starts_with(b"(1700000000.123456) any")
            );
            for _ in 0..20_000 {
                let mut l = line.to_vec();
                for _ in 0..1 + next(3) {
                    let at = next(l.len() + 1);
                    let b = alphabet[next(alphabet.len())];
                    match next(3) {
                        0 if at < l.len() => l[at] = b,
                        1 if at < l.len() => {
                            l.remove(at);
                        }
                        _ => l.insert(at, b),
                    }
                }
                if let Some(fast) = parse_candump_l(&l) {
                    taken += 1;
                    assert_eq!(
                        fast,
                        parse_line_general(&l),
                        "{}",
                        String::from_utf8_lossy(&l)
                    );
                }
            }
        }
        // The mutations reach both sides of the fast path's checks.
        assert!(taken > 10_000 && taken < 100_000, "{taken}");
    }

    #[test]
    fn timestamps() {
        assert_eq!(
            timestamp_millis(b"1700000000.123456").as_millis(),
            (1_700_000_000_123u64 as u32)
        );
        assert_eq!(timestamp_millis(b"5").as_millis(), 5000);
        assert_eq!(timestamp_millis(b"5.1").as_millis(), 5100);
        assert!(is_number(b"000.000123"));
        assert!(!is_number(b"5."));
        assert!(!is_number(b".5"));
        assert!(!is_number(b"2023-11-14 22:13:20.1"));
    }
}
