//! The fuzz targets' properties (`fuzz/properties.rs`), run by `cargo test` so CI exercises
//! them on every run.

#[path = "../fuzz/properties.rs"]
mod properties;

use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn command_decode(data in proptest::collection::vec(any::<u8>(), 0..12)) {
        properties::command_decode(&data);
    }

    /// Bytes biased toward the stream's own vocabulary (`EB 90 0A/0C`), so that false
    /// headers and near-frames are common.
    #[test]
    fn stream_parser(
        data in proptest::collection::vec(prop_oneof![any::<u8>(), Just(0xEB), Just(0x90), Just(0x0A), Just(0x0C)], 0..300),
    ) {
        properties::stream_parser(&data);
    }

    /// Operations biased toward postback frames and the transmit path (see
    /// `properties::link` for the record layout).
    #[test]
    fn link(data in proptest::collection::vec(prop_oneof![any::<u8>(), Just(0xEB), Just(0x90)], 0..600)) {
        properties::link(&data);
    }

    #[test]
    fn assembler(data in proptest::collection::vec(prop_oneof![any::<u8>(), Just(0xEB), Just(0x90)], 0..400)) {
        properties::assembler(&data);
    }
}

proptest! {
    // Each case runs up to 150 operations with a stream parser on either side: 300 cases
    // keep this near the others' time (the fuzz target runs it at length).
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Operations biased toward postbacks received in two parts and partial writes (see
    /// `properties::serial_link` for the record layout).
    #[test]
    fn serial_link(data in proptest::collection::vec(prop_oneof![any::<u8>(), Just(0xEB), Just(0x90), Just(1), Just(2), Just(5)], 0..600)) {
        properties::serial_link(&data);
    }
}
