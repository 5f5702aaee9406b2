//! Reports of the stages' results: JSON for machines and one self-contained HTML page with
//! inline SVG for people. So far: planarity.

pub mod demo_index;
pub mod planarity;
