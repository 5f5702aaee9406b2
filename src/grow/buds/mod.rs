//! Growth forms (George W. Hart, "Growth Forms"): buds that run small programs grow a
//! triangulated cellular surface, from a tetrahedron, into a printable solid.
//!
//! - [`graph`]: the cell graph, a closed oriented triangulated manifold kept by a rotation
//!   system; division as the paper's Figure 2; the hole's tunnel; `check()`.
//! - [`embed`]: positions by a 3D Kamada-Kawai spring embedder relaxed locally after each
//!   division, with a spatial hash for contact and collision queries.
//! - [`program`]: the bud language of the paper's Figure 8.
//! - [`sim`]: buds and their time-sharing scheduler, tropism, bud splitting, line buds, holes
//!   and the collision freeze.
//! - [`skin`]: the form as a mesh, each cell's texture made geometry, with no self-intersection.
//!
//! Guarantees: after every operation the graph is a closed oriented triangulated surface of
//! genus equal to the holes grown (`check()` verifies it; `GrowthOptions::verify` runs it after
//! each operation). Degrees stay at least 3. A bud freezes when a cell it moved comes within
//! the clearance of a part of the form more than four hops away, and such parts repel in the
//! embedder; the output mesh is tested triangle against triangle and textures are reduced where
//! they would touch. Not guaranteed: that the base surface never self-intersects under every
//! program (the final test reports any intersection it finds).

pub mod embed;
pub mod graph;
mod hole;
pub mod program;
pub mod sim;
pub mod skin;

pub use graph::{CellGraph, Census, GraphError};
pub use program::{parse_program, read_program, Command, Program, ProgramError, Texture};
pub use sim::{grow, Form, Growth, GrowthOptions, GrowthReport, Sample};
pub use skin::{skin, SkinOptions, SkinReport};

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BudError {
    #[error(transparent)]
    Program(#[from] ProgramError),
    #[error("the cell graph broke after {operation}: {source}")]
    Graph {
        operation: String,
        #[source]
        source: GraphError,
    },
    #[error("{0}")]
    Options(String),
}
