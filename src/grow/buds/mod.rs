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
//! - [`skin()`]: the form as a mesh, each cell's texture made geometry, with no self-intersection.
//!
//! Guarantees: after every operation the graph is a closed oriented triangulated surface of
//! genus equal to the holes grown (`check()` verifies it; `GrowthOptions::verify` runs it after
//! each operation). Degrees stay at least 3. No move of a cell, and no placement of new cells,
//! is made if a triangle round it would meet another triangle of the form, so the surface
//! never passes through itself; distant parts of the form that come within the clearance
//! repel, and freeze the bud that brought them there. The output mesh is tested triangle
//! against triangle again and textures are reduced where they would touch. The tests are in
//! floating point with a relative tolerance of 1e-9: not exact predicates.

pub mod embed;
pub mod graph;
mod hole;
pub mod program;
pub mod sim;
pub mod skin;

pub use graph::{CellGraph, Census, GraphError};
pub use program::{parse_program, read_program, Command, Program, ProgramError, Texture};
pub use sim::{grow, BudAt, Form, Growth, GrowthOptions, GrowthReport, Sample};
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
