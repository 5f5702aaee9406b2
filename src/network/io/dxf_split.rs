//! Splitting a large ASCII DXF so the `dxf` crate can parse its parts on several cores.
//!
//! The crate reads a whole drawing into memory before we see an entity (about 1 s and 400 MiB
//! for 200k LINEs, most of it allocating per-entity structs). The ENTITIES section is a flat
//! list, so it can be cut at entity starts (never inside a POLYLINE's VERTEX/SEQEND run), and
//! each part wrapped as a drawing of its own with the file's version and code page. The parts
//! parse independently; joined in order they give what the whole file gives, and errors are
//! mapped back to the file's line numbers. Anything unusual makes `split` return `None` and the
//! caller parses the whole file, so the crate still has the last word on malformed input.

use std::borrow::Cow;

/// A piece of the file, wrapped as a drawing of its own.
pub(super) struct Part<'a> {
    pub text: Cow<'a, [u8]>,
    /// `(first text line, shift)`, ascending: a line the crate reports for `text`, plus the
    /// shift of the last entry at or before it, is the line in the file.
    shifts: Vec<(usize, isize)>,
}

impl<'a> Part<'a> {
    /// Maps a 1-based line of `text` to the line in the file.
    pub fn file_line(&self, line: usize) -> usize {
        let i = self.shifts.partition_point(|&(from, _)| from <= line);
        let shift = if i == 0 { 0 } else { self.shifts[i - 1].1 };
        (line as isize + shift).max(1) as usize
    }

    /// The whole file as it is: the fallback when it cannot be split.
    pub fn whole(bytes: &'a [u8]) -> Part<'a> {
        Part {
            text: Cow::Borrowed(bytes),
            shifts: Vec::new(),
        }
    }
}

/// Entity types that continue the entity before them and must stay with it.
const CONTINUATIONS: &[&[u8]] = &[b"VERTEX", b"SEQEND", b"ATTRIB"];

/// Cuts the ENTITIES section of an ASCII DXF into at most `parts` pieces of similar size. The
/// first piece returned is the rest of the file (header, tables, blocks, objects) without the
/// entity list, so that errors there are still found.
pub(super) fn split(bytes: &[u8], parts: usize) -> Option<Vec<Part<'static>>> {
    if parts < 2 || bytes.starts_with(b"AutoCAD Binary DXF") || bytes.starts_with(b"AutoCAD DXB") {
        return None;
    }
    let scan = scan(bytes)?;
    let (body_start, body_end) = (scan.body.0, scan.body.1);
    let starts = &scan.entity_starts;
    if starts.len() < parts {
        return None;
    }
    let mut prefix = Vec::new();
    prefix.extend_from_slice(b"  0\nSECTION\n  2\nHEADER\n  9\n$ACADVER\n  1\n");
    prefix.extend_from_slice(&scan.version);
    prefix.push(b'\n');
    if let Some(cp) = &scan.codepage {
        prefix.extend_from_slice(b"  9\n$DWGCODEPAGE\n  3\n");
        prefix.extend_from_slice(cp);
        prefix.push(b'\n');
    }
    prefix.extend_from_slice(b"  0\nENDSEC\n  0\nSECTION\n  2\nENTITIES\n");
    let prefix_lines = prefix.iter().filter(|&&b| b == b'\n').count() as isize;
    let suffix = b"  0\nENDSEC\n  0\nEOF\n";

    // Cut at the first entity start at or after each k/parts of the body's bytes.
    let span = body_end - body_start;
    let mut cuts: Vec<(usize, usize)> = vec![(body_start, scan.body_line)];
    for k in 1..parts {
        let target = body_start + span * k / parts;
        let i = starts.partition_point(|&(off, _)| off < target);
        if let Some(&cut) = starts.get(i) {
            if cut.0 > cuts.last().map_or(0, |c| c.0) {
                cuts.push(cut);
            }
        }
    }
    let mut out = Vec::with_capacity(cuts.len() + 1);
    let mut skeleton = bytes[..body_start].to_vec();
    skeleton.extend_from_slice(&bytes[body_end..]);
    out.push(Part {
        text: Cow::Owned(skeleton),
        shifts: vec![(
            scan.body_line,
            (scan.body_end_line - scan.body_line) as isize,
        )],
    });
    for (i, &(start, line)) in cuts.iter().enumerate() {
        let end = cuts.get(i + 1).map_or(body_end, |c| c.0);
        let mut text = Vec::with_capacity(prefix.len() + end - start + suffix.len());
        text.extend_from_slice(&prefix);
        text.extend_from_slice(&bytes[start..end]);
        if !text.ends_with(b"\n") {
            text.push(b'\n');
        }
        text.extend_from_slice(suffix);
        out.push(Part {
            text: Cow::Owned(text),
            shifts: vec![(0, line as isize - prefix_lines - 1)],
        });
    }
    Some(out)
}

struct Scan {
    version: Vec<u8>,
    codepage: Option<Vec<u8>>,
    /// Byte range of the ENTITIES section's content.
    body: (usize, usize),
    /// 1-based file line of the content's first line.
    body_line: usize,
    /// 1-based file line of the section's closing `0/ENDSEC`.
    body_end_line: usize,
    /// (byte offset, 1-based line) of each entity that may start a part.
    entity_starts: Vec<(usize, usize)>,
}

/// Walks the group-code/value pairs once, without allocating per pair.
fn scan(bytes: &[u8]) -> Option<Scan> {
    let mut pos = 0usize;
    let mut line = 1usize;
    let next_line = |pos: &mut usize, line: &mut usize| -> Option<(usize, &[u8])> {
        if *pos >= bytes.len() {
            return None;
        }
        let start = *pos;
        let end = memchr::memchr(b'\n', &bytes[start..]).map_or(bytes.len(), |i| start + i);
        *pos = (end + 1).min(bytes.len() + 1);
        *line += 1;
        Some((start, bytes[start..end].trim_ascii()))
    };
    let (mut version, mut codepage) = (None, None);
    let mut want: Option<&'static str> = None;
    let mut last_section = false;
    let mut body: Option<(usize, usize)> = None;
    let mut entity_starts = Vec::new();
    loop {
        let code_line_no = line;
        let (code_at, code) = next_line(&mut pos, &mut line)?;
        let (_, value) = next_line(&mut pos, &mut line)?;
        let code = group_code(code)?;
        match (body, code) {
            (None, 9) => {
                want = match value {
                    b"$ACADVER" => Some("version"),
                    b"$DWGCODEPAGE" => Some("codepage"),
                    _ => None,
                };
                continue;
            }
            (None, 1) if want == Some("version") => version = Some(value.to_vec()),
            (None, 3) if want == Some("codepage") => codepage = Some(value.to_vec()),
            (None, 0) => last_section = value == b"SECTION",
            (None, 2) if last_section && value == b"ENTITIES" => {
                body = Some((pos.min(bytes.len()), line));
            }
            (Some(_), 0) if value == b"ENDSEC" => {
                let (start, body_line) = body?;
                return Some(Scan {
                    version: version?,
                    codepage,
                    body: (start, code_at),
                    body_line,
                    body_end_line: code_line_no,
                    entity_starts,
                });
            }
            (Some(_), 0) if !CONTINUATIONS.contains(&value) => {
                entity_starts.push((code_at, code_line_no));
            }
            _ => {}
        }
        want = None;
        if code != 0 {
            last_section = false;
        }
    }
}

/// A group code: decimal digits, optionally signed, as `str::parse` would take them.
fn group_code(text: &[u8]) -> Option<i32> {
    let (negative, digits) = match text.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, text),
    };
    if digits.is_empty() || digits.len() > 9 {
        return None;
    }
    let mut v = 0i32;
    for &d in digits {
        if !d.is_ascii_digit() {
            return None;
        }
        v = v * 10 + (d - b'0') as i32;
    }
    Some(if negative { -v } else { v })
}

#[cfg(test)]
mod tests {
    use super::*;

    const DXF: &str = "  0\nSECTION\n  2\nHEADER\n  9\n$ACADVER\n  1\nAC1015\n  0\nENDSEC\n\
                       0\nSECTION\n  2\nENTITIES\n\
                       0\nLINE\n 10\n0\n 20\n0\n 30\n0\n 11\n1\n 21\n0\n 31\n0\n\
                       0\nPOLYLINE\n 66\n1\n 70\n8\n\
                       0\nVERTEX\n 10\n1\n 20\n0\n 30\n0\n 70\n32\n\
                       0\nVERTEX\n 10\n2\n 20\n0\n 30\n0\n 70\n32\n\
                       0\nSEQEND\n\
                       0\nLINE\n 10\n2\n 20\n0\n 30\n0\n 11\n3\n 21\n0\n 31\n0\n\
                       0\nENDSEC\n  0\nEOF\n";

    #[test]
    fn cuts_only_at_entity_starts() {
        let parts = split(DXF.as_bytes(), 3).expect("splits");
        assert!(parts.len() >= 3);
        let skeleton = String::from_utf8_lossy(&parts[0].text);
        assert!(
            !skeleton.contains("LINE"),
            "the first part holds no entities"
        );
        for p in &parts[1..] {
            let body = String::from_utf8_lossy(&p.text);
            let body = body.split("ENTITIES\n").nth(1).unwrap_or("");
            let first_entity = body.lines().nth(1).unwrap_or("");
            assert!(
                ["LINE", "POLYLINE"].contains(&first_entity),
                "part starts inside an entity: {first_entity}"
            );
        }
    }

    #[test]
    fn binary_and_small_inputs_are_not_split() {
        assert!(split(b"AutoCAD Binary DXF\r\n\x1a\0....", 4).is_none());
        assert!(split(DXF.as_bytes(), 1).is_none());
        assert!(
            split(DXF.as_bytes(), 50).is_none(),
            "more parts than entities"
        );
    }
}
