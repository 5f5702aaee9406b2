//! `lsystem`: a bracketed L-system derived lazily (the word is never held) and drawn by a 2D/3D
//! turtle, then shaped (widths, façade, projection: [`branching::Shape`](super::branching)).
//!
//! ```
//! use lamina::stage::{lsystem, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let opts = lsystem::Options {
//!     axiom: Some("X".into()),
//!     rule: vec!["X=F[-X]F[+X]-X".into(), "F=FF".into()],
//!     iterations: Some(5),
//!     ..Default::default()
//! };
//! let drawn = lsystem::run(&opts, &Quiet)?;
//! assert_eq!(drawn.report.lsystem.counts.symbols, lsystem::count(&opts, &Quiet)?.symbols);
//! # Ok(()) }
//! ```

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use serde_json::json;

use super::branching::{shape, Sections, Shape, ShapeError};
pub use crate::grow::lsystem::Angle;
use crate::grow::lsystem::{
    derive_until, parse_rule, word_length, Counts, DeriveError, Grammar, GrammarError, GrammarFile,
    Turtle, TurtleError, TurtleOptions, TurtleStats, DEFAULT_MAX_SYMBOLS,
};
use crate::stage::{OptionError, Progress};
use crate::Network;

/// The most rewriting steps: the derivation's cost grows with them even for a word that does
/// not (`F -> F`), and no drawn L-system needs more.
pub const MAX_ITERATIONS: u32 = 1000;
/// The largest `max_symbols`: ten times the default's budget of time is the most a drawing
/// should take.
pub const MAX_MAX_SYMBOLS: u64 = 1_000_000_000;

/// The grammar and the turtle. `Default` is the command's defaults (give an axiom, rules and
/// iterations, here or in `grammar`).
#[derive(Clone, Debug)]
pub struct Options {
    /// The axiom. Default: the grammar file's.
    pub axiom: Option<String>,
    /// Productions `P=successor`, `P -> successor`, weighted `P(0.3)=…`. Default: the
    /// grammar file's.
    pub rule: Vec<String>,
    /// A grammar read from a file (its lines fill what is not given here).
    pub grammar: Option<GrammarFile>,
    /// The grammar's name for errors (its path). Default "grammar".
    pub grammar_name: String,
    /// Derivation steps. Default: the grammar file's.
    pub iterations: Option<u32>,
    /// Turn angle, degrees, or a range drawn per turn. Default 22 (or the file's).
    pub angle: Option<Angle>,
    /// Length of one F, mm. Default 500 (or the file's).
    pub step: Option<f64>,
    /// Step factor per bracket depth. Default 1.
    pub length_scale: f64,
    /// Draw every F as its own segment. Default false.
    pub no_simplify: bool,
    /// Member radius at depth 0, mm. Default 40.
    pub radius: f64,
    /// Radius factor per bracket depth. Default 0.8.
    pub radius_scale: f64,
    /// Radius factor of `!`. Default 0.7.
    pub decay: f64,
    /// Default 1.
    pub seed: u64,
    /// Refuse derivations longer than this. Default 100 M.
    pub max_symbols: u64,
    /// What happens to the drawn tree.
    pub shape: Shape,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            axiom: None,
            rule: Vec::new(),
            grammar: None,
            grammar_name: "grammar".into(),
            iterations: None,
            angle: None,
            step: None,
            length_scale: 1.0,
            no_simplify: false,
            radius: 40.0,
            radius_scale: 0.8,
            decay: 0.7,
            seed: 1,
            max_symbols: DEFAULT_MAX_SYMBOLS,
            shape: Shape::default(),
        }
    }
}

/// Why nothing was drawn.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error("{source_name}: {error}")]
    /// The grammar refused.
    Grammar {
        /// Where the grammar came from.
        source_name: String,
        /// The grammar's error.
        error: GrammarError,
    },
    #[error(transparent)]
    /// The derivation failed.
    Derive(#[from] DeriveError),
    #[error(transparent)]
    /// The turtle refused.
    Turtle(#[from] TurtleError),
    #[error("the derived word draws nothing (no F in {0} symbols)")]
    /// The word draws nothing.
    NothingDrawn(u64),
    #[error(transparent)]
    /// Shaping failed.
    Shape(#[from] ShapeError),
}

impl Error {
    /// Whether the caller stopped the derivation.
    pub fn is_cancelled(&self) -> bool {
        matches!(self, Error::Derive(DeriveError::Cancelled))
    }
}

/// The drawn tree and its report.
#[derive(Clone, Debug)]
pub struct Drawn {
    /// The network made.
    pub network: Network,
    /// The report, as the command writes it.
    pub report: Report,
}

/// The report: the turtle's figures and the common sections. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    #[serde(flatten)]
    /// The sections shared with the other generators.
    pub sections: Sections,
    /// The turtle's figures.
    pub lsystem: TurtleStats,
}

/// The grammar, iterations and turtle, every option checked.
struct Setup {
    grammar: Grammar,
    iterations: u32,
    turtle: TurtleOptions,
}

impl Options {
    fn setup(&self) -> Result<Setup, Error> {
        let file = self.grammar.clone().unwrap_or_default();
        let rules = if self.rule.is_empty() {
            file.rules.into_iter().map(|(r, _)| r).collect()
        } else {
            self.rule
                .iter()
                .enumerate()
                .map(|(k, r)| parse_rule(r, &format!("rule= {}", k + 1)))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|error| Error::Grammar {
                    source_name: "rule=".into(),
                    error,
                })?
        };
        let axiom = self.axiom.clone().or(file.axiom).unwrap_or_default();
        let from_file = self.grammar.is_some() && (self.rule.is_empty() || self.axiom.is_none());
        let grammar = Grammar::new(&axiom, rules).map_err(|error| Error::Grammar {
            source_name: if from_file {
                self.grammar_name.clone()
            } else {
                "axiom=/rule=".into()
            },
            error,
        })?;
        let Some(iterations) = self.iterations.or(file.iterations) else {
            return Err(OptionError::new(
                "iterations",
                "is needed (or an `iterations:` line in the grammar file)",
            )
            .into());
        };
        if iterations > MAX_ITERATIONS {
            let problem = format!(
                "{iterations} iterations, more than {MAX_ITERATIONS} (each costs time even when the word does not grow)"
            );
            return Err(if self.iterations.is_some() {
                OptionError::new("iterations", problem)
            } else {
                OptionError::new("grammar", format!("{}: {problem}", self.grammar_name))
            }
            .into());
        }
        if self.max_symbols > MAX_MAX_SYMBOLS {
            return Err(OptionError::new(
                "max_symbols",
                format!("{}: at most {MAX_MAX_SYMBOLS}", self.max_symbols),
            )
            .into());
        }
        let angle = match (self.angle, &file.angle) {
            (Some(a), _) => a,
            (None, Some(text)) => text.parse().map_err(|e: String| {
                OptionError::new("grammar", format!("{}: angle {e}", self.grammar_name))
            })?,
            (None, None) => Angle::fixed(22.0),
        };
        let turtle = TurtleOptions {
            step: self.step.or(file.step).unwrap_or(500.0),
            angle,
            length_scale: self.length_scale,
            simplify: !self.no_simplify,
            radius: self.radius,
            radius_scale: self.radius_scale,
            decay: self.decay,
        };
        turtle.check()?;
        Ok(Setup {
            grammar,
            iterations,
            turtle,
        })
    }
}

/// Every 2^20 symbols progress moves.
const TICK: u64 = 1 << 20;

/// Derives, draws and shapes. `progress` counts the symbols derived and can stop the
/// derivation between two blocks of 65,536 symbols.
pub fn run(opts: &Options, progress: &dyn Progress) -> Result<Drawn, Error> {
    let s = opts.setup()?;
    let (_, most) = word_length(&s.grammar, s.iterations);
    progress.begin("deriving", Some(most.min(u64::MAX as u128) as u64));
    let mut turtle = Turtle::new(&s.turtle, opts.seed);
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let mut n = 0u64;
    let stop = || progress.cancelled();
    derive_until(
        &s.grammar,
        s.iterations,
        &mut rng,
        opts.max_symbols,
        |c| {
            turtle.feed(c);
            n += 1;
            if n.is_multiple_of(TICK) {
                progress.set(n);
            }
        },
        &stop,
    )?;
    let (tree, stats) = turtle.finish();
    if tree.network.edges.is_empty() {
        return Err(Error::NothingDrawn(stats.counts.symbols));
    }
    let rules: Vec<String> = s
        .grammar
        .rules()
        .iter()
        .map(|r| {
            format!(
                "{} ({}) -> {}",
                r.predecessor as char,
                r.weight,
                String::from_utf8_lossy(&r.successor)
            )
        })
        .collect();
    let t = &s.turtle;
    let (mut network, sections) = shape(tree, t.radius / 8.0, &opts.shape)?;
    network.meta.generator = Some("lsystem".into());
    network.meta.seed = Some(opts.seed);

    for (k, v) in [
        ("axiom", json!(String::from_utf8_lossy(s.grammar.axiom()))),
        ("rules", json!(rules)),
        ("iterations", json!(s.iterations)),
        ("angle_deg", json!([t.angle.min, t.angle.max])),
        ("step", json!(t.step)),
        ("length_scale", json!(t.length_scale)),
        ("simplify", json!(t.simplify)),
    ] {
        network.meta.parameters.insert(k.into(), v);
    }
    Ok(Drawn {
        network,
        report: Report {
            sections,
            lsystem: stats,
        },
    })
}

/// Only derives: the counts (symbols, segments, simplified segments), each symbol handed to
/// `each` as it is derived.
pub fn derive_only(
    opts: &Options,
    mut each: impl FnMut(u8),
    progress: &dyn Progress,
) -> Result<Counts, Error> {
    let s = opts.setup()?;
    let (_, most) = word_length(&s.grammar, s.iterations);
    progress.begin("deriving", Some(most.min(u64::MAX as u128) as u64));
    let mut counts = Counts::default();
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let stop = || progress.cancelled();
    derive_until(
        &s.grammar,
        s.iterations,
        &mut rng,
        opts.max_symbols,
        |c| {
            counts.feed(c);
            each(c);
            if counts.symbols.is_multiple_of(TICK) {
                progress.set(counts.symbols);
            }
        },
        &stop,
    )?;
    Ok(counts)
}

/// The counts of the derived word (see [`derive_only`]).
pub fn count(opts: &Options, progress: &dyn Progress) -> Result<Counts, Error> {
    derive_only(opts, |_| {}, progress)
}
