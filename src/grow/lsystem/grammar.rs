//! Grammars of bracketed L-systems (Prusinkiewicz and Lindenmayer 1990; Hanafin et al. §5.3):
//! an axiom and productions `P -> successor`, deterministic (DOL) or stochastic (several
//! successors for one predecessor, each with a relative weight, `P (0.3) -> successor`).
//!
//! Symbols are single printable ASCII characters; whitespace inside a successor is ignored.
//! Every successor and the axiom must balance their brackets, so every derived word does too
//! and the turtle never pops an empty stack. Parametric (`F(2)`) and context-sensitive
//! (`A < B > C`) productions are not supported and say so.
//!
//! Grammar files, by extension:
//! - `.json`: `{"axiom": "X", "rules": ["X -> F[-X]F[+X]-X", "F -> FF"], "iterations": 7,
//!   "angle": 22, "step": 500}` (`angle` a number or a range `"15..30"`; only `axiom` and
//!   `rules` are required);
//! - anything else, text: one `key: value` (`axiom`, `iterations`, `angle`, `step`) or one
//!   production per line, `#` starts a comment.

use crate::text::printable;
use std::path::{Path, PathBuf};

/// A production's separator: `->`, `=` or `→`.
const ARROWS: [&str; 3] = ["->", "→", "="];

/// Symbols that may not be rewritten: brackets carry the turtle's stack.
const NOT_PREDECESSORS: &[u8] = b"[]()<>=";

/// One production `predecessor -> successor` with a relative weight (1 when not given).
#[derive(Clone, Debug, PartialEq)]
pub struct Rule {
    pub predecessor: u8,
    pub successor: Vec<u8>,
    pub weight: f64,
}

/// The successors of one predecessor with cumulative probabilities (the last is 1).
#[derive(Clone, Debug)]
pub(crate) struct Production {
    pub(crate) successors: Vec<Vec<u8>>,
    cumulative: Vec<f64>,
}

impl Production {
    /// The successor for a uniform draw `u` in [0, 1).
    pub(crate) fn pick(&self, u: f64) -> &[u8] {
        let k = self.cumulative.partition_point(|&c| c <= u);
        &self.successors[k.min(self.successors.len() - 1)]
    }

    pub(crate) fn is_stochastic(&self) -> bool {
        self.successors.len() > 1
    }
}

/// A validated grammar: a non-empty balanced axiom and at most one production per symbol.
#[derive(Clone, Debug)]
pub struct Grammar {
    axiom: Vec<u8>,
    rules: Vec<Rule>,
    /// Production index by symbol.
    table: Vec<Option<u16>>,
    productions: Vec<Production>,
}

/// What is wrong with a grammar, and where.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GrammarError {
    /// `at` names the place: `--rule 2, column 5` or `tree.txt line 3, column 5`.
    #[error("{}: {}", printable(.at), printable(.problem))]
    Syntax { at: String, problem: String },
    #[error("{}: cannot read the grammar: {}", .path.display(), printable(.msg))]
    Io { path: PathBuf, msg: String },
    #[error("the grammar has no axiom (give --axiom or an `axiom:` line)")]
    NoAxiom,
}

/// Settings a grammar file may carry besides the grammar; the command line overrides them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GrammarFile {
    pub axiom: Option<String>,
    /// Productions with where each was written (for errors).
    pub rules: Vec<(Rule, String)>,
    pub iterations: Option<u32>,
    /// As written: `22` or `15..30`.
    pub angle: Option<String>,
    pub step: Option<f64>,
}

impl Grammar {
    /// Checks the axiom and builds the lookup table; several productions for one symbol make
    /// it stochastic, chosen by their relative weights.
    pub fn new(axiom: &str, rules: Vec<Rule>) -> Result<Grammar, GrammarError> {
        let axiom_bytes = symbols(axiom, "the axiom", 0)?;
        if axiom_bytes.is_empty() {
            return Err(GrammarError::NoAxiom);
        }
        let mut table: Vec<Option<u16>> = vec![None; 256];
        let mut grouped: Vec<(Vec<Vec<u8>>, Vec<f64>)> = Vec::new();
        for rule in &rules {
            let slot = &mut table[rule.predecessor as usize];
            let k = *slot.get_or_insert_with(|| {
                grouped.push((Vec::new(), Vec::new()));
                (grouped.len() - 1) as u16
            });
            grouped[k as usize].0.push(rule.successor.clone());
            grouped[k as usize].1.push(rule.weight);
        }
        let productions = grouped
            .into_iter()
            .map(|(successors, weights)| {
                let total: f64 = weights.iter().sum();
                let mut acc = 0.0;
                let cumulative = weights
                    .iter()
                    .map(|w| {
                        acc += w / total;
                        acc
                    })
                    .collect();
                Production {
                    successors,
                    cumulative,
                }
            })
            .collect();
        Ok(Grammar {
            axiom: axiom_bytes,
            rules,
            table,
            productions,
        })
    }

    pub fn axiom(&self) -> &[u8] {
        &self.axiom
    }

    pub fn rules(&self) -> &[Rule] {
        &self.rules
    }

    pub(crate) fn production(&self, symbol: u8) -> Option<&Production> {
        self.table[symbol as usize].map(|k| &self.productions[k as usize])
    }

    /// Whether any symbol has several successors.
    pub fn is_stochastic(&self) -> bool {
        self.productions.iter().any(Production::is_stochastic)
    }

    /// The grammar with every `+` and `-` swapped: its drawing is the mirror image.
    pub fn mirrored(&self) -> Grammar {
        let swap = |s: &[u8]| -> Vec<u8> {
            s.iter()
                .map(|&c| match c {
                    b'+' => b'-',
                    b'-' => b'+',
                    c => c,
                })
                .collect()
        };
        let rules = self
            .rules
            .iter()
            .map(|r| Rule {
                successor: swap(&r.successor),
                ..r.clone()
            })
            .collect();
        let axiom = String::from_utf8(swap(&self.axiom)).expect("symbols are ASCII");
        Grammar::new(&axiom, rules).expect("mirroring keeps a grammar valid")
    }
}

/// Parses one production, `X -> F[-X]F`, `X=F[-X]F` or `X (0.3) -> F[-X]F`. `at` names it in
/// errors (`--rule 2`); columns count from 1.
pub fn parse_rule(text: &str, at: &str) -> Result<Rule, GrammarError> {
    let err = |col: usize, problem: String| GrammarError::Syntax {
        at: format!("{at}, column {col}"),
        problem,
    };
    let (arrow_at, arrow) = ARROWS
        .iter()
        .filter_map(|a| text.find(a).map(|i| (i, *a)))
        .min()
        .ok_or_else(|| {
            err(
                1,
                format!("`{text}` is not a production: write `P -> successor` or `P=successor`"),
            )
        })?;
    let left = &text[..arrow_at];
    let right_start = arrow_at + arrow.len();
    let successor = symbols(&text[right_start..], at, column(text, right_start))?;
    if let Some(p) = successor.iter().position(|&c| c == b'(') {
        return Err(err(
            column(text, right_start) + p,
            "parametric symbols (`F(2)`) are not supported".into(),
        ));
    }
    // The left side: one symbol, then optionally a weight in parentheses.
    let trimmed = left.trim_start();
    let lead = left.len() - trimmed.len();
    let mut chars = trimmed.char_indices();
    let Some((_, pred)) = chars.next() else {
        return Err(err(
            1,
            "the production has no predecessor before the arrow".into(),
        ));
    };
    if !pred.is_ascii_graphic() || NOT_PREDECESSORS.contains(&(pred as u8)) {
        return Err(err(
            column(text, lead),
            format!("`{pred}` cannot be rewritten: a predecessor is one printable ASCII symbol other than [ ] ( ) < > ="),
        ));
    }
    let rest = &trimmed[pred.len_utf8()..];
    let rest_col = column(text, lead + pred.len_utf8());
    let weight = match rest.trim() {
        "" => 1.0,
        w if w.starts_with('(') && w.ends_with(')') => {
            let inner = &w[1..w.len() - 1];
            match inner.trim().parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => v,
                _ => {
                    return Err(err(
                        rest_col,
                        format!("the weight `{inner}` must be a positive number"),
                    ))
                }
            }
        }
        w if w.starts_with('<') || w.starts_with('>') => {
            return Err(err(
                rest_col,
                "context-sensitive productions are not supported".into(),
            ))
        }
        w => {
            return Err(err(
                rest_col,
                format!("unexpected `{w}` after the predecessor `{pred}` (one symbol, then an optional weight like `(0.3)`)"),
            ))
        }
    };
    Ok(Rule {
        predecessor: pred as u8,
        successor,
        weight,
    })
}

/// The 1-based column of byte offset `i` in `text` (counting characters).
fn column(text: &str, i: usize) -> usize {
    text[..i].chars().count() + 1
}

/// The symbols of a word, whitespace dropped; checks they are printable ASCII and the brackets
/// balance. `first_col` is the column of the word's first character (0: no columns).
fn symbols(word: &str, at: &str, first_col: usize) -> Result<Vec<u8>, GrammarError> {
    let where_ = |k: usize| {
        if first_col == 0 {
            format!("{at}, symbol {}", k + 1)
        } else {
            format!("{at}, column {}", first_col + k)
        }
    };
    let mut out = Vec::with_capacity(word.len());
    let mut open: Vec<usize> = Vec::new();
    for (k, c) in word.chars().enumerate() {
        if c.is_whitespace() {
            continue;
        }
        if !c.is_ascii_graphic() {
            return Err(GrammarError::Syntax {
                at: where_(k),
                problem: format!("`{c}` is not a symbol: symbols are printable ASCII characters"),
            });
        }
        match c {
            '[' => open.push(k),
            ']' if open.pop().is_none() => {
                return Err(GrammarError::Syntax {
                    at: where_(k),
                    problem: "`]` closes no `[`".into(),
                })
            }
            _ => {}
        }
        out.push(c as u8);
    }
    if let Some(&k) = open.last() {
        return Err(GrammarError::Syntax {
            at: where_(k),
            problem: "`[` is never closed".into(),
        });
    }
    Ok(out)
}

/// Reads a grammar file (JSON by extension, otherwise text).
pub fn read_grammar_file(path: &Path) -> Result<GrammarFile, GrammarError> {
    let text = std::fs::read_to_string(path).map_err(|e| GrammarError::Io {
        path: path.to_path_buf(),
        msg: e.to_string(),
    })?;
    let name = path.display().to_string();
    if crate::files::extension(path) == "json" {
        parse_json(&text, &name)
    } else {
        parse_text(&text, &name)
    }
}

/// The text form: `key: value` lines and productions, `#` comments.
pub fn parse_text(text: &str, name: &str) -> Result<GrammarFile, GrammarError> {
    let mut file = GrammarFile::default();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        if line.trim().is_empty() {
            continue;
        }
        let at = format!("{name} line {}", i + 1);
        let key = line
            .split_once(':')
            .map(|(k, v)| (k.trim(), v.trim()))
            .filter(|(k, _)| ["axiom", "iterations", "angle", "step"].contains(k));
        let bad = |problem: String| GrammarError::Syntax {
            at: at.clone(),
            problem,
        };
        match key {
            Some(("axiom", v)) => file.axiom = Some(v.to_string()),
            Some(("iterations", v)) => {
                file.iterations = Some(
                    v.parse()
                        .map_err(|_| bad(format!("iterations `{v}` must be a whole number ≥ 0")))?,
                )
            }
            Some(("angle", v)) => file.angle = Some(v.to_string()),
            Some(("step", v)) => {
                file.step = Some(
                    v.parse()
                        .map_err(|_| bad(format!("step `{v}` must be a number (mm)")))?,
                )
            }
            _ => file.rules.push((parse_rule(line, &at)?, at.clone())),
        }
    }
    Ok(file)
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonGrammar {
    axiom: String,
    rules: Vec<String>,
    iterations: Option<u32>,
    angle: Option<serde_json::Value>,
    step: Option<f64>,
}

pub fn parse_json(text: &str, name: &str) -> Result<GrammarFile, GrammarError> {
    let g: JsonGrammar = serde_json::from_str(text).map_err(|e| GrammarError::Syntax {
        at: format!("{name} line {}, column {}", e.line(), e.column()),
        problem: e.to_string(),
    })?;
    let rules = g
        .rules
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let at = format!("{name} rules[{k}]");
            parse_rule(r, &at).map(|rule| (rule, at))
        })
        .collect::<Result<_, _>>()?;
    let angle = match g.angle {
        None => None,
        Some(serde_json::Value::Number(n)) => Some(n.to_string()),
        Some(serde_json::Value::String(s)) => Some(s),
        Some(other) => {
            return Err(GrammarError::Syntax {
                at: format!("{name} angle"),
                problem: format!("`{other}` must be a number or a range like \"15..30\""),
            })
        }
    };
    Ok(GrammarFile {
        axiom: Some(g.axiom),
        rules,
        iterations: g.iterations,
        angle,
        step: g.step,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn productions_parse_in_every_spelling() -> Result<(), GrammarError> {
        let want = Rule {
            predecessor: b'X',
            successor: b"F[-X]F[+X]-X".to_vec(),
            weight: 1.0,
        };
        assert_eq!(parse_rule("X=F[-X]F[+X]-X", "r")?, want);
        assert_eq!(parse_rule(" X -> F[-X] F[+X] -X ", "r")?, want);
        assert_eq!(parse_rule("X → F[-X]F[+X]-X", "r")?, want);
        let w = parse_rule("F (0.25) -> F[+F]F", "r")?;
        assert_eq!((w.predecessor, w.weight), (b'F', 0.25));
        Ok(())
    }

    #[test]
    fn bad_productions_say_where() {
        let at = |r: &str| match parse_rule(r, "--rule 1") {
            Err(GrammarError::Syntax { at, .. }) => at,
            other => panic!("{r}: {other:?}"),
        };
        assert_eq!(at("X F[-X]"), "--rule 1, column 1");
        assert_eq!(at("X=F[-X"), "--rule 1, column 4");
        assert_eq!(at("X=F]"), "--rule 1, column 4");
        assert_eq!(at("[=F"), "--rule 1, column 1");
        assert_eq!(at("X(0)=F"), "--rule 1, column 2");
        assert_eq!(at("XY=F"), "--rule 1, column 2");
        assert_eq!(at("X=F(2)"), "--rule 1, column 4");
        assert_eq!(at("A<B=F"), "--rule 1, column 2");
        assert_eq!(at("X=Fé"), "--rule 1, column 4");
    }

    #[test]
    fn stochastic_choice_follows_the_weights() -> Result<(), GrammarError> {
        let g = Grammar::new(
            "F",
            vec![
                parse_rule("F (1) -> A", "a")?,
                parse_rule("F (3) -> B", "b")?,
            ],
        )?;
        let p = g.production(b'F').expect("F has a production");
        assert!(g.is_stochastic());
        assert_eq!(p.pick(0.0), b"A");
        assert_eq!(p.pick(0.2499), b"A");
        assert_eq!(p.pick(0.25), b"B");
        assert_eq!(p.pick(0.999_999), b"B");
        Ok(())
    }

    #[test]
    fn text_and_json_files_hold_the_same_grammar() -> Result<(), GrammarError> {
        let text = "# Hanafin et al. 5.3\naxiom: X\nX -> F[-X]F[+X]-X\nF -> FF  # doubling\n\
                    iterations: 7\nangle: 15..30\nstep: 500\n";
        let t = parse_text(text, "tree.txt")?;
        let j = parse_json(
            r#"{"axiom": "X", "rules": ["X -> F[-X]F[+X]-X", "F -> FF"],
                "iterations": 7, "angle": "15..30", "step": 500}"#,
            "tree.json",
        )?;
        assert_eq!(t.axiom.as_deref(), Some("X"));
        assert_eq!(t.iterations, Some(7));
        assert_eq!(t.angle.as_deref(), Some("15..30"));
        assert_eq!(t.step, Some(500.0));
        let rules = |f: &GrammarFile| f.rules.iter().map(|r| r.0.clone()).collect::<Vec<_>>();
        assert_eq!(rules(&t), rules(&j));
        assert_eq!(t.rules[1].1, "tree.txt line 4");
        let bad = parse_text("axiom: X\nX -> F[\n", "t.txt");
        assert!(
            matches!(&bad, Err(GrammarError::Syntax { at, .. }) if at == "t.txt line 2, column 7"),
            "{bad:?}"
        );
        Ok(())
    }
}
