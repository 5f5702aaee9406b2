//! `lamina lsystem`: derive a bracketed L-system and draw it with the turtle, or only count it
//! (`--derive-only`), optionally fitted to a façade and projected onto a surface.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args as ClapArgs;
use indicatif::{ProgressBar, ProgressStyle};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::json;

use super::branching::{check_outputs, finish, print, FacadeArgs, Made, OutputArgs, WidthArgs};
use lamina::grow::lsystem::{
    derive, parse_rule, read_grammar_file, word_length, Angle, Counts, Grammar, Turtle,
    TurtleOptions, DEFAULT_MAX_SYMBOLS,
};

#[derive(ClapArgs)]
pub struct Args {
    /// The axiom (start word), e.g. X
    #[arg(long)]
    pub axiom: Option<String>,
    /// A production `P=successor` or `P -> successor`; several for one symbol make it
    /// stochastic, weighted `P(0.3)=successor` (repeat the option; replaces the file's rules)
    #[arg(long = "rule", value_name = "P=SUCCESSOR")]
    pub rules: Vec<String>,
    /// A grammar file: text (`axiom: X`, `X -> F[-X]F[+X]-X`, `iterations: 7`, `angle: 22`,
    /// `step: 500`) or .json; the command line overrides it
    #[arg(long, value_name = "FILE")]
    pub grammar: Option<PathBuf>,
    /// Derivation steps (parallel rewritings)
    #[arg(short = 'n', long)]
    pub iterations: Option<u32>,
    /// Turn angle in degrees, or a range `15..30` drawn afresh at every turn [default: 22]
    #[arg(long)]
    pub angle: Option<Angle>,
    /// Length of one F, mm [default: 500]
    #[arg(long)]
    pub step: Option<f64>,
    /// Step factor per bracket depth
    #[arg(long, default_value_t = 1.0)]
    pub length_scale: f64,
    /// Draw every F as its own segment (no merging of straight runs)
    #[arg(long)]
    pub no_simplify: bool,
    /// Member radius at depth 0, mm
    #[arg(long, default_value_t = 40.0)]
    pub radius: f64,
    /// Radius factor per bracket depth
    #[arg(long, default_value_t = 0.8)]
    pub radius_scale: f64,
    /// Radius factor of `!`
    #[arg(long, default_value_t = 0.7)]
    pub decay: f64,
    #[command(flatten)]
    pub widths: WidthArgs,
    /// Random seed (stochastic rules, angle ranges): the same seed gives the same bytes
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Refuse derivations longer than this many symbols
    #[arg(long, default_value_t = DEFAULT_MAX_SYMBOLS)]
    pub max_symbols: u64,
    /// Only derive: print the counts (symbols, segments, simplified_segments), draw nothing
    #[arg(long)]
    pub derive_only: bool,
    /// With --derive-only: print the derived word itself
    #[arg(long, requires = "derive_only")]
    pub string: bool,
    #[command(flatten)]
    pub facade: FacadeArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

/// The most rewriting steps: the derivation's cost grows with them even for a word that does
/// not (`F -> F`), and no drawn L-system needs more.
pub const MAX_ITERATIONS: u32 = 1000;
/// The largest `--max-symbols`: ten times the default's budget of time is the most a drawing
/// should take.
pub const MAX_MAX_SYMBOLS: u64 = 1_000_000_000;

/// The grammar and settings from the file and the command line.
struct Setup {
    grammar: Grammar,
    iterations: u32,
    turtle: TurtleOptions,
}

fn setup(args: &Args) -> Result<Setup> {
    let file = args
        .grammar
        .as_deref()
        .map(read_grammar_file)
        .transpose()?
        .unwrap_or_default();
    let rules = if args.rules.is_empty() {
        file.rules.into_iter().map(|(r, _)| r).collect()
    } else {
        args.rules
            .iter()
            .enumerate()
            .map(|(k, r)| parse_rule(r, &format!("--rule {}", k + 1)))
            .collect::<Result<Vec<_>, _>>()?
    };
    let axiom = args.axiom.clone().or(file.axiom).unwrap_or_default();
    // Errors in what came from the grammar file name the file.
    let from_file = |what: &str| match &args.grammar {
        Some(path) => format!("{}: {what}", path.display()),
        None => format!("--{what}"),
    };
    let grammar = Grammar::new(&axiom, rules).map_err(|e| {
        let source = if args.grammar.is_some() && (args.rules.is_empty() || args.axiom.is_none()) {
            from_file("grammar")
        } else {
            "--axiom/--rule".to_string()
        };
        anyhow::anyhow!("{source}: {e}")
    })?;
    let Some(iterations) = args.iterations.or(file.iterations) else {
        bail!("give --iterations (or an `iterations:` line in the grammar file)");
    };
    if iterations > MAX_ITERATIONS {
        let source = if args.iterations.is_some() {
            "--iterations".to_string()
        } else {
            from_file("iterations")
        };
        bail!("{source}: {iterations} iterations, more than {MAX_ITERATIONS} (each costs time even when the word does not grow)");
    }
    if args.max_symbols > MAX_MAX_SYMBOLS {
        bail!(
            "--max-symbols {}: at most {MAX_MAX_SYMBOLS}",
            args.max_symbols
        );
    }
    let angle = match (args.angle, &file.angle) {
        (Some(a), _) => a,
        (None, Some(text)) => text.parse().map_err(|e: String| {
            anyhow::anyhow!(
                "{}: angle {e}",
                args.grammar.as_deref().unwrap_or("".as_ref()).display()
            )
        })?,
        (None, None) => Angle::fixed(22.0),
    };
    let turtle = TurtleOptions {
        step: args.step.or(file.step).unwrap_or(500.0),
        angle,
        length_scale: args.length_scale,
        simplify: !args.no_simplify,
        radius: args.radius,
        radius_scale: args.radius_scale,
        decay: args.decay,
    };
    turtle.check()?;
    Ok(Setup {
        grammar,
        iterations,
        turtle,
    })
}

/// A bar over the symbols derived, for derivations long enough to wait for.
fn progress(grammar: &Grammar, iterations: u32) -> ProgressBar {
    let (_, most) = word_length(grammar, iterations);
    let bar = super::progress::bar("deriving", Some(most.min(u64::MAX as u128) as u64));
    if let Ok(style) =
        ProgressStyle::with_template("deriving {bar:40} {human_pos}/{human_len} symbols {elapsed}")
    {
        bar.set_style(style);
    }
    bar
}

/// Every 2^20 symbols the bar moves.
const TICK: u64 = 1 << 20;

pub fn run(args: Args) -> Result<()> {
    if args.derive_only {
        let o = &args.out;
        if o.output.is_some() || o.svg.is_some() || o.png.is_some() || o.report.is_some() {
            bail!("--derive-only draws nothing: leave out -o, --svg, --png and --report");
        }
        return derive_only(&args, &setup(&args)?);
    }
    let report = execute(&args)?;
    print(&report, &args.out)
}

/// Derives, draws and writes; returns the report.
pub fn execute(args: &Args) -> Result<serde_json::Value> {
    let s = setup(args)?;
    check_outputs(&args.out)?;
    let bar = progress(&s.grammar, s.iterations);
    let mut turtle = Turtle::new(&s.turtle, args.seed);
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let mut n = 0u64;
    derive(&s.grammar, s.iterations, &mut rng, args.max_symbols, |c| {
        turtle.feed(c);
        n += 1;
        if n.is_multiple_of(TICK) {
            bar.set_position(n);
        }
    })?;
    bar.finish_and_clear();
    let (tree, stats) = turtle.finish();
    if tree.network.edges.is_empty() {
        bail!(
            "the derived word draws nothing (no F in {} symbols)",
            stats.counts.symbols
        );
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
    let default_tip = t.radius / 8.0;
    let made = Made {
        tree,
        generator: "lsystem",
        parameters: vec![
            ("axiom", json!(String::from_utf8_lossy(s.grammar.axiom()))),
            ("rules", json!(rules)),
            ("iterations", json!(s.iterations)),
            ("angle_deg", json!([t.angle.min, t.angle.max])),
            ("step", json!(t.step)),
            ("length_scale", json!(t.length_scale)),
            ("simplify", json!(t.simplify)),
        ],
        seed: args.seed,
        report: serde_json::to_value(&stats)?,
        default_tip,
    };
    finish(made, &args.widths, &args.facade, &args.out)
}

fn derive_only(args: &Args, s: &Setup) -> Result<()> {
    let bar = progress(&s.grammar, s.iterations);
    let mut counts = Counts::default();
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let mut word = std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock());
    let mut failed: Option<std::io::Error> = None;
    derive(&s.grammar, s.iterations, &mut rng, args.max_symbols, |c| {
        counts.feed(c);
        if args.string && failed.is_none() {
            if let Err(e) = word.write_all(&[c]) {
                failed = Some(e);
            }
        }
        if counts.symbols.is_multiple_of(TICK) {
            bar.set_position(counts.symbols);
        }
    })?;
    bar.finish_and_clear();
    if args.string && failed.is_none() {
        failed = word.write_all(b"\n").and_then(|_| word.flush()).err();
    }
    drop(word);
    match failed {
        // A reader that stops early (`| head`) is not an error.
        Some(e) if e.kind() == std::io::ErrorKind::BrokenPipe => return Ok(()),
        Some(e) => bail!("cannot write the word to stdout: {e}"),
        None => {}
    }
    if args.out.json {
        let v = json!({
            "symbols": counts.symbols,
            "segments": counts.segments,
            "simplified_segments": counts.simplified_segments,
        });
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else if !args.string {
        outln!(
            "{} symbols, {} segments, {} after simplification",
            counts.symbols,
            counts.segments,
            counts.simplified_segments
        );
    }
    Ok(())
}
