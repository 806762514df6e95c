//! Local majorants and IOP bounds for delta tracking.
//!
//! Delta tracking against one majorant for the whole water wastes a
//! tentative collision wherever the water is clearer than its most turbid
//! point (a quarter of them in the built-in scene's chlorophyll gradient),
//! and decides every tentative collision with the full bio-optical model (a
//! logarithm and an exponential per constituent power law). A
//! [`MajorantGrid`] cuts the water into cells along the one axis its IOPs
//! vary on and holds, per band and cell, the largest extinction and lower
//! and upper bounds of a, a + b_w and c. Free paths then sample a
//! piecewise-constant majorant (Woodcock tracking cell by cell, as pbrt-v4's
//! majorant grids do): an Exp(1) optical depth is spent cell by cell, each
//! at its own majorant. A collision is decided from the bounds alone unless
//! the random number falls between a bound pair, and only then from the
//! exact IOPs; the decision is the exact one either way.
//!
//! Cells per field: a horizontal gradient gets [`GRADIENT_CELLS`] equal
//! cells along its axis, depth layers one cell per layer (and one above and
//! below them), every other field one cell (the water's global bounds).
//! Each cell's bounds cover its two neighbours as well, so a collision
//! position that rounds across a cell face is still inside them, and every
//! bound is widened by [`WIDEN`] of itself so that rounding in the IOP
//! formulas cannot step outside it.

use super::iop::{case1_bp_550, BandSpectra, ConstituentField, Constituents, Iop, WaterModel};
use glam::Vec3;

/// Cells along the axis of a horizontal gradient.
pub const GRADIENT_CELLS: usize = 64;

/// Relative widening of every bound (rounding of the IOP formulas is some
/// 1e-15 of the value).
pub const WIDEN: f64 = 1e-9;

/// A band's majorant and IOP bounds in one cell (1/m): `[lower, upper]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellBounds {
    /// The extinction majorant, `c[1]`.
    pub majorant: f64,
    pub a: [f64; 2],
    /// a + b_w: below it a collision scatters off pure water.
    pub a_bw: [f64; 2],
    pub c: [f64; 2],
}

/// [`CellBounds`] without the majorant, rounded outward to f32.
#[derive(Clone, Copy, Debug)]
struct PackedBounds {
    a: [f32; 2],
    a_bw: [f32; 2],
    c_lo: f32,
}

/// The largest f32 not above `x`.
fn f32_below(x: f64) -> f32 {
    let y = x as f32;
    if y as f64 > x {
        y.next_down()
    } else {
        y
    }
}

/// The smallest f32 not below `x`.
fn f32_above(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x {
        y.next_up()
    } else {
        y
    }
}

/// What a tentative collision turns out to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Collision {
    Absorbed,
    /// Scattering by pure water (the Rayleigh-like phase function).
    WaterScatter,
    /// Scattering by particles (the scene's phase function).
    ParticleScatter,
    /// A null collision: the flight goes on.
    Null,
}

impl Collision {
    /// The exact decision for `xi` (uniform on [0, majorant)) against the
    /// IOPs at the collision.
    pub fn decide(iop: &Iop, xi: f64) -> Collision {
        if xi < iop.a {
            Collision::Absorbed
        } else if xi >= iop.c() {
            Collision::Null
        } else if xi < iop.a + iop.b_w {
            Collision::WaterScatter
        } else {
            Collision::ParticleScatter
        }
    }
}

/// The coordinate the cells are cut along.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    fn of(self, v: Vec3) -> f64 {
        match self {
            Axis::X => v.x as f64,
            Axis::Y => v.y as f64,
            Axis::Z => v.z as f64,
        }
    }
}

/// Per-band, per-cell majorants and IOP bounds of a water model.
#[derive(Clone, Debug)]
pub struct MajorantGrid {
    axis: Axis,
    /// Cell faces along the axis, ascending: cell `i` spans
    /// `[cuts[i - 1], cuts[i])`, the first and last cells are unbounded.
    cuts: Vec<f64>,
    /// Equal cells from 0: 1 / the cell width, to find a cell without a
    /// search.
    inv_width: Option<f64>,
    cells: usize,
    /// `[band * cells + cell]`, in f32 rounded outward (20 bytes rather
    /// than 56: the table of 128 bands stays in cache).
    bounds: Vec<PackedBounds>,
    /// The bounds' majorants alone, in the same order: the free path reads
    /// only these, and a compact table stays in cache.
    majorants: Vec<f64>,
}

impl MajorantGrid {
    /// The grid of `water` in `bands` bands.
    pub fn new(water: &WaterModel, bands: usize) -> MajorantGrid {
        let (axis, cuts, inv_width) = match water {
            WaterModel::Constituents { field, .. } => match field {
                ConstituentField::Gradient { axis, size_m, .. } => {
                    let axis = if *axis == 0 { Axis::X } else { Axis::Y };
                    let w = size_m / GRADIENT_CELLS as f64;
                    let cuts = (1..GRADIENT_CELLS).map(|i| i as f64 * w).collect();
                    (axis, cuts, Some(1.0 / w))
                }
                ConstituentField::Layers { .. } => {
                    // Depth d is z = -d.
                    let mut z: Vec<f64> = water.depth_boundaries().iter().map(|d| -d).collect();
                    z.sort_by(f64::total_cmp);
                    (Axis::Z, z, None)
                }
                ConstituentField::Uniform(_) | ConstituentField::Grid(_) => {
                    (Axis::Z, Vec::new(), None)
                }
            },
            WaterModel::Explicit { .. } | WaterModel::Bands(_) => (Axis::Z, Vec::new(), None),
        };
        let cells = cuts.len() + 1;
        // Each cell's own bounds, then widened over its neighbours.
        let own: Vec<Vec<(Iop, Iop)>> = (0..cells)
            .map(|cell| cell_iops(water, bands, axis, &cuts, cell))
            .collect();
        let mut bounds = Vec::with_capacity(bands * cells);
        for band in 0..bands {
            for cell in 0..cells {
                let near = cell.saturating_sub(1)..(cell + 2).min(cells);
                let (mut lo, mut hi) = own[cell][band];
                for (l, h) in own[near].iter().map(|o| o[band]) {
                    lo = Iop {
                        a: lo.a.min(l.a),
                        b_w: lo.b_w.min(l.b_w),
                        b_p: lo.b_p.min(l.b_p),
                    };
                    hi = Iop {
                        a: hi.a.max(h.a),
                        b_w: hi.b_w.max(h.b_w),
                        b_p: hi.b_p.max(h.b_p),
                    };
                }
                let down = |x: f64| x * (1.0 - WIDEN);
                let up = |x: f64| x * (1.0 + WIDEN);
                let c_hi = up(hi.c());
                bounds.push(CellBounds {
                    majorant: c_hi,
                    a: [down(lo.a), up(hi.a)],
                    a_bw: [down(lo.a + lo.b_w), up(hi.a + hi.b_w)],
                    c: [down(lo.c()), c_hi],
                });
            }
        }
        MajorantGrid {
            axis,
            cuts,
            inv_width,
            cells,
            majorants: bounds.iter().map(|b| b.majorant).collect(),
            bounds: bounds
                .iter()
                .map(|b| PackedBounds {
                    a: [f32_below(b.a[0]), f32_above(b.a[1])],
                    a_bw: [f32_below(b.a_bw[0]), f32_above(b.a_bw[1])],
                    c_lo: f32_below(b.c[0]),
                })
                .collect(),
        }
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.cells
    }

    /// The cell holding `p` (for equal cells, to rounding at a face: the
    /// bounds of either cell hold a point on their common face).
    pub fn locate(&self, p: Vec3) -> usize {
        let u = self.axis.of(p);
        match self.inv_width {
            Some(inv_w) => (u * inv_w).clamp(0.0, (self.cells - 1) as f64) as usize,
            None => self.cuts.partition_point(|&c| c <= u),
        }
    }

    /// Bounds of `band` in `cell` (as the collision test uses them).
    pub fn bounds(&self, band: usize, cell: usize) -> CellBounds {
        let i = band * self.cells + cell;
        let b = &self.bounds[i];
        let f = |r: [f32; 2]| [r[0] as f64, r[1] as f64];
        CellBounds {
            majorant: self.majorants[i],
            a: f(b.a),
            a_bw: f(b.a_bw),
            c: [b.c_lo as f64, self.majorants[i]],
        }
    }

    /// The majorant of `band` in `cell`.
    #[inline]
    pub fn majorant(&self, band: usize, cell: usize) -> f64 {
        self.majorants[band * self.cells + cell]
    }

    /// The largest majorant of `band` in any cell.
    pub fn global_majorant(&self, band: usize) -> f64 {
        self.majorants[band * self.cells..(band + 1) * self.cells]
            .iter()
            .fold(0.0, |m, &b| m.max(b))
    }

    /// The distance to the next tentative collision of a flight from `pos`
    /// along `dir` in `band` that has optical depth `tau` (an Exp(1) sample)
    /// to spend against the cells' majorants, and the cell it falls in; None
    /// when the flight reaches `t_max` first.
    pub fn free_path(
        &self,
        band: usize,
        pos: Vec3,
        dir: Vec3,
        t_max: f64,
        mut tau: f64,
    ) -> Option<(f64, usize)> {
        let row = &self.majorants[band * self.cells..(band + 1) * self.cells];
        if self.cells == 1 {
            let m = row[0];
            return (tau < m * t_max).then(|| (tau / m, 0));
        }
        let u0 = self.axis.of(pos);
        let du = self.axis.of(dir);
        let inv_du = 1.0 / du;
        let mut cell = self.locate(pos);
        let mut t = 0.0f64;
        loop {
            let m = row[cell];
            let exit = if du > 0.0 && cell + 1 < self.cells {
                (self.cuts[cell] - u0) * inv_du
            } else if du < 0.0 && cell > 0 {
                (self.cuts[cell - 1] - u0) * inv_du
            } else {
                f64::INFINITY
            };
            // Rounding may put a face just behind the flight's start.
            let exit = exit.max(t);
            let seg = exit.min(t_max) - t;
            if tau < m * seg {
                // The collision test reads the cell's bounds next, after the
                // geometry's own work: ask for their line now (it was a
                // cache miss in 7.7 % of the transport loop's samples).
                crate::simd::prefetch(self.bounds.as_ptr().wrapping_add(band * self.cells + cell));
                return Some((t + tau / m, cell));
            }
            if exit >= t_max {
                return None;
            }
            tau -= m * seg;
            t = exit;
            if du > 0.0 {
                cell += 1;
            } else {
                cell -= 1;
            }
        }
    }

    /// Decide a tentative collision at `p` in `cell` of `band` for `xi`
    /// (uniform on [0, the cell's majorant)): from the bounds when they
    /// settle it, else from the exact IOPs of `water`. The same answer as
    /// [`Collision::decide`] on the exact IOPs.
    #[inline]
    pub fn collide(
        &self,
        water: &WaterModel,
        band: usize,
        cell: usize,
        p: Vec3,
        xi: f64,
    ) -> Collision {
        // xi is below the majorant, c's upper bound: a null collision is
        // never certain from the bounds, and is rare.
        let b = &self.bounds[band * self.cells + cell];
        if xi < b.a[0] as f64 {
            Collision::Absorbed
        } else if xi >= b.a[1] as f64 && xi < b.a_bw[0] as f64 {
            Collision::WaterScatter
        } else if xi >= b.a_bw[1] as f64 && xi < b.c_lo as f64 {
            Collision::ParticleScatter
        } else {
            Collision::decide(&water.iop(p, band), xi)
        }
    }
}

/// Lower and upper IOPs of every band in `cell` (unwidened).
fn cell_iops(
    water: &WaterModel,
    bands: usize,
    axis: Axis,
    cuts: &[f64],
    cell: usize,
) -> Vec<(Iop, Iop)> {
    match water {
        WaterModel::Explicit { .. } | WaterModel::Bands(_) => (0..bands)
            .map(|b| {
                let iop = water.iop(Vec3::ZERO, b);
                (iop, iop)
            })
            .collect(),
        WaterModel::Constituents {
            spectra,
            field,
            bp_550,
        } => {
            let (lo, hi) = constituent_range(field, axis, cuts, cell);
            (0..bands)
                .map(|b| iop_range(spectra, &lo, &hi, *bp_550, b))
                .collect()
        }
    }
}

/// Component-wise least and greatest concentrations in `cell`.
fn constituent_range(
    field: &ConstituentField,
    axis: Axis,
    cuts: &[f64],
    cell: usize,
) -> (Constituents, Constituents) {
    let point = |u: f64| match axis {
        Axis::X => Vec3::new(u as f32, 0.0, -1.0),
        Axis::Y => Vec3::new(0.0, u as f32, -1.0),
        Axis::Z => Vec3::new(0.0, 0.0, u as f32),
    };
    match field {
        ConstituentField::Uniform(c) => (*c, *c),
        ConstituentField::Gradient { .. } => {
            // Linear along the axis (clamped): the extremes are at the faces.
            let a = field.at(point(if cell == 0 { 0.0 } else { cuts[cell - 1] }));
            let b = field.at(point(if cell == cuts.len() {
                f64::MAX
            } else {
                cuts[cell]
            }));
            (a.min(&b), a.max(&b))
        }
        ConstituentField::Layers { .. } => {
            // Constant inside the cell: its value halfway (or a metre
            // beyond the outermost face).
            let u = match (cell.checked_sub(1).map(|i| cuts[i]), cuts.get(cell)) {
                (Some(a), Some(b)) => 0.5 * (a + b),
                (Some(a), None) => a + 1.0,
                (None, Some(b)) => b - 1.0,
                (None, None) => -1.0,
            };
            let c = field.at(point(u));
            (c, c)
        }
        ConstituentField::Grid(_) => (field.min(), field.max()),
    }
}

/// Lower and upper IOPs of `band` for concentrations between `lo` and
/// `hi`: every term is monotone in its one concentration (either way), so
/// its extremes are at the ends.
fn iop_range(
    s: &BandSpectra,
    lo: &Constituents,
    hi: &Constituents,
    bp_550: Option<f64>,
    band: usize,
) -> (Iop, Iop) {
    let a_phi = |chl: f64| {
        if chl > 0.0 {
            s.a_phi_a[band] * chl.powf(s.a_phi_e[band])
        } else {
            0.0
        }
    };
    let b_p = |chl: f64| bp_550.unwrap_or_else(|| case1_bp_550(chl)) * s.bp_shape[band];
    let span = |f: &dyn Fn(f64) -> f64, a: f64, b: f64| {
        let (x, y) = (f(a), f(b));
        (x.min(y), x.max(y))
    };
    let (phi_lo, phi_hi) = span(&a_phi, lo.chl, hi.chl);
    let (g_lo, g_hi) = span(&|c| c * s.cdom_shape[band], lo.cdom_440, hi.cdom_440);
    let (n_lo, n_hi) = span(&|c| c * s.nap_shape[band], lo.nap_440, hi.nap_440);
    let (bp_lo, bp_hi) = span(&b_p, lo.chl, hi.chl);
    let b_w = s.b_w[band];
    (
        Iop {
            a: s.a_w[band] + phi_lo + g_lo + n_lo,
            b_w,
            b_p: bp_lo,
        },
        Iop {
            a: s.a_w[band] + phi_hi + g_hi + n_hi,
            b_w,
            b_p: bp_hi,
        },
    )
}

#[cfg(test)]
mod tests;
