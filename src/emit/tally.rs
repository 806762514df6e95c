//! Irradiance tallies and energy accounting, summed without regard to order.
//!
//! Each photon's contributions are first gathered in a small per-photon
//! record (its band is fixed), then added to the run totals as fixed-point
//! integers (2^-32 resolution). Integer sums are associative, so the report
//! is bit-identical whatever the thread count or batch order, and the totals
//! need no per-batch storage. Sums of per-photon squares give the standard
//! errors (photons are independent: Var(sum x) = sum x^2 - (sum x)^2 / N).
//!
//! Units: tallies count in units of "photon power per domain area" — the
//! report multiplies by the band's photon power and divides by the area.

/// Quantities tallied at each depth.
pub const ED: usize = 0;
pub const EU: usize = 1;
pub const EOD: usize = 2;
pub const EOU: usize = 3;
/// Upward crossings within [`LU_CONE_DEG`] of the zenith: nadir-viewing
/// upwelling radiance, an oracle for the renderer's radiometers.
pub const LU: usize = 4;
/// Downward crossings within [`LU_CONE_DEG`] of straight down: the
/// radiance a radiometer looking at the zenith measures.
pub const LD: usize = 5;
pub const QUANTITIES: usize = 6;

/// Half-angle of the cones around straight up and straight down in which
/// crossings count toward `LU` and `LD`. The tally is the cone average of L weighted by cos(theta);
/// 10 degrees keeps that within a fraction of a per cent of nadir L for the
/// smooth upwelling light field while catching 3 % of the upward photons.
pub const LU_CONE_DEG: f64 = 10.0;

/// Projected solid angle of the `LU` (and `LD`) cone, pi sin^2(theta_c) (sr): power
/// per area through it divided by this is radiance.
pub fn lu_cone_projected_solid_angle() -> f64 {
    std::f64::consts::PI * LU_CONE_DEG.to_radians().sin().powi(2)
}

/// Whether a direction with vertical component `mu` lies within
/// [`LU_CONE_DEG`] of straight up (`LU`), or with `-mu` of straight down (`LD`).
#[inline]
pub fn in_lu_cone(mu: f64) -> bool {
    mu >= LU_CONE_DEG.to_radians().cos()
}

/// Smallest |cos| used in scalar irradiance just below the surface (1/|mu|
/// per crossing): caps the infinite-variance tail of grazing crossings at a
/// negligible bias.
pub const MIN_ABS_MU: f64 = 0.001;

/// Half the thickness of the layer around each depth below the surface in
/// which scalar irradiance is tallied by track length (m). The layer
/// averages E_o over +-2 cm: for E_o ~ exp(-K z) that reads
/// sinh(K h) / (K h) - 1 ~ (K h)^2 / 6 high, 0.07 % at K = 3 /m.
pub const EO_HALF_WIDTH_M: f64 = 0.02;

const SCALE: f64 = (1u64 << 32) as f64;

fn fixed(x: f64) -> i128 {
    let v = (x * SCALE).round();
    // The same value either way; the i64 conversion is one instruction,
    // the i128 one a library call.
    if v.abs() < 9.0e18 {
        v as i64 as i128
    } else {
        v as i128
    }
}

/// What one photon contributed (indices: depth x quantity, then the two
/// above-surface quantities), and which slots it touched: a path crosses a
/// few of them, so [`Totals::record`] and [`PhotonTally::clear`] visit only
/// those (bit `i` for slot `i`; bit 63 for any slot from 63 up).
#[derive(Clone, Debug)]
pub struct PhotonTally {
    values: Vec<f64>,
    depths: usize,
    touched: u64,
}

impl PhotonTally {
    pub fn new(depths: usize) -> Self {
        PhotonTally {
            values: vec![0.0; depths * QUANTITIES + 2],
            depths,
            touched: 0,
        }
    }
    pub fn clear(&mut self) {
        let mut m = self.touched;
        while m != 0 {
            let bit = m.trailing_zeros() as usize;
            m &= m - 1;
            if bit < 63 {
                self.values[bit] = 0.0;
            } else {
                self.values[63..].iter_mut().for_each(|v| *v = 0.0);
            }
        }
        self.touched = 0;
    }
    /// Contribution in each slot.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    #[inline]
    fn add_slot(&mut self, slot: usize, x: f64) {
        self.values[slot] += x;
        self.touched |= 1 << slot.min(63);
    }
    #[inline]
    pub fn add(&mut self, depth: usize, q: usize, x: f64) {
        self.add_slot(depth * QUANTITIES + q, x);
    }
    /// Downward irradiance just above the surface.
    #[inline]
    pub fn add_above_down(&mut self) {
        self.add_slot(self.depths * QUANTITIES, 1.0);
    }
    /// Upward irradiance just above the surface, of a path branch of weight `w`.
    #[inline]
    pub fn add_above_up(&mut self, w: f64) {
        self.add_slot(self.depths * QUANTITIES + 1, w);
    }
}

/// Where a photon's power ended (in the band it travelled in).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fate {
    Escaped,
    AbsorbedWater,
    AbsorbedSurface,
    LostEdge,
    /// Raman-scattered or fluoresced into another band of the grid
    /// (where it goes on).
    Shifted,
    /// Raman-scattered or fluoresced beyond the grid's last band (or
    /// between the cells of an explicit grid): lost to the bands.
    ShiftedOut,
    /// Fell on land (`[land]`) from the sky: reflected or absorbed there,
    /// not traced on.
    Land,
}

impl Fate {
    /// Number of fates.
    pub const COUNT: usize = 7;

    /// Index of the fate in per-fate arrays.
    pub fn index(self) -> usize {
        self as usize
    }
}

/// What one photon path contributed in one band it travelled in: its
/// tallies, the weight that ended in each fate there, and the weight that
/// inelastic light brought into it (units of 1 / `trace::FATE_UNIT` of a
/// photon of this band).
#[derive(Clone, Debug)]
pub struct BandPart {
    pub band: usize,
    pub tally: PhotonTally,
    pub fates: [u64; Fate::COUNT],
    pub inelastic_in: u64,
    /// Weight that left the water up through the surface, and the part
    /// of it inelastic light had moved (same units).
    pub left_water: u64,
    pub left_water_inelastic: u64,
}

/// One photon path's parts, one per band it travelled in (one unless
/// inelastic light moved it), in the order first met.
#[derive(Clone, Debug)]
pub struct PathTally {
    depths: usize,
    parts: Vec<BandPart>,
    used: usize,
}

impl PathTally {
    pub fn new(depths: usize) -> Self {
        PathTally {
            depths,
            parts: Vec::new(),
            used: 0,
        }
    }

    /// Empty, keeping the storage.
    pub fn clear(&mut self) {
        for p in &mut self.parts[..self.used] {
            p.tally.clear();
            p.fates = [0; Fate::COUNT];
            p.inelastic_in = 0;
            p.left_water = 0;
            p.left_water_inelastic = 0;
        }
        self.used = 0;
    }

    /// The index of `band`'s part, made if the path has none yet.
    pub fn part(&mut self, band: usize) -> usize {
        if let Some(i) = self.parts[..self.used].iter().position(|p| p.band == band) {
            return i;
        }
        if self.used == self.parts.len() {
            self.parts.push(BandPart {
                band,
                tally: PhotonTally::new(self.depths),
                fates: [0; Fate::COUNT],
                inelastic_in: 0,
                left_water: 0,
                left_water_inelastic: 0,
            });
        }
        self.parts[self.used].band = band;
        self.used += 1;
        self.used - 1
    }

    /// Part `i`.
    #[inline]
    pub fn at(&mut self, i: usize) -> &mut BandPart {
        &mut self.parts[i]
    }

    /// The parts in use.
    pub fn parts(&self) -> &[BandPart] {
        &self.parts[..self.used]
    }
}

/// Run totals over photons, per band.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Totals {
    pub bands: usize,
    pub depths: usize,
    /// Photons emitted per band.
    pub emitted: Vec<u64>,
    /// Photon weight that ended in each fate per band, in units of
    /// 1 / `trace::FATE_UNIT` photon (split paths end in several).
    pub escaped: Vec<u64>,
    pub absorbed_water: Vec<u64>,
    pub absorbed_surfaces: Vec<u64>,
    pub lost_edges: Vec<u64>,
    /// Moved by inelastic light out of the band into another of the grid, beyond
    /// the grid, and into the band from shorter ones (the last in the
    /// receiving band's photons).
    pub inelastic_out: Vec<u64>,
    pub inelastic_lost: Vec<u64>,
    pub inelastic_in: Vec<u64>,
    /// Weight that left the water up through the surface (the
    /// water-leaving light, without the surface's reflection), and the
    /// part of it inelastic light had moved into the band.
    #[serde(default)]
    pub left_water: Vec<u64>,
    #[serde(default)]
    pub left_water_inelastic: Vec<u64>,
    /// Weight that fell on land from the sky (none in totals written
    /// before land existed).
    #[serde(default)]
    pub on_land: Vec<u64>,
    /// Fixed-point sums of per-photon contributions, [slot][band].
    pub sum: Vec<i128>,
    pub sum_sq: Vec<i128>,
    pub traced: u64,
    pub stored_volume: u64,
    pub stored_surface: u64,
    /// Photons stopped after the maximum number of events (counted as absorbed in water).
    pub truncated: u64,
}

impl Totals {
    pub fn new(bands: usize, depths: usize) -> Self {
        let slots = depths * QUANTITIES + 2;
        Totals {
            bands,
            depths,
            emitted: vec![0; bands],
            escaped: vec![0; bands],
            absorbed_water: vec![0; bands],
            absorbed_surfaces: vec![0; bands],
            lost_edges: vec![0; bands],
            inelastic_out: vec![0; bands],
            inelastic_lost: vec![0; bands],
            inelastic_in: vec![0; bands],
            left_water: vec![0; bands],
            left_water_inelastic: vec![0; bands],
            on_land: vec![0; bands],
            sum: vec![0; slots * bands],
            sum_sq: vec![0; slots * bands],
            traced: 0,
            stored_volume: 0,
            stored_surface: 0,
            truncated: 0,
        }
    }

    /// Account one finished photon path of `band`, whose weight ended in
    /// `fates` (units of 1 / `trace::FATE_UNIT`, by [`Fate::index`]).
    pub fn record(&mut self, band: usize, fates: &[u64; Fate::COUNT], t: &PhotonTally) {
        self.traced += 1;
        self.emitted[band] += 1;
        self.add_part(band, fates, [0; 3], t);
    }

    /// Account one finished photon path that started in `band`, its
    /// parts per band it travelled in.
    pub fn record_path(&mut self, band: usize, path: &PathTally) {
        self.traced += 1;
        self.emitted[band] += 1;
        for p in path.parts() {
            let flows = [p.inelastic_in, p.left_water, p.left_water_inelastic];
            self.add_part(p.band, &p.fates, flows, &p.tally);
        }
    }

    /// A path's fates, its flows (inelastic inflow, weight that left the
    /// water and the inelastic part of it) and tallies in `band`.
    fn add_part(
        &mut self,
        band: usize,
        fates: &[u64; Fate::COUNT],
        [inelastic_in, left, left_inelastic]: [u64; 3],
        t: &PhotonTally,
    ) {
        self.escaped[band] += fates[Fate::Escaped.index()];
        self.absorbed_water[band] += fates[Fate::AbsorbedWater.index()];
        self.absorbed_surfaces[band] += fates[Fate::AbsorbedSurface.index()];
        self.lost_edges[band] += fates[Fate::LostEdge.index()];
        self.inelastic_out[band] += fates[Fate::Shifted.index()];
        self.inelastic_lost[band] += fates[Fate::ShiftedOut.index()];
        self.on_land[band] += fates[Fate::Land.index()];
        self.inelastic_in[band] += inelastic_in;
        self.left_water[band] += left;
        self.left_water_inelastic[band] += left_inelastic;
        let mut add = |slot: usize, x: f64| {
            if x != 0.0 {
                self.sum[slot * self.bands + band] += fixed(x);
                self.sum_sq[slot * self.bands + band] += fixed(x * x);
            }
        };
        let mut m = t.touched;
        while m != 0 {
            let bit = m.trailing_zeros() as usize;
            m &= m - 1;
            if bit < 63 {
                add(bit, t.values[bit]);
            } else {
                for (slot, &x) in t.values.iter().enumerate().skip(63) {
                    add(slot, x);
                }
            }
        }
    }

    /// Add another set of totals (order does not matter).
    pub fn merge(&mut self, o: &Totals) {
        let add = |a: &mut Vec<u64>, b: &Vec<u64>| a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        add(&mut self.emitted, &o.emitted);
        add(&mut self.escaped, &o.escaped);
        add(&mut self.absorbed_water, &o.absorbed_water);
        add(&mut self.absorbed_surfaces, &o.absorbed_surfaces);
        add(&mut self.lost_edges, &o.lost_edges);
        add(&mut self.inelastic_out, &o.inelastic_out);
        add(&mut self.inelastic_lost, &o.inelastic_lost);
        add(&mut self.inelastic_in, &o.inelastic_in);
        add(&mut self.left_water, &o.left_water);
        add(&mut self.left_water_inelastic, &o.left_water_inelastic);
        if !o.on_land.is_empty() {
            self.on_land.resize(self.bands, 0);
            add(&mut self.on_land, &o.on_land);
        }
        self.sum.iter_mut().zip(&o.sum).for_each(|(x, y)| *x += y);
        self.sum_sq
            .iter_mut()
            .zip(&o.sum_sq)
            .for_each(|(x, y)| *x += y);
        self.traced += o.traced;
        self.stored_volume += o.stored_volume;
        self.stored_surface += o.stored_surface;
        self.truncated += o.truncated;
    }

    /// Mean per traced photon and its standard error for `slot`, `band`,
    /// in tally units (multiply by N x photon power / area for irradiance).
    pub fn mean_and_stderr(&self, slot: usize, band: usize) -> (f64, f64) {
        let n = self.traced.max(1) as f64;
        let s = self.sum[slot * self.bands + band] as f64 / SCALE;
        let s2 = self.sum_sq[slot * self.bands + band] as f64 / SCALE;
        let mean = s / n;
        let var = ((s2 / n - mean * mean).max(0.0)) / (n - 1.0).max(1.0);
        (mean, var.sqrt())
    }

    /// Slot index of quantity `q` at depth index `d`.
    pub fn slot(&self, d: usize, q: usize) -> usize {
        d * QUANTITIES + q
    }

    /// Slots of the above-surface Ed and Eu.
    pub fn above_slots(&self) -> (usize, usize) {
        (self.depths * QUANTITIES, self.depths * QUANTITIES + 1)
    }
}

#[cfg(test)]
mod tests;
