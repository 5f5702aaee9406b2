//! One module per subcommand: an argument struct and a `run` that calls the library.

pub mod bifurcate;
pub mod branching;
pub mod buds;
pub mod cells;
pub mod convert;
pub mod demo;
pub mod info;
pub mod input;
pub mod lsystem;
pub mod nest;
pub mod planarize;
pub mod plates;
pub mod print;
pub mod render;
pub mod simplify;
pub mod size;
pub mod sl1;
pub mod slice;
pub mod solid;
pub mod surface;
pub mod veins;
pub mod venation;
pub mod view;
