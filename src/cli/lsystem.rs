//! `lamina lsystem`: derive a bracketed L-system and draw it with the turtle, or only count it
//! (`--derive-only`), optionally fitted to a façade and projected onto a surface.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args as ClapArgs;
use serde_json::json;

use super::branching::{check_outputs, print, write, FacadeArgs, OutputArgs, WidthArgs};
use super::progress::Bar;
use lamina::grow::lsystem::{read_grammar_file, Angle, DEFAULT_MAX_SYMBOLS};
use lamina::stage::lsystem;

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

/// The stage's options from the flags (the grammar file and the surface read).
fn options(args: &Args) -> Result<lsystem::Options> {
    Ok(lsystem::Options {
        axiom: args.axiom.clone(),
        rule: args.rules.clone(),
        grammar: args.grammar.as_deref().map(read_grammar_file).transpose()?,
        grammar_name: args
            .grammar
            .as_ref()
            .map_or_else(|| "grammar".into(), |p| p.display().to_string()),
        iterations: args.iterations,
        angle: args.angle,
        step: args.step,
        length_scale: args.length_scale,
        no_simplify: args.no_simplify,
        radius: args.radius,
        radius_scale: args.radius_scale,
        decay: args.decay,
        seed: args.seed,
        max_symbols: args.max_symbols,
        shape: if args.derive_only {
            Default::default()
        } else {
            args.facade.shape(&args.widths)?
        },
    })
}

pub fn run(args: Args) -> Result<()> {
    if args.derive_only {
        let o = &args.out;
        if o.output.is_some() || o.svg.is_some() || o.png.is_some() || o.report.is_some() {
            bail!("--derive-only draws nothing: leave out -o, --svg, --png and --report");
        }
        return derive_only(&args, &options(&args)?);
    }
    let report = execute(&args)?;
    print(&report, &args.out)
}

/// Derives, draws, shapes and writes; returns the report.
pub fn execute(args: &Args) -> Result<serde_json::Value> {
    check_outputs(&args.out)?;
    let opts = options(args)?;
    let drawn = lsystem::run(&opts, &Bar::new())?;
    write(
        &drawn.network,
        &drawn.report,
        opts.shape.onto.as_ref(),
        &args.out,
    )
}

fn derive_only(args: &Args, opts: &lsystem::Options) -> Result<()> {
    let mut word = std::io::BufWriter::with_capacity(1 << 16, std::io::stdout().lock());
    let mut failed: Option<std::io::Error> = None;
    let counts = lsystem::derive_only(
        opts,
        |c| {
            if args.string && failed.is_none() {
                if let Err(e) = word.write_all(&[c]) {
                    failed = Some(e);
                }
            }
        },
        &Bar::new(),
    )?;
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
