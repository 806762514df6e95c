//! Tracing one photon from the sky or the sun through the sea surface,
//! the water, the floor and the targets.
//!
//! Free paths use delta tracking against the band's majorant extinction, so
//! heterogeneous water is sampled without bias: a tentative collision is
//! real with probability c(x)/c_max, then absorption (a/c), pure-water
//! scattering (b_w/c) or particle scattering (b_p/c) is chosen; otherwise it
//! is a null collision and the flight goes on. Absorption is analog (the
//! photon ends) so every photon of one band carries the same power. The
//! floor and targets are Lambertian: a photon is absorbed with probability
//! 1 - R, else reflected into a cosine-weighted direction.
//!
//! Stored photons: a volume photon at every real scattering event, a
//! surface photon at every floor or target hit, each with the direction it
//! arrived in — except that light still on its unscattered path from the sun
//! (transmitted once through the surface) is not stored unless the scene
//! asks for it, since the renderer adds that single scattering directly.

use super::tally::{in_lu_cone, Fate, PhotonTally, ED, EOD, EOU, EU, LD, LU, MIN_ABS_MU};
use crate::optics::phase::{cosine_hemisphere, scatter};
use crate::photon::{Photon, LAYER_SURFACE, LAYER_VOLUME};
use crate::rng::Pcg32;
use crate::scene::Scene;
use crate::store::StagedPhoton;
use glam::Vec3;

/// Events per photon path before it is stopped (ids keep 20 bits for them).
pub const MAX_EVENTS: u32 = (1 << 20) - 1;

/// Where a photon starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    Sun,
    Sky,
}

/// The outcome of one traced photon.
pub struct Traced {
    pub fate: Fate,
    pub truncated: bool,
    pub stored_volume: u32,
    pub stored_surface: u32,
}

/// Trace photon `index` of band `band` from `source`; stored photons go to
/// `out`, tallies to `tally`.
#[allow(clippy::too_many_arguments)]
pub fn trace(
    scene: &Scene,
    index: u64,
    rng: &mut Pcg32,
    source: Source,
    band: usize,
    power: f32,
    tally: &mut PhotonTally,
    out: &mut Vec<StagedPhoton>,
) -> Traced {
    let d = &scene.domain;
    let (sx, sy) = (d.size_m[0], d.size_m[1]);
    let mut events: u32 = 0;
    let group = crate::photon::group_of_path(index);
    let mut result = Traced {
        fate: Fate::Escaped,
        truncated: false,
        stored_volume: 0,
        stored_surface: 0,
    };
    let store =
        |pos: Vec3, dir: Vec3, layer: u16, events: &mut u32, out: &mut Vec<StagedPhoton>| {
            *events += 1;
            out.push(StagedPhoton::new(
                &Photon {
                    position: pos,
                    direction: dir,
                    band: band as u16,
                    power,
                    group,
                },
                layer,
                (index << 20) | (*events as u64),
            ));
        };

    // Start on the surface, anywhere in the domain.
    let mut pos = Vec3::new(
        (rng.uniform_f64() * sx) as f32,
        (rng.uniform_f64() * sy) as f32,
        0.0,
    );
    let mut dir = match source {
        Source::Sun => scene.sun.direction,
        Source::Sky => cosine_hemisphere(-Vec3::Z, rng),
    };
    let mut direct = source == Source::Sun;
    tally.add_above_down();
    let ev = scene.surface.interact(dir, rng);
    if !ev.transmitted {
        tally.add_above_up();
        return result;
    }
    dir = ev.direction;
    cross_surface_down(scene, tally, dir);

    let depths = &scene.tally_depths;
    // The band is fixed for the whole path, and so is its majorant.
    let c_max = scene.water.majorant(band);
    loop {
        if events >= MAX_EVENTS {
            result.fate = Fate::AbsorbedWater;
            result.truncated = true;
            return result;
        }
        let t_flight = rng.exponential(c_max);
        let t_surface = crate::scene::Domain::surface_distance(pos, dir);
        let t_edge = scene.domain.edge_distance(pos, dir);
        let t_limit = t_flight.min(t_surface).min(t_edge);
        let hit = scene
            .geometry
            .intersect(pos, dir, t_limit.min(f32::MAX as f64) as f32);
        if let Some(h) = hit {
            let next = h.position;
            tally_segment(depths, tally, pos, next, dir);
            pos = next;
            if !direct || scene.store_direct {
                store(pos, dir, LAYER_SURFACE, &mut events, out);
                result.stored_surface += 1;
            } else {
                events += 1;
            }
            let r = scene.reflectance(h.surface, pos, band);
            if rng.uniform_f64() >= r {
                result.fate = Fate::AbsorbedSurface;
                return result;
            }
            dir = cosine_hemisphere(h.normal, rng);
            direct = false;
            continue;
        }
        if t_surface <= t_limit {
            let next = pos + dir * t_surface as f32;
            let next = Vec3::new(next.x, next.y, 0.0);
            tally_segment(depths, tally, pos, next, dir);
            pos = next;
            // Arriving at the surface from below: Eu just below the surface.
            if depths.first() == Some(&0.0) {
                tally.add(0, EU, 1.0);
                tally.add(0, EOU, 1.0 / (dir.z as f64).abs().max(MIN_ABS_MU));
                if in_lu_cone(dir.z as f64) {
                    tally.add(0, LU, 1.0);
                }
            }
            let ev = scene.surface.interact(dir, rng);
            events += 1;
            if ev.transmitted {
                tally.add_above_up();
                result.fate = Fate::Escaped;
                return result;
            }
            dir = ev.direction;
            direct = false;
            cross_surface_down(scene, tally, dir);
            continue;
        }
        if t_edge <= t_limit {
            let next = pos + dir * t_edge as f32;
            tally_segment(depths, tally, pos, next, dir);
            if !scene.domain.periodic {
                result.fate = Fate::LostEdge;
                return result;
            }
            pos = scene.domain.wrap(next, dir);
            continue;
        }
        // A tentative collision.
        let next = pos + dir * t_flight as f32;
        tally_segment(depths, tally, pos, next, dir);
        pos = next;
        let iop = scene.water.iop(pos, band);
        let xi = rng.uniform_f64() * c_max;
        if xi < iop.a {
            result.fate = Fate::AbsorbedWater;
            return result;
        }
        if xi >= iop.c() {
            continue; // null collision
        }
        let phase = if xi < iop.a + iop.b_w {
            &scene.water_phase
        } else {
            &scene.particle_phase
        };
        if !direct || scene.store_direct {
            store(pos, dir, LAYER_VOLUME, &mut events, out);
            result.stored_volume += 1;
        } else {
            events += 1;
        }
        let mu = phase.sample_cos(rng.uniform_f64());
        let phi = std::f64::consts::TAU * rng.uniform_f64();
        dir = scatter(dir, mu as f32, phi as f32);
        direct = false;
    }
}

/// Light entering the water (or reflected down at the surface from below)
/// crosses the depth-0 tally going down.
fn cross_surface_down(scene: &Scene, tally: &mut PhotonTally, dir: Vec3) {
    if scene.tally_depths.first() == Some(&0.0) {
        tally.add(0, ED, 1.0);
        tally.add(0, EOD, 1.0 / (dir.z as f64).abs().max(MIN_ABS_MU));
        if in_lu_cone(-dir.z as f64) {
            tally.add(0, LD, 1.0);
        }
    }
}

/// Tally crossings of the depths strictly below the surface by the segment
/// from `a` to `b` along `dir`.
fn tally_segment(depths: &[f64], tally: &mut PhotonTally, a: Vec3, b: Vec3, dir: Vec3) {
    let inv_mu = 1.0 / (dir.z as f64).abs().max(MIN_ABS_MU);
    for (i, &depth) in depths.iter().enumerate() {
        if depth == 0.0 {
            continue;
        }
        let z = -depth as f32;
        if a.z > z && b.z <= z {
            tally.add(i, ED, 1.0);
            tally.add(i, EOD, inv_mu);
            if in_lu_cone(-dir.z as f64) {
                tally.add(i, LD, 1.0);
            }
        } else if a.z < z && b.z >= z {
            tally.add(i, EU, 1.0);
            tally.add(i, EOU, inv_mu);
            if in_lu_cone(dir.z as f64) {
                tally.add(i, LU, 1.0);
            }
        }
    }
}
