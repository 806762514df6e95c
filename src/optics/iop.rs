//! Inherent optical properties of the water, per band and per position.
//!
//! a = a_w + a_phi + a_g + a_nap and b = b_w + b_p (1/m), with
//! - a_w pure water (Pope & Fry 1997 composite), b_w pure seawater
//!   (Smith & Baker 1981), pure-water phase function Rayleigh-like with
//!   q = 0.835;
//! - a_phi = A_phi(l) Chl^E_phi(l) (Bricaud et al. 1998), Chl in mg m^-3;
//! - a_g = CDOM(440) exp(-S_g (l - 440)), a_nap = NAP(440) exp(-S_nap (l - 440));
//! - b_p = b_p(550) (550 / l)^n with b_p(550) = 0.30 Chl^0.62 (case-1
//!   water) unless given, and the scene's particle phase function.
//!
//! In explicit mode a and b are given directly (the same in every band)
//! and all scattering uses the scene's phase function. From a table
//! (`[water] iop_file`: a, b and bb/b against wavelength, HydroLight's
//! explicit-IOP input) each band has its own a and b, and its scattering is
//! split between the two phase functions so that the band's backscatter
//! fraction is the table's ([`Iop::with_backscatter_fraction`]): with
//! fractions r_w (pure water, 0.5) and r_p (the particle phase function,
//! 0.0183 by default), b_w = b (r - r_p) / (r_w - r_p), b_p = b - b_w. The
//! mixture has the table's a, b and b_b exactly; its shape between the two
//! is an assumption (a Fournier–Forand function of each band's bb/b would
//! be another).
//!
//! Constituents may vary in space (`ConstituentField`). Every IOP grows
//! with every constituent, so the per-band majorant (for delta tracking) is
//! the extinction at the field's largest concentrations.
//!
//! Not for: the sampling of free paths (see `emit`).

use crate::optics::inelastic::Absorbers;
use glam::Vec3;

/// Particle scattering at 550 nm of case-1 water, 0.30 Chl^0.62 (1/m;
/// 0 without chlorophyll).
pub(crate) fn case1_bp_550(chl: f64) -> f64 {
    if chl > 0.0 {
        0.30 * chl.powf(0.62)
    } else {
        0.0
    }
}

/// Concentrations at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Constituents {
    /// Chlorophyll a, mg m^-3.
    pub chl: f64,
    /// CDOM absorption at 440 nm, 1/m.
    pub cdom_440: f64,
    /// Non-algal particle absorption at 440 nm, 1/m.
    pub nap_440: f64,
}

impl Constituents {
    fn lerp(&self, o: &Constituents, t: f64) -> Constituents {
        Constituents {
            chl: self.chl + (o.chl - self.chl) * t,
            cdom_440: self.cdom_440 + (o.cdom_440 - self.cdom_440) * t,
            nap_440: self.nap_440 + (o.nap_440 - self.nap_440) * t,
        }
    }
    pub(crate) fn max(&self, o: &Constituents) -> Constituents {
        Constituents {
            chl: self.chl.max(o.chl),
            cdom_440: self.cdom_440.max(o.cdom_440),
            nap_440: self.nap_440.max(o.nap_440),
        }
    }
    pub(crate) fn min(&self, o: &Constituents) -> Constituents {
        Constituents {
            chl: self.chl.min(o.chl),
            cdom_440: self.cdom_440.min(o.cdom_440),
            nap_440: self.nap_440.min(o.nap_440),
        }
    }
}

/// A regular 3-D grid of constituents, trilinear between nodes and clamped
/// at its faces.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstituentGrid {
    /// Node coordinates: x (m), y (m), depth (m, positive down).
    pub xs: Vec<f64>,
    pub ys: Vec<f64>,
    pub depths: Vec<f64>,
    /// Values, x fastest, then y, then depth.
    pub values: Vec<Constituents>,
}

impl ConstituentGrid {
    fn at(&self, p: Vec3) -> Constituents {
        let (ix, tx) = cell(&self.xs, p.x as f64);
        let (iy, ty) = cell(&self.ys, p.y as f64);
        let (iz, tz) = cell(&self.depths, -(p.z as f64));
        let (nx, ny) = (self.xs.len(), self.ys.len());
        let v = |i: usize, j: usize, k: usize| &self.values[i + nx * (j + ny * k)];
        let i1 = (ix + 1).min(nx - 1);
        let j1 = (iy + 1).min(ny - 1);
        let k1 = (iz + 1).min(self.depths.len() - 1);
        let x0 = v(ix, iy, iz).lerp(v(i1, iy, iz), tx);
        let x1 = v(ix, j1, iz).lerp(v(i1, j1, iz), tx);
        let x2 = v(ix, iy, k1).lerp(v(i1, iy, k1), tx);
        let x3 = v(ix, j1, k1).lerp(v(i1, j1, k1), tx);
        x0.lerp(&x1, ty).lerp(&x2.lerp(&x3, ty), tz)
    }

    fn max(&self) -> Constituents {
        self.values
            .iter()
            .fold(Constituents::default(), |m, c| m.max(c))
    }

    fn min(&self) -> Constituents {
        let first = self.values.first().copied().unwrap_or_default();
        self.values.iter().fold(first, |m, c| m.min(c))
    }
}

/// Index of the cell holding `x` and the fraction across it (clamped).
fn cell(nodes: &[f64], x: f64) -> (usize, f64) {
    if nodes.len() < 2 || x <= nodes[0] {
        return (0, 0.0);
    }
    let last = nodes.len() - 1;
    if x >= nodes[last] {
        return (last, 0.0);
    }
    let i = nodes.partition_point(|&n| n <= x) - 1;
    (i, (x - nodes[i]) / (nodes[i + 1] - nodes[i]))
}

/// How the concentrations vary through the water.
#[derive(Clone, Debug, PartialEq)]
pub enum ConstituentField {
    Uniform(Constituents),
    /// Linear across the domain along x (axis 0) or y (axis 1), from the
    /// low edge to the high edge.
    Gradient {
        axis: usize,
        size_m: f64,
        from: Constituents,
        to: Constituents,
    },
    /// Depth layers (top, bottom in m, positive down); outside every layer
    /// the `base` concentrations hold.
    Layers {
        base: Constituents,
        layers: Vec<(f64, f64, Constituents)>,
    },
    Grid(ConstituentGrid),
}

impl ConstituentField {
    /// Concentrations at `p`.
    pub fn at(&self, p: Vec3) -> Constituents {
        match self {
            ConstituentField::Uniform(c) => *c,
            ConstituentField::Gradient {
                axis,
                size_m,
                from,
                to,
            } => {
                let t = (p[*axis] as f64 / size_m).clamp(0.0, 1.0);
                from.lerp(to, t)
            }
            ConstituentField::Layers { base, layers } => {
                let depth = -(p.z as f64);
                layers
                    .iter()
                    .find(|(top, bottom, _)| depth >= *top && depth < *bottom)
                    .map_or(*base, |l| l.2)
            }
            ConstituentField::Grid(g) => g.at(p),
        }
    }

    /// The largest concentrations anywhere.
    pub fn max(&self) -> Constituents {
        match self {
            ConstituentField::Uniform(c) => *c,
            ConstituentField::Gradient { from, to, .. } => from.max(to),
            ConstituentField::Layers { base, layers } => {
                layers.iter().fold(*base, |m, l| m.max(&l.2))
            }
            ConstituentField::Grid(g) => g.max(),
        }
    }

    /// The smallest concentrations anywhere.
    pub fn min(&self) -> Constituents {
        match self {
            ConstituentField::Uniform(c) => *c,
            ConstituentField::Gradient { from, to, .. } => from.min(to),
            ConstituentField::Layers { base, layers } => {
                layers.iter().fold(*base, |m, l| m.min(&l.2))
            }
            ConstituentField::Grid(g) => g.min(),
        }
    }
}

/// Per-band spectra of the bio-optical model, already band-averaged.
#[derive(Clone, Debug, PartialEq)]
pub struct BandSpectra {
    pub a_w: Vec<f64>,
    pub b_w: Vec<f64>,
    pub a_phi_a: Vec<f64>,
    pub a_phi_e: Vec<f64>,
    /// exp(-S_g (l - 440)) per band.
    pub cdom_shape: Vec<f64>,
    /// exp(-S_nap (l - 440)) per band.
    pub nap_shape: Vec<f64>,
    /// (550 / l)^n per band.
    pub bp_shape: Vec<f64>,
}

/// The IOPs at a point in one band (1/m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Iop {
    pub a: f64,
    /// Scattering by pure water (Rayleigh-like phase function).
    pub b_w: f64,
    /// Scattering by particles (the scene's phase function).
    pub b_p: f64,
}

impl Iop {
    /// A band's IOPs from its absorption `a`, scattering `b` and
    /// backscatter fraction `bb_ratio`, scattering split between the
    /// pure-water phase function (backscatter fraction `r_w`) and the
    /// particle one (`r_p`) so that (b_w r_w + b_p r_p) / b = `bb_ratio`.
    /// An error (what is wrong) when `bb_ratio` lies outside [r_p, r_w].
    pub fn with_backscatter_fraction(
        a: f64,
        b: f64,
        bb_ratio: f64,
        r_w: f64,
        r_p: f64,
    ) -> std::result::Result<Iop, String> {
        let (lo, hi) = (r_p.min(r_w), r_p.max(r_w));
        // Within rounding of an end, the end itself.
        let tol = 1e-9;
        if !(bb_ratio >= lo - tol && bb_ratio <= hi + tol) {
            return Err(format!(
                "bb/b = {bb_ratio} is outside [{lo:.4}, {hi:.4}], the range a mixture of the \
                 particle phase function (bb/b = {r_p:.4}) and pure water's ({r_w:.4}) reaches; \
                 choose a [water.phase] with a lower bb_ratio"
            ));
        }
        let share = if (r_w - r_p).abs() > 0.0 {
            ((bb_ratio - r_p) / (r_w - r_p)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let b_w = b * share;
        Ok(Iop {
            a,
            b_w,
            b_p: b - b_w,
        })
    }

    pub fn b(&self) -> f64 {
        self.b_w + self.b_p
    }
    pub fn c(&self) -> f64 {
        self.a + self.b_w + self.b_p
    }
}

/// The water's optical model.
#[derive(Clone, Debug, PartialEq)]
pub enum WaterModel {
    /// a and b the same everywhere and in every band; all scattering uses
    /// the particle phase function.
    Explicit { a: f64, b: f64 },
    /// Uniform water with its own IOPs in each band (`[water] iop_file`):
    /// one entry per band, scattering split between the two phase
    /// functions so that each band's backscatter fraction is the table's.
    Bands(Vec<Iop>),
    Constituents {
        spectra: Box<BandSpectra>,
        field: ConstituentField,
        /// Fixed b_p(550) (1/m), or None for 0.30 Chl^0.62.
        bp_550: Option<f64>,
    },
}

impl WaterModel {
    /// IOPs at `p` in `band`.
    #[inline]
    pub fn iop(&self, p: Vec3, band: usize) -> Iop {
        match self {
            WaterModel::Explicit { a, b } => Iop {
                a: *a,
                b_w: 0.0,
                b_p: *b,
            },
            WaterModel::Bands(iops) => iops[band],
            WaterModel::Constituents {
                spectra,
                field,
                bp_550,
            } => Self::from_constituents(spectra, &field.at(p), *bp_550, band),
        }
    }

    /// IOPs at `p` in every band (`out` has one entry per band): the
    /// constituent field is evaluated once, and the chlorophyll power laws
    /// through one logarithm.
    pub fn iops(&self, p: Vec3, out: &mut [Iop]) {
        match self {
            WaterModel::Explicit { .. } => {
                let iop = self.iop(p, 0);
                out.iter_mut().for_each(|o| *o = iop);
            }
            WaterModel::Bands(iops) => out.copy_from_slice(iops),
            WaterModel::Constituents {
                spectra: s,
                field,
                bp_550,
            } => {
                let c = field.at(p);
                let ln_chl = if c.chl > 0.0 { c.chl.ln() } else { 0.0 };
                let bp550 = bp_550.unwrap_or(if c.chl > 0.0 {
                    0.30 * (0.62 * ln_chl).exp()
                } else {
                    0.0
                });
                for (band, o) in out.iter_mut().enumerate() {
                    let a_phi = if c.chl > 0.0 {
                        s.a_phi_a[band] * (s.a_phi_e[band] * ln_chl).exp()
                    } else {
                        0.0
                    };
                    *o = Iop {
                        a: s.a_w[band]
                            + a_phi
                            + c.cdom_440 * s.cdom_shape[band]
                            + c.nap_440 * s.nap_shape[band],
                        b_w: s.b_w[band],
                        b_p: bp550 * s.bp_shape[band],
                    };
                }
            }
        }
    }

    /// The absorbers fluorescence draws on (phytoplankton and CDOM) at
    /// `p` in every band (`out` has one entry per band); zero for water
    /// given by its IOPs.
    pub fn absorbers(&self, p: Vec3, out: &mut [Absorbers]) {
        match self {
            WaterModel::Constituents { spectra, field, .. } => {
                let c = field.at(p);
                for (band, o) in out.iter_mut().enumerate() {
                    *o = Self::absorbers_of(spectra, &c, band);
                }
            }
            _ => out.iter_mut().for_each(|o| *o = Absorbers::default()),
        }
    }

    /// The absorbers at `p` in `band` (see [`Self::absorbers`]).
    pub fn absorbers_in(&self, p: Vec3, band: usize) -> Absorbers {
        match self {
            WaterModel::Constituents { spectra, field, .. } => {
                Self::absorbers_of(spectra, &field.at(p), band)
            }
            _ => Absorbers::default(),
        }
    }

    /// The largest absorbers anywhere in `band` (each grows with its
    /// concentration).
    pub fn absorbers_max(&self, band: usize) -> Absorbers {
        match self {
            WaterModel::Constituents { spectra, field, .. } => {
                Self::absorbers_of(spectra, &field.max(), band)
            }
            _ => Absorbers::default(),
        }
    }

    /// a_φ and a_g of concentrations `c` in `band`, as the absorption
    /// `from_constituents` sums has them.
    fn absorbers_of(s: &BandSpectra, c: &Constituents, band: usize) -> Absorbers {
        Absorbers {
            a_phi: if c.chl > 0.0 {
                s.a_phi_a[band] * (s.a_phi_e[band] * c.chl.ln()).exp()
            } else {
                0.0
            },
            a_g: c.cdom_440 * s.cdom_shape[band],
        }
    }

    fn from_constituents(
        s: &BandSpectra,
        c: &Constituents,
        bp_550: Option<f64>,
        band: usize,
    ) -> Iop {
        // Both chlorophyll power laws through one logarithm, as `iops` does.
        let ln_chl = if c.chl > 0.0 { c.chl.ln() } else { 0.0 };
        let a_phi = if c.chl > 0.0 {
            s.a_phi_a[band] * (s.a_phi_e[band] * ln_chl).exp()
        } else {
            0.0
        };
        let a =
            s.a_w[band] + a_phi + c.cdom_440 * s.cdom_shape[band] + c.nap_440 * s.nap_shape[band];
        let bp550 = bp_550.unwrap_or(if c.chl > 0.0 {
            0.30 * (0.62 * ln_chl).exp()
        } else {
            0.0
        });
        Iop {
            a,
            b_w: s.b_w[band],
            b_p: bp550 * s.bp_shape[band],
        }
    }

    /// An upper bound of the extinction anywhere in `band` (exact for
    /// uniform water).
    pub fn majorant(&self, band: usize) -> f64 {
        self.extinction_at_bound(band, ConstituentField::max)
    }

    /// A lower bound of the extinction anywhere in `band` (exact for
    /// uniform water): every IOP grows with each concentration, so the
    /// smallest concentrations give it.
    pub fn minorant(&self, band: usize) -> f64 {
        self.extinction_at_bound(band, ConstituentField::min)
    }

    /// A lower bound of the absorption anywhere in `band` (exact for
    /// uniform water), by the same argument as [`Self::minorant`].
    pub fn absorption_minorant(&self, band: usize) -> f64 {
        self.iop_at_bound(band, ConstituentField::min).a
    }

    /// The extinction in `band` at the concentrations `bound` picks from
    /// the field (its largest or smallest).
    fn extinction_at_bound(
        &self,
        band: usize,
        bound: fn(&ConstituentField) -> Constituents,
    ) -> f64 {
        self.iop_at_bound(band, bound).c()
    }

    /// The IOPs in `band` at the concentrations `bound` picks from the
    /// field.
    fn iop_at_bound(&self, band: usize, bound: fn(&ConstituentField) -> Constituents) -> Iop {
        match self {
            WaterModel::Explicit { a, b } => Iop {
                a: *a,
                b_w: 0.0,
                b_p: *b,
            },
            WaterModel::Bands(iops) => iops[band],
            WaterModel::Constituents {
                spectra,
                field,
                bp_550,
            } => Self::from_constituents(spectra, &bound(field), *bp_550, band),
        }
    }

    /// Optical depth per band (c integrated, into `out`) along the segment
    /// from `x` along unit `dir` for `len` m, exactly, when the IOPs are
    /// piecewise constant in depth (uniform water or depth layers): the
    /// segment is cut at every layer boundary. False (and `out` untouched)
    /// for other fields. `tmp` holds one entry per band.
    pub fn layered_optical_depth(
        &self,
        x: Vec3,
        dir: Vec3,
        len: f32,
        tmp: &mut [Iop],
        out: &mut [f64],
    ) -> bool {
        let layers = match self {
            WaterModel::Explicit { .. } | WaterModel::Bands(_) => &[][..],
            WaterModel::Constituents { field, .. } => match field {
                ConstituentField::Uniform(_) => &[][..],
                ConstituentField::Layers { layers, .. } => &layers[..],
                _ => return false,
            },
        };
        let (d0, d1) = (-(x.z as f64), -((x + dir * len).z as f64));
        let (lo, hi) = (d0.min(d1), d0.max(d1));
        let mut cuts = vec![lo, hi];
        for &(top, bottom, _) in layers {
            cuts.extend([top, bottom].into_iter().filter(|&d| d > lo && d < hi));
        }
        cuts.sort_by(f64::total_cmp);
        out.iter_mut().for_each(|o| *o = 0.0);
        let per_depth = if hi > lo { len as f64 / (hi - lo) } else { 0.0 };
        for w in cuts.windows(2) {
            let mid = 0.5 * (w[0] + w[1]);
            self.iops(Vec3::new(x.x, x.y, -mid as f32), tmp);
            let length = if hi > lo {
                (w[1] - w[0]) * per_depth
            } else {
                len as f64
            };
            for (o, iop) in out.iter_mut().zip(tmp.iter()) {
                *o += iop.c() * length;
            }
        }
        if hi <= lo {
            // A level segment stays at one depth.
            self.iops(x, tmp);
            for (o, iop) in out.iter_mut().zip(tmp.iter()) {
                *o = iop.c() * len as f64;
            }
        }
        true
    }

    /// Optical depth per band (c integrated, into `out`) along the segment
    /// from `x` along unit `dir` for `len` m, exactly, in a gradient of
    /// constituents with chlorophyll above zero at both ends: the segment
    /// is cut where it leaves the gradient's span (beyond it the
    /// concentrations hold their end values), and across each piece the
    /// concentrations change linearly, so that the mean of chl^E (the
    /// phytoplankton's absorption, and the particles' scattering without a
    /// fixed `bp_550`) over a piece from chl_0 to chl_1 is chl_0^E times
    /// expm1((E + 1) l) / ((E + 1) expm1(l)), l = ln(chl_1 / chl_0). False
    /// (and `out` untouched) for other fields.
    ///
    /// Why: the sun's transmittance from every sample of a march was the
    /// midpoint rule at most 0.5 m apart, at least four samples of every
    /// band's IOPs (a power of chlorophyll each); this is two per band
    /// for the whole way, with no error of the rule.
    pub fn gradient_optical_depth(&self, x: Vec3, dir: Vec3, len: f32, out: &mut [f64]) -> bool {
        let WaterModel::Constituents {
            spectra: s,
            field:
                ConstituentField::Gradient {
                    axis,
                    size_m,
                    from,
                    to,
                },
            bp_550,
        } = self
        else {
            return false;
        };
        if !(from.chl > 0.0 && to.chl > 0.0) {
            return false;
        }
        out.iter_mut().for_each(|o| *o = 0.0);
        // The gradient's coordinate at the start and its change along the
        // segment; the pieces end where it crosses 0 or 1.
        let len = f64::from(len);
        let (t0, dt) = (
            f64::from(x[*axis]) / size_m,
            f64::from(dir[*axis]) * len / size_m,
        );
        let mut cuts = [0.0, 1.0, 1.0, 1.0];
        if dt != 0.0 {
            for (c, edge) in cuts[1..3].iter_mut().zip([0.0, 1.0]) {
                let f = (edge - t0) / dt;
                if f > 0.0 && f < 1.0 {
                    *c = f;
                }
            }
        }
        cuts.sort_by(f64::total_cmp);
        let at = |f: f64| from.lerp(to, (t0 + dt * f).clamp(0.0, 1.0));
        for w in cuts.windows(2) {
            let piece = (w[1] - w[0]) * len;
            if piece <= 0.0 {
                continue;
            }
            let (a, b) = (at(w[0]), at(w[1]));
            let (ln_a, l) = (a.chl.ln(), (b.chl / a.chl).ln());
            // The mean of chl^e over the piece.
            let mean_pow = |e: f64| {
                let ratio = if l == 0.0 {
                    1.0
                } else if e + 1.0 == 0.0 {
                    l / l.exp_m1()
                } else {
                    (l * (e + 1.0)).exp_m1() / ((e + 1.0) * l.exp_m1())
                };
                (e * ln_a).exp() * ratio
            };
            let bp550 = bp_550.unwrap_or_else(|| 0.30 * mean_pow(0.62));
            let (cdom, nap) = (
                0.5 * (a.cdom_440 + b.cdom_440),
                0.5 * (a.nap_440 + b.nap_440),
            );
            for (band, o) in out.iter_mut().enumerate() {
                let c = s.a_w[band]
                    + s.a_phi_a[band] * mean_pow(s.a_phi_e[band])
                    + cdom * s.cdom_shape[band]
                    + nap * s.nap_shape[band]
                    + s.b_w[band]
                    + bp550 * s.bp_shape[band];
                *o += c * piece;
            }
        }
        true
    }

    /// Depths (m, positive down) where the IOPs jump: the tops and bottoms
    /// of depth layers; empty for every other field.
    pub fn depth_boundaries(&self) -> Vec<f64> {
        match self {
            WaterModel::Constituents {
                field: ConstituentField::Layers { layers, .. },
                ..
            } => {
                let mut d: Vec<f64> = layers.iter().flat_map(|l| [l.0, l.1]).collect();
                d.sort_by(f64::total_cmp);
                d.dedup();
                d
            }
            _ => Vec::new(),
        }
    }

    /// The scattering coefficient b at `p` in `band` (one power law, not
    /// the whole IOP set).
    #[inline]
    pub fn scattering(&self, p: Vec3, band: usize) -> f64 {
        match self {
            WaterModel::Explicit { b, .. } => *b,
            WaterModel::Bands(iops) => iops[band].b(),
            WaterModel::Constituents {
                spectra,
                field,
                bp_550,
            } => {
                let bp550 = bp_550.unwrap_or_else(|| case1_bp_550(field.at(p).chl));
                spectra.b_w[band] + bp550 * spectra.bp_shape[band]
            }
        }
    }

    /// True when the IOPs jump at depth boundaries (depth layers).
    pub fn is_layered(&self) -> bool {
        matches!(
            self,
            WaterModel::Constituents {
                field: ConstituentField::Layers { layers, .. },
                ..
            } if !layers.is_empty()
        )
    }

    /// True when the IOPs vary with depth alone (uniform, or in layers).
    pub fn is_horizontally_uniform(&self) -> bool {
        match self {
            WaterModel::Explicit { .. } | WaterModel::Bands(_) => true,
            WaterModel::Constituents { field, .. } => matches!(
                field,
                ConstituentField::Uniform(_) | ConstituentField::Layers { .. }
            ),
        }
    }

    /// True when the IOPs do not depend on position.
    pub fn is_uniform(&self) -> bool {
        match self {
            WaterModel::Explicit { .. } | WaterModel::Bands(_) => true,
            WaterModel::Constituents { field, .. } => matches!(field, ConstituentField::Uniform(_)),
        }
    }
}

#[cfg(test)]
mod tests;
