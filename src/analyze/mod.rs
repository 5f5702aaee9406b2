//! Structural analysis of the plate network: a linear 3D frame ([`frame`]) or the panels as
//! flat shells ([`shell`]), steels
//! ([`material`]), sizing the gauges from utilisation and deflection ([`sizing`]), its report
//! page ([`report`]) and a CalculiX deck of the same model ([`ccx`]).

pub mod ccx;
pub mod frame;
pub mod material;
pub mod report;
pub mod shell;
pub mod sizing;
