//! The photon map's own noise: per-group contributions carried along a ray,
//! and the standard error they give.
//!
//! **Idea** (the random-groups variance estimator of survey sampling, here
//! over photon paths). Every emitted path draws one of [`GROUPS`] groups
//! (`photon::group_of_path`), so the groups are independent random subsets
//! of the map. A photon-map radiance is linear in the photons' powers once
//! its search regions are fixed, L = sum_g D_g, with D_g the part carried
//! by group g's photons; the D_g are independent and alike, so
//!
//! ```text
//! Var(L) ~ G / (G - 1) sum_g (D_g - mean_g D)^2
//! ```
//!
//! One render pass gives it: each estimate writes its D_g beside its value,
//! the march and the surface transfer are linear and carry them along the
//! ray (the sky, direct sun and single scattering add to the value only:
//! they have no photon noise), and the pixel's variance is formed at the
//! end. Correlations between the steps of a march (overlapping searches),
//! between the level and the band shape, and between the photons of one
//! path are all inside the D_g.
//!
//! Ratio estimates (the compensated band shapes, the grid's band shares)
//! are linearised: for L_b = D e_b / E the group part is
//! D_g e_b / E + D (e_{g,b} - e_b E_g / E) / E, which sums over g to L_b
//! (the delta method, per group).
//!
//! What it does not count: the search region itself (k-nearest radii
//! depend on all groups; for a fixed k the count noise moves into the
//! volume, which this estimator still sees as between-group spread), bias
//! (search blur, the forward-peak delta), and the renderer's own sampling
//! (sub-pixel position, march jitter, rough-surface facets), which a
//! pixel's spread between samples gives when it has two or more.
//!
//! With G = 16 the variance estimate has 15 degrees of freedom: a single
//! pixel's standard error is itself uncertain by about 18 %.

use crate::estimate::spectral::{density, BandSums, SpectralMode};
pub use crate::photon::GROUPS;

/// Channels of a radiance vector that carries its photon noise: the
/// radiance, then the contribution of each group (each `bands` long).
pub const CHANNELS: usize = 1 + GROUPS;

/// Weighted power per group, in total and (optionally) per band.
#[derive(Clone, Debug)]
pub struct GroupSums {
    bands: usize,
    totals: [f64; GROUPS],
    /// Per group then band, when kept.
    per_band: Vec<f64>,
    keep_bands: bool,
}

impl GroupSums {
    pub fn new(bands: usize) -> Self {
        GroupSums {
            bands,
            totals: [0.0; GROUPS],
            per_band: Vec::new(),
            keep_bands: false,
        }
    }

    /// Reset, keeping per-band sums when `per_band`.
    pub fn clear(&mut self, per_band: bool) {
        self.totals = [0.0; GROUPS];
        self.keep_bands = per_band;
        if per_band {
            self.per_band.clear();
            self.per_band.resize(GROUPS * self.bands, 0.0);
        }
    }

    /// Add `w` to `group` (and its `band`); non-finite values and bands
    /// outside the grid are skipped, as `BandSums::add` skips them.
    #[inline]
    pub fn add(&mut self, group: u8, band: u16, w: f64) {
        let (g, b) = (group as usize % GROUPS, band as usize);
        if !w.is_finite() || b >= self.bands {
            return;
        }
        self.totals[g] += w;
        if self.keep_bands {
            self.per_band[g * self.bands + b] += w;
        }
    }

    pub fn totals(&self) -> &[f64; GROUPS] {
        &self.totals
    }

    /// Group g's per-band sums (kept only after `clear(true)`).
    pub fn bands_of(&self, g: usize) -> &[f64] {
        &self.per_band[g * self.bands..(g + 1) * self.bands]
    }
}

/// The variance per band of the radiance whose group channels are
/// `groups` (`GROUPS` runs of `out.len()` values), into `out`.
pub fn variance(groups: &[f64], out: &mut [f64]) {
    let nb = out.len();
    debug_assert_eq!(groups.len(), GROUPS * nb);
    let g = GROUPS as f64;
    for (b, o) in out.iter_mut().enumerate() {
        let mean = (0..GROUPS).map(|k| groups[k * nb + b]).sum::<f64>() / g;
        let ss: f64 = (0..GROUPS)
            .map(|k| (groups[k * nb + b] - mean).powi(2))
            .sum();
        *o = g / (g - 1.0) * ss;
    }
}

/// The group sums of one estimate and where their parts go.
pub(crate) struct Groups<'s> {
    pub local: &'s GroupSums,
    pub coarse: &'s GroupSums,
    pub expanded: &'s GroupSums,
    /// `GROUPS` runs of bands.
    pub out: &'s mut [f64],
}

impl Groups<'_> {
    /// Group g's level, D_g = local_g / V + coarse_g / V' (V' = 0: no
    /// coarse part).
    fn level(&self, g: usize, v_local: f64, v_coarse: f64) -> f64 {
        density(self.local.totals()[g], v_local) + density(self.coarse.totals()[g], v_coarse)
    }

    /// The grid combination L_b = D s_b: D_g s_b + D s_{g,b}, with s_{g,b}
    /// the group's part of the grid's shares.
    pub fn shape(self, v_local: f64, v_big: f64, shape: &[f64], shape_groups: &[f64], out: &[f64]) {
        let nb = shape.len();
        let level: f64 = out.iter().sum();
        for g in 0..GROUPS {
            let d_g = self.level(g, v_local, v_big);
            let dev = &shape_groups[g * nb..(g + 1) * nb];
            for ((o, s), d) in self.out[g * nb..(g + 1) * nb]
                .iter_mut()
                .zip(shape)
                .zip(dev)
            {
                *o = d_g * s + level * d;
            }
        }
    }

    /// The naive and compensated combinations (`coarse`: the volume split
    /// of `combine_with_coarse`), linearised per group.
    pub fn ratio(
        self,
        mode: SpectralMode,
        v_local: f64,
        v_big: f64,
        coarse: bool,
        expanded: &BandSums,
        out: &[f64],
    ) {
        let nb = out.len();
        let v_coarse = if coarse { v_big } else { 0.0 };
        match mode {
            SpectralMode::Naive => {
                for g in 0..GROUPS {
                    let o = &mut self.out[g * nb..(g + 1) * nb];
                    for (b, o) in o.iter_mut().enumerate() {
                        *o = density(self.local.bands_of(g)[b], v_local)
                            + density(self.coarse.bands_of(g)[b], v_coarse);
                    }
                }
            }
            SpectralMode::Compensated | SpectralMode::Grid => {
                let e_total = expanded.total();
                let level: f64 = out.iter().sum();
                if !(e_total > 0.0 && level > 0.0 && level.is_finite()) {
                    return;
                }
                for g in 0..GROUPS {
                    let d_g = self.level(g, v_local, v_coarse);
                    let e_g = self.expanded.totals()[g];
                    let e_gb = self.expanded.bands_of(g);
                    let o = &mut self.out[g * nb..(g + 1) * nb];
                    for (b, (o, e_b)) in o.iter_mut().zip(expanded.sums()).enumerate() {
                        let share = e_b / e_total;
                        *o = d_g * share + level * (e_gb[b] - share * e_g) / e_total;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
