//! Running sums over the samples of a pixel or a radiometer reading: the
//! mean, its standard error (the samples' spread and the photon groups'),
//! the band mean's standard error, and the tail statistics (VOV, the
//! largest sample's share) that say when a few samples dominate.

use crate::estimate::groups;

/// Running sums over the samples of a pixel or radiometer: the radiance's
/// first two moments, and the mean of the photon-group channels.
pub(crate) struct Moments {
    n: u64,
    bands: usize,
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
    /// Third and fourth moments' sums and the largest sample, per band,
    /// for the variance of the variance.
    sum_cu: Vec<f64>,
    sum_qu: Vec<f64>,
    max: Vec<f64>,
    /// Sums of the group channels (empty for a one-channel integrator).
    groups: Vec<f64>,
    /// Sums of each sample's band mean and of its square.
    band_mean: f64,
    band_mean_sq: f64,
    scratch: Vec<f64>,
}

impl Moments {
    pub(crate) fn new(bands: usize, channels: usize) -> Self {
        Moments {
            n: 0,
            bands,
            sum: vec![0.0; bands],
            sum_sq: vec![0.0; bands],
            sum_cu: vec![0.0; bands],
            sum_qu: vec![0.0; bands],
            max: vec![0.0; bands],
            groups: vec![0.0; bands * (channels - 1)],
            band_mean: 0.0,
            band_mean_sq: 0.0,
            scratch: vec![0.0; bands],
        }
    }

    pub(crate) fn clear(&mut self) {
        self.n = 0;
        self.sum.iter_mut().for_each(|v| *v = 0.0);
        self.sum_sq.iter_mut().for_each(|v| *v = 0.0);
        self.sum_cu.iter_mut().for_each(|v| *v = 0.0);
        self.sum_qu.iter_mut().for_each(|v| *v = 0.0);
        self.max.iter_mut().for_each(|v| *v = 0.0);
        self.groups.iter_mut().for_each(|v| *v = 0.0);
        self.band_mean = 0.0;
        self.band_mean_sq = 0.0;
    }

    /// Add one sample (its channels, radiance first).
    pub(crate) fn add(&mut self, sample: &[f64]) {
        self.n += 1;
        let (l, g) = sample.split_at(self.bands);
        for ((s, s2), v) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(l) {
            *s += v;
            *s2 += v * v;
        }
        for (b, v) in l.iter().enumerate() {
            let v2 = v * v;
            self.sum_cu[b] += v2 * v;
            self.sum_qu[b] += v2 * v2;
            self.max[b] = self.max[b].max(v.abs());
        }
        for (a, v) in self.groups.iter_mut().zip(g) {
            *a += v;
        }
        let m = l.iter().sum::<f64>() / self.bands as f64;
        self.band_mean += m;
        self.band_mean_sq += m * m;
    }

    pub(crate) fn mean(&self) -> impl Iterator<Item = f64> + '_ {
        let n = self.n.max(1) as f64;
        self.sum.iter().map(move |s| s / n)
    }

    /// Per band, the relative variance of the variance (see
    /// [`RadiometerReading::vov`]; 0 with fewer than two samples or none
    /// spread) and the largest sample's share of the sum.
    pub(crate) fn tail(&self) -> (Vec<f64>, Vec<f64>) {
        let n = self.n as f64;
        (0..self.bands)
            .map(|b| {
                let (s1, s2, s3, s4) =
                    (self.sum[b], self.sum_sq[b], self.sum_cu[b], self.sum_qu[b]);
                let share = if s1 != 0.0 {
                    self.max[b] / s1.abs()
                } else {
                    0.0
                };
                if self.n < 2 {
                    return (0.0, share);
                }
                let m = s1 / n;
                let m2 = s2 - n * m * m;
                let m4 = s4 - 4.0 * m * s3 + 6.0 * m * m * s2 - 3.0 * n * m.powi(4);
                let vov = if m2 > 0.0 {
                    (m4.max(0.0) / (m2 * m2) - 1.0 / n).max(0.0)
                } else {
                    0.0
                };
                (vov, share)
            })
            .unzip()
    }

    /// Standard error per band of the mean: the samples' spread over their
    /// count (two or more samples), plus the photon noise of the mean group
    /// channels.
    pub(crate) fn standard_error(&mut self, out: &mut [f64]) {
        let n = self.n as f64;
        for ((o, s), s2) in out.iter_mut().zip(&self.sum).zip(&self.sum_sq) {
            *o = if self.n >= 2 {
                let m = s / n;
                (s2 / n - m * m).max(0.0) / (n - 1.0)
            } else {
                0.0
            };
        }
        if !self.groups.is_empty() {
            // The variance of the mean channels: that of their sums over n^2.
            groups::variance(&self.groups, &mut self.scratch);
            let n2 = n * n;
            out.iter_mut()
                .zip(&self.scratch)
                .for_each(|(o, v)| *o += v / n2);
        }
        out.iter_mut().for_each(|o| *o = o.sqrt());
    }

    /// Standard error of the band mean: [`Self::standard_error`] with the
    /// bands of every sample and every photon group averaged first.
    pub(crate) fn band_mean_standard_error(&self) -> f64 {
        let n = self.n as f64;
        let mut var = if self.n >= 2 {
            let m = self.band_mean / n;
            (self.band_mean_sq / n - m * m).max(0.0) / (n - 1.0)
        } else {
            0.0
        };
        if !self.groups.is_empty() {
            let nb = self.bands as f64;
            let means: Vec<f64> = self
                .groups
                .chunks(self.bands)
                .map(|g| g.iter().sum::<f64>() / nb)
                .collect();
            let mut v = [0.0];
            groups::variance(&means, &mut v);
            var += v[0] / (n * n);
        }
        var.sqrt()
    }
}
