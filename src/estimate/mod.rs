//! Radiance-estimate compensations: boundary bias (search volumes cut by
//! the surface, floor, targets and open edges) and spectral bias.

pub mod boundary;
pub mod spectral;
