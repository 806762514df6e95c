//! Optics: data tables, inherent optical properties, phase functions, the
//! sky's radiance distribution and the sea surface.

pub mod iop;
pub mod majorant;
pub mod phase;
pub mod sky;
pub mod surface;
pub mod tables;
pub mod water_index;
