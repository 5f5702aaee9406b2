//! Replays the fuzz harness's seeds and every input it kept (fuzz/crashes/TARGET/) through
//! their readers in process: none may panic. The harness itself is `examples/fuzz.rs`.

use std::path::Path;

use lamina::fuzz::{seed_files, TARGETS};

#[test]
fn every_seed_and_kept_input_reads_without_a_panic() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut failures = Vec::new();
    let mut replayed = 0;
    for target in TARGETS {
        let files = seed_files(root, target);
        assert!(!files.is_empty(), "{}: no seeds", target.name);
        let dir = tempfile::tempdir().expect("a temporary folder");
        // The reader picks the format by extension: replay each input under the target's.
        let path = dir.path().join(format!("input.{}", target.ext));
        for file in files {
            std::fs::copy(&file, &path).expect("copy the input");
            if std::panic::catch_unwind(|| (target.run)(&path)).is_err() {
                failures.push(format!("{}: {} panics", target.name, file.display()));
            }
            replayed += 1;
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(replayed >= TARGETS.len());
}
