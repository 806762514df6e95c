//! Optics: data tables, inherent optical properties, phase functions and
//! the sea surface.

pub mod iop;
pub mod phase;
pub mod surface;
pub mod tables;
