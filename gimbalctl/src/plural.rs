//! Counts in messages: "1 frame", "2 frames".

/// `n` `noun`s in words, the noun in the singular for one: "1 datagram", "2 datagrams".
pub fn counted(n: u64, noun: &str) -> String {
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}
