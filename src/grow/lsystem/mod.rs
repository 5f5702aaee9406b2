//! Bracketed L-systems (Hanafin, Datta and Rolfe, "Tree façades", §5): grammars with
//! deterministic or stochastic productions, derived lazily (the word is never held in memory)
//! and drawn by a 2D/3D turtle that can merge runs of `F` into single members.
//!
//! `interpret` draws the n-th word into a [`Tree`]; `count` gives the paper's figures (symbols,
//! segments, simplified segments) without geometry. Both stream: memory is the drawing (or
//! nothing), whatever the word's length.

mod derive;
mod grammar;
mod turtle;

pub use derive::{derive, derive_until, word_length, DeriveError};
pub use grammar::{
    parse_json, parse_rule, parse_text, read_grammar_file, Grammar, GrammarError, GrammarFile, Rule,
};
pub use turtle::{Angle, Counts, Turtle, TurtleError, TurtleOptions, TurtleStats};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::tree::Tree;

/// Symbols a derivation may produce unless told otherwise. Counting holds none of them; a
/// drawing holds each member it draws (about 200 bytes with its node, while vectors grow):
/// the paper's grammar at n = 14 (31 M symbols, 4.8 M members) draws in about 1 GB.
pub const DEFAULT_MAX_SYMBOLS: u64 = 100_000_000;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LsystemError {
    #[error(transparent)]
    Grammar(#[from] GrammarError),
    #[error(transparent)]
    Derive(#[from] DeriveError),
    #[error(transparent)]
    Turtle(#[from] TurtleError),
}

/// Counts of the word derived in `iterations` steps.
pub fn count(
    grammar: &Grammar,
    iterations: u32,
    seed: u64,
    limit: u64,
) -> Result<Counts, LsystemError> {
    let mut counts = Counts::default();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    derive(grammar, iterations, &mut rng, limit, |c| counts.feed(c))?;
    Ok(counts)
}

/// Draws the word derived in `iterations` steps.
pub fn interpret(
    grammar: &Grammar,
    iterations: u32,
    opts: &TurtleOptions,
    seed: u64,
    limit: u64,
) -> Result<(Tree, TurtleStats), LsystemError> {
    opts.check()?;
    let mut turtle = Turtle::new(opts, seed);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    derive(grammar, iterations, &mut rng, limit, |c| turtle.feed(c))?;
    Ok(turtle.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    type Res = Result<(), Box<dyn std::error::Error>>;

    /// Hanafin et al. §5.3: X → F[-X]F[+X]-X, F → FF.
    fn paper() -> Result<Grammar, GrammarError> {
        Grammar::new(
            "X",
            vec![
                parse_rule("X -> F[-X]F[+X]-X", "p1")?,
                parse_rule("F -> FF", "p2")?,
            ],
        )
    }

    fn word(g: &Grammar, n: u32) -> Result<String, DeriveError> {
        let mut w = Vec::new();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        derive(g, n, &mut rng, u64::MAX, |c| w.push(c))?;
        Ok(String::from_utf8(w).expect("ASCII"))
    }

    #[test]
    fn the_papers_counts_at_seven_iterations() -> Res {
        let g = paper()?;
        let c = count(&g, 7, 1, DEFAULT_MAX_SYMBOLS)?;
        assert_eq!(
            (c.symbols, c.segments, c.simplified_segments),
            (13_956, 4_118, 2_186)
        );
        // The drawing has as many members as the count says, both ways.
        let (tree, stats) = interpret(&g, 7, &TurtleOptions::default(), 1, DEFAULT_MAX_SYMBOLS)?;
        assert_eq!(stats.counts, c);
        assert_eq!(tree.network.edges.len(), 2_186);
        assert!(tree.is_consistent());
        let plain = TurtleOptions {
            simplify: false,
            ..Default::default()
        };
        let (tree, _) = interpret(&g, 7, &plain, 1, DEFAULT_MAX_SYMBOLS)?;
        assert_eq!(tree.network.edges.len(), 4_118);
        Ok(())
    }

    #[test]
    fn the_papers_words_at_one_and_two_iterations() -> Res {
        let g = paper()?;
        assert_eq!(word(&g, 0)?, "X");
        assert_eq!(word(&g, 1)?, "F[-X]F[+X]-X");
        // As printed, with its typo `- F[X]` read as the grammar gives it, `-F[-X]`.
        let printed = "FF[-F[-X]F[+X]-X]FF[+F[-X]F[+X]-X]- F[X]F[+X]-X";
        let corrected = printed.replace("- F[X]", "-F[-X]");
        assert_ne!(printed, corrected, "the typo is where the issue says");
        assert_eq!(word(&g, 2)?, corrected);
        // The paper's n3 has the same slip once more (`-F[X]` at the end); elsewhere it agrees.
        let n3 = "FFFF[-FF[-F[-X]F[+X]-X]FF[+F[-X]F[+X]-X]-F[-X]F[+X]-X]FFFF[+FF[-F[-X]F[+X]-X]\
                  FF[+F[-X]F[+X]-X]-F[-X]F[+X]-X]-FF[-F[-X]F[+X]-X]FF[+F[-X]F[+X]-X]-F[X]F[+X]-X";
        assert_eq!(word(&g, 3)?, n3.replace("-F[X]", "-F[-X]"));
        Ok(())
    }

    #[test]
    fn simplified_segments_are_straight_runs_of_the_plain_drawing() -> Res {
        let g = paper()?;
        let plain = TurtleOptions {
            simplify: false,
            ..Default::default()
        };
        let (a, _) = interpret(&g, 5, &plain, 1, u64::MAX)?;
        let (b, _) = interpret(&g, 5, &TurtleOptions::default(), 1, u64::MAX)?;
        let total = |t: &Tree| t.network.lengths().map_or(0.0, |l| l.total);
        assert!((total(&a) - total(&b)).abs() < 1e-6 * total(&a));
        // Every simplified segment is a whole number of steps long.
        for e in &b.network.edges {
            let k = b.network.edge_length(e) / 500.0;
            assert!((k - k.round()).abs() < 1e-9 && k.round() >= 1.0, "{k}");
        }
        Ok(())
    }

    #[test]
    fn a_mirrored_grammar_draws_the_mirror_image() -> Res {
        let g = paper()?;
        let opts = TurtleOptions::default();
        let (a, _) = interpret(&g, 6, &opts, 1, u64::MAX)?;
        let (b, _) = interpret(&g.mirrored(), 6, &opts, 1, u64::MAX)?;
        assert_eq!(a.network.nodes.len(), b.network.nodes.len());
        assert_eq!(a.network.edges, b.network.edges);
        for (p, q) in a.network.nodes.iter().zip(&b.network.nodes) {
            // Exactly: IEEE arithmetic is symmetric under sign changes.
            assert_eq!((p.p.x, p.p.y, p.p.z), (-q.p.x, q.p.y, q.p.z));
        }
        assert!(a.network.nodes.iter().any(|n| n.p.x.abs() > 1.0));
        Ok(())
    }

    #[test]
    fn an_angle_range_draws_every_turn_inside_it_and_repeats_by_seed() -> Res {
        let g = paper()?;
        let opts = TurtleOptions {
            angle: "15..30".parse()?,
            ..Default::default()
        };
        let (a, sa) = interpret(&g, 6, &opts, 3, u64::MAX)?;
        let (b, _) = interpret(&g, 6, &opts, 3, u64::MAX)?;
        let (c, _) = interpret(&g, 6, &opts, 4, u64::MAX)?;
        assert_eq!(a, b);
        assert_ne!(a, c);
        let (lo, hi) = (
            sa.turn_min_deg.ok_or("turns")?,
            sa.turn_max_deg.ok_or("turns")?,
        );
        assert!((15.0..=30.0).contains(&lo) && (15.0..=30.0).contains(&hi));
        assert!(hi - lo > 10.0, "the range is used: {lo}..{hi}");
        // From the geometry alone: along a chain F+F+F… every bend is one turn.
        let chain = Grammar::new(&"F+".repeat(200), vec![])?;
        let (t, _) = interpret(&chain, 0, &opts, 9, u64::MAX)?;
        let n = &t.network.nodes;
        for w in n.windows(3).skip(1) {
            let (d0, d1) = (w[1].p - w[0].p, w[2].p - w[1].p);
            if d0.length() < 1.0 || d1.length() < 1.0 {
                continue;
            }
            let turn = d0.angle_between(d1).to_degrees();
            assert!((15.0 - 1e-9..=30.0 + 1e-9).contains(&turn), "{turn}");
        }
        Ok(())
    }

    #[test]
    fn three_d_symbols_leave_the_plane_and_keep_the_frame() -> Res {
        let g = Grammar::new("A", vec![parse_rule("A -> F[&FA]/[^FA]\\\\F|FA", "r")?])?;
        let (t, _) = interpret(
            &g,
            4,
            &TurtleOptions {
                angle: Angle::fixed(30.0),
                ..Default::default()
            },
            1,
            u64::MAX,
        )?;
        assert!(t.network.nodes.iter().any(|n| n.p.z.abs() > 1.0));
        for e in &t.network.edges {
            let l = t.network.edge_length(e);
            let k = l / 500.0;
            assert!((k - k.round()).abs() < 1e-9, "{l}");
        }
        Ok(())
    }

    #[test]
    fn widths_follow_depth_and_decay() -> Res {
        let g = Grammar::new("F[F[!F]]", vec![])?;
        let opts = TurtleOptions {
            radius: 10.0,
            radius_scale: 0.5,
            decay: 0.5,
            length_scale: 0.5,
            ..Default::default()
        };
        let (t, stats) = interpret(&g, 0, &opts, 1, u64::MAX)?;
        let r: Vec<f64> = t.network.edges.iter().map(|e| e.radius).collect();
        assert_eq!(r, vec![10.0, 5.0, 1.25]);
        let l: Vec<f64> = t
            .network
            .edges
            .iter()
            .map(|e| t.network.edge_length(e))
            .collect();
        assert_eq!(l, vec![500.0, 250.0, 125.0]);
        assert_eq!(stats.max_depth, 2);
        Ok(())
    }
}
