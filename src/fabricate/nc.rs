//! NC programs for a sheet's cut path: RS-274 G-code (LinuxCNC, QtPlasmaC, Mach3, GRBL in
//! laser mode) and ESSI (ISO 6582), from a table of post-processors a shop picks from and can
//! adjust (`--nc-on`, `--nc-off`).
//!
//! Both run the [`SheetPlan`]: etching first with the marker, then each contour with the torch
//! or beam, rapids between with it off. Contours are already offset by half the kerf (no
//! G41/G42 cutter compensation: the program is what the machine does). G-code is absolute,
//! millimetres, 3 decimals, arcs as G2/G3 with I/J from the arc's start; the feed is the speed
//! table's cutting (or marking) speed for the sheet's thickness and the post's machine, and
//! posts that want it dwell the table's pierce time after the torch comes on. ESSI is
//! incremental in the post's unit (each point rounded once, absolutely, so rounding never
//! accumulates); a line is `+dx+dy`, an arc `+dx+dy+i+j+` (last sign `+` counter-clockwise,
//! `-` clockwise), a zero written as its sign alone; 5/6 rapid on/off, 7/8 torch on/off, 9/10
//! marker on/off, 3 … 4 a comment, 0 the end.

use std::fmt::Write as _;

use glam::DVec2;

use crate::fabricate::cutpath::{Op, Seg, SheetPlan};
use crate::fabricate::cutplan::SpeedRow;

/// The program's language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NcFormat {
    Gcode,
    Essi,
}

impl NcFormat {
    pub fn name(self) -> &'static str {
        match self {
            NcFormat::Gcode => "gcode",
            NcFormat::Essi => "essi",
        }
    }

    /// The program files' extension.
    pub fn extension(self) -> &'static str {
        match self {
            NcFormat::Gcode => "ngc",
            NcFormat::Essi => "esi",
        }
    }

    /// The post-processor used when none is named.
    pub fn default_post(self) -> &'static str {
        match self {
            NcFormat::Gcode => "linuxcnc",
            NcFormat::Essi => "essi",
        }
    }

    /// The format by its name (`gcode` or `essi`).
    pub fn parse(name: &str) -> Option<NcFormat> {
        [NcFormat::Gcode, NcFormat::Essi]
            .into_iter()
            .find(|f| f.name() == name)
    }
}

/// Why a post-processor could not be had as asked.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PostError {
    #[error("`{name}` is not a {format} post-processor; known: {known}")]
    Unknown {
        name: String,
        format: &'static str,
        known: String,
    },
    /// A torch-on or torch-off line that is empty, too long or has control characters.
    #[error("give 1 to 80 printable characters, got {0:?}")]
    BadOn(String),
    #[error("give 1 to 80 printable characters, got {0:?}")]
    BadOff(String),
}

impl PostError {
    /// The option it is about, as a field name: `post`, `nc_on` or `nc_off`.
    pub fn field(&self) -> &'static str {
        match self {
            PostError::Unknown { .. } => "post",
            PostError::BadOn(_) => "nc_on",
            PostError::BadOff(_) => "nc_off",
        }
    }
}

/// The post-processor `name` (the format's default when `None`) writing `format`, with its
/// torch-on and torch-off lines (codes for ESSI) replaced by `on` and `off` where given.
pub fn post_for(
    format: NcFormat,
    name: Option<&str>,
    on: Option<&str>,
    off: Option<&str>,
) -> Result<Post, PostError> {
    let name = name.unwrap_or(format.default_post());
    let mut post = post(name)
        .filter(|p| p.format == format)
        .ok_or_else(|| PostError::Unknown {
            name: name.to_string(),
            format: format.name(),
            known: posts()
                .into_iter()
                .filter(|p| p.format == format)
                .map(|p| p.name)
                .collect::<Vec<_>>()
                .join(", "),
        })?;
    let fits = |v: &str| !v.trim().is_empty() && v.len() <= 80 && !v.chars().any(char::is_control);
    if let Some(v) = on {
        if !fits(v) {
            return Err(PostError::BadOn(v.to_string()));
        }
        post.on = v.to_string();
    }
    if let Some(v) = off {
        if !fits(v) {
            return Err(PostError::BadOff(v.to_string()));
        }
        post.off = v.to_string();
    }
    Ok(post)
}

/// Which speed table rows set the feeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Machine {
    Laser,
    Plasma,
}

/// One post-processor: how a controller wants its program.
#[derive(Clone, Debug, PartialEq)]
pub struct Post {
    pub name: &'static str,
    pub format: NcFormat,
    pub machine: Machine,
    /// What it is for, for the table in docs/nc.md and `--post help`.
    pub about: &'static str,
    /// Torch (or beam) on and off.
    pub on: String,
    pub off: String,
    /// Marker on and off, for etching.
    pub mark_on: String,
    pub mark_off: String,
    /// Dwell the pierce time (G4 P seconds) after the torch comes on.
    pub dwell: bool,
    /// Lines after the heading comments.
    pub start: &'static [&'static str],
    /// Lines at the end.
    pub end: &'static [&'static str],
    /// ESSI: mm per unit.
    pub unit: f64,
}

/// The post-processors built in, by name.
pub fn posts() -> Vec<Post> {
    let gcode = |name, machine, about, on: &str, off: &str, mark_on: &str, mark_off: &str| Post {
        name,
        format: NcFormat::Gcode,
        machine,
        about,
        on: on.into(),
        off: off.into(),
        mark_on: mark_on.into(),
        mark_off: mark_off.into(),
        dwell: true,
        start: &["G21", "G90", "G17", "G40", "G64 P0.01"],
        end: &["M2"],
        unit: 0.001,
    };
    let essi = |name, about, unit| Post {
        name,
        format: NcFormat::Essi,
        machine: Machine::Plasma,
        about,
        on: "7".into(),
        off: "8".into(),
        mark_on: "9".into(),
        mark_off: "10".into(),
        dwell: false,
        start: &[],
        end: &["0"],
        unit,
    };
    vec![
        gcode(
            "linuxcnc",
            Machine::Plasma,
            "LinuxCNC plasma: torch on the spindle (M3 S1 / M5), a scribe on M7 / M9, G4 pierce dwell",
            "M3 S1",
            "M5",
            "M7",
            "M9",
        ),
        Post {
            dwell: false,
            start: &["G21", "G90", "G17", "G40", "G64 P0.01", "M52 P1"],
            ..gcode(
                "qtplasmac",
                Machine::Plasma,
                "LinuxCNC QtPlasmaC: torch M3 $0 S1 / M5 $0, scribe M3 $2 S1 / M5 $2, pierce delay from the material table",
                "M3 $0 S1",
                "M5 $0",
                "M3 $2 S1",
                "M5 $2",
            )
        },
        Post {
            start: &["G21", "G90", "G17", "G40"],
            end: &["M5", "M30"],
            ..gcode(
                "mach3",
                Machine::Plasma,
                "Mach3 / Mach4 plasma: torch M3 / M5, marker M7 / M9, G4 P in seconds (set Mach's dwell to seconds)",
                "M3",
                "M5",
                "M7",
                "M9",
            )
        },
        Post {
            start: &["G21", "G90", "G17"],
            end: &["M5", "M2"],
            ..gcode(
                "grbl-laser",
                Machine::Laser,
                "GRBL 1.1 laser mode ($32=1): beam M4 S1000 / M5, marking at M4 S300, laser feeds",
                "M4 S1000",
                "M5",
                "M4 S300",
                "M5",
            )
        },
        essi(
            "essi",
            "ESSI (ISO 6582), 0.01 mm units (set the controller's ESSI resolution to match), plasma",
            0.01,
        ),
        essi(
            "essi-0.1mm",
            "ESSI (ISO 6582), 0.1 mm units: every point rounded to 0.1 mm",
            0.1,
        ),
    ]
}

/// The built-in post of that name.
pub fn post(name: &str) -> Option<Post> {
    posts().into_iter().find(|p| p.name == name)
}

/// What heads the program: lines of plain text, written as comments.
#[derive(Clone, Debug, Default)]
pub struct Heading {
    pub lines: Vec<String>,
    /// Part names by plate index, for the comments before each part's paths.
    pub names: Vec<String>,
}

/// A number as G-code writes it: 3 decimals, no negative zero.
fn g(v: f64) -> String {
    let s = format!("{v:.3}");
    if s == "-0.000" {
        "0.000".into()
    } else {
        s
    }
}

/// Feed per minute as G-code writes it.
fn feed(v: f64) -> String {
    format!("{v:.0}")
}

/// G-code comment text: no parentheses inside.
fn comment(s: &str) -> String {
    s.replace(['(', ')'], "")
}

/// The G-code program of a sheet. `speeds` is the speed table's row for the sheet's
/// thickness and the post's machine.
pub fn gcode(plan: &SheetPlan, post: &Post, speeds: &SpeedRow, heading: &Heading) -> String {
    let mut out = String::new();
    for l in &heading.lines {
        let _ = writeln!(out, "({})", comment(l));
    }
    let _ = writeln!(
        out,
        "(post {}: torch {} / {}, marker {} / {})",
        post.name,
        comment(&post.on),
        comment(&post.off),
        comment(&post.mark_on),
        comment(&post.mark_off)
    );
    let _ = writeln!(
        out,
        "(contours offset {} mm for the kerf: outside outer contours, inside holes; no G41/G42)",
        g(plan.offset)
    );
    let _ = writeln!(out, "(rapid travel {} mm)", g(plan.rapid_mm));
    for l in post.start {
        let _ = writeln!(out, "{l}");
    }
    let mut last_part: Option<Option<usize>> = None;
    let mut last_op: Option<Op> = None;
    for path in &plan.paths {
        if last_op != Some(path.op) || last_part != Some(path.part) {
            let what = match path.op {
                Op::Etch => "etch",
                Op::Inner => "hole",
                Op::Outer => "outer contour",
                Op::FromKerf => "outer contour from the common line's kerf, no pierce",
            };
            let part = |i: usize| {
                heading.names.get(i).map_or_else(
                    || format!(" of part {i}"),
                    |n| format!(" of {}", comment(n)),
                )
            };
            let _ = writeln!(out, "({what}{})", path.part.map_or(String::new(), part));
        }
        last_op = Some(path.op);
        last_part = Some(path.part);
        let _ = writeln!(out, "G0 X{} Y{}", g(path.start.x), g(path.start.y));
        let (on, off, f) = if path.op == Op::Etch {
            (&post.mark_on, &post.mark_off, speeds.etch_mm_per_min)
        } else {
            (&post.on, &post.off, speeds.cut_mm_per_min)
        };
        let _ = writeln!(out, "{on}");
        if post.dwell && matches!(path.op, Op::Inner | Op::Outer) && speeds.pierce_s > 0.0 {
            let _ = writeln!(out, "G4 P{}", speeds.pierce_s);
        }
        let mut at = path.start;
        for (k, s) in path.segs.iter().enumerate() {
            let fw = if k == 0 {
                format!(" F{}", feed(f))
            } else {
                String::new()
            };
            match *s {
                Seg::Line(p) => {
                    let _ = writeln!(out, "G1 X{} Y{}{fw}", g(p.x), g(p.y));
                }
                Seg::Arc { to, centre, ccw } => {
                    let ij = centre - at;
                    let _ = writeln!(
                        out,
                        "{} X{} Y{} I{} J{}{fw}",
                        if ccw { "G3" } else { "G2" },
                        g(to.x),
                        g(to.y),
                        g(ij.x),
                        g(ij.y)
                    );
                }
            }
            at = s.end();
        }
        let _ = writeln!(out, "{off}");
    }
    for l in post.end {
        let _ = writeln!(out, "{l}");
    }
    out
}

/// An ESSI value: the sign alone for zero.
fn essi_value(v: i64) -> String {
    if v == 0 {
        "+".into()
    } else {
        format!("{v:+}")
    }
}

/// ESSI comment text: letters, digits and a few signs, upper case (no `+`/`-` a reader could
/// take for a move).
fn essi_comment(s: &str) -> String {
    s.chars()
        .map(|c| {
            let c = c.to_ascii_uppercase();
            if c.is_ascii_alphanumeric() || " .,:/_=".contains(c) {
                c
            } else {
                ' '
            }
        })
        .collect()
}

/// The ESSI program of a sheet.
pub fn essi(plan: &SheetPlan, post: &Post, heading: &Heading) -> String {
    let mut out = String::from("%\n");
    let mut lines: Vec<String> = heading.lines.clone();
    lines.push(format!(
        "post {}, unit {} mm, contours offset {} mm for the kerf",
        post.name,
        post.unit,
        g(plan.offset)
    ));
    lines.push(format!("rapid travel {} mm", g(plan.rapid_mm)));
    out.push_str("3\n");
    for l in &lines {
        let _ = writeln!(out, "{}", essi_comment(l));
    }
    out.push_str("4\n");
    for l in post.start {
        let _ = writeln!(out, "{l}");
    }
    let q = |p: DVec2| -> (i64, i64) {
        (
            (p.x / post.unit).round() as i64,
            (p.y / post.unit).round() as i64,
        )
    };
    let mut cur = (0i64, 0i64);
    for path in &plan.paths {
        let t = q(path.start);
        let _ = writeln!(
            out,
            "5\n{}{}\n6",
            essi_value(t.0 - cur.0),
            essi_value(t.1 - cur.1)
        );
        cur = t;
        let (on, off) = if path.op == Op::Etch {
            (&post.mark_on, &post.mark_off)
        } else {
            (&post.on, &post.off)
        };
        let _ = writeln!(out, "{on}");
        for s in &path.segs {
            let t = q(s.end());
            match *s {
                Seg::Line(_) => {
                    let _ = writeln!(
                        out,
                        "{}{}",
                        essi_value(t.0 - cur.0),
                        essi_value(t.1 - cur.1)
                    );
                }
                Seg::Arc { centre, ccw, .. } => {
                    let c = q(centre);
                    let _ = writeln!(
                        out,
                        "{}{}{}{}{}",
                        essi_value(t.0 - cur.0),
                        essi_value(t.1 - cur.1),
                        essi_value(c.0 - cur.0),
                        essi_value(c.1 - cur.1),
                        if ccw { "+" } else { "-" }
                    );
                }
            }
            cur = t;
        }
        let _ = writeln!(out, "{off}");
    }
    for l in post.end {
        let _ = writeln!(out, "{l}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fabricate::cutpath::ToolPath;

    #[test]
    fn a_post_is_had_by_format_and_name_with_its_torch_lines_replaced_where_asked() {
        let g = post_for(NcFormat::Gcode, None, None, None).unwrap();
        assert_eq!((g.name, g.format), ("linuxcnc", NcFormat::Gcode));
        let e = post_for(NcFormat::Essi, None, Some("7"), Some("8")).unwrap();
        assert_eq!((e.name, e.on.as_str(), e.off.as_str()), ("essi", "7", "8"));
        let q = post_for(NcFormat::Gcode, Some("qtplasmac"), Some("M3 $0 S77"), None).unwrap();
        assert_eq!(
            (q.on.as_str(), q.off),
            ("M3 $0 S77", post("qtplasmac").unwrap().off)
        );
        // A post of the other format, an unknown one, and torch lines that do not fit.
        let wrong = post_for(NcFormat::Essi, Some("linuxcnc"), None, None).unwrap_err();
        assert_eq!(
            wrong.to_string(),
            "`linuxcnc` is not a essi post-processor; known: essi, essi-0.1mm"
        );
        assert!(matches!(
            post_for(NcFormat::Gcode, Some("fanuc"), None, None),
            Err(PostError::Unknown { .. })
        ));
        assert_eq!(
            post_for(NcFormat::Gcode, None, Some(" "), None),
            Err(PostError::BadOn(" ".into()))
        );
        assert_eq!(
            post_for(NcFormat::Gcode, None, None, Some("M5\nM2")),
            Err(PostError::BadOff("M5\nM2".into()))
        );
        assert!(post_for(NcFormat::Gcode, None, Some(&"M".repeat(81)), None).is_err());
        assert_eq!(NcFormat::parse("essi"), Some(NcFormat::Essi));
        assert_eq!(NcFormat::parse("ESSI"), None);
    }

    fn plan() -> SheetPlan {
        let paths = vec![ToolPath {
            op: Op::Outer,
            part: Some(0),
            start: DVec2::new(10.0, 10.0),
            segs: vec![
                Seg::Line(DVec2::new(20.0, 10.0)),
                Seg::Arc {
                    to: DVec2::new(21.0, 11.0),
                    centre: DVec2::new(20.0, 11.0),
                    ccw: true,
                },
            ],
        }];
        SheetPlan {
            rapid_mm: SheetPlan::travel(&paths),
            rapids: 1,
            parts: vec![0],
            etch: Vec::new(),
            paths,
            offset: 0.0,
        }
    }

    #[test]
    fn essi_moves_are_increments_with_a_bare_sign_for_zero() {
        let text = essi(
            &plan(),
            &post("essi").expect("built in"),
            &Heading::default(),
        );
        let moves: Vec<&str> = text
            .lines()
            .filter(|l| l.len() > 2 && l.starts_with(['+', '-']))
            .collect();
        assert_eq!(moves, vec!["+1000+1000", "+1000+", "+100+100++100+"]);
        assert!(
            text.starts_with("%\n3\n") && text.ends_with("8\n0\n"),
            "{text}"
        );
    }

    #[test]
    fn gcode_cuts_with_the_torch_on_and_arcs_from_their_start() {
        let row = SpeedRow {
            thickness: 5.0,
            cut_mm_per_min: 3600.0,
            etch_mm_per_min: 8000.0,
            pierce_s: 0.5,
        };
        let text = gcode(
            &plan(),
            &post("linuxcnc").expect("built in"),
            &row,
            &Heading::default(),
        );
        let body: Vec<&str> = text.lines().filter(|l| !l.starts_with('(')).collect();
        let at = body.iter().position(|l| *l == "M3 S1").expect("torch on");
        assert_eq!(body[at - 1], "G0 X10.000 Y10.000");
        assert_eq!(body[at + 1], "G4 P0.5");
        assert_eq!(body[at + 2], "G1 X20.000 Y10.000 F3600");
        assert_eq!(body[at + 3], "G3 X21.000 Y11.000 I0.000 J1.000");
        assert_eq!(body[at + 4], "M5");
    }
}
