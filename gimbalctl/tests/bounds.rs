//! Resource bounds of what gimbalctl reads from outside (the table in TESTING.md): a line
//! longer than any log line is counted as malformed without being held in memory, and the
//! lines around it decode.

mod common;

use common::*;

#[test]
fn a_one_megabyte_line_is_counted_not_buffered() {
    let mut input = b"00000F01#0F07000000000000\n".to_vec();
    input.extend(std::iter::repeat_n(b'x', 1 << 20));
    input.extend_from_slice(b"\n00000F01#0F08023EFE000000\n");
    // And one more without a newline at the end of the input.
    input.extend(std::iter::repeat_n(b'y', 1 << 20));
    let out = run_stdin(&["decode", "--stats"], &input);
    assert_eq!(out.code, 0, "{out:?}");
    let objects = out.json();
    assert_eq!(objects.len(), 3, "{}", out.stdout);
    assert_eq!(objects[0]["command"], "look-down");
    assert_eq!(objects[1]["command"], "pitch");
    let stats = &objects[2];
    assert_eq!(stats["type"], "stats");
    assert_eq!(stats["malformed_lines"], 2);
    assert_eq!(stats["frames"], 2);
}
