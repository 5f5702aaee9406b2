//! Generators: they make `Network`s. Leaf venation in 2D, open and closed, in a blade that may
//! grow, with its outlines, source placement, density maps, Murray widths and quality report;
//! venation on surfaces and geodesic veins; L-systems and recursive bifurcation drawn as trees,
//! fitted to a façade boundary and projected onto a surface.

pub mod bifurcation;
pub mod buds;
pub mod density;
pub mod facade;
pub mod frames;
pub mod geodesic;
pub mod leaf;
pub mod lsystem;
pub mod murray;
pub mod outline;
pub mod outline_file;
pub mod poisson;
pub mod project;
pub mod report;
pub mod space;
pub mod surface;
pub mod tree;
pub mod venation;
