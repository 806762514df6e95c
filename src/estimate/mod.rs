//! Radiance from photons: the photon-map estimate at a point along a ray,
//! with the paper's boundary-bias compensation (search volumes cut by the
//! surface, floor, targets and open edges) and spectral-bias compensation,
//! and the forward peak of the phase functions taken out as a delta.
//!
//! - [`estimator`]: the estimate itself ([`Estimator`]): one search, the
//!   volume or disc, the phase weights, the band combination.
//! - [`boundary`]: search volumes and discs cut by boundaries ([`BoundaryMode`]).
//! - [`spectral`]: band sums and their combination ([`SpectralMode`]).
//! - [`groups`]: the photon noise of an estimate from independent photon
//!   groups, carried along a ray ([`groups::CHANNELS`]).
//! - [`peak`]: phase functions with the forward peak as a delta ([`peak::TruncatedPhase`]).
//! - [`shape`]: band shapes of the light travelling up and down on a coarse
//!   grid over every volume photon ([`shape::BandShapeGrid`]).
//!
//! Not for: finding photons (`store::query`), marching rays or direct
//! light (`render`).

pub mod boundary;
pub mod estimator;
pub mod groups;
pub mod peak;
pub mod shape;
pub mod spectral;

pub use boundary::BoundaryMode;
pub use estimator::{Estimator, Scratch};
pub use spectral::SpectralMode;
