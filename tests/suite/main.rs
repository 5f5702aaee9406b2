//! lamina's integration tests, one module per capability, built as one test binary (one link
//! instead of eighteen; `cargo test --test suite print::` runs one module).

mod common;

mod bad_inputs;
mod buds;
mod cells;
mod cli;
mod fuzz_cases;
mod fuzz_replay;
mod lsystem;
mod pathological;
mod planarize;
mod plates;
mod print;
mod real_files;
mod roundtrip;
mod simplify;
mod sizing;
mod surface;
mod venation;
mod view;
