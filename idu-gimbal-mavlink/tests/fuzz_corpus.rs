//! Replays the bridge's fuzz corpora (`fuzz/corpus/<target>/`, minimized) and seeds
//! (`fuzz/seeds/<target>/`, from MAVLink 2 frames encoded by pymavlink) through the fuzz
//! targets' properties. An empty or missing directory is a failure, not a pass.

#[path = "../../fuzz/mavlink_properties.rs"]
mod mavlink_properties;

use std::fs;
use std::path::Path;

fn replay(target: &str, property: fn(&[u8])) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut n = 0;
    for dir in ["corpus", "seeds"] {
        let d = root.join(dir).join(target);
        let before = n;
        for entry in fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.unwrap().path();
            let data = fs::read(&path).unwrap();
            let result = std::panic::catch_unwind(|| property(&data));
            assert!(result.is_ok(), "{} breaks the property", path.display());
            n += 1;
        }
        assert!(n > before, "{}: no inputs", d.display());
    }
    eprintln!("{target}: {n} inputs replayed");
}

#[test]
fn mavlink_bridge() {
    replay("mavlink_bridge", mavlink_properties::mavlink_bridge);
}

/// With the `roi` feature too (CI runs the bridge's tests both ways): the seeds hold a
/// region of interest relative to a home at the ends of `i32`.
#[test]
fn mavlink_messages() {
    replay("mavlink_messages", mavlink_properties::mavlink_messages);
}
