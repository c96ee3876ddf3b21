//! Replays the `mavlink_bridge` fuzz corpus (`fuzz/corpus/mavlink_bridge/`, minimized) and
//! its seeds (`fuzz/seeds/mavlink_bridge/`, MAVLink 2 frames encoded by pymavlink) through
//! the fuzz target's property. An empty or missing corpus is a failure, not a pass.

#[path = "../../fuzz/mavlink_properties.rs"]
mod mavlink_properties;

use std::fs;
use std::path::Path;

#[test]
fn mavlink_bridge() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut n = 0;
    for dir in ["corpus", "seeds"] {
        let d = root.join(dir).join("mavlink_bridge");
        let before = n;
        for entry in fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.unwrap().path();
            let data = fs::read(&path).unwrap();
            let result = std::panic::catch_unwind(|| mavlink_properties::mavlink_bridge(&data));
            assert!(result.is_ok(), "{} breaks the property", path.display());
            n += 1;
        }
        assert!(n > before, "{}: no inputs", d.display());
    }
    eprintln!("mavlink_bridge: {n} inputs replayed");
}
