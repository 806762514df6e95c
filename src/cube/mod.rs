//! Radiance-cube outputs: the ENVI cube written tile by tile, and the
//! true-colour quicklook.
//!
//! Design note: a cube of hundreds of bands over a large scene does not fit
//! in memory, so the writer ([`envi::EnviWriter`]) takes tiles in any order
//! from any thread and scatters them into a pre-sized file, and the reader
//! ([`envi::EnviCube`]) answers pixel and band requests with positioned
//! reads. The quicklook ([`quicklook::Quicklook`]) reduces each spectrum to
//! three numbers, so a whole RGB image is small enough to hold.
//!
//! The spectral OpenEXR copy ([`exr::write_spectral_exr`]) is made from the
//! finished ENVI cube, one tile of all bands at a time.
//!
//! Modules: [`envi`] (the cube writer and reader), [`exr`] (the spectral
//! OpenEXR copy), [`quicklook`] (true colour and PNGs), [`georef`] (map
//! geometry and CRS for the header), [`ops`] (whole-cube operations that
//! stream: windows, resampling into a real sensor's bands, whose spectral
//! responses are `spectral::response`).
//!
//! Not for: rendering (the sensor produces the spectra). The reader takes
//! BSQ, BIL and BIP cubes of 16-bit integers or 32/64-bit floats in either
//! byte order; anything else is refused with an error rather than guessed.

pub mod envi;
pub mod exr;
pub mod georef;
pub mod ops;
pub mod quicklook;

pub use envi::{CubeSpec, EnviCube, EnviWriter};
pub use quicklook::Quicklook;
