//! Tracing one photon from the sky or the sun through the sea surface,
//! the water, the floor and the targets.
//!
//! Free paths use delta tracking against the band's local majorant
//! extinction ([`MajorantGrid`]: piecewise constant along the axis the
//! water varies on), so heterogeneous water is sampled without bias: a
//! tentative collision is real with probability c(x)/c_maj, then absorption
//! (a/c), pure-water scattering (b_w/c) or particle scattering (b_p/c) is
//! chosen; otherwise it is a null collision and the flight goes on.
//! Absorption is analog (the photon ends). With inelastic light (`[water]
//! raman`, `[water.fluorescence]`) the share c_k / a of absorption events
//! is process k's instead: the photon goes on in the longer band its drawn
//! wavelength lands in (`shift`), and its tallies and fates from then on
//! count in that band. The floor and targets are Lambertian: a photon is absorbed with
//! probability 1 - R, else reflected into a cosine-weighted direction.
//!
//! **Upward splitting.** A viewer looking down sees upwelling light, which
//! rests on the few photons travelling up (in deep water a few per cent of
//! the stored photons): through the phase function's forward lobe they carry
//! most of the in-scatter toward the viewer. When a path of full weight
//! scatters or reflects into a direction within 60 degrees of straight up
//! ([`SPLIT_MU`]), it splits into `[photons] upward_split` copies of equal
//! weight that go on independently from there (splitting in the sense of
//! Kahn's particle splitting: the expected stored power is unchanged, and
//! the weights of a path's branches sum to exactly one, so every unit of
//! emitted power still ends in exactly one fate). A copy never splits
//! upward again. Stored powers and tallies carry the branch's weight.
//!
//! **Splitting over targets.** A small submerged target is read from the
//! photons around it, and at the default density a 1–2 m box has too few
//! near it for its estimates to hold their level. A path that enters the
//! water over a target (within [`crate::scene::Scene::split_footprints`]:
//! the target's extent widened by the depth of its top and 1 m) splits
//! there into `[photons] target_split` copies of weight 1 / target_split,
//! each entering at its own point of the footprint (drawn uniformly where
//! that footprint is the first to hold it, so that the power entering
//! every point is unchanged in expectation) in the path's refracted
//! direction, each free to split upward once more. The map
//! is that many times denser around the targets at the same expected power
//! everywhere (the adaptive emission of the poster's title, with exact
//! weights), and the weights stay powers of two, so fates still add up
//! exactly.
//!
//! Stored photons: a volume photon at every real scattering event (in the
//! layer of its vertical direction, [`crate::photon::volume_layer`]), a
//! surface photon at every floor or target hit, each with the direction it
//! arrived in — except that light still on its unscattered path from the
//! sun (transmitted once through the surface) is not stored unless the
//! scene asks for it, since the renderer adds that single scattering
//! directly.

use super::tally::{
    in_lu_cone, Fate, PathTally, PhotonTally, ED, EOD, EOU, EO_HALF_WIDTH_M, EU, LD, LU, MIN_ABS_MU,
};
use crate::optics::inelastic::{Absorbers, Inelastic, Process};
use crate::optics::majorant::{Collision, MajorantGrid};
use crate::optics::phase::{cosine_hemisphere, scatter};
use crate::photon::{volume_layer, Photon, LAYER_SURFACE};
use crate::rng::Pcg32;
use crate::scene::Scene;
use crate::store::StagedPhoton;
use glam::Vec3;

/// Events per photon path before it is stopped: a guard against paths that
/// never end (the emission report counts those truncated).
pub const MAX_EVENTS: u32 = (1 << 20) - 1;

/// A path of full weight splits when it turns into a direction whose
/// vertical component exceeds this (within 60 degrees of straight up).
pub const SPLIT_MU: f32 = 0.5;

/// Fates are counted in units of 1 / `FATE_UNIT` of a photon: split weights
/// (1 / a power of two up to this) add up exactly in integers.
pub const FATE_UNIT: u64 = 1 << 16;

/// Where a photon starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    Sun,
    Sky,
}

/// The outcome of one traced photon path (its fates and tallies per band
/// are in the [`PathTally`] it was traced with: in units of 1 /
/// [`FATE_UNIT`] of a photon of each band, they sum to `FATE_UNIT` plus
/// what Raman scattering brought in).
pub struct Traced {
    pub truncated: bool,
    pub stored_volume: u32,
    pub stored_surface: u32,
}

/// One branch of a split path: where it is, where it goes, its band and
/// weight (relative to a photon of that band).
#[derive(Clone, Copy)]
struct Branch {
    pos: Vec3,
    dir: Vec3,
    band: usize,
    weight: f64,
    /// The weight the branch began with: 1, or 1 / `target_split` for a
    /// copy of a path split over a target. A branch still of this weight
    /// has not split upward (nor been moved by inelastic light).
    full: f64,
    /// Still the sun's unscattered light.
    direct: bool,
    /// Inelastic light moved it into its band.
    shifted: bool,
}

/// What a path shares between its branches.
struct Path<'a> {
    scene: &'a Scene,
    /// Power per photon of each band (W nm^-1).
    photon_power: &'a [f64],
    group: u8,
    /// The water's local majorants and IOP bounds.
    grid: &'a MajorantGrid,
    split: usize,
    events: u32,
    result: Traced,
    /// Branches waiting to be traced (copies of a split).
    pending: Vec<Branch>,
}

/// Trace photon `index` of band `band` from `source` through water whose
/// majorants are `grid`, photons of each band carrying `photon_power`;
/// stored photons go to `out`, tallies and fates to `tallies` (cleared by
/// the caller).
#[allow(clippy::too_many_arguments)]
pub fn trace(
    scene: &Scene,
    grid: &MajorantGrid,
    index: u64,
    rng: &mut Pcg32,
    source: Source,
    band: usize,
    photon_power: &[f64],
    tallies: &mut PathTally,
    out: &mut Vec<StagedPhoton>,
) -> Traced {
    let d = &scene.domain;
    let (sx, sy) = (d.size_m[0], d.size_m[1]);
    let mut path = Path {
        scene,
        photon_power,
        group: crate::photon::group_of_path(index),
        grid,
        split: scene.upward_split.max(1),
        events: 0,
        result: Traced {
            truncated: false,
            stored_volume: 0,
            stored_surface: 0,
        },
        pending: Vec::new(),
    };

    // Start on the surface, anywhere in the domain.
    let pos = Vec3::new(
        (rng.uniform_f64() * sx) as f32,
        (rng.uniform_f64() * sy) as f32,
        0.0,
    );
    let dir = match source {
        Source::Sun => scene.sun.direction,
        Source::Sky => scene.sky.model.sample_travel(band, rng),
    };
    let first = tallies.part(band);
    let tally = &mut tallies.at(first).tally;
    tally.add_above_down();
    // Land there: the light goes up again in the share the land reflects
    // (no water to enter, nothing to store).
    if scene.is_land(pos.x, pos.y) {
        let reflected = scene.land.as_ref().map_or(0.0, |l| l.reflectance[band]);
        tally.add_above_up(reflected);
        end(tallies, band, Fate::Land, 1.0);
        return path.result;
    }
    // The surface at this band's refractive index.
    let surface = scene.surface_in(band);
    let ev = surface.interact(dir, rng);
    if !ev.transmitted {
        tally.add_above_up(1.0);
        end(tallies, band, Fate::Escaped, 1.0);
        return path.result;
    }
    cross_surface_down(scene, tally, ev.direction, 1.0);
    // Over a target the path splits into copies of equal weight, each
    // entering at its own point of the same footprint.
    // (No footprints without splitting: `Scene::split_footprints`.)
    let footprint = first_footprint(scene, pos);
    let copies = footprint.map_or(1, |_| scene.target_split);
    let weight = 1.0 / copies as f64;
    let entering = Branch {
        pos,
        dir: ev.direction,
        band,
        weight,
        full: weight,
        direct: source == Source::Sun,
        shifted: false,
    };
    if let Some(j) = footprint {
        for _ in 1..copies {
            let pos = point_in_footprint(scene, j, rng);
            path.pending.push(Branch { pos, ..entering });
        }
    }
    let mut next = Some(entering);
    while let Some(branch) = next {
        let (band, fate, weight) = path.run(branch, rng, tallies, out);
        end(tallies, band, fate, weight);
        next = path.pending.pop();
    }
    path.result
}

/// The first of the scene's split footprints that holds the surface point
/// `pos`.
fn first_footprint(scene: &Scene, pos: Vec3) -> Option<usize> {
    let (x, y) = (f64::from(pos.x), f64::from(pos.y));
    scene
        .split_footprints
        .iter()
        .position(|f| f.contains(&scene.domain, x, y))
}

/// A surface point drawn uniformly from the water of the domain whose
/// first split footprint is `j` (by rejection from footprint `j`), so that
/// the copies of a path split there stand for the same region as the path
/// itself: the expected power entering each point is unchanged, and the
/// copies start apart (copies at one point would stay near one line
/// through forward-peaked water, a clump that biases a k-nearest estimate
/// high).
fn point_in_footprint(scene: &Scene, j: usize, rng: &mut Pcg32) -> Vec3 {
    let f = &scene.split_footprints[j];
    let d = &scene.domain;
    loop {
        let x = f.min[0] + (f.max[0] - f.min[0]) * rng.uniform_f64();
        let y = f.min[1] + (f.max[1] - f.min[1]) * rng.uniform_f64();
        let (x, y) = if d.periodic {
            (x.rem_euclid(d.size_m[0]), y.rem_euclid(d.size_m[1]))
        } else {
            (x, y)
        };
        let inside = (0.0..d.size_m[0]).contains(&x) && (0.0..d.size_m[1]).contains(&y);
        let p = Vec3::new(x as f32, y as f32, 0.0);
        if inside && first_footprint(scene, p) == Some(j) && !scene.is_land(p.x, p.y) {
            return p;
        }
    }
}

/// Weight `weight` of a photon of `band` ended in `fate`.
fn end(tallies: &mut PathTally, band: usize, fate: Fate, weight: f64) {
    let i = tallies.part(band);
    tallies.at(i).fates[fate.index()] += (weight * FATE_UNIT as f64).round() as u64;
}

impl Path<'_> {
    fn store(&mut self, b: &Branch, layer: u16, out: &mut Vec<StagedPhoton>) {
        self.events += 1;
        out.push(StagedPhoton::new(
            &Photon {
                position: b.pos,
                direction: b.dir,
                band: b.band as u16,
                power: (self.photon_power[b.band] as f32 as f64 * b.weight) as f32,
                group: self.group,
            },
            layer,
        ));
    }

    /// After the branch turned into `b.dir`: split a path of full weight
    /// that now travels up, leaving the copies for later.
    fn maybe_split(&mut self, b: &mut Branch) {
        if self.split > 1 && b.weight == b.full && b.dir.z > SPLIT_MU {
            b.weight = b.full / self.split as f64;
            self.pending.extend(std::iter::repeat_n(*b, self.split - 1));
        }
    }

    /// Trace one branch to its end: the band it ended in, its fate and
    /// weight.
    fn run(
        &mut self,
        mut b: Branch,
        rng: &mut Pcg32,
        tallies: &mut PathTally,
        out: &mut Vec<StagedPhoton>,
    ) -> (usize, Fate, f64) {
        let scene = self.scene;
        let depths = &scene.tally_depths;
        let mut part = tallies.part(b.band);
        // Branches start at the sea surface or in the water; only a
        // reflection leaves one on the floor or a target.
        let mut on_surface = false;
        loop {
            let tally = &mut tallies.at(part).tally;
            if self.events >= MAX_EVENTS {
                self.result.truncated = true;
                return (b.band, Fate::AbsorbedWater, b.weight);
            }
            let tau = rng.exponential(1.0);
            let t_surface = crate::scene::Domain::surface_distance(b.pos, b.dir);
            let t_edge = scene.domain.edge_distance(b.pos, b.dir);
            let t_wall = t_surface.min(t_edge);
            let flight = self.grid.free_path(b.band, b.pos, b.dir, t_wall, tau);
            let (t_flight, cell) = flight.unwrap_or((f64::INFINITY, 0));
            let t_limit = t_flight.min(t_wall);
            // From a point in the water (a collision, the sea surface) a
            // floor or target nearer than the self-intersection epsilon
            // still counts: with `intersect` alone, a photon scattered
            // within the epsilon (0.4 mm in a 40 m domain) above the floor
            // and heading down went through it, and it and its path's
            // later photons were stored down to tens of metres below (150
            // of 590 k photons over a 3.5 m sand floor in Chl 2 water).
            let t_max = t_limit.min(f32::MAX as f64) as f32;
            let hit = if on_surface {
                scene.geometry.intersect(b.pos, b.dir, t_max)
            } else {
                scene.geometry.intersect_from_point(b.pos, b.dir, t_max)
            };
            on_surface = hit.is_some();
            if let Some(h) = hit {
                tally_segment(depths, tally, b.pos, h.position, b.dir, b.weight);
                b.pos = h.position;
                if !b.direct || scene.store_direct {
                    self.store(&b, LAYER_SURFACE, out);
                    self.result.stored_surface += 1;
                } else {
                    self.events += 1;
                }
                let r = scene.reflectance(h.surface, b.pos, b.band);
                if rng.uniform_f64() >= r {
                    return (b.band, Fate::AbsorbedSurface, b.weight);
                }
                b.dir = cosine_hemisphere(h.normal, rng);
                b.direct = false;
                continue;
            }
            if t_surface <= t_limit {
                let next = b.pos + b.dir * t_surface as f32;
                let next = Vec3::new(next.x, next.y, 0.0);
                tally_segment(depths, tally, b.pos, next, b.dir, b.weight);
                b.pos = next;
                // Arriving at the surface from below: Eu just below the surface.
                if depths.first() == Some(&0.0) {
                    let w = b.weight;
                    tally.add(0, EU, w);
                    tally.add(0, EOU, w / (b.dir.z as f64).abs().max(MIN_ABS_MU));
                    if in_lu_cone(b.dir.z as f64) {
                        tally.add(0, LU, w);
                    }
                }
                let ev = scene.surface_in(b.band).interact(b.dir, rng);
                self.events += 1;
                if ev.transmitted {
                    tally.add_above_up(b.weight);
                    let p = tallies.at(part);
                    let w = (b.weight * FATE_UNIT as f64).round() as u64;
                    p.left_water += w;
                    if b.shifted {
                        p.left_water_inelastic += w;
                    }
                    return (b.band, Fate::Escaped, b.weight);
                }
                b.dir = ev.direction;
                b.direct = false;
                cross_surface_down(scene, tally, b.dir, b.weight);
                continue;
            }
            if t_edge <= t_limit {
                let next = b.pos + b.dir * t_edge as f32;
                tally_segment(depths, tally, b.pos, next, b.dir, b.weight);
                if !scene.domain.periodic {
                    return (b.band, Fate::LostEdge, b.weight);
                }
                b.pos = scene.domain.wrap(next, b.dir);
                if scene.under_floor(b.pos) {
                    // A seam where the floor does not meet itself (deeper
                    // on the side left than on the side entered, or land
                    // there): the step between is a wall the photon ends at.
                    return (b.band, Fate::LostEdge, b.weight);
                }
                continue;
            }
            // A tentative collision.
            let next = b.pos + b.dir * t_flight as f32;
            tally_segment(depths, tally, b.pos, next, b.dir, b.weight);
            b.pos = next;
            let xi = rng.uniform_f64() * self.grid.majorant(b.band, cell);
            let phase = match self.grid.collide(&scene.water, b.band, cell, b.pos, xi) {
                Collision::Absorbed => {
                    let Some(inelastic) = &scene.inelastic else {
                        return (b.band, Fate::AbsorbedWater, b.weight);
                    };
                    // Each inelastic process is its share c_k / a of
                    // absorption.
                    let a = scene.water.iop(b.pos, b.band).a;
                    let parts = if inelastic.fluoresces() {
                        scene.water.absorbers_in(b.pos, b.band)
                    } else {
                        Absorbers::default()
                    };
                    let mut u = rng.uniform_f64() * a;
                    let Some(process) = inelastic.processes.iter().find(|p| {
                        let c = p.coefficient(b.band, &parts);
                        u -= c;
                        u < 0.0
                    }) else {
                        return (b.band, Fate::AbsorbedWater, b.weight);
                    };
                    let (band, weight) = match shift(inelastic, process, self.photon_power, &b, rng)
                    {
                        Shift::Absorbed => return (b.band, Fate::AbsorbedWater, b.weight),
                        Shift::Out => return (b.band, Fate::ShiftedOut, b.weight),
                        Shift::To(band, weight) => (band, weight),
                    };
                    end(tallies, b.band, Fate::Shifted, b.weight);
                    part = tallies.part(band);
                    tallies.at(part).inelastic_in += (weight * FATE_UNIT as f64).round() as u64;
                    self.events += 1;
                    let u = [rng.uniform_f64(), rng.uniform_f64()];
                    b.dir = process.phase.sample_direction(b.dir, u);
                    (b.band, b.weight, b.direct, b.shifted) = (band, weight, false, true);
                    continue;
                }
                Collision::Null => continue,
                Collision::WaterScatter => &scene.water_phase,
                Collision::ParticleScatter => &scene.particle_phase,
            };
            if !b.direct || scene.store_direct {
                self.store(&b, volume_layer(b.dir), out);
                self.result.stored_volume += 1;
            } else {
                self.events += 1;
            }
            let mu = phase.sample_cos(rng.uniform_f64());
            let phi = std::f64::consts::TAU * rng.uniform_f64();
            b.dir = scatter(b.dir, mu as f32, phi as f32);
            b.direct = false;
            self.maybe_split(&mut b);
        }
    }
}

/// Light of weight `w` entering the water (or reflected down at the surface
/// from below) crosses the depth-0 tally going down.
fn cross_surface_down(scene: &Scene, tally: &mut PhotonTally, dir: Vec3, w: f64) {
    if scene.tally_depths.first() == Some(&0.0) {
        tally.add(0, ED, w);
        tally.add(0, EOD, w / (dir.z as f64).abs().max(MIN_ABS_MU));
        if in_lu_cone(-dir.z as f64) {
            tally.add(0, LD, w);
        }
    }
}

/// Tally the segment from `a` to `b` along `dir`, of weight `w`, at the
/// depths strictly below the surface: its crossing of each depth (E_d,
/// E_u and the radiance cones), and its track length within
/// [`EO_HALF_WIDTH_M`] of each depth (scalar irradiance).
///
/// Scalar irradiance is the track length per unit volume (photon power per
/// area times path length over the layer's thickness): a segment that
/// crosses the layer scores 1 / |mu| as a crossing estimate would, but a
/// grazing one scores its length in the layer over the thickness, bounded
/// by its free path, where the crossing estimate's 1 / |mu| has no useful
/// bound (its variance diverges logarithmically and a rare grazing photon
/// made the standard error itself unreliable).
fn tally_segment(depths: &[f64], tally: &mut PhotonTally, a: Vec3, b: Vec3, dir: Vec3, w: f64) {
    let (za, zb) = (a.z as f64, b.z as f64);
    let (lo, hi) = (za.min(zb), za.max(zb));
    for (i, &depth) in depths.iter().enumerate() {
        if depth == 0.0 {
            continue;
        }
        let z = -depth;
        if lo - EO_HALF_WIDTH_M >= z || hi + EO_HALF_WIDTH_M <= z {
            continue;
        }
        let zf = z as f32;
        if a.z > zf && b.z <= zf {
            tally.add(i, ED, w);
            if in_lu_cone(-dir.z as f64) {
                tally.add(i, LD, w);
            }
        } else if a.z < zf && b.z >= zf {
            tally.add(i, EU, w);
            if in_lu_cone(dir.z as f64) {
                tally.add(i, LU, w);
            }
        }
        let inside = hi.min(z + EO_HALF_WIDTH_M) - lo.max(z - EO_HALF_WIDTH_M);
        if inside > 0.0 {
            let length = (b - a).length() as f64;
            let track = if hi > lo {
                length * (inside / (hi - lo)).min(1.0)
            } else {
                length
            };
            let q = if dir.z > 0.0 { EOU } else { EOD };
            tally.add(i, q, w * track / (2.0 * EO_HALF_WIDTH_M));
        }
    }
}

/// What an inelastic event made of a photon.
enum Shift {
    /// Nothing emitted (fluorescence excited outside its range, or
    /// emitted at or below the excitation wavelength): absorbed.
    Absorbed,
    /// Emitted beyond the grid.
    Out,
    /// Emitted into this band with this weight (relative to a photon of
    /// that band).
    To(usize, f64),
}

/// An inelastic event of `process` for the photon on branch `b`. The
/// excitation wavelength is drawn uniformly in the band's cell and the
/// emission from the process's spectrum (`optics::inelastic::spectra`),
/// with the photon count it carries over the band's nominal yield; the
/// energy scales by λ'/λ, so the spectral power in band m is P_e w n
/// (λ'/λ) (Δ_e / Δ_m): in expectation the `Process::transfer` the
/// renderers read.
fn shift(
    inelastic: &Inelastic,
    process: &Process,
    photon_power: &[f64],
    b: &Branch,
    rng: &mut Pcg32,
) -> Shift {
    let cells = &inelastic.cells;
    let (lo, hi) = cells[b.band];
    let nm = lo + (hi - lo) * rng.uniform_f64();
    let Some((em, count)) = process.kind.sample(nm, rng) else {
        return Shift::Absorbed;
    };
    let m = cells.partition_point(|c| c.1 <= em);
    if m >= cells.len() || em < cells[m].0 {
        return Shift::Out;
    }
    let width = |i: usize| cells[i].1 - cells[i].0;
    let spectral = b.weight * count / process.nominal[b.band] * nm / em * width(b.band) / width(m);
    Shift::To(m, spectral * photon_power[b.band] / photon_power[m])
}
