//! A warning for every target whose top face is smaller than the surface
//! search that would read it.
//!
//! With `[estimate] gather_rays = 0` a target's faces are read from the
//! surface photon map like the floor: the k nearest surface photons around
//! the hit. Where a face holds fewer than k, the search reaches past its
//! edges to the floor below and the faces beside, and the face's level
//! and colour come from them (a 1 m box read 18 % low in the band mean at
//! 400 k photons). Final gathering (the default) reads faces from the
//! volume map instead and needs no such warning. Not for the renderers
//! themselves: this only reads the map.

use crate::error::Result;
use crate::photon::LAYER_SURFACE;
use crate::scene::Scene;
use crate::store::query::{Neighbour, PhotonQuery, Search};
use glam::Vec3;

/// One message per target whose top face is narrower than the diameter of
/// the surface search at its centre (none while targets are gathered).
pub fn face_warnings(scene: &Scene, map: &dyn PhotonQuery) -> Result<Vec<String>> {
    let e = &scene.estimate;
    if e.gather_rays > 0 {
        return Ok(Vec::new());
    }
    let search = match e.radius_m {
        Some(r) => Search::Radius { radius: r as f32 },
        None => Search::Nearest {
            k: e.k,
            max_radius: Some(e.max_radius_m as f32),
        },
    };
    let mut found: Vec<Neighbour> = Vec::new();
    let mut out = Vec::new();
    for (i, b) in scene.target_extents.iter().enumerate() {
        let size = b.max - b.min;
        let side = size.x.min(size.y);
        let top = Vec3::new(
            0.5 * (b.min.x + b.max.x),
            0.5 * (b.min.y + b.max.y),
            b.max.z,
        );
        map.query_into(top, Some(LAYER_SURFACE), search, &mut found)?;
        let radius = match search {
            Search::Radius { radius } => radius,
            Search::Nearest { k, max_radius } => match found.last() {
                Some(n) if found.len() >= k => n.distance_sq.sqrt(),
                _ => max_radius.unwrap_or(f32::INFINITY),
            },
        };
        if 2.0 * radius > side {
            out.push(format!(
                "target {i}: its top face ({:.2} x {:.2} m) is narrower than the surface search \
                 that reads it ({} within {radius:.2} m of its centre), so its level and colour \
                 come partly from the surfaces around it; set [estimate] gather_rays > 0 (final \
                 gathering, the default) or trace more photons",
                size.x,
                size.y,
                match search {
                    Search::Radius { .. } => format!("{} surface photons", found.len()),
                    Search::Nearest { k, .. } => format!("the {k} nearest surface photons"),
                },
            ));
        }
    }
    Ok(out)
}
