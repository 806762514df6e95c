//! Phase functions tabulated in angle: the Petzold "average particle" table
//! and user tables.
//!
//! Between nodes p is linear in angle, so each piece's mass
//! 2 pi int p sin psi dpsi and cosine moment have closed forms; the CDF at
//! the nodes is exact (no quadrature grid), and sampling inverts it inside
//! one piece by a safeguarded Newton solve. Petzold's power law below
//! 0.12589° is integrated by its (rapidly converging) series.

use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::{Arc, OnceLock};

use super::{solve_increasing, S2_MIN, TWO_PI};
use crate::error::{Error, Result};

const PETZOLD_FILE: &str = "petzold_avg_particle_mobley1993.csv";
const PETZOLD_CSV: &str = include_str!("../../../data/petzold_avg_particle_mobley1993.csv");
/// Below this angle (deg) the paper replaces the table by a power law.
const PETZOLD_POWER_LAW_BELOW_DEG: f64 = 0.12589;
/// Exponent of that power law: p = p(0.12589°) (0.12589°/psi)^1.346.
const PETZOLD_POWER_LAW_EXPONENT: f64 = 1.346;
const PETZOLD_COLUMN: &str = "beta_corrected_per_sr";

/// A phase function tabulated in angle: linear between nodes, exactly
/// integrated, normalised to 1. Cheap to clone (the table is shared).
#[derive(Clone, Debug)]
pub struct TabulatedPhase {
    table: Arc<Table>,
}

impl TabulatedPhase {
    /// From (angle in degrees, value) pairs: angles strictly increasing in
    /// [0, 180], values finite and >= 0, at least 2 points, not all zero.
    /// Linear in angle between nodes; the first and last values are held
    /// constant down to 0° and up to 180° when the table stops short. Values
    /// are rescaled so the function integrates to 1. Errors name `field`.
    pub fn new(angles_deg: &[f64], values: &[f64], field: &str) -> Result<Self> {
        let invalid = |what: String| Err(Error::invalid(field, what));
        if angles_deg.len() != values.len() {
            return invalid(format!(
                "{} angles but {} values",
                angles_deg.len(),
                values.len()
            ));
        }
        if angles_deg.len() < 2 {
            return invalid(format!(
                "a phase-function table needs at least 2 (angle, value) points, got {}",
                angles_deg.len()
            ));
        }
        for (i, (&angle, &value)) in angles_deg.iter().zip(values).enumerate() {
            if !(0.0..=180.0).contains(&angle) {
                return invalid(format!(
                    "angle {angle} deg at index {i} is outside [0, 180]"
                ));
            }
            if i > 0 && angle <= angles_deg[i - 1] {
                return invalid(format!(
                    "angles must increase strictly: {angle} deg at index {i} follows {} deg",
                    angles_deg[i - 1]
                ));
            }
            if !(value.is_finite() && value >= 0.0) {
                return invalid(format!(
                    "value {value} at index {i} must be finite and non-negative"
                ));
            }
        }
        Table::build(angles_deg, values, None, field).map(|table| TabulatedPhase {
            table: Arc::new(table),
        })
    }

    /// The Petzold "average particle" phase function, parsed once from the
    /// embedded table.
    pub fn petzold() -> Self {
        static PETZOLD: OnceLock<TabulatedPhase> = OnceLock::new();
        PETZOLD
            .get_or_init(|| {
                // The table is compiled in and parsed by a test, so failure
                // here is a build defect, not bad input.
                parse_petzold(PETZOLD_CSV).expect("embedded Petzold table parses")
            })
            .clone()
    }

    /// 2 pi int p sin psi dpsi of the values as given, before they were
    /// divided by it: how far the input was from normalised.
    pub fn raw_integral(&self) -> f64 {
        self.table.raw_integral
    }

    /// Backscatter fraction 2 pi int_{90°}^{180°} p sin psi dpsi.
    pub fn backscatter_fraction(&self) -> f64 {
        self.table.backscatter
    }

    /// Mean cosine 2 pi int cos psi p sin psi dpsi.
    pub fn mean_cosine(&self) -> f64 {
        self.table.mean_cos
    }

    /// The bytes of its table.
    pub fn heap_bytes(&self) -> u64 {
        (self.table.pieces.len() * std::mem::size_of::<Piece>() + self.table.first.len() * 4) as u64
    }

    /// p [sr^-1] at scattering angle `psi` (rad).
    pub(super) fn density(&self, psi: f64) -> f64 {
        self.table.density(psi)
    }

    /// See [`super::PhaseFunction::sample_cos`].
    pub(super) fn sample_cos(&self, u: f64) -> f64 {
        self.table.sample_cos(u)
    }
}

/// Reads the embedded CSV: `#` lines are its source notes, the header names
/// the columns, and the corrected column is used (see the file's notes on the
/// misprint at 0.50119°). Rows below 0.12589° are not nodes: the paper's power
/// law replaces the table there.
fn parse_petzold(text: &str) -> Result<TabulatedPhase> {
    const FIELD: &str = "petzold table";
    let csv = crate::csv::parse(text, std::path::Path::new(PETZOLD_FILE), FIELD)?;
    let col = csv.column(PETZOLD_COLUMN)?;
    let (mut angles, mut values) = (Vec::new(), Vec::new());
    for row in &csv.rows {
        let angle = csv.number(row, 0)?;
        let value = csv.number(row, col)?;
        if angle >= PETZOLD_POWER_LAW_BELOW_DEG {
            angles.push(angle);
            values.push(value);
        }
    }
    if angles.first() != Some(&PETZOLD_POWER_LAW_BELOW_DEG) {
        return Err(Error::invalid(
            FIELD,
            format!("first node must be {PETZOLD_POWER_LAW_BELOW_DEG} deg"),
        ));
    }
    Table::build(&angles, &values, Some(PETZOLD_POWER_LAW_EXPONENT), FIELD).map(|table| {
        TabulatedPhase {
            table: Arc::new(table),
        }
    })
}

/// Buckets of equal angle over [0, pi] indexing the pieces.
const BUCKETS: usize = 1024;

/// The first angle of bucket `k` (rad), a little below it so that it is
/// never above an angle the bucket takes after rounding.
fn bucket_start(k: usize) -> f64 {
    k as f64 * (PI / BUCKETS as f64) - 1e-9
}

/// Pieces covering [0, pi] in order, each with its exact mass.
#[derive(Debug)]
struct Table {
    pieces: Vec<Piece>,
    /// Per bucket of `BUCKETS` equal angles over [0, pi]: the first piece
    /// whose end is at or beyond the bucket's start, where the search for
    /// an angle in it begins.
    first: Vec<u32>,
    /// The factor the input values were divided by: their integral over the sphere.
    raw_integral: f64,
    backscatter: f64,
    mean_cos: f64,
}

#[derive(Clone, Copy, Debug)]
struct Piece {
    /// Angular interval [lo, hi], rad.
    lo: f64,
    hi: f64,
    shape: PieceShape,
    /// P(<lo) and P(<hi), normalised.
    cdf_lo: f64,
    cdf_hi: f64,
}

#[derive(Clone, Copy, Debug)]
enum PieceShape {
    /// p = p_lo + slope (psi - lo) [sr^-1, sr^-1 rad^-1].
    Linear { p_lo: f64, slope: f64 },
    /// p = p_hi (hi/psi)^alpha on [0, hi], alpha < 2 so the mass is finite.
    Power { p_hi: f64, alpha: f64 },
}

impl Table {
    /// `head_exponent`: a power law below the first node instead of a constant.
    fn build(
        angles_deg: &[f64],
        values: &[f64],
        head_exponent: Option<f64>,
        field: &str,
    ) -> Result<Table> {
        let psi: Vec<f64> = angles_deg.iter().map(|a| a.to_radians().min(PI)).collect();
        let (first, last) = (psi[0], psi[psi.len() - 1]);
        let mut shapes = Vec::with_capacity(psi.len() + 1);
        if first > 0.0 {
            let shape = match head_exponent {
                Some(alpha) => PieceShape::Power {
                    p_hi: values[0],
                    alpha,
                },
                None => PieceShape::Linear {
                    p_lo: values[0],
                    slope: 0.0,
                },
            };
            shapes.push((0.0, first, shape));
        }
        for i in 1..psi.len() {
            let slope = (values[i] - values[i - 1]) / (psi[i] - psi[i - 1]);
            let p_lo = values[i - 1];
            shapes.push((psi[i - 1], psi[i], PieceShape::Linear { p_lo, slope }));
        }
        if last < PI {
            let p_lo = values[values.len() - 1];
            shapes.push((last, PI, PieceShape::Linear { p_lo, slope: 0.0 }));
        }
        let mut pieces: Vec<Piece> = shapes
            .into_iter()
            .map(|(lo, hi, shape)| Piece {
                lo,
                hi,
                shape,
                cdf_lo: 0.0,
                cdf_hi: 0.0,
            })
            .collect();

        let masses: Vec<f64> = pieces.iter().map(|p| p.mass_to(p.hi)).collect();
        let raw_integral: f64 = masses.iter().sum();
        if !(raw_integral > 0.0 && raw_integral.is_finite()) {
            return Err(Error::invalid(
                field,
                format!(
                    "values integrate to {raw_integral} over the sphere; need a positive total"
                ),
            ));
        }
        // Cumulative sums in the same order as the total, so the last is exactly 1.
        let mut cum = 0.0;
        for (piece, mass) in pieces.iter_mut().zip(&masses) {
            piece.cdf_lo = cum / raw_integral;
            cum += mass;
            piece.cdf_hi = cum / raw_integral;
            piece.shape.scale(1.0 / raw_integral);
        }
        if let Some(end) = pieces.last_mut() {
            end.cdf_hi = 1.0;
        }
        // Summed over the back hemisphere directly rather than as 1 - P(<90°),
        // which would lose digits to cancellation.
        let backscatter = pieces
            .iter()
            .filter(|p| p.hi > FRAC_PI_2)
            .map(|p| {
                let whole = p.mass_to(p.hi);
                if p.lo < FRAC_PI_2 {
                    whole - p.mass_to(FRAC_PI_2)
                } else {
                    whole
                }
            })
            .sum();
        let mean_cos = pieces.iter().map(Piece::cos_moment).sum();
        let first = (0..BUCKETS)
            .map(|k| pieces.partition_point(|p| p.hi < bucket_start(k)) as u32)
            .collect();
        Ok(Table {
            pieces,
            first,
            raw_integral,
            backscatter,
            mean_cos,
        })
    }

    fn density(&self, psi: f64) -> f64 {
        // The first piece whose end is at or beyond psi (the last for psi
        // beyond pi or NaN), found from its bucket's first: the phase
        // function is evaluated toward every sky cell at every collision.
        let last = self.pieces.len() - 1;
        let k = (psi * (BUCKETS as f64 / PI)) as usize;
        let mut i = if psi >= 0.0 && k < BUCKETS {
            self.first[k] as usize
        } else if psi >= 0.0 {
            self.first[BUCKETS - 1] as usize
        } else {
            0
        };
        while i < last && self.pieces[i].hi < psi {
            i += 1;
        }
        self.pieces[i.min(last)].density(psi)
    }

    /// P(<psi) = 1 - u, so that u -> 1 is forward and cos is non-decreasing in u.
    fn sample_cos(&self, u: f64) -> f64 {
        // At u = 0 aim just below 1 so that a zero-valued tail is never chosen.
        let v = (1.0 - u).min(1.0 - 0.5 * f64::EPSILON);
        let i = self
            .pieces
            .partition_point(|p| p.cdf_hi <= v)
            .min(self.pieces.len() - 1);
        self.pieces[i].sample_angle(v - self.pieces[i].cdf_lo).cos()
    }
}

impl PieceShape {
    fn scale(&mut self, factor: f64) {
        match self {
            PieceShape::Linear { p_lo, slope } => {
                *p_lo *= factor;
                *slope *= factor;
            }
            PieceShape::Power { p_hi, .. } => *p_hi *= factor,
        }
    }
}

impl Piece {
    fn density(&self, psi: f64) -> f64 {
        match self.shape {
            PieceShape::Linear { p_lo, slope } => (p_lo + slope * (psi - self.lo)).max(0.0),
            PieceShape::Power { p_hi, alpha } => {
                // No nearer forward than the cap of cosines that round to 1.
                let psi_min = 2.0 * S2_MIN.sqrt();
                p_hi * (self.hi / psi.max(psi_min)).powf(alpha)
            }
        }
    }

    /// 2 pi int_lo^psi p(t) sin t dt, exact.
    fn mass_to(&self, psi: f64) -> f64 {
        match self.shape {
            PieceShape::Linear { p_lo, slope } => {
                let h = psi - self.lo;
                TWO_PI * (p_lo * sin_integral(self.lo, h) + slope * r_sin_integral(self.lo, h))
            }
            PieceShape::Power { p_hi, alpha } => {
                if psi <= 0.0 {
                    return 0.0;
                }
                TWO_PI * p_hi * psi * psi * (self.hi / psi).powf(alpha) * power_series(psi, alpha)
            }
        }
    }

    /// 2 pi int_lo^hi p(t) cos t sin t dt, exact: sin t cos t = sin(2t)/2.
    fn cos_moment(&self) -> f64 {
        match self.shape {
            PieceShape::Linear { p_lo, slope } => {
                let h2 = 2.0 * (self.hi - self.lo);
                let a = 2.0 * self.lo;
                TWO_PI * 0.25 * (p_lo * sin_integral(a, h2) + 0.5 * slope * r_sin_integral(a, h2))
            }
            PieceShape::Power { p_hi, alpha } => {
                let psi = self.hi;
                TWO_PI * p_hi * psi * psi * power_series(2.0 * psi, alpha)
            }
        }
    }

    /// The angle psi in [lo, hi] with mass_to(psi) = m, 0 <= m <= this piece's mass.
    fn sample_angle(&self, m: f64) -> f64 {
        let m = m.max(0.0);
        match self.shape {
            PieceShape::Linear { .. } => {
                let h_max = self.hi - self.lo;
                let mass = self.mass_to(self.hi);
                let h0 = if mass > 0.0 {
                    m / mass * h_max
                } else {
                    0.5 * h_max
                };
                let h = solve_increasing(0.0, h_max, h0, 1e-15 * self.hi, |h| {
                    let psi = self.lo + h;
                    (
                        self.mass_to(psi) - m,
                        TWO_PI * self.density(psi) * psi.sin(),
                    )
                });
                self.lo + h
            }
            PieceShape::Power { p_hi, alpha } => {
                if m <= 0.0 {
                    return 0.0;
                }
                // Solve in ln psi, where the mass is nearly a straight line;
                // start from its leading term 2 pi A psi^(2-alpha)/(2-alpha).
                let a = p_hi * self.hi.powf(alpha);
                let ln_guess =
                    ((m * (2.0 - alpha) / (TWO_PI * a)).ln() / (2.0 - alpha)).min(self.hi.ln());
                let ln_m = m.ln();
                let f = |t: f64| {
                    let psi = t.exp();
                    let mass = self.mass_to(psi);
                    (
                        mass.ln() - ln_m,
                        TWO_PI * self.density(psi) * psi.sin() * psi / mass,
                    )
                };
                let mut lo = ln_guess - 1.0;
                while f(lo).0 > 0.0 {
                    lo -= 1.0;
                }
                solve_increasing(lo, self.hi.ln(), ln_guess, 1e-14, f).exp()
            }
        }
    }
}

/// int_0^h sin(a + r) dr = 2 sin(a + h/2) sin(h/2), free of the cancellation in cos a - cos(a+h).
fn sin_integral(a: f64, h: f64) -> f64 {
    2.0 * (a + 0.5 * h).sin() * (0.5 * h).sin()
}

/// int_0^h r sin(a + r) dr = sin a (h sin h - 2 sin^2(h/2)) + cos a (sin h - h cos h).
fn r_sin_integral(a: f64, h: f64) -> f64 {
    let half = (0.5 * h).sin();
    a.sin() * (h * h.sin() - 2.0 * half * half) + a.cos() * sin_minus_h_cos(h)
}

/// sin h - h cos h, by its series for small h where the difference cancels:
/// sum_{k>=1} (-1)^(k+1) 2k h^(2k+1) / (2k+1)!.
fn sin_minus_h_cos(h: f64) -> f64 {
    if h.abs() >= 0.5 {
        return h.sin() - h * h.cos();
    }
    let h2 = h * h;
    let mut term = h * h2 / 6.0; // h^3/3!
    let mut sum = 0.0;
    for k in 1..12 {
        sum += 2.0 * k as f64 * term;
        let kk = 2 * k as u32;
        term *= -h2 / f64::from((kk + 2) * (kk + 3));
    }
    sum
}

/// sum_{k>=0} (-1)^k y^(2k) / ((2k+1)! (2k+2-alpha)): int_0^psi t^-alpha sin t dt
/// = psi^(2-alpha) S(psi), and int_0^psi t^-alpha sin(2t)/2 dt = psi^(2-alpha) S(2 psi).
fn power_series(y: f64, alpha: f64) -> f64 {
    let y2 = y * y;
    let mut term = 1.0; // y^(2k) / (2k+1)!
    let mut sum = 0.0;
    for k in 0..16u32 {
        sum += term / (2.0 * f64::from(k) + 2.0 - alpha);
        term *= -y2 / f64::from((2 * k + 2) * (2 * k + 3));
    }
    sum
}

#[cfg(test)]
mod tests;
