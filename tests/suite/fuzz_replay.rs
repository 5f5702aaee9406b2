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

/// Bytes a hostile or broken file might hold where a name or a number should be: a terminal
/// colour escape, a bell, a carriage return, a NUL, a line break inside a token.
const CONTROL: &[&[u8]] = &[b"\x1b[31m", b"\x07", b"\r", b"\0", b"X\nY", b"\x7f"];

#[test]
fn refusals_never_echo_control_characters() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut echoes = Vec::new();
    let mut refusals = 0;
    for target in TARGETS {
        let dir = tempfile::tempdir().expect("a temporary folder");
        let path = dir.path().join(format!("input.{}", target.ext));
        // The seeds proper: kept crash inputs are replayed above, and some take a second each.
        let seeds = seed_files(root, target);
        for file in seeds
            .iter()
            .filter(|f| !f.starts_with(root.join("fuzz/crashes")))
        {
            let seed = std::fs::read(file).expect("read the seed");
            // Spliced in at 24 places spread over the file (over names, numbers, keywords),
            // replacing the byte there or inserted before it.
            for k in 0..24 {
                let at = seed.len() * k / 24;
                for (c, bytes) in CONTROL.iter().enumerate() {
                    let mut input = seed[..at].to_vec();
                    input.extend_from_slice(bytes);
                    let skip = usize::from((k + c) % 2 == 0 && at < seed.len());
                    input.extend_from_slice(&seed[at + skip..]);
                    std::fs::write(&path, &input).expect("write the input");
                    let Ok(Err(msg)) = std::panic::catch_unwind(|| (target.run)(&path)) else {
                        continue;
                    };
                    refusals += 1;
                    if msg.chars().any(char::is_control) {
                        echoes.push(format!(
                            "{}: {} with {:?} at byte {at}: {:?}",
                            target.name,
                            file.display(),
                            String::from_utf8_lossy(bytes),
                            msg
                        ));
                    }
                }
            }
        }
    }
    assert!(
        refusals > 100,
        "only {refusals} refusals: the check saw too little"
    );
    echoes.sort();
    echoes.dedup();
    assert!(
        echoes.is_empty(),
        "{} messages echo control characters, e.g.:\n{}",
        echoes.len(),
        echoes.join("\n")
    );
}
