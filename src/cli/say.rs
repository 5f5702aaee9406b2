//! Where the commands' printed lines go: stdout for results, stderr for notes (defaults taken,
//! things read but not used). Errors in writing them (a closed pipe) are ignored, as `head`
//! expects.

use std::fmt::Arguments;
use std::io::Write as _;

/// Writes to stdout.
pub fn out(args: Arguments) {
    let _ = std::io::stdout().lock().write_fmt(args);
}

/// Writes one line to stderr, options the library names (`material=`) as flags.
pub fn note(args: Arguments) {
    let _ = writeln!(
        std::io::stderr().lock(),
        "{}",
        super::as_flags(&args.to_string())
    );
}
