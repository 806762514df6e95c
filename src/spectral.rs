//! The band grid: centre wavelengths and widths of the sensor's bands.
//!
//! Every photon carries exactly one band index into this grid. The grid is
//! stored in the map header so a map always knows its own spectral layout.

use crate::error::{Error, Result};

/// Centre wavelengths and full widths at half maximum (Gaussian response), in nm.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BandGrid {
    centers_nm: Vec<f32>,
    fwhm_nm: Vec<f32>,
}

/// The most bands a grid may hold (band indices are stored in 12 bits of
/// a photon record, beside its group).
pub const MAX_BANDS: usize = crate::photon::MAX_BANDS;

impl BandGrid {
    /// `count` evenly spaced band centres from `start_nm` to `end_nm` inclusive,
    /// each as wide (FWHM) as the spacing. One band sits at `start_nm` with the
    /// width of the whole interval.
    pub fn even(start_nm: f32, end_nm: f32, count: usize) -> Result<Self> {
        if count == 0 || count > MAX_BANDS {
            return Err(Error::invalid(
                "bands",
                format!("must be between 1 and {MAX_BANDS}, got {count}"),
            ));
        }
        if !(start_nm.is_finite() && end_nm.is_finite() && start_nm > 0.0 && end_nm >= start_nm) {
            return Err(Error::invalid(
                "spectral range",
                format!("need 0 < start <= end, got {start_nm}..{end_nm} nm"),
            ));
        }
        if count == 1 {
            let width = (end_nm - start_nm).max(1.0);
            return Self::explicit(vec![0.5 * (start_nm + end_nm)], vec![width]);
        }
        let step = (end_nm - start_nm) / (count - 1) as f32;
        let centers = (0..count).map(|i| start_nm + step * i as f32).collect();
        Self::explicit(centers, vec![step; count])
    }

    /// Explicit centres and widths (nm); centres must increase strictly.
    pub fn explicit(centers_nm: Vec<f32>, fwhm_nm: Vec<f32>) -> Result<Self> {
        if centers_nm.is_empty() || centers_nm.len() > MAX_BANDS {
            return Err(Error::invalid(
                "centers_nm",
                format!("must hold 1 to {MAX_BANDS} bands, got {}", centers_nm.len()),
            ));
        }
        if centers_nm.len() != fwhm_nm.len() {
            return Err(Error::invalid(
                "fwhm_nm",
                format!(
                    "has {} entries but centers_nm has {}",
                    fwhm_nm.len(),
                    centers_nm.len()
                ),
            ));
        }
        if let Some(i) = centers_nm.iter().position(|c| !(c.is_finite() && *c > 0.0)) {
            return Err(Error::invalid(
                format!("centers_nm[{i}]"),
                "must be a positive wavelength",
            ));
        }
        if let Some(i) = centers_nm.windows(2).position(|w| w[1] <= w[0]) {
            return Err(Error::invalid(
                format!("centers_nm[{}]", i + 1),
                "band centres must increase strictly",
            ));
        }
        if let Some(i) = fwhm_nm.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(Error::invalid(format!("fwhm_nm[{i}]"), "must be positive"));
        }
        Ok(BandGrid {
            centers_nm,
            fwhm_nm,
        })
    }

    /// Number of bands.
    pub fn len(&self) -> usize {
        self.centers_nm.len()
    }

    /// Always false: a grid holds at least one band.
    pub fn is_empty(&self) -> bool {
        self.centers_nm.is_empty()
    }

    /// Band centres in nm.
    pub fn centers_nm(&self) -> &[f32] {
        &self.centers_nm
    }

    /// Band widths (FWHM) in nm.
    pub fn fwhm_nm(&self) -> &[f32] {
        &self.fwhm_nm
    }
}

pub mod response;

#[cfg(test)]
mod tests;
