//! Counts in messages: "1 frame", "2 frames", and counters said as they grow.

/// `n` `noun`s in words, the noun in the singular for one: "1 datagram", "2 datagrams".
pub fn counted(n: u64, noun: &str) -> String {
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

/// How much each of `counts` grew since `said`, which then holds them; `None` if none did.
pub fn grown<const N: usize>(counts: [u32; N], said: &mut [u32; N]) -> Option<[u32; N]> {
    let new: [u32; N] = std::array::from_fn(|i| counts[i].wrapping_sub(said[i]));
    *said = counts;
    new.iter().any(|&n| n != 0).then_some(new)
}
