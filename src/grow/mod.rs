//! Generators: they make `Network`s. So far: leaf venation in 2D, open and closed, in a blade
//! that may grow, with its outlines, source placement, density maps, Murray widths and quality
//! report.

pub mod density;
pub mod frames;
pub mod geodesic;
pub mod leaf;
pub mod murray;
pub mod outline;
pub mod outline_file;
pub mod poisson;
pub mod report;
pub mod space;
pub mod surface;
pub mod venation;
