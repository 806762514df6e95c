//! The expected lookups of the air view's control variate, from adjoint
//! paths shared by every sample.
//!
//! With surroundings, each sample's paths that meet the ground add its
//! class's table (or the surroundings' radiance) by a lookup, and one of
//! those within the domain its difference from that by an integrator
//! call. The lookups alone were most of the noise from 3 km: a path from a
//! deep-water pixel that met the beach added its class's excess, ten
//! times the water's radiance in the red, to that one pixel (7 % per pixel
//! band at 671 nm from 16 paths). What the lookups add has the same mean
//! at every ground point g, a known function of g, because the air is the
//! same everywhere: the paths from g meet the ground at g plus offsets
//! drawn the same way for every g. So [`SHARED_PATHS`] adjoint paths are
//! drawn once, and each sample adds their mean lookup at its own ground
//! point:
//!
//! ```text
//! A(g) = 1/M sum_i w_i V(class(g + d_i), up_i)
//! ```
//!
//! unbiased at every g, with a standard error from the paths' spread that
//! the standard-error cube holds. Most offsets leave the domain, where V is
//! the same for every g: their sum is kept once, and a sample visits only
//! the paths whose offset from it lands within the domain (sorted by
//! offset in x). The sample's own paths then serve only to draw the one
//! that makes the integrator call.

use super::{AirView, Class, Surround};
use crate::rng::Pcg32;
use glam::DVec3;
use rayon::prelude::*;

/// Adjoint paths shared by every sample for the lookups' mean.
pub const SHARED_PATHS: u64 = 1 << 13;

/// Stream of the shared paths' randoms.
const SHARED_KEY: u64 = 0x7368_6172_6564_5f70;

/// The shared adjoint paths that met the ground, sorted by their offset in
/// x, and what their lookups add beyond the domain.
pub(super) struct Shared {
    /// Paths drawn (those that met the ground and those that did not).
    drawn: f64,
    /// Per path that met the ground: where, from the ground point it left.
    dx: Vec<f64>,
    dy: Vec<f64>,
    /// Its direction cell.
    cell: Vec<u32>,
    /// Per path and band (path-major): its band weight w, and that times
    /// the glint along it, wg.
    w: Vec<f32>,
    wg: Vec<f32>,
    /// What a path sees beyond the domain, times its weight: x =
    /// `beyond_w` w `beyond[cell]` + `beyond_g` wg (per direction cell
    /// and band, cell-major).
    beyond: Vec<f64>,
    beyond_w: f64,
    beyond_g: f64,
    /// Per band: the sums over the paths of x and x^2.
    x_sum: Vec<f64>,
    x2_sum: Vec<f64>,
    /// For mean surroundings: within the domain a path sees its class's
    /// control less the water's table (the view's `env`), the glint
    /// taken out over the land; otherwise its class's control.
    mean: bool,
}

/// A sample's mean lookup and the variance of that mean, per band.
pub(super) struct Lookup<'a> {
    pub mean: &'a mut [f64],
    pub var: &'a mut [f64],
}

impl AirView<'_> {
    /// The shared paths for surroundings `surround`: beyond the domain a
    /// path sees the surroundings (for mean surroundings: the land's
    /// share of its excess over the water's table); within, its class's
    /// table (for mean surroundings: that less the water's, the glint
    /// taken out over the land). Drawn from the stream of `seed`.
    pub(super) fn shared(&self, surround: &Surround, seed: u64) -> Shared {
        let nb = self.columns.len();
        let mean = matches!(surround, Surround::Mean);
        let seed = crate::rng::mix64(seed ^ SHARED_KEY);
        let chunks = 64u64;
        let per = SHARED_PATHS / chunks;
        // Beyond the domain, as x = beyond_w w beyond[cell] + beyond_g wg:
        // for mean surroundings the land's share of its table's excess over
        // the water's, less the glint; the surroundings' land radiance (the
        // same in every cell); or the sea's table plus the glint.
        let cells = crate::optics::atmosphere::transport::CELLS;
        let ls = self.land_share;
        let (beyond, beyond_w, beyond_g) = match surround {
            Surround::Mean if ls > 0.0 => (
                self.land_env
                    .iter()
                    .zip(&self.env)
                    .map(|(l, e)| l - e)
                    .collect(),
                ls,
                -ls,
            ),
            Surround::Mean => (vec![0.0; cells * nb], 0.0, 0.0),
            Surround::Land(r) => (r.repeat(cells), 1.0, 0.0),
            Surround::Water(sea) => (sea.clone(), 1.0, 1.0),
        };
        // Per path that met the ground within reach of the domain (an
        // offset beyond its size lands outside it from every ground point):
        // where, its cell, w and wg (f32); the sums of x over them all.
        type Met = (DVec3, u32, Vec<f32>, Vec<f32>);
        let chunked: Vec<(Vec<Met>, Vec<f64>, Vec<f64>)> = (0..chunks)
            .into_par_iter()
            .map(|k| {
                let mut met = Vec::new();
                let (mut x_sum, mut x2_sum) = (vec![0.0; nb], vec![0.0; nb]);
                let mut glint = vec![0.0; nb];
                self.shared_paths(seed, k * per..(k + 1) * per, |at, up, w| {
                    self.glint(up, &mut glint);
                    let c = self.cell(up);
                    let row = &beyond[c * nb..(c + 1) * nb];
                    let wg: Vec<f32> = (0..nb).map(|b| (w[b] * glint[b]) as f32).collect();
                    let w: Vec<f32> = w.iter().map(|&v| v as f32).collect();
                    for b in 0..nb {
                        let x = beyond_w * f64::from(w[b]) * row[b] + beyond_g * f64::from(wg[b]);
                        x_sum[b] += x;
                        x2_sum[b] += x * x;
                    }
                    if self.within_reach(at) {
                        met.push((at, c as u32, w, wg));
                    }
                });
                (met, x_sum, x2_sum)
            })
            .collect();
        let (mut x_sum, mut x2_sum) = (vec![0.0; nb], vec![0.0; nb]);
        let mut met: Vec<Met> = Vec::new();
        for (m, xs, x2s) in chunked {
            met.extend(m);
            for b in 0..nb {
                x_sum[b] += xs[b];
                x2_sum[b] += x2s[b];
            }
        }
        met.sort_by(|a, b| a.0.x.total_cmp(&b.0.x));
        Shared {
            drawn: SHARED_PATHS as f64,
            dx: met.iter().map(|m| m.0.x).collect(),
            dy: met.iter().map(|m| m.0.y).collect(),
            cell: met.iter().map(|m| m.1).collect(),
            w: met.iter().flat_map(|m| m.2.iter().copied()).collect(),
            wg: met.iter().flat_map(|m| m.3.iter().copied()).collect(),
            beyond,
            beyond_w,
            beyond_g,
            x_sum,
            x2_sum,
            mean,
        }
    }

    /// The shared adjoint paths `range` of the stream `seed` (mixed with
    /// the shared paths' key) from the ground point at the origin: for
    /// each that meets the ground, `at(where, up, band weights)`.
    fn shared_paths(
        &self,
        seed: u64,
        range: std::ops::Range<u64>,
        mut at: impl FnMut(DVec3, DVec3, &[f64]),
    ) {
        for i in range {
            let mut rng = Pcg32::new(seed, i);
            self.adjoint(DVec3::ZERO, &mut rng, |_, meet, dir, w| {
                at(meet, -dir, w);
                Ok(())
            })
            .expect("the shared paths call no integrator");
        }
    }

    /// True for an offset that lands within the domain from some ground
    /// point in it.
    fn within_reach(&self, at: DVec3) -> bool {
        let [sx, sy] = self.scene.domain.size_m;
        at.x.abs() < sx && at.y.abs() < sy
    }

    /// How many shared paths of `scene`'s seed the air view keeps: those
    /// that meet the ground within reach of the domain.
    pub(super) fn shared_kept(&self) -> u64 {
        let seed = crate::rng::mix64(self.scene.seed ^ SHARED_KEY);
        let chunks = 64u64;
        let per = SHARED_PATHS / chunks;
        (0..chunks)
            .into_par_iter()
            .map(|k| {
                let mut kept = 0;
                self.shared_paths(seed, k * per..(k + 1) * per, |at, _, _| {
                    kept += u64::from(self.within_reach(at));
                });
                kept
            })
            .sum()
    }

    /// The shared paths' mean lookup at the ground point `ground`, and the
    /// variance of that mean (from the paths' spread), per band.
    pub(super) fn lookup(&self, shared: &Shared, ground: DVec3, out: Lookup<'_>) {
        let nb = self.columns.len();
        let [sx, sy] = self.scene.domain.size_m;
        let (mean, var) = (out.mean, out.var);
        // y_b = w (within - beyond) summed over the paths within, with its
        // square and its product with x.
        let mut y = vec![0.0; nb];
        let mut yy = vec![0.0; nb];
        let mut xy = vec![0.0; nb];
        let (ones, zeros) = (vec![1.0; nb], vec![0.0; nb]);
        // The offsets whose x lands within [0, sx), with a margin for
        // rounding: each is tested again below.
        let lo = shared.dx.partition_point(|&d| d < -ground.x - 1e-6);
        let hi = shared.dx.partition_point(|&d| d < sx - ground.x + 1e-6);
        for i in lo..hi {
            let at = DVec3::new(ground.x + shared.dx[i], ground.y + shared.dy[i], 0.0);
            if !((0.0..sx).contains(&at.x) && (0.0..sy).contains(&at.y)) {
                continue;
            }
            let c = shared.cell[i] as usize;
            // The class's table, its depth bin's factors (none on land)
            // and the glint's weight, as `control` and `excess` take them.
            let (table, factor, g) = match self.classes.at(at) {
                (Class::Water(k), j) => (
                    &self.water_env[k],
                    Some(&self.water_bins[k][j * nb..(j + 1) * nb]),
                    if shared.mean { 0.0 } else { 1.0 },
                ),
                (Class::Land, _) => (&self.land_env, None, if shared.mean { -1.0 } else { 0.0 }),
            };
            let row = i * nb..(i + 1) * nb;
            let (w, wg) = (&shared.w[row.clone()], &shared.wg[row]);
            let beyond = &shared.beyond[c * nb..(c + 1) * nb];
            let table = &table[c * nb..(c + 1) * nb];
            // Ones and zeros where there is no factor or base: the same
            // values, in a loop without branches over the bands.
            let f = factor.unwrap_or(&ones);
            let base = if shared.mean {
                &self.env[c * nb..(c + 1) * nb]
            } else {
                &zeros[..]
            };
            let (bw, bg) = (shared.beyond_w, shared.beyond_g);
            let (f, base, y, yy, xy) = (
                &f[..nb],
                &base[..nb],
                &mut y[..nb],
                &mut yy[..nb],
                &mut xy[..nb],
            );
            for b in 0..nb {
                let (w, wg) = (f64::from(w[b]), f64::from(wg[b]));
                let x = bw * w * beyond[b] + bg * wg;
                let v = w * (table[b] * f[b] - base[b]) + g * wg - x;
                y[b] += v;
                yy[b] += v * v;
                xy[b] += x * v;
            }
        }
        let m = shared.drawn;
        for b in 0..nb {
            let a = (shared.x_sum[b] + y[b]) / m;
            let second = (shared.x2_sum[b] + 2.0 * xy[b] + yy[b]) / m;
            mean[b] = a;
            var[b] = ((second - a * a) / (m - 1.0)).max(0.0);
        }
    }
}
