//! File plumbing shared by every reader and writer: errors that say which file, which line or
//! record, and what was wrong; and writes that never leave a half-written file behind.

use crate::text::printable;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Why a file could not be read. Every variant names the file; most name the place in it.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: line {line}: {}", path.display(), printable(.msg))]
    Line {
        path: PathBuf,
        line: usize,
        msg: String,
    },
    #[error("{}: {}: {}", path.display(), printable(.record), printable(.msg))]
    Record {
        path: PathBuf,
        record: String,
        msg: String,
    },
    #[error("{}: {}", path.display(), printable(.msg))]
    File { path: PathBuf, msg: String },
}

impl ReadError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        ReadError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
    pub(crate) fn line(path: &Path, line: usize, msg: impl Into<String>) -> Self {
        ReadError::Line {
            path: path.to_path_buf(),
            line,
            msg: msg.into(),
        }
    }
    pub fn record(path: &Path, record: impl Into<String>, msg: impl Into<String>) -> Self {
        ReadError::Record {
            path: path.to_path_buf(),
            record: record.into(),
            msg: msg.into(),
        }
    }
    pub fn file(path: &Path, msg: impl Into<String>) -> Self {
        ReadError::File {
            path: path.to_path_buf(),
            msg: msg.into(),
        }
    }
}

/// Why a file could not be written. Nothing is left at the target path when this is returned.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("{}: cannot write: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: {msg}", path.display())]
    Content { path: PathBuf, msg: String },
}

/// Writes `path` by handing `fill` a buffered writer on a temporary file in the same folder,
/// then renaming it into place. If `fill` fails, the temporary file is removed and `path` is
/// left as it was: a crash or an error never leaves a half-written output.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<(), WriteError>
where
    F: FnOnce(&mut BufWriter<&File>) -> std::io::Result<()>,
{
    let io_err = |source| WriteError::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".lamina-").suffix(".part");
    // Temporary files are private (0600); an output should get the permissions any new file
    // gets (0666 less the umask), as if it had been created in place.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder.tempfile_in(dir).map_err(io_err)?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w).map_err(io_err)?;
        w.flush().map_err(io_err)?;
    }
    tmp.as_file().sync_all().map_err(io_err)?;
    tmp.persist(path).map_err(|e| io_err(e.error))?;
    Ok(())
}

/// The path's last part, as reports name their inputs and outputs (the same bytes wherever
/// the files sit); the whole path when it has no last part.
pub fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// Lower-case extension of `path`, without the dot ("" when there is none).
pub fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Reads a whole file, rejecting an empty one with a clear message.
pub(crate) fn read_nonempty(path: &Path) -> Result<Vec<u8>, ReadError> {
    let bytes = std::fs::read(path).map_err(|e| ReadError::io(path, e))?;
    if bytes.is_empty() {
        return Err(ReadError::file(path, "file is empty"));
    }
    Ok(bytes)
}

/// Decodes a text file as UTF-8, naming the line of the first invalid byte.
pub(crate) fn utf8_text(path: &Path, bytes: Vec<u8>) -> Result<String, ReadError> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
        ReadError::line(
            path,
            line,
            "not UTF-8 text (is this a binary file with the wrong extension?)",
        )
    })
}

/// The `format` a lamina JSON file names at its top level, if any.
pub fn json_format(path: &Path, text: &str) -> Result<Option<String>, ReadError> {
    #[derive(serde::Deserialize)]
    struct Header {
        format: Option<String>,
    }
    let header: Header =
        serde_json::from_str(text).map_err(|e| ReadError::line(path, e.line(), e.to_string()))?;
    Ok(header.format)
}

/// Checks a lamina JSON file's `format` and `version` before its schema, so that another lamina
/// file given by mistake is named as such (`what` says which file was expected).
pub(crate) fn check_format(
    path: &Path,
    text: &str,
    format: &str,
    version: u32,
    what: &str,
) -> Result<(), ReadError> {
    #[derive(serde::Deserialize)]
    struct Header {
        format: Option<String>,
        version: Option<u32>,
    }
    let header: Header =
        serde_json::from_str(text).map_err(|e| ReadError::line(path, e.line(), e.to_string()))?;
    if header.format.as_deref() == Some(format) && header.version == Some(version) {
        return Ok(());
    }
    Err(ReadError::file(
        path,
        format!(
            "format {} version {} is not {format} version {version} ({what})",
            header
                .format
                .map_or("(none)".into(), |f| format!("\"{f}\"")),
            header.version.map_or("(none)".into(), |v| v.to_string())
        ),
    ))
}

/// Reads a lamina JSON file of `format` and `version` into `T` (only the fields `T` names).
pub(crate) fn read_lamina_json<T: serde::de::DeserializeOwned>(
    path: &Path,
    format: &str,
    version: u32,
    what: &str,
) -> Result<T, ReadError> {
    let text = utf8_text(path, read_nonempty(path)?)?;
    check_format(path, &text, format, version, what)?;
    serde_json::from_str(&text).map_err(|e| ReadError::line(path, e.line(), e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_fill_leaves_no_file() -> Result<(), Box<dyn std::error::Error>> {
        let dir = tempfile::tempdir()?;
        let target = dir.path().join("out.txt");
        let res = write_atomic(&target, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(res.is_err());
        assert!(!target.exists());
        assert_eq!(std::fs::read_dir(dir.path())?.count(), 0, "temp file left");
        Ok(())
    }

    #[test]
    fn successful_fill_replaces_target() -> Result<(), Box<dyn std::error::Error>> {
        let dir = tempfile::tempdir()?;
        let target = dir.path().join("out.txt");
        std::fs::write(&target, "old")?;
        write_atomic(&target, |w| w.write_all(b"new"))?;
        assert_eq!(std::fs::read_to_string(&target)?, "new");
        Ok(())
    }

    #[cfg(unix)]
    #[test]
    fn outputs_get_the_permissions_of_a_plain_new_file() -> Result<(), Box<dyn std::error::Error>> {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir()?;
        let (ours, plain) = (dir.path().join("ours.txt"), dir.path().join("plain.txt"));
        write_atomic(&ours, |w| w.write_all(b"x"))?;
        std::fs::write(&plain, b"x")?;
        let mode =
            |p: &Path| -> std::io::Result<u32> { Ok(p.metadata()?.permissions().mode() & 0o777) };
        assert_eq!(mode(&ours)?, mode(&plain)?);
        Ok(())
    }
}

/// The name of the threads that run another crate's decoder on a file's bytes (PNG): a value it
/// cannot take may make it panic; [`guarded`] turns the panic into the file's error, and the
/// CLI's panic hook keeps quiet for threads of this name.
pub const DECODER_THREAD: &str = "lamina-decoder";

/// Runs `decode` on a decoder thread: its result, or its panic's message as an error.
pub fn guarded<T: Send>(decode: impl FnOnce() -> T + Send) -> Result<T, String> {
    std::thread::scope(|scope| {
        let handle = std::thread::Builder::new()
            .name(DECODER_THREAD.into())
            .spawn_scoped(scope, decode)
            .map_err(|e| format!("cannot start the decoder: {e}"))?;
        handle.join().map_err(|panic| {
            let what = (panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "no message".into());
            format!("the decoder failed on it ({})", printable(&what))
        })
    })
}

/// A PNG decoder's message as a user reads it: the png crate writes chunk names as Rust debug
/// structs ("ChunkType { type: IDAT, critical: true, … }"), here just the name ("IDAT").
pub fn png_message(e: &png::DecodingError) -> String {
    let text = e.to_string();
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    const OPEN: &str = "ChunkType { type: ";
    while let Some(at) = rest.find(OPEN) {
        out.push_str(&rest[..at]);
        let after = &rest[at + OPEN.len()..];
        let (Some(comma), Some(close)) = (after.find(','), after.find(" }")) else {
            out.push_str(&rest[at..]);
            rest = "";
            break;
        };
        out.push_str(&after[..comma.min(close)]);
        rest = &after[close + 2..];
    }
    out.push_str(rest);
    printable(&out).into_owned()
}

/// What is wrong with a PNG's palette, if anything: a PLTE chunk must hold whole RGB entries,
/// 1 to 256 of them (decoders index past a partial one). Chunks are walked by their lengths;
/// a truncated file is left to the decoder.
pub fn png_palette_problem(bytes: &[u8]) -> Option<String> {
    let mut at = 8usize;
    if !bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        return None;
    }
    while at + 8 <= bytes.len() {
        let len = u32::from_be_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
        let kind = &bytes[at + 4..at + 8];
        if kind == b"PLTE" && (len == 0 || !len.is_multiple_of(3) || len > 768) {
            return Some(format!(
                "its palette (PLTE) is {len} bytes: it must be 1 to 256 RGB entries of 3 bytes"
            ));
        }
        if kind == b"IEND" {
            break;
        }
        at = at.saturating_add(12).saturating_add(len as usize);
    }
    None
}

#[cfg(test)]
mod decoder_tests {
    use super::*;

    #[test]
    fn a_decoder_panic_is_an_error_with_its_message() {
        assert_eq!(guarded(|| 7), Ok(7));
        let e = guarded(|| -> u8 { panic!("index 3 out of range") }).unwrap_err();
        assert!(e.contains("index 3 out of range"), "{e}");
    }

    #[test]
    fn a_palette_of_partial_entries_is_named() {
        let chunk = |kind: &[u8], data: &[u8]| {
            let mut c = (data.len() as u32).to_be_bytes().to_vec();
            c.extend_from_slice(kind);
            c.extend_from_slice(data);
            c.extend_from_slice(&[0; 4]);
            c
        };
        let png = |palette: &[u8]| {
            let mut b = b"\x89PNG\r\n\x1a\n".to_vec();
            b.extend(chunk(b"IHDR", &[0, 0, 0, 1, 0, 0, 0, 1, 8, 3, 0, 0, 0]));
            b.extend(chunk(b"PLTE", palette));
            b.extend(chunk(b"IEND", &[]));
            b
        };
        assert!(png_palette_problem(&png(&[1, 2, 3, 4])).is_some_and(|m| m.contains("4 bytes")));
        assert_eq!(png_palette_problem(&png(&[1, 2, 3])), None);
        assert!(png_palette_problem(&png(&[])).is_some());
    }
}
