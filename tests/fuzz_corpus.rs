//! Replays the checked-in fuzz corpora (`fuzz/corpus/<target>/`, minimized with
//! `cargo fuzz cmin`) and the seeds they grew from (`fuzz/seeds/<target>/`, the protocol's
//! own vectors, written by `fuzz/seeds.py`) through the same properties the fuzz targets
//! check, so every CI run exercises what the fuzzing campaigns found. An empty or missing
//! corpus is a failure, not a pass.

#[path = "../fuzz/properties.rs"]
mod properties;

use std::fs;
use std::path::Path;

/// Every input of `target`, from the corpus and the seeds; fails when there are none.
fn inputs(target: &str) -> Vec<(String, Vec<u8>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut out = Vec::new();
    for dir in ["corpus", "seeds"] {
        let d = root.join(dir).join(target);
        let entries = fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
        let before = out.len();
        for entry in entries {
            let path = entry.unwrap().path();
            out.push((path.display().to_string(), fs::read(&path).unwrap()));
        }
        assert!(out.len() > before, "{}: no inputs", d.display());
    }
    out
}

fn replay(target: &str, property: fn(&[u8])) {
    let inputs = inputs(target);
    for (name, data) in &inputs {
        let result = std::panic::catch_unwind(|| property(data));
        assert!(result.is_ok(), "{target}: {name} breaks the property");
    }
    eprintln!("{target}: {} inputs replayed", inputs.len());
}

#[test]
fn command_decode() {
    replay("command_decode", properties::command_decode);
}

#[test]
fn stream_parser() {
    replay("stream_parser", properties::stream_parser);
}

#[test]
fn assembler() {
    replay("assembler", properties::assembler);
}

#[test]
fn link() {
    replay("link", properties::link);
}

#[test]
fn serial_link() {
    replay("serial_link", properties::serial_link);
}
