pub mod boundary;
pub mod spectral;
