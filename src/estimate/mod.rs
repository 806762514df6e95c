pub mod spectral;
