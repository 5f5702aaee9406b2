//! Every command of the `lamina` binary as one call on values in memory.
//!
//! A stage takes typed inputs ([`Network`](crate::Network), [`TriMesh`](crate::TriMesh),
//! [`Axes`](crate::rationalize::axes::Axes), plate records, …) and an options struct whose
//! `Default` is the command's defaults, and returns a typed result that carries its report
//! (serde types: the report files the command writes are these, serialized). A stage reads no
//! file, writes no file, prints nothing and knows nothing of flags: the command line, the
//! Python package and a Rust program all call the same function, and the writers (JSON, DXF,
//! SVG, STL, SL1, HTML) are separate calls on the result.
//!
//! Long stages take a [`Progress`] handle owned by the caller, which shows where the work is
//! and can stop it ([`Progress::cancelled`], checked between steps).
//!
//! Options out of range are refused with an [`OptionError`] naming the option as its field is
//! named, written `name=` in the message (`tolerance= must be a positive distance in mm`):
//! the command line shows it as `--tolerance`, Python as `tolerance=`.
//!
//! ```
//! use lamina::stage::{nest, planarize, plates, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/calyx_veins.json"))?;
//! let solved = planarize::run(&net, None, &planarize::Options::default(), &Quiet)?;
//! let made = plates::run(&solved.axes, &plates::Options { thickness: Some(3.0), ..Default::default() })?;
//! let cut = nest::run(made.records(), made.core_records(), &nest::Options::default(), &Quiet)?;
//! assert_eq!(cut.places.len(), made.set.plates.len());
//! # Ok(()) }
//! ```

#![warn(missing_docs)]

pub mod audit;
pub mod bifurcate;
pub mod branching;
pub mod buds;
pub mod cells;
pub mod info;
pub mod lsystem;
pub mod nest;
pub mod planarize;
pub mod plates;
pub mod print;
pub mod progress;
pub mod simplify;
pub mod size;
pub mod slice;
pub mod solid;
pub mod veins;
pub mod venation;

pub use progress::{checkpoint, Cancelled, Progress, Quiet};

/// An option out of its range or inconsistent with another. `option` is the options struct's
/// field; the message writes it `option=` so that a front end can show it as its users type
/// it (see the module notes).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{option}= {problem}")]
pub struct OptionError {
    /// The field of the stage's options struct.
    pub option: &'static str,
    /// What is wrong with it, as a sentence that follows the option's name.
    pub problem: String,
}

impl OptionError {
    /// `option= problem`.
    pub fn new(option: &'static str, problem: impl Into<String>) -> Self {
        OptionError {
            option,
            problem: problem.into(),
        }
    }
}

/// `Ok(())` when `value` is finite and within `lo..=hi`; else an error saying the range, in
/// `unit` (as "must be from 0 to 1e6 mm, got -1").
pub fn in_range(
    option: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    unit: &str,
) -> Result<(), OptionError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        return Ok(());
    }
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    Err(OptionError::new(
        option,
        format!(
            "must be from {} to {}{unit}, got {}",
            crate::text::num(lo),
            crate::text::num(hi),
            crate::text::num(value)
        ),
    ))
}

/// `Ok(())` when `value` is finite, more than 0 and at most `hi`.
pub fn positive(option: &'static str, value: f64, hi: f64, unit: &str) -> Result<(), OptionError> {
    if value.is_finite() && value > 0.0 && value <= hi {
        return Ok(());
    }
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    Err(OptionError::new(
        option,
        format!(
            "must be more than 0 and at most {}{unit}, got {}",
            crate::text::num(hi),
            crate::text::num(value)
        ),
    ))
}
