//! Spectral-bias compensation: per-band radiance from band-tagged photons.
//!
//! **Base estimate** (Jensen 2001, *Realistic Image Synthesis Using Photon
//! Mapping*, ch. 7): the radiance of band i at a site is the weighted power of
//! the band-i photons found by a search, divided by the search volume (or
//! area, on a surface):
//!
//! ```text
//! L_i = sum_{p in search, band(p) = i} w_p Phi_p / V
//! ```
//!
//! with `w_p` the phase-function (volume) or BRDF (surface) value for the
//! photon's direction and `Phi_p` its power. Every photon carries exactly one
//! of N bands, so a search of k photons holds about k/N of each band: with
//! hundreds of bands most bands hold zero or one photon and the per-band
//! estimate is noise (relative error about sqrt(N/k)).
//!
//! **Compensation** (the RIT/DIRSIG poster *Simulated Spectral Light Transport
//! in Coastal Waters Using Adaptive Photon Mapping*, Goodenough): take the
//! level from a small *local* search and the spectral shape from a larger
//! *expanded* one,
//!
//! ```text
//! Lbar  = (1/N) sum_i L_i             local search, volume V
//! L'bar = (1/N) sum_i L'_i            expanded search, volume V'
//! L_i  <- Lbar * L'_i / L'bar         (0 where L'bar = 0)
//! ```
//!
//! Writing T and E for the local and expanded band totals of weighted power
//! and e_i for the expanded band-i sum, this is `L_i = (T / V) * e_i / E`:
//! - the band sum is preserved: `sum_i L_i = (T / V) * E / E = T / V`, the
//!   band sum of the naive local estimate, so the compensated result keeps
//!   the local search's spatial resolution and low bias in total radiance;
//!   only how that total is shared among bands changes;
//! - `V'` cancels: only the expanded search's band *proportions* matter, so
//!   an error in its (boundary-compensated) volume cannot leak into the result;
//! - per band the relative variance drops from about `1/(k S_i)` to about
//!   `1/k + 1/(K S_i)` (k local, K expanded photons, S_i the band's share of
//!   the power); the price is that the shape is averaged over the expanded
//!   region, which blurs spectral edges (e.g. across a change of floor
//!   material) but not the level.
//!
//! The combination is computed in the `(T / V) * e_i / E` form: one division
//! per site and one product per band, and the band-sum identity then holds to
//! rounding (tested to 1e-12 relative).
//!
//! **Hot path.** [`BandSums`] (the estimator holds three per thread:
//! local, expanded, coarse) is allocated once and cleared per site; nothing in the
//! accumulate/combine loop allocates. Clearing and combining cost O(N) per
//! site, as writing the N-band result does anyway.
//!
//! Not for: finding photons ([`crate::store::query`]), search volumes and boundary
//! compensation (the caller passes the volumes), or the weights themselves
//! (`crate::optics`).

use crate::photon::Photon;
pub use crate::scene::settings::SpectralMode;
use crate::store::query::Neighbour;

impl SpectralMode {
    /// Whether [`combine`] reads the expanded search; callers can skip that
    /// search (the costlier of the two) when it does not.
    pub fn needs_expanded(self) -> bool {
        self != SpectralMode::Naive
    }
}

/// Per-band accumulation of one search: contributions (weight x power, where
/// the weight is e.g. a phase-function or BRDF value) per band, and the search
/// volume (or area) they are divided by.
///
/// The volume is not stored: it is passed to [`BandSums::estimates`] and
/// [`combine`], since the caller computes it (boundary compensation) after
/// the search. Contributions are expected to be non-negative (weights and
/// powers are); sums are kept in f64 so that hundreds of f32 powers add up
/// without loss.
#[derive(Clone, Debug, PartialEq)]
pub struct BandSums {
    sums: Vec<f64>,
    dropped: u64,
}

impl BandSums {
    /// Empty sums over `bands` bands.
    pub fn new(bands: usize) -> Self {
        BandSums {
            sums: vec![0.0; bands],
            dropped: 0,
        }
    }

    /// Number of bands.
    pub fn bands(&self) -> usize {
        self.sums.len()
    }

    /// Reset every band to zero (and the dropped count), keeping the storage.
    pub fn clear(&mut self) {
        self.sums.fill(0.0);
        self.dropped = 0;
    }

    /// Add `contribution` (weight x power, W-based units) to `band`.
    ///
    /// A band outside the grid or a non-finite contribution is not added but
    /// counted in [`BandSums::dropped`]: one bad photon or weight must neither
    /// crash a render nor turn a whole spectrum into NaN, and the count lets
    /// the caller report it.
    #[inline]
    pub fn add(&mut self, band: u16, contribution: f64) {
        match self.sums.get_mut(band as usize) {
            Some(sum) if contribution.is_finite() => *sum += contribution,
            _ => self.dropped += 1,
        }
    }

    /// Add a photon's power times `weight`.
    #[inline]
    pub fn add_photon(&mut self, photon: &Photon, weight: f64) {
        self.add(photon.band, weight * photon.power as f64);
    }

    /// Add every neighbour's power times `weight(neighbour)`; the weight sees
    /// the distance as well as the photon, so a filter kernel fits here too.
    pub fn add_neighbours(
        &mut self,
        neighbours: &[Neighbour],
        mut weight: impl FnMut(&Neighbour) -> f64,
    ) {
        for n in neighbours {
            self.add_photon(&n.photon, weight(n));
        }
    }

    /// The per-band sums of contributions.
    pub fn sums(&self) -> &[f64] {
        &self.sums
    }

    /// Sum over all bands.
    pub fn total(&self) -> f64 {
        self.sums.iter().sum()
    }

    /// Contributions refused by [`BandSums::add`] since the last clear.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Per-band estimates `sum_i / volume` into `out` (length = bands).
    ///
    /// A volume that is not positive and finite has no density (an empty or
    /// degenerate search): `out` is set to zero rather than to inf or NaN.
    pub fn estimates(&self, volume: f64, out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.sums.len(), "output sized to the band grid");
        if !valid_volume(volume) {
            out.fill(0.0);
            return;
        }
        // Divide rather than multiply by 1/V so that the naive estimate is
        // exactly sum / V; N divisions per site cost nothing next to a search.
        for (o, s) in out.iter_mut().zip(&self.sums) {
            *o = s / volume;
        }
    }
}

fn valid_volume(v: f64) -> bool {
    v > 0.0 && v.is_finite()
}

/// `total / v`, or 0 for a volume that is not positive and finite.
pub(crate) fn density(total: f64, v: f64) -> f64 {
    if valid_volume(v) {
        total / v
    } else {
        0.0
    }
}

/// [`combine`] with part of the signal estimated at the expanded scale:
/// `coarse` holds the contributions of one class of photons (those the
/// caller counts only in the expanded search) and the local sums the rest.
/// `Naive` -> local_i / V + coarse_i / V'; `Compensated` ->
/// (Lbar + C'bar) L'_i / L'bar, with Lbar = local total / V and C'bar =
/// coarse total / V'. Splitting a density estimate by photon class and estimating each
/// class with its own bandwidth keeps it consistent; the renderer uses it
/// for the few heavy photons travelling toward the viewer (see
/// `estimate::estimator`). With an empty `coarse` this is [`combine`].
pub fn combine_with_coarse(
    mode: SpectralMode,
    local: &BandSums,
    v_local: f64,
    coarse: &BandSums,
    expanded: &BandSums,
    v_expanded: f64,
    out: &mut [f64],
) {
    let coarse_ok = valid_volume(v_expanded);
    match mode {
        SpectralMode::Naive => {
            local.estimates(v_local, out);
            if coarse_ok {
                for (o, c) in out.iter_mut().zip(coarse.sums()) {
                    *o += c / v_expanded;
                }
            }
        }
        SpectralMode::Compensated | SpectralMode::Grid => {
            let expanded_total = expanded.total();
            let mut density = 0.0;
            if valid_volume(v_local) {
                density += local.total() / v_local;
            }
            if coarse_ok {
                density += coarse.total() / v_expanded;
            }
            let scale = if coarse_ok && expanded_total > 0.0 {
                density / expanded_total
            } else {
                0.0
            };
            let scale = if scale.is_finite() { scale } else { 0.0 };
            for (o, e) in out.iter_mut().zip(expanded.sums()) {
                *o = scale * e;
            }
        }
    }
}

/// The `grid` combination: the level of [`combine_with_coarse`] (local
/// photons at the local scale, heavy ones at the expanded scale, all
/// bands) times the band shares `shape` from the band-shape grid (sum 1).
/// Without a shape (`None`: no weight near) this is the compensated
/// combination. The band sum is the level, as in the compensated mode.
pub fn combine_with_shape(
    local: &BandSums,
    v_local: f64,
    coarse: &BandSums,
    expanded: &BandSums,
    v_expanded: f64,
    shape: Option<&[f64]>,
    out: &mut [f64],
) {
    let Some(shape) = shape else {
        combine_with_coarse(
            SpectralMode::Compensated,
            local,
            v_local,
            coarse,
            expanded,
            v_expanded,
            out,
        );
        return;
    };
    let level = density(local.total(), v_local) + density(coarse.total(), v_expanded);
    let level = if level.is_finite() { level } else { 0.0 };
    for (o, s) in out.iter_mut().zip(shape) {
        *o = level * s;
    }
}

/// Combine a local and an expanded search into per-band radiance in `out`
/// (length = bands): `Naive` -> local / `v_local`; `Compensated` ->
/// `Lbar * L'_i / L'bar` (see the module notes), which is 0 in every band
/// when the expanded search is empty, has no positive total, or has an
/// invalid volume, and 0 in the bands the expanded search did not see.
///
/// Its band sum equals the naive local band sum whenever the expanded total
/// is positive. `v_expanded` cancels out of the result; it is checked only so
/// that an invalid expanded search counts as empty.
pub fn combine(
    mode: SpectralMode,
    local: &BandSums,
    v_local: f64,
    expanded: &BandSums,
    v_expanded: f64,
    out: &mut [f64],
) {
    match mode {
        SpectralMode::Naive => local.estimates(v_local, out),
        SpectralMode::Compensated | SpectralMode::Grid => {
            debug_assert_eq!(out.len(), expanded.bands(), "output sized to the band grid");
            debug_assert_eq!(local.bands(), expanded.bands(), "searches share one grid");
            let expanded_total = expanded.total();
            let scale = if valid_volume(v_local) && valid_volume(v_expanded) && expanded_total > 0.0
            {
                // N Lbar / (N L'bar / L'_i) with the expanded volume cancelled.
                local.total() / v_local / expanded_total
            } else {
                0.0
            };
            // A subnormal expanded total can overflow the scale; such a site
            // has no usable shape.
            let scale = if scale.is_finite() { scale } else { 0.0 };
            for (o, e) in out.iter_mut().zip(expanded.sums()) {
                *o = scale * e;
            }
        }
    }
}

#[cfg(test)]
mod tests;
