//! Upward splitting in emission (`emit::trace`) and the volume layers by
//! direction: splitting changes how the light is sampled, never what it
//! is. The tallies of a split emission agree with an analog one within
//! their standard errors, every unit of emitted power still ends in exactly
//! one fate, and the map keeps photons travelling up apart from the rest,
//! the copies of a split path carrying their share of its power.

use crate::common::{all_photons, minimal, tempdir};
use littoral::emit::tally::{Totals, EOU, EU, LU};
use littoral::emit::trace::FATE_UNIT;
use littoral::emit::Emitter;
use littoral::job::{EmitJob, MemoryBudget};
use littoral::photon::{LAYER_SURFACE, LAYER_VOLUME, LAYER_VOLUME_UP, OCT_MAX_ANGLE_ERROR_RAD};
use littoral::progress::Silent;
use littoral::scene::{Overrides, Scene};
use littoral::store::MapFile;
use std::path::Path;

/// Deep water with a forward-peaked phase function (upwelling light is a
/// few per cent of the downwelling), or the same over a grey floor.
fn deep(split: u32, photons: u64, floor: bool) -> Scene {
    let mut text = minimal().merge(&format!(
        r#"
seed = 11
spectral = {{ start_nm = 500.0, end_nm = 500.0, bands = 1 }}
water = {{ iop = {{ a = 0.1, b = 0.4 }}, phase = {{ kind = "fournier-forand", bb_ratio = 0.0183 }} }}
photons = {{ count = {photons}, upward_split = {split} }}
tally = {{ depths_m = [0.0, 1.0, 3.0] }}
"#
    ));
    if floor {
        text = text.and_then(|t| t.merge("bottom = { depth_m = 4.0, reflectance = 0.3 }"));
    }
    let text = text.unwrap().text();
    Scene::parse(&text, Path::new("split.toml"), &Overrides::default())
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn run(s: &Scene) -> Totals {
    Emitter::new(s).unwrap().trace_all(0).unwrap()
}

/// The upwelling tallies (Eu, Eou and the Lu cone at every depth) of an
/// emission splitting 16 ways agree with an analog emission's within four
/// combined standard errors (the runs share a seed, which only makes them
/// closer). The split run's standard error of Lu just below the surface
/// is the smaller one: the copies sample the rare upward light more often.
#[test]
fn upward_splitting_leaves_the_tallies_unbiased() {
    let analog = run(&deep(1, 200_000, false));
    let split = run(&deep(16, 200_000, false));
    for d in 0..3 {
        for q in [EU, EOU, LU] {
            let (m1, s1) = analog.mean_and_stderr(analog.slot(d, q), 0);
            let (m2, s2) = split.mean_and_stderr(split.slot(d, q), 0);
            let z = (m2 - m1) / (s1 * s1 + s2 * s2).sqrt();
            assert!(
                z.abs() < 4.0,
                "depth {d} quantity {q}: {m1} vs {m2} ({z} sigma)"
            );
        }
    }
    let (_, se_analog) = analog.mean_and_stderr(analog.slot(0, LU), 0);
    let (_, se_split) = split.mean_and_stderr(split.slot(0, LU), 0);
    eprintln!("Lu(0-) standard error: analog {se_analog}, split {se_split}");
    assert!(se_split < se_analog, "{se_split} vs {se_analog}");
}

/// Split paths end in several fates with fractional weights, counted in
/// units of 1 / FATE_UNIT: per band they add up to exactly the photons
/// emitted, over a floor that reflects upward (and so splits) too.
#[test]
fn split_paths_end_in_exactly_one_fate_in_all() {
    let t = run(&deep(16, 20_000, true));
    let ended = t.escaped[0] + t.absorbed_water[0] + t.absorbed_surfaces[0] + t.lost_edges[0];
    assert_eq!(ended, t.emitted[0] * FATE_UNIT);
    assert!(
        !t.escaped[0].is_multiple_of(FATE_UNIT),
        "no path split: {t:?}"
    );
}

/// Emitted into a map, volume photons travelling up are in their own
/// layer and the rest in the other; a split path's copies carry 1 / split
/// of the photon power each, and surface photons stay in theirs.
#[test]
fn volume_photons_are_layered_by_direction_and_copies_carry_their_share() {
    let dir = tempdir();
    let scene = deep(4, 20_000, true);
    let path = dir.path().join("split.map");
    EmitJob {
        scene: &scene,
        map: path.clone(),
        report: None,
        threads: 2,
        budget: MemoryBudget::new(64 << 20),
        scene_seconds: 0.0,
    }
    .run(&Silent)
    .unwrap();
    let power = Emitter::new(&scene).unwrap().photon_power(0) as f32;
    let map = MapFile::open(&path).unwrap();
    let mut counts = [0usize; 3];
    let mut shares = [0usize; 2];
    for (t, entry) in map.tiles().iter().enumerate() {
        for p in tile_photons(&map, t as u32) {
            let layer = entry.layer as u16;
            counts[layer as usize] += 1;
            match layer {
                // Layered by the direction before quantisation.
                LAYER_VOLUME_UP => assert!(p.direction.z > -OCT_MAX_ANGLE_ERROR_RAD, "{p:?}"),
                LAYER_VOLUME => assert!(p.direction.z <= OCT_MAX_ANGLE_ERROR_RAD, "{p:?}"),
                _ => assert_eq!(layer, LAYER_SURFACE),
            }
            if p.power == power {
                shares[0] += 1;
            } else {
                assert_eq!(p.power, power / 4.0, "{p:?}");
                shares[1] += 1;
            }
        }
    }
    assert!(counts.iter().all(|&c| c > 0), "{counts:?}");
    assert!(shares[1] > 0, "no split copies: {shares:?}");
    assert_eq!(counts.iter().sum::<usize>(), all_photons(&map).len());
}

/// The photons of tile `t`.
fn tile_photons(map: &MapFile, t: u32) -> Vec<littoral::photon::Photon> {
    let mut dec = littoral::store::codec::TileDecoder::default();
    let mut tile = Vec::new();
    map.decode_tile(t, &mut dec, &mut tile).unwrap();
    tile.iter().map(|p| p.unpack()).collect()
}
