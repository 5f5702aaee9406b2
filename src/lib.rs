//! lamina: grow branching structures and turn polyline networks into things that can be built.
//!
//! The core type is [`Network`] (nodes and edges in 3D, millimetres); surfaces are [`TriMesh`].
//! Formats live in each type's `io` module; `files` holds the error types and atomic writes.

pub mod analyze;
pub mod fabricate;
pub mod files;
pub mod fuzz;
pub mod geom;
pub mod grow;
pub mod mesh;
pub mod network;
pub mod rationalize;
pub mod report;
pub mod stage;
pub mod text;
pub mod view;

pub use files::{ReadError, WriteError};

/// The README's Rust example ("As a Rust library"), run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
pub use mesh::TriMesh;
pub use network::{Edge, Meta, Network, Node};
