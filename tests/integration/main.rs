//! littoral's integration tests, compiled as one crate.

mod common;

mod against_path;
mod atmosphere;
mod band_shapes;
mod cache;
mod cli;
mod clients;
mod convergence;
mod corruption;
mod cube_tool;
mod determinism;
mod fluorescence;
mod georef;
mod ground;
mod inelastic;
mod job;
mod land;
mod memory;
mod oracle;
mod path;
mod physics;
mod products;
mod publication;
mod render;
mod roundtrip;
mod scenes;
mod searches;
mod sharding;
mod sky;
mod slurm;
mod splitting;
mod surface;
mod viewers;
mod water_optics;
