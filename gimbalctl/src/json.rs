//! A small, allocation-free JSON object writer for the hot decode path.
//!
//! `decode` writes one object per message, millions of them for a long log, so objects are
//! appended to a reused byte buffer with hand-written integer and fixed-point formatting
//! instead of building `serde_json::Value`s. Strings go through `serde_json` for escaping.
//!
//! Physical values are written from their integer wire units (`-4567` centidegrees is
//! `-45.67`), so they are exact decimals with no floating-point noise.

/// Writes the decimal digits of `v`.
#[inline]
pub fn push_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(itoa::Buffer::new().format(v).as_bytes());
}

/// Writes `v` as a JSON integer.
#[inline]
pub fn push_i64(out: &mut Vec<u8>, v: i64) {
    if v < 0 {
        out.push(b'-');
    }
    push_u64(out, v.unsigned_abs());
}

/// Writes `value / 10^decimals` as the shortest exact decimal (`-4560, 2` is `-45.6`,
/// `-4500, 2` is `-45`), by placing the decimal point in the digits of `|value|`.
#[inline]
pub fn push_fixed(out: &mut Vec<u8>, value: i64, decimals: u32) {
    if value < 0 {
        out.push(b'-');
    }
    let mut buf = itoa::Buffer::new();
    let digits = buf.format(value.unsigned_abs()).as_bytes();
    let point = usize::try_from(decimals).unwrap_or(usize::MAX);
    let (int, frac): (&[u8], &[u8]) = match digits.len().checked_sub(point) {
        Some(n) if n > 0 => digits.split_at(n),
        _ => (b"0", digits),
    };
    out.extend_from_slice(int);
    let significant = frac.iter().rposition(|&b| b != b'0').map_or(0, |i| i + 1);
    if significant > 0 {
        out.push(b'.');
        // Leading zeros of a fraction shorter than `decimals` digits (`5, 2` is `0.05`).
        let pad = point.saturating_sub(frac.len());
        out.resize(out.len() + pad, b'0');
        out.extend_from_slice(&frac[..significant]);
    }
}

/// Whether `s` can be written between quotes as it is.
fn is_plain(s: &str) -> bool {
    s.bytes()
        .all(|b| b >= 0x20 && b != b'"' && b != b'\\' && b < 0x7F)
}

/// Writes `s` as a JSON string (quoted and escaped).
#[inline]
pub fn push_str(out: &mut Vec<u8>, s: &str) {
    if is_plain(s) {
        out.push(b'"');
        out.extend_from_slice(s.as_bytes());
        out.push(b'"');
    } else {
        // Writing into a Vec cannot fail.
        let _ = serde_json::to_writer(&mut *out, s);
    }
}

/// Writes a JSON number from a log timestamp's text (`digits[.digits]`), dropping the
/// leading zeros JSON does not allow (`000.5` is `0.5`). The caller has checked the form.
pub fn push_timestamp(out: &mut Vec<u8>, text: &[u8]) {
    let int_len = text.iter().position(|&b| b == b'.').unwrap_or(text.len());
    let mut skip = 0;
    while skip + 1 < int_len && text[skip] == b'0' {
        skip += 1;
    }
    out.extend_from_slice(&text[skip..]);
    if text.last() == Some(&b'.') {
        out.push(b'0');
    }
}

/// An object being written: `{"type":...,"t":...,"id":...` then fields, then [`Obj::end`].
pub struct Obj<'a> {
    out: &'a mut Vec<u8>,
}

impl<'a> Obj<'a> {
    /// Starts an object with the three fields every decoded message has. `kind` (like every
    /// key) is a literal of the program that needs no escaping, so it is written as it is.
    #[inline]
    pub fn start(out: &'a mut Vec<u8>, kind: &str, t: Option<&[u8]>, id: Option<u32>) -> Self {
        debug_assert!(is_plain(kind), "{kind:?}");
        out.extend_from_slice(b"{\"type\":\"");
        out.extend_from_slice(kind.as_bytes());
        out.extend_from_slice(b"\",\"t\":");
        match t {
            Some(t) => push_timestamp(out, t),
            None => out.extend_from_slice(b"null"),
        }
        out.extend_from_slice(b",\"id\":");
        match id {
            Some(id) => push_u64(out, id.into()),
            None => out.extend_from_slice(b"null"),
        }
        Obj { out }
    }

    /// Starts an object with only a `type` field.
    pub fn bare(out: &'a mut Vec<u8>, kind: &str) -> Self {
        debug_assert!(is_plain(kind), "{kind:?}");
        out.extend_from_slice(b"{\"type\":\"");
        out.extend_from_slice(kind.as_bytes());
        out.push(b'"');
        Obj { out }
    }

    #[inline]
    fn key(&mut self, key: &str) -> &mut Vec<u8> {
        debug_assert!(is_plain(key), "{key:?}");
        self.out.extend_from_slice(b",\"");
        self.out.extend_from_slice(key.as_bytes());
        self.out.extend_from_slice(b"\":");
        self.out
    }

    /// An integer field.
    #[inline]
    pub fn int(&mut self, key: &str, v: i64) -> &mut Self {
        push_i64(self.key(key), v);
        self
    }

    /// A fixed-point field: `value / 10^decimals`.
    #[inline]
    pub fn fixed(&mut self, key: &str, value: i64, decimals: u32) -> &mut Self {
        push_fixed(self.key(key), value, decimals);
        self
    }

    /// A string field, or null.
    #[inline]
    pub fn str_or_null(&mut self, key: &str, v: Option<&str>) -> &mut Self {
        let out = self.key(key);
        match v {
            Some(s) => push_str(out, s),
            None => out.extend_from_slice(b"null"),
        }
        self
    }

    /// A string field.
    #[inline]
    pub fn str(&mut self, key: &str, v: &str) -> &mut Self {
        push_str(self.key(key), v);
        self
    }

    /// A boolean field.
    #[inline]
    pub fn bool(&mut self, key: &str, v: bool) -> &mut Self {
        let out = self.key(key);
        out.extend_from_slice(if v { b"true" } else { b"false" });
        self
    }

    /// A field whose value the caller writes next with the returned buffer.
    #[inline]
    pub fn raw(&mut self, key: &str) -> &mut Vec<u8> {
        self.key(key)
    }

    /// Closes the object and ends the line.
    #[inline]
    pub fn end(self) {
        self.out.extend_from_slice(b"}\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixed(v: i64, d: u32) -> String {
        let mut out = Vec::new();
        push_fixed(&mut out, v, d);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn fixed_point() {
        assert_eq!(fixed(-4567, 2), "-45.67");
        assert_eq!(fixed(-4560, 2), "-45.6");
        assert_eq!(fixed(-4500, 2), "-45");
        assert_eq!(fixed(5, 2), "0.05");
        assert_eq!(fixed(-5, 2), "-0.05");
        assert_eq!(fixed(0, 7), "0");
        assert_eq!(fixed(473_977_000, 7), "47.3977");
        assert_eq!(fixed(-1_800_000_000, 7), "-180");
        assert_eq!(fixed(1, 7), "0.0000001");
        assert_eq!(fixed(i64::MIN, 2), "-92233720368547758.08");
        assert_eq!(fixed(12, 0), "12");
    }

    /// The digit-placing `push_fixed` against the arithmetic it replaced, on edge values and
    /// a fixed-seed sweep, for every number of decimals the tool uses and more.
    #[test]
    fn fixed_point_matches_arithmetic() {
        fn reference(value: i64, decimals: u32) -> String {
            let scale = 10u64.pow(decimals);
            let abs = value.unsigned_abs();
            let mut s = String::new();
            if value < 0 {
                s.push('-');
            }
            s += &(abs / scale).to_string();
            let mut frac = abs % scale;
            if frac == 0 {
                return s;
            }
            let mut digits = decimals as usize;
            while frac.is_multiple_of(10) {
                frac /= 10;
                digits -= 1;
            }
            s + &format!(".{frac:0digits$}")
        }
        let mut values = vec![
            0,
            1,
            -1,
            9,
            10,
            99,
            100,
            101,
            i64::MAX,
            i64::MIN + 1,
            i64::MIN,
        ];
        let mut seed = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..20_000 {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            // Every magnitude, with runs of zeros at the end now and then.
            let v = (seed as i64) >> (seed % 64);
            values.push(v);
            values.push(v / 1000 * 1000);
        }
        for &v in &values {
            for d in 0..=18 {
                assert_eq!(fixed(v, d), reference(v, d), "{v} / 10^{d}");
            }
        }
    }

    #[test]
    fn timestamps() {
        let ts = |s: &str| {
            let mut out = Vec::new();
            push_timestamp(&mut out, s.as_bytes());
            String::from_utf8(out).unwrap()
        };
        assert_eq!(ts("1700000000.123456"), "1700000000.123456");
        assert_eq!(ts("000.000123"), "0.000123");
        assert_eq!(ts("0"), "0");
        assert_eq!(ts("007"), "7");
        assert_eq!(ts("5."), "5.0");
    }

    #[test]
    fn strings_are_escaped() {
        let mut out = Vec::new();
        push_str(&mut out, "a\"b\\c\u{1}");
        assert_eq!(String::from_utf8(out).unwrap(), r#""a\"b\\c\u0001""#);
    }
}
