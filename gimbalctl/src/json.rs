//! A small, allocation-free JSON object writer for the hot decode path.
//!
//! `decode` writes one object per message, millions of them for a long log, so objects are
//! appended to a reused byte buffer with hand-written integer and fixed-point formatting
//! instead of building `serde_json::Value`s. Strings go through `serde_json` for escaping.
//!
//! Physical values are written from their integer wire units (`-4567` centidegrees is
//! `-45.67`), so they are exact decimals with no floating-point noise.

/// Writes the decimal digits of `v`.
pub fn push_u64(out: &mut Vec<u8>, mut v: u64) {
    let mut buf = [0u8; 20];
    let mut i = buf.len();
    loop {
        i -= 1;
        buf[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    out.extend_from_slice(&buf[i..]);
}

/// Writes `v` as a JSON integer.
pub fn push_i64(out: &mut Vec<u8>, v: i64) {
    if v < 0 {
        out.push(b'-');
    }
    push_u64(out, v.unsigned_abs());
}

/// Writes `value / 10^decimals` as the shortest exact decimal (`-4560, 2` is `-45.6`,
/// `-4500, 2` is `-45`).
pub fn push_fixed(out: &mut Vec<u8>, value: i64, decimals: u32) {
    let scale = 10u64.pow(decimals);
    let abs = value.unsigned_abs();
    if value < 0 {
        out.push(b'-');
    }
    push_u64(out, abs / scale);
    let mut frac = abs % scale;
    if frac == 0 {
        return;
    }
    let mut digits = decimals;
    while frac.is_multiple_of(10) {
        frac /= 10;
        digits -= 1;
    }
    out.push(b'.');
    let mut buf = [b'0'; 20];
    let mut i = digits as usize;
    while frac > 0 {
        i -= 1;
        buf[i] = b'0' + (frac % 10) as u8;
        frac /= 10;
    }
    out.extend_from_slice(&buf[..digits as usize]);
}

/// Writes `s` as a JSON string (quoted and escaped).
pub fn push_str(out: &mut Vec<u8>, s: &str) {
    if s.bytes()
        .all(|b| b >= 0x20 && b != b'"' && b != b'\\' && b < 0x7F)
    {
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
    /// Starts an object with the three fields every decoded message has.
    pub fn start(out: &'a mut Vec<u8>, kind: &str, t: Option<&[u8]>, id: Option<u32>) -> Self {
        out.extend_from_slice(b"{\"type\":");
        push_str(out, kind);
        out.extend_from_slice(b",\"t\":");
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
        out.extend_from_slice(b"{\"type\":");
        push_str(out, kind);
        Obj { out }
    }

    fn key(&mut self, key: &str) -> &mut Vec<u8> {
        self.out.extend_from_slice(b",\"");
        self.out.extend_from_slice(key.as_bytes());
        self.out.extend_from_slice(b"\":");
        self.out
    }

    /// An integer field.
    pub fn int(&mut self, key: &str, v: i64) -> &mut Self {
        push_i64(self.key(key), v);
        self
    }

    /// A fixed-point field: `value / 10^decimals`.
    pub fn fixed(&mut self, key: &str, value: i64, decimals: u32) -> &mut Self {
        push_fixed(self.key(key), value, decimals);
        self
    }

    /// A string field, or null.
    pub fn str_or_null(&mut self, key: &str, v: Option<&str>) -> &mut Self {
        let out = self.key(key);
        match v {
            Some(s) => push_str(out, s),
            None => out.extend_from_slice(b"null"),
        }
        self
    }

    /// A string field.
    pub fn str(&mut self, key: &str, v: &str) -> &mut Self {
        push_str(self.key(key), v);
        self
    }

    /// A boolean field.
    pub fn bool(&mut self, key: &str, v: bool) -> &mut Self {
        let out = self.key(key);
        out.extend_from_slice(if v { b"true" } else { b"false" });
        self
    }

    /// A field whose value the caller writes next with the returned buffer.
    pub fn raw(&mut self, key: &str) -> &mut Vec<u8> {
        self.key(key)
    }

    /// Closes the object and ends the line.
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
