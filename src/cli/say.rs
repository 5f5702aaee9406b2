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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capture_takes_output_and_notes_and_restores_the_outer_capture() {
        let ((), outer) = capture(|| {
            outln!("kept outside");
            let ((), inner) = capture(|| {
                outln!("a {}", 1);
                out!("b");
                errln!("lamina: a note");
            });
            assert_eq!(inner.out, "a 1\nb");
            assert_eq!(inner.notes, ["lamina: a note"]);
            errln!("lamina: outer note");
        });
        assert_eq!(outer.out, "kept outside\n");
        assert_eq!(outer.notes, ["lamina: outer note"]);
        assert!(!capturing());
    }

    #[test]
    fn stdout_writer_follows_the_capture() {
        use std::io::Write as _;
        let ((), c) = capture(|| {
            let mut w = std::io::BufWriter::new(Stdout);
            w.write_all(b"word\n").expect("write");
        });
        assert_eq!(c.out, "word\n");
    }

    #[test]
    fn each_thread_has_its_own_bar() {
        use crate::cli::progress::{active, bar, reset};
        let here = std::thread::current().id();
        let b = bar("here", Some(10));
        b.set_position(3);
        let there = std::thread::spawn(|| {
            let b = bar("there", None);
            (std::thread::current().id(), b)
        });
        let (id, other) = there.join().expect("thread");
        let mine = active(here).expect("a bar");
        assert_eq!((mine.stage, mine.done, mine.total), ("here", 3, Some(10)));
        assert_eq!(active(id).expect("its bar").stage, "there");
        other.finish();
        assert!(active(id).is_none(), "a finished bar is not reported");
        reset();
        assert!(active(here).is_none());
    }
}
