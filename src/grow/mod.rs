//! Generators: they make `Network`s. So far: leaf venation in 2D (open), its blade outlines,
//! Poisson-disk source placement and Murray widths.

pub mod murray;
pub mod outline;
pub mod poisson;
pub mod venation;
