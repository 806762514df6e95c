//! Optics: data tables, inherent optical properties, phase functions, the
//! sky's radiance distribution, the sea surface, local majorants for delta
//! tracking and the water's refractive index per band.

pub mod atmosphere;
pub mod inelastic;
pub mod iop;
pub mod majorant;
pub mod phase;
pub mod sky;
pub mod surface;
pub mod tables;
pub mod water_index;
