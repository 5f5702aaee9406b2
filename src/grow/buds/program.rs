//! The bud language (Hart, "Growth Forms", Figure 8).
//!
//! A program is a list of bud types; each is a name followed by a colon and its commands, run
//! in order. Commands are separated by commas, semicolons or line ends; `#` starts a comment.
//! The paper prints its program in three tab-separated columns; a header line of two or more
//! `Name:` fields separated by tabs switches to that layout, each following line's k-th tab
//! field belonging to the k-th bud type. Both layouts give the same program.
//!
//! Commands: colours (`yellow`, `green`, `red`, … or `colour R G B` in 0..255), textures
//! (`flat`, `bumpy`, `spiky`, `dimple`, `hair`), `blob N`, `grow N`, `fat R`, `size S`,
//! `head up|down|none|X,Y,Z`, `create TYPE [K]`, `sleep N`, `split`, `line`, `hole`. The end of
//! a bud's list is its death.

use crate::text::printable;
use std::path::Path;

use glam::DVec3;

/// Hop radius `fat` may take: growth is chosen among the cells within it.
pub const MAX_FAT: u32 = 16;

/// Cell sizes `size` may take, relative to the default 1.
pub const SIZE_RANGE: (f64, f64) = (0.05, 20.0);

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ProgramError {
    #[error("{file}: cannot read: {}", printable(.msg))]
    Io { file: String, msg: String },
    #[error("{file} line {line}, column {column}: {}", printable(.problem))]
    Syntax {
        file: String,
        line: usize,
        column: usize,
        problem: String,
    },
    #[error("{file}: no bud type: a program starts with `Name:` and its commands")]
    Empty { file: String },
}

/// Cell surface textures, turned into geometry on output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Texture {
    Flat,
    Bumpy,
    Spiky,
    Dimple,
    Hair,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    Colour([f32; 3]),
    Texture(Texture),
    /// General growth: N divisions anywhere in the blob this command grows around the bud.
    Blob(u32),
    /// N divisions of cells within the bud's hop radius.
    Grow(u32),
    Fat(u32),
    Size(f64),
    /// Tropism: the bud follows the child cell furthest along this direction (`None`: random).
    Head(Option<DVec3>),
    /// `count` new buds of type `bud` in cells near this one.
    Create {
        bud: usize,
        count: u32,
    },
    Sleep(u32),
    Split,
    Line,
    Hole,
}

#[derive(Clone, Debug, PartialEq)]
pub struct BudType {
    pub name: String,
    pub commands: Vec<Command>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    pub types: Vec<BudType>,
}

/// The paper's Figure 8, as printed (three tab-separated columns).
pub const FIGURE_8: &str = "Base:\tStem:\tPod:
yellow, flat\thead up\tgrow 10
blob 300\tgreen, bumpy\tred, spiky
create Stem\tfat 0\tsize 1.3
\tgrow 30\tgrow 20
\tcreate Pod\tsize 2.0
\tgrow 10\tfat 4
\tcreate Stem 2\tgrow 20
";

const COLOURS: [(&str, [u8; 3]); 14] = [
    ("white", [240, 240, 235]),
    ("grey", [150, 150, 150]),
    ("gray", [150, 150, 150]),
    ("black", [35, 35, 35]),
    ("red", [205, 45, 40]),
    ("green", [70, 150, 60]),
    ("blue", [50, 90, 190]),
    ("yellow", [235, 200, 50]),
    ("orange", [235, 130, 40]),
    ("purple", [125, 60, 160]),
    ("pink", [235, 140, 170]),
    ("brown", [130, 85, 50]),
    ("cyan", [60, 180, 200]),
    ("magenta", [200, 60, 170]),
];

/// Reads and parses a program file.
pub fn read_program(path: &Path) -> Result<Program, ProgramError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| ProgramError::Io {
        file: file.clone(),
        msg: e.to_string(),
    })?;
    parse_program(&text, &file)
}

/// A piece of program text that belongs to one bud type: its line, the column it starts at.
struct Piece<'a> {
    bud: usize,
    line: usize,
    column: usize,
    text: &'a str,
}

/// Parses a program; `file` names it in errors.
pub fn parse_program(text: &str, file: &str) -> Result<Program, ProgramError> {
    let err = |line: usize, column: usize, problem: String| ProgramError::Syntax {
        file: file.to_string(),
        line,
        column,
        problem,
    };
    let mut names: Vec<(String, usize, usize)> = Vec::new();
    let mut pieces: Vec<Piece> = Vec::new();
    let mut columns: Option<Vec<usize>> = None; // the bud type of each tab field
    let mut current: Option<usize> = None;
    for (ln, raw) in text.lines().enumerate() {
        let line = ln + 1;
        let code = raw.split('#').next().unwrap_or("");
        if code.trim().is_empty() {
            continue;
        }
        let fields: Vec<(usize, &str)> = tab_fields(code);
        let headers: Option<Vec<(usize, &str)>> = fields
            .iter()
            .map(|&(col, f)| header(f).map(|name| (col + leading(f), name)))
            .collect();
        match headers {
            Some(hs) if hs.len() >= 2 => {
                let mut ids = Vec::new();
                for (col, name) in hs {
                    ids.push(declare(&mut names, name, line, col).map_err(|p| err(line, col, p))?);
                }
                columns = Some(ids);
                continue;
            }
            _ => {}
        }
        if let Some(ids) = &columns {
            if fields.len() > ids.len() {
                let col = fields[ids.len()].0;
                return Err(err(
                    line,
                    col,
                    format!(
                        "{} tab-separated fields under a header of {} bud types",
                        fields.len(),
                        ids.len()
                    ),
                ));
            }
            for (k, &(col, f)) in fields.iter().enumerate() {
                if !f.trim().is_empty() {
                    pieces.push(Piece {
                        bud: ids[k],
                        line,
                        column: col,
                        text: f,
                    });
                }
            }
            continue;
        }
        // Linear layout: an optional `Name:` header, then commands.
        let lead = leading(code);
        let mut rest = (lead + 1, &code[lead..]);
        if let Some(colon) = rest.1.find(':') {
            let name = rest.1[..colon].trim_end();
            if is_name(name) {
                let id =
                    declare(&mut names, name, line, rest.0).map_err(|p| err(line, rest.0, p))?;
                current = Some(id);
                rest = (rest.0 + colon + 1, &rest.1[colon + 1..]);
            }
        }
        if rest.1.trim().is_empty() {
            continue;
        }
        let Some(bud) = current else {
            return Err(err(
                line,
                rest.0 + leading(rest.1),
                "a command before the first bud type: start with `Name:`".into(),
            ));
        };
        pieces.push(Piece {
            bud,
            line,
            column: rest.0,
            text: rest.1,
        });
    }
    if names.is_empty() {
        return Err(ProgramError::Empty {
            file: file.to_string(),
        });
    }
    let mut types: Vec<BudType> = names
        .iter()
        .map(|(name, _, _)| BudType {
            name: name.clone(),
            commands: Vec::new(),
        })
        .collect();
    for piece in &pieces {
        let commands = parse_commands(piece, &names).map_err(|(c, p)| err(piece.line, c, p))?;
        types[piece.bud].commands.extend(commands);
    }
    Ok(Program { types })
}

/// Splits a line at tabs: (1-based column, field).
fn tab_fields(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (k, ch) in line.char_indices() {
        if ch == '\t' {
            out.push((start + 1, &line[start..k]));
            start = k + 1;
        }
    }
    out.push((start + 1, &line[start..]));
    out
}

fn leading(s: &str) -> usize {
    s.len() - s.trim_start().len()
}

/// `Name:` alone in a field.
fn header(field: &str) -> Option<&str> {
    let t = field.trim();
    let name = t.strip_suffix(':')?.trim_end();
    is_name(name).then_some(name)
}

fn is_name(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

fn declare(
    names: &mut Vec<(String, usize, usize)>,
    name: &str,
    line: usize,
    column: usize,
) -> Result<usize, String> {
    if let Some((_, l, c)) = names.iter().find(|(n, _, _)| n == name) {
        return Err(format!(
            "bud type `{name}` is already defined at line {l}, column {c}"
        ));
    }
    names.push((name.to_string(), line, column));
    Ok(names.len() - 1)
}

/// A word of a command, with its 1-based column in the line.
#[derive(Clone, Copy)]
struct Word<'a> {
    column: usize,
    text: &'a str,
}

/// Words and separators (`,` `;`) of a piece of text.
fn words<'a>(piece: &Piece<'a>) -> Vec<Word<'a>> {
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    let text = piece.text;
    let base = piece.column;
    for (k, ch) in text.char_indices() {
        let sep = ch == ',' || ch == ';';
        if ch.is_whitespace() || sep {
            if let Some(s) = start.take() {
                out.push(Word {
                    column: base + s,
                    text: &text[s..k],
                });
            }
            if sep {
                out.push(Word {
                    column: base + k,
                    text: &text[k..k + 1],
                });
            }
        } else if start.is_none() {
            start = Some(k);
        }
    }
    if let Some(s) = start {
        out.push(Word {
            column: base + s,
            text: &text[s..],
        });
    }
    out
}

type Problem = (usize, String);

fn parse_commands(
    piece: &Piece,
    names: &[(String, usize, usize)],
) -> Result<Vec<Command>, Problem> {
    let ws = words(piece);
    let end_column = piece.column + piece.text.trim_end().len();
    let mut at = 0;
    let mut out = Vec::new();
    while at < ws.len() {
        let w = ws[at];
        if is_separator(w.text) {
            at += 1;
            continue;
        }
        at += 1;
        let mut args = Args {
            ws: &ws,
            at: &mut at,
            command: w,
            end_column,
        };
        let keyword = w.text.to_ascii_lowercase();
        let command = match keyword.as_str() {
            "blob" => Command::Blob(args.count()?),
            "grow" => Command::Grow(args.count()?),
            "sleep" => Command::Sleep(args.count()?),
            "fat" => {
                let (col, r) = (args.peek_column(), args.count()?);
                if r > MAX_FAT {
                    return Err((col, format!("fat {r} is above {MAX_FAT} hops")));
                }
                Command::Fat(r)
            }
            "size" => {
                let (col, s) = (args.peek_column(), args.number()?);
                if !(SIZE_RANGE.0..=SIZE_RANGE.1).contains(&s) {
                    return Err((
                        col,
                        format!(
                            "size {s} is outside {}..{} (1 is the default cell size)",
                            SIZE_RANGE.0, SIZE_RANGE.1
                        ),
                    ));
                }
                Command::Size(s)
            }
            "head" => Command::Head(args.heading()?),
            "create" => {
                let name = args.word("a bud type after `create`")?;
                let bud = names
                    .iter()
                    .position(|(n, _, _)| n == name.text)
                    .ok_or_else(|| {
                        (
                            name.column,
                            format!(
                                "unknown bud type `{}` (defined: {})",
                                name.text,
                                names
                                    .iter()
                                    .map(|(n, _, _)| n.as_str())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        )
                    })?;
                let count = if args.next_is_number() {
                    let (col, k) = (args.peek_column(), args.count()?);
                    if k == 0 {
                        return Err((col, "create 0 makes nothing: leave the line out".into()));
                    }
                    k
                } else {
                    1
                };
                Command::Create { bud, count }
            }
            "split" => Command::Split,
            "line" => Command::Line,
            "hole" => Command::Hole,
            "flat" => Command::Texture(Texture::Flat),
            "bumpy" => Command::Texture(Texture::Bumpy),
            "spiky" => Command::Texture(Texture::Spiky),
            "dimple" => Command::Texture(Texture::Dimple),
            "hair" | "hairy" => Command::Texture(Texture::Hair),
            "colour" | "color" => {
                let mut rgb = [0f32; 3];
                for c in &mut rgb {
                    let (col, v) = (args.peek_column(), args.number()?);
                    if !(0.0..=255.0).contains(&v) {
                        return Err((col, format!("colour component {v} is outside 0..255")));
                    }
                    *c = (v / 255.0) as f32;
                }
                Command::Colour(rgb)
            }
            name => match COLOURS.iter().find(|(n, _)| *n == name) {
                Some((_, rgb)) => Command::Colour(rgb.map(|c| c as f32 / 255.0)),
                None => return Err((w.column, format!("unknown command `{}`", w.text))),
            },
        };
        // A command ends at a separator or the end of the line.
        if let Some(next) = ws.get(at) {
            if !is_separator(next.text) {
                return Err((
                    next.column,
                    format!(
                        "`{}` after `{}`: separate commands with a comma or a new line",
                        next.text, w.text
                    ),
                ));
            }
        }
        out.push(command);
    }
    Ok(out)
}

fn is_separator(s: &str) -> bool {
    s == "," || s == ";"
}

struct Args<'w, 'a> {
    ws: &'w [Word<'a>],
    at: &'w mut usize,
    command: Word<'a>,
    end_column: usize,
}

impl<'a> Args<'_, 'a> {
    fn peek_column(&self) -> usize {
        self.ws.get(*self.at).map_or(self.end_column, |w| w.column)
    }

    fn next_is_number(&self) -> bool {
        self.ws
            .get(*self.at)
            .is_some_and(|w| w.text.parse::<f64>().is_ok())
    }

    fn word(&mut self, what: &str) -> Result<Word<'a>, Problem> {
        match self.ws.get(*self.at) {
            Some(w) if !is_separator(w.text) => {
                *self.at += 1;
                Ok(*w)
            }
            _ => Err((
                self.peek_column(),
                format!("`{}` needs {what}", self.command.text),
            )),
        }
    }

    fn number(&mut self) -> Result<f64, Problem> {
        let w = self.word("a number")?;
        match w.text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err((
                w.column,
                format!(
                    "`{}` is not a number (after `{}`)",
                    w.text, self.command.text
                ),
            )),
        }
    }

    fn count(&mut self) -> Result<u32, Problem> {
        let w = self.word("a whole number")?;
        w.text.parse::<u32>().map_err(|_| {
            (
                w.column,
                format!(
                    "`{}` is not a whole number 0..{} (after `{}`)",
                    w.text,
                    u32::MAX,
                    self.command.text
                ),
            )
        })
    }

    /// `up`, `down`, `none`, or `X,Y,Z` (commas or spaces between).
    fn heading(&mut self) -> Result<Option<DVec3>, Problem> {
        let first = self.word("`up`, `down`, `none` or X,Y,Z")?;
        match first.text.to_ascii_lowercase().as_str() {
            "up" => return Ok(Some(DVec3::Z)),
            "down" => return Ok(Some(-DVec3::Z)),
            "none" | "off" => return Ok(None),
            _ => {}
        }
        *self.at -= 1;
        let col = first.column;
        let mut v = [0.0; 3];
        for (k, c) in v.iter_mut().enumerate() {
            if k > 0 && self.ws.get(*self.at).is_some_and(|w| w.text == ",") {
                *self.at += 1;
            }
            *c = self.number()?;
        }
        let d = DVec3::from(v);
        if d.length() < 1e-12 {
            return Err((col, "the heading 0,0,0 has no direction".into()));
        }
        Ok(Some(d.normalize()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn linear() -> &'static str {
        "# Figure 8, written linearly
Base:
  yellow, flat
  blob 300
  create Stem
Stem:
  head up
  green, bumpy
  fat 0
  grow 30
  create Pod
  grow 10
  create Stem 2
Pod: grow 10
  red, spiky
  size 1.3
  grow 20
  size 2.0
  fat 4
  grow 20
"
    }

    #[test]
    fn figure_8_parses_in_both_layouts() -> Result<(), ProgramError> {
        let columns = parse_program(FIGURE_8, "fig8")?;
        let lines = parse_program(linear(), "fig8")?;
        assert_eq!(columns, lines);
        let names: Vec<&str> = columns.types.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, ["Base", "Stem", "Pod"]);
        assert_eq!(
            columns.types[1].commands,
            [
                Command::Head(Some(DVec3::Z)),
                Command::Colour([70.0 / 255.0, 150.0 / 255.0, 60.0 / 255.0]),
                Command::Texture(Texture::Bumpy),
                Command::Fat(0),
                Command::Grow(30),
                Command::Create { bud: 2, count: 1 },
                Command::Grow(10),
                Command::Create { bud: 1, count: 2 },
            ]
        );
        assert_eq!(columns.types[2].commands.len(), 8);
        Ok(())
    }

    #[test]
    fn headings_and_the_rest() -> Result<(), ProgramError> {
        let p = parse_program(
            "A: head 1,0,0; head 0 2 0, head down, head none\nsleep 3, split, line, hole, hair, colour 255 0 0",
            "t",
        )?;
        let c = &p.types[0].commands;
        assert_eq!(c[0], Command::Head(Some(DVec3::X)));
        assert_eq!(c[1], Command::Head(Some(DVec3::Y)));
        assert_eq!(c[2], Command::Head(Some(-DVec3::Z)));
        assert_eq!(c[3], Command::Head(None));
        assert_eq!(
            c[4..8],
            [
                Command::Sleep(3),
                Command::Split,
                Command::Line,
                Command::Hole
            ]
        );
        assert_eq!(c[9], Command::Colour([1.0, 0.0, 0.0]));
        Ok(())
    }

    #[test]
    fn errors_name_line_and_column() {
        let at = |text: &str| match parse_program(text, "p.bud") {
            Err(ProgramError::Syntax { line, column, .. }) => (line, column),
            other => panic!("{other:?}"),
        };
        assert_eq!(at("A:\n  grwo 10"), (2, 3));
        assert_eq!(at("A:\n  grow ten"), (2, 8));
        assert_eq!(at("A:\n  grow 10 20"), (2, 11));
        assert_eq!(at("A:\n  create B"), (2, 10));
        assert_eq!(at("grow 3"), (1, 1));
        assert_eq!(at("A:\nA:"), (2, 1));
        assert_eq!(at("A:\tB:\ngrow 1\tgrow 2\tgrow 3"), (2, 15));
        assert_eq!(at("A: fat 99"), (1, 8));
        assert_eq!(at("A: head 0,0,0"), (1, 9));
        assert_eq!(at("A: size 0"), (1, 9));
        let msg = parse_program("A:\n  grwo 10", "p.bud")
            .unwrap_err()
            .to_string();
        assert_eq!(msg, "p.bud line 2, column 3: unknown command `grwo`");
        assert!(matches!(
            parse_program("# nothing\n", "p"),
            Err(ProgramError::Empty { .. })
        ));
    }
}
