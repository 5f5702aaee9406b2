//! Parallel rewriting without the word in memory: the n-th derived word is produced symbol by
//! symbol, depth first. A stack holds one frame per derivation level (at most n + 1), each the
//! successor being read and the position in it; a symbol with a production below level n opens
//! a frame for its successor, every other symbol is emitted. The word is the same as rewriting
//! the whole string n times (`expand_naive` in the tests checks it), in the same order.
//!
//! Stochastic productions draw once per occurrence and level, as parallel rewriting does, in
//! the order the word is read; the same seed gives the same word.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::grammar::Grammar;

/// Why a derivation stopped.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DeriveError {
    #[error(
        "{iterations} iterations would derive at least {at_least} symbols, more than \
         max_symbols= {limit}: use fewer iterations or raise the limit"
    )]
    TooLong {
        iterations: u32,
        at_least: u128,
        limit: u64,
    },
    #[error("cancelled")]
    Cancelled,
}

/// Fewest and most symbols the n-th word can have (equal for a deterministic grammar),
/// saturating at `u128::MAX`.
pub fn word_length(grammar: &Grammar, iterations: u32) -> (u128, u128) {
    // len[s] = lengths of symbol s after k rewritings, for k = 0..=iterations.
    let mut lo = [1u128; 256];
    let mut hi = [1u128; 256];
    for _ in 0..iterations {
        let (mut nlo, mut nhi) = (lo, hi);
        for s in 0..=255u8 {
            if let Some(p) = grammar.production(s) {
                let sum = |len: &[u128; 256], succ: &[u8]| {
                    succ.iter()
                        .fold(0u128, |a, &c| a.saturating_add(len[c as usize]))
                };
                nlo[s as usize] = p.successors.iter().map(|w| sum(&lo, w)).min().unwrap_or(0);
                nhi[s as usize] = p.successors.iter().map(|w| sum(&hi, w)).max().unwrap_or(0);
            }
        }
        (lo, hi) = (nlo, nhi);
    }
    let total = |len: &[u128; 256]| {
        grammar
            .axiom()
            .iter()
            .fold(0u128, |a, &c| a.saturating_add(len[c as usize]))
    };
    (total(&lo), total(&hi))
}

/// Streams the word derived in `iterations` steps into `emit`, one symbol at a time, and
/// returns its length. Fails before emitting anything when even the shortest possible word is
/// longer than `limit`, and stops with the same error when a stochastic derivation passes it.
pub fn derive(
    grammar: &Grammar,
    iterations: u32,
    rng: &mut ChaCha8Rng,
    limit: u64,
    emit: impl FnMut(u8),
) -> Result<u64, DeriveError> {
    derive_until(grammar, iterations, rng, limit, emit, &|| false)
}

/// Symbols emitted between two questions to `stop`.
const STOP_EVERY: u64 = 1 << 16;

/// [`derive()`], asking `stop` every 65,536 symbols and ending with `DeriveError::Cancelled`
/// when it says so.
pub fn derive_until(
    grammar: &Grammar,
    iterations: u32,
    rng: &mut ChaCha8Rng,
    limit: u64,
    mut emit: impl FnMut(u8),
    stop: &dyn Fn() -> bool,
) -> Result<u64, DeriveError> {
    let (shortest, _) = word_length(grammar, iterations);
    let too_long = |at_least: u128| DeriveError::TooLong {
        iterations,
        at_least,
        limit,
    };
    if shortest > limit as u128 {
        return Err(too_long(shortest));
    }
    let stochastic = grammar.is_stochastic();
    let mut count = 0u64;
    // (word, next position, level of the word's symbols)
    let mut stack: Vec<(&[u8], usize, u32)> = Vec::with_capacity(iterations as usize + 1);
    stack.push((grammar.axiom(), 0, 0));
    while let Some(top) = stack.last_mut() {
        let (word, pos, level) = (top.0, top.1, top.2);
        if pos == word.len() {
            stack.pop();
            continue;
        }
        top.1 += 1;
        let symbol = word[pos];
        let production = if level < iterations {
            grammar.production(symbol)
        } else {
            None
        };
        let Some(p) = production else {
            emit(symbol);
            count += 1;
            if count.is_multiple_of(STOP_EVERY) && stop() {
                return Err(DeriveError::Cancelled);
            }
            if stochastic && count > limit {
                return Err(too_long(count as u128));
            }
            continue;
        };
        let successor = if p.is_stochastic() {
            p.pick(rng.random::<f64>())
        } else {
            &p.successors[0]
        };
        if level + 1 == iterations {
            // Its symbols are final: emit them without a frame.
            for &c in successor {
                emit(c);
            }
            let before = count;
            count += successor.len() as u64;
            if before / STOP_EVERY != count / STOP_EVERY && stop() {
                return Err(DeriveError::Cancelled);
            }
            if stochastic && count > limit {
                return Err(too_long(count as u128));
            }
        } else {
            stack.push((successor, 0, level + 1));
        }
    }
    Ok(count)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grow::lsystem::grammar::{parse_rule, GrammarError};
    use rand::SeedableRng;

    fn paper() -> Result<Grammar, GrammarError> {
        Grammar::new(
            "X",
            vec![
                parse_rule("X=F[-X]F[+X]-X", "p1")?,
                parse_rule("F=FF", "p2")?,
            ],
        )
    }

    /// Rewriting the whole string n times: the definition the stream must agree with.
    fn expand_naive(g: &Grammar, n: u32) -> Vec<u8> {
        let mut word = g.axiom().to_vec();
        for _ in 0..n {
            word = word
                .iter()
                .flat_map(|&c| match g.production(c) {
                    Some(p) => p.successors[0].clone(),
                    None => vec![c],
                })
                .collect();
        }
        word
    }

    fn stream(g: &Grammar, n: u32, seed: u64) -> Result<Vec<u8>, DeriveError> {
        let mut out = Vec::new();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let len = derive(g, n, &mut rng, u64::MAX, |c| out.push(c))?;
        assert_eq!(len as usize, out.len());
        Ok(out)
    }

    #[test]
    fn the_stream_is_the_rewritten_string() -> Result<(), Box<dyn std::error::Error>> {
        let g = paper()?;
        for n in 0..=7 {
            let w = stream(&g, n, 1)?;
            assert_eq!(w, expand_naive(&g, n), "n = {n}");
            let (lo, hi) = word_length(&g, n);
            assert_eq!((lo, hi), (w.len() as u128, w.len() as u128));
        }
        assert_eq!(stream(&g, 7, 1)?.len(), 13_956);
        Ok(())
    }

    #[test]
    fn the_length_guard_stops_before_any_symbol() -> Result<(), GrammarError> {
        let g = paper()?;
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut emitted = 0;
        let r = derive(&g, 14, &mut rng, 10_000_000, |_| emitted += 1);
        assert!(
            matches!(r, Err(DeriveError::TooLong { at_least, .. }) if at_least > 10_000_000),
            "{r:?}"
        );
        assert_eq!(emitted, 0);
        // Lengths far past u64 saturate rather than wrap.
        assert!(word_length(&g, 200).0 > u64::MAX as u128);
        Ok(())
    }

    #[test]
    fn stochastic_words_repeat_by_seed_and_stop_at_the_limit(
    ) -> Result<(), Box<dyn std::error::Error>> {
        let g = Grammar::new(
            "F",
            vec![
                parse_rule("F (1) -> F[+F]F", "a")?,
                parse_rule("F (1) -> F[-F]", "b")?,
                parse_rule("F (1) -> FF[+F]F[-F]F", "c")?,
            ],
        )?;
        let a = stream(&g, 5, 7)?;
        assert_eq!(a, stream(&g, 5, 7)?);
        assert_ne!(a, stream(&g, 5, 8)?);
        let (lo, hi) = word_length(&g, 5);
        assert!(lo <= a.len() as u128 && a.len() as u128 <= hi);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let r = derive(&g, 5, &mut rng, lo as u64, |_| {});
        if a.len() as u128 > lo {
            assert!(matches!(r, Err(DeriveError::TooLong { .. })), "{r:?}");
        }
        Ok(())
    }
}
