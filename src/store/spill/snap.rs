//! The fixed-point grid spilled positions are snapped to (see `store::spill`).

use crate::bounds::Aabb;
use crate::error::{Error, Result};
use crate::store::codec::StagedPhoton;

/// Grid coordinates must stay below this in magnitude (about 2^18 times the
/// map's largest coordinate), so a frame's offsets fit the 42 bits per axis
/// of its Morton codes.
const GRID_LIMIT: i64 = 1 << 41;

/// Per axis, the fixed-point grid photon positions are snapped to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnapGrid {
    /// Grid spacing per axis, a power of two.
    step: [f64; 3],
    /// Its reciprocal (exact: a power of two), to divide by multiplying.
    per_m: [f64; 3],
    /// The map bounds it was made for (named in errors).
    bounds: Aabb,
}

impl SnapGrid {
    /// The grid of a map with `bounds`: per axis, the f32 spacing at the
    /// axis's largest coordinate magnitude (at least 2^-40).
    pub fn new(bounds: &Aabb) -> SnapGrid {
        let step = |axis: usize| {
            let m = bounds.min[axis].abs().max(bounds.max[axis].abs());
            let m = if m.is_finite() && m > 0.0 { m } else { 1.0 };
            // 2^exponent(m), then 23 bits below it: the f32 spacing at m.
            let binade = f32::from_bits(m.to_bits() & 0x7f80_0000) as f64;
            (binade * (-23f64).exp2()).max((-40f64).exp2())
        };
        let step = [step(0), step(1), step(2)];
        SnapGrid {
            step,
            per_m: step.map(|s| 1.0 / s),
            bounds: *bounds,
        }
    }

    /// Grid spacing (m) on each axis.
    pub fn step(&self) -> [f64; 3] {
        self.step
    }

    /// The grid coordinates of `position`, or `None` outside the grid's range.
    #[inline]
    pub fn index(&self, position: [f32; 3]) -> Option<[i64; 3]> {
        let mut out = [0i64; 3];
        for axis in 0..3 {
            let i = (position[axis] as f64 * self.per_m[axis]).round();
            if i.is_nan() || i.abs() >= GRID_LIMIT as f64 {
                return None;
            }
            out[axis] = i as i64;
        }
        Some(out)
    }

    /// The position of grid coordinates `i` (exact: every grid point in
    /// range is an f32).
    #[inline]
    pub fn position(&self, i: [i64; 3]) -> [f32; 3] {
        [
            (i[0] as f64 * self.step[0]) as f32,
            (i[1] as f64 * self.step[1]) as f32,
            (i[2] as f64 * self.step[2]) as f32,
        ]
    }

    /// `p` snapped to the grid, or the error for a photon outside its range.
    pub fn snapped(&self, p: &StagedPhoton) -> Result<StagedPhoton> {
        let mut p = *p;
        if self.snap(&mut p) {
            return Ok(p);
        }
        Err(self.outside(&p))
    }

    /// The error for a photon [`SnapGrid::snap`] refused.
    pub fn outside(&self, p: &StagedPhoton) -> Error {
        Error::invalid(
            "photon position",
            format!(
                "{:?} is not finite or lies far outside the map's bounds {:?}",
                p.photon.position, self.bounds
            ),
        )
    }

    /// Snap `p` to the grid in place; false if it lies outside the grid's range.
    #[inline]
    pub fn snap(&self, p: &mut StagedPhoton) -> bool {
        match self.index(p.photon.position) {
            Some(i) => {
                p.photon.position = self.position(i);
                true
            }
            None => false,
        }
    }
}
