//! From a network to things that can be built. So far: panels and their planarity metrics, and
//! node axes that make every panel planar (`planarize`).

pub mod audit;
pub mod axes;
pub mod bolts;
pub mod cells;
pub mod clearance;
pub mod groups;
pub mod panels;
pub mod planarize;
pub mod plates;
pub mod reference;
pub mod simplify;
pub mod tolerance;
pub mod welds;
