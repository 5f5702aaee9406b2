//! L-system derivation and interpretation (Hanafin et al.'s grammar, X → F[-X]F[+X]-X,
//! F → FF): n = 13 is 10,346,712 symbols, n = 14 is 31,038,794. Counting streams the word
//! through the paper's counters; drawing streams it through the turtle into a network of
//! simplified members. Peak memory (VmHWM) is read after each stage: counting must not grow it.
//! `harness = false`: `cargo bench --bench lsystem`.

use lamina::grow::lsystem::{count, interpret, parse_rule, Grammar, TurtleOptions};

#[path = "common/timing.rs"]
mod timing;
use timing::{best_of, peak_mib};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let g = Grammar::new(
        "X",
        vec![
            parse_rule("X -> F[-X]F[+X]-X", "p1")?,
            parse_rule("F -> FF", "p2")?,
        ],
    )?;
    println!("peak before: {:.1} MiB", peak_mib());
    for n in [7, 13, 14] {
        let (secs, c) = best_of(5, || count(&g, n, 1, u64::MAX));
        let c = c?;
        println!(
            "count  n = {n:2}: {:>11} symbols {:>10} segments {:>9} simplified  {:8.3} s  {:6.1} M symbols/s  peak {:.1} MiB",
            c.symbols,
            c.segments,
            c.simplified_segments,
            secs,
            c.symbols as f64 / secs / 1e6,
            peak_mib()
        );
    }
    let opts = TurtleOptions::default();
    for n in [7, 13] {
        let (secs, r) = best_of(5, || interpret(&g, n, &opts, 1, u64::MAX));
        let (tree, stats) = r?;
        println!(
            "draw   n = {n:2}: {:>11} symbols {:>10} members {:>9} nodes       {:8.3} s  {:6.1} M symbols/s  peak {:.1} MiB",
            stats.counts.symbols,
            tree.network.edges.len(),
            tree.network.nodes.len(),
            secs,
            stats.counts.symbols as f64 / secs / 1e6,
            peak_mib()
        );
    }
    let ranged = TurtleOptions {
        angle: "15..30".parse()?,
        ..Default::default()
    };
    let (secs, r) = best_of(5, || interpret(&g, 13, &ranged, 1, u64::MAX));
    let (tree, stats) = r?;
    println!(
        "draw   n = 13, angle 15..30: {} members in {secs:.3} s ({:.1} M symbols/s)",
        tree.network.edges.len(),
        stats.counts.symbols as f64 / secs / 1e6
    );
    Ok(())
}
