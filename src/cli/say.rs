//! Where the commands' printed lines go. The binary prints them (stdout for results, stderr for
//! notes); when the Python package runs a command in-process it captures them on that thread
//! instead, so a library call prints nothing and hands the notes to the caller.

use std::cell::RefCell;
use std::fmt::{Arguments, Write as _};
use std::io::Write as _;

/// What a captured command printed.
#[derive(Default, Debug)]
pub struct Captured {
    /// Its standard output.
    pub out: String,
    /// Its notes (each line it wrote to stderr: defaults taken, things read but not used).
    pub notes: Vec<String>,
}

thread_local! {
    static CAPTURE: RefCell<Option<Captured>> = const { RefCell::new(None) };
}

/// Writes to stdout, or to the capture of this thread.
pub fn out(args: Arguments) {
    let captured = CAPTURE.with_borrow_mut(|c| match c {
        Some(c) => {
            let _ = c.out.write_fmt(args);
            true
        }
        None => false,
    });
    if !captured {
        let _ = std::io::stdout().lock().write_fmt(args);
    }
}

/// Writes one line to stderr, or keeps it as a note of this thread's capture.
pub fn note(args: Arguments) {
    let captured = CAPTURE.with_borrow_mut(|c| match c {
        Some(c) => {
            c.notes.push(args.to_string());
            true
        }
        None => false,
    });
    if !captured {
        let _ = writeln!(std::io::stderr().lock(), "{args}");
    }
}

/// Whether this thread's printing is being captured.
pub fn capturing() -> bool {
    CAPTURE.with_borrow(|c| c.is_some())
}

/// Runs `f` with everything it prints on this thread captured (the Python package does; the
/// binary prints).
#[allow(dead_code)]
pub fn capture<R>(f: impl FnOnce() -> R) -> (R, Captured) {
    let outer = CAPTURE.replace(Some(Captured::default()));
    let result = f();
    let captured = CAPTURE.replace(outer).unwrap_or_default();
    (result, captured)
}

/// Standard output as a writer that follows this thread's capture (bytes that are not UTF-8
/// are replaced when captured).
pub struct Stdout;

impl std::io::Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if capturing() {
            out(format_args!("{}", String::from_utf8_lossy(buf)));
            Ok(buf.len())
        } else {
            std::io::stdout().lock().write(buf)
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        std::io::stdout().lock().flush()
    }
}
