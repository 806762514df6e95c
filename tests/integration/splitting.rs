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

/// Each of `quantities` at each of the three tally depths agrees between
/// two emissions within four combined standard errors.
fn assert_tallies_agree(a: &Totals, b: &Totals, quantities: &[usize]) {
    for d in 0..3 {
        for &q in quantities {
            let (m1, s1) = a.mean_and_stderr(a.slot(d, q), 0);
            let (m2, s2) = b.mean_and_stderr(b.slot(d, q), 0);
            let z = (m2 - m1) / (s1 * s1 + s2 * s2).sqrt();
            assert!(
                z.abs() < 4.0,
                "depth {d} quantity {q}: {m1} vs {m2} ({z} sigma)"
            );
        }
    }
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
    assert_tallies_agree(&analog, &split, &[EU, EOU, LU]);
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
    emit_map(&scene, &path);
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

/// Emit `scene` into a photon map at `path` on two threads.
fn emit_map(scene: &Scene, path: &Path) {
    EmitJob {
        scene,
        map: path.to_path_buf(),
        report: None,
        threads: 2,
        budget: MemoryBudget::new(64 << 20),
        scene_seconds: 0.0,
    }
    .run(&Silent)
    .unwrap();
}

/// The photons of tile `t`.
fn tile_photons(map: &MapFile, t: u32) -> Vec<littoral::photon::Photon> {
    let mut dec = littoral::store::codec::TileDecoder::default();
    let mut tile = Vec::new();
    map.decode_tile(t, &mut dec, &mut tile).unwrap();
    tile.iter().map(|p| p.unpack()).collect()
}

/// Deep water 20 m across with a 2 m box whose top is 1 m down, its paths
/// entering over the box splitting `split` ways.
fn over_box(split: u32, photons: u64) -> Scene {
    let text = minimal()
        .merge(&format!(
            r#"
seed = 5
spectral = {{ start_nm = 500.0, end_nm = 500.0, bands = 1 }}
domain = {{ size_m = [20.0, 20.0] }}
water = {{ iop = {{ a = 0.1, b = 0.4 }}, phase = {{ kind = "fournier-forand", bb_ratio = 0.0183 }} }}
bottom = {{ depth_m = 6.0, reflectance = 0.3 }}
target = [{{ kind = "box", center_m = [10.0, 10.0, -1.5], size_m = [2.0, 2.0, 1.0], reflectance = 0.5 }}]
photons = {{ count = {photons}, target_split = {split} }}
tally = {{ depths_m = [0.0, 0.5, 3.0] }}
"#
        ))
        .unwrap()
        .text();
    Scene::parse(&text, Path::new("over_box.toml"), &Overrides::default())
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Splitting over a target changes where the photons are, not the light:
/// the domain's tallies (E_d, E_u, E_ou and the Lu cone at three depths)
/// of an emission splitting 16 ways over a box agree with an unsplit one
/// within four combined standard errors, and every path's copies still end
/// in exactly one fate in all. The footprint over the box (its 2 m widened
/// by 1 m of depth and 1 m on each side: 6 m of the 20) takes 9 % of the
/// entering paths.
#[test]
fn target_splitting_leaves_the_tallies_unbiased() {
    use littoral::emit::tally::ED;
    let analog = run(&over_box(1, 100_000));
    let split = run(&over_box(16, 100_000));
    assert_tallies_agree(&analog, &split, &[ED, EU, EOU, LU]);
    let ended = split.escaped[0] + split.absorbed_water[0] + split.absorbed_surfaces[0];
    assert_eq!(ended + split.lost_edges[0], split.emitted[0] * FATE_UNIT);
}

/// Around the box the map is many times denser than the same column far
/// from it when paths split there, and no denser without splitting; the
/// copies carry 1 / 16 of the photon power.
#[test]
fn target_splitting_makes_the_map_dense_over_the_target() {
    let ratio = |split: u32| -> (f64, Vec<f32>) {
        let dir = tempdir();
        let scene = over_box(split, 40_000);
        let path = dir.path().join("box.map");
        emit_map(&scene, &path);
        let map = MapFile::open(&path).unwrap();
        let in_column = |p: &littoral::photon::Photon, cx: f32, cy: f32| {
            (p.position.x - cx).abs() < 1.0
                && (p.position.y - cy).abs() < 1.0
                && p.position.z > -1.0
        };
        let (mut over, mut far) = (0usize, 0usize);
        let mut powers = Vec::new();
        for p in all_photons(&map) {
            if in_column(&p, 10.0, 10.0) {
                over += 1;
                powers.push(p.power);
            } else if in_column(&p, 2.0, 2.0) {
                far += 1;
            }
        }
        assert!(far > 20, "too few photons far from the box: {far}");
        (over as f64 / far as f64, powers)
    };
    let (analog, _) = ratio(1);
    let (split, powers) = ratio(16);
    eprintln!("photons over the box / far from it: analog {analog:.2}, split {split:.2}");
    assert!(analog < 2.0, "{analog}");
    assert!(split > 6.0 * analog, "{split} vs {analog}");
    let power = Emitter::new(&over_box(16, 40_000)).unwrap().photon_power(0) as f32;
    assert!(
        powers.iter().any(|&p| p == power / 16.0),
        "no copy over the box"
    );
}

/// The footprint test wraps across periodic edges and not across open ones;
/// `target_split` must be a power of two from 1 to 64, named when not.
#[test]
fn target_split_footprints_wrap_and_bad_counts_are_refused() {
    use littoral::scene::{Domain, Footprint};
    let f = Footprint {
        min: [-2.0, 4.0],
        max: [3.0, 6.0],
    };
    let periodic = Domain {
        size_m: [20.0, 20.0],
        periodic: true,
    };
    let open = Domain {
        periodic: false,
        ..periodic
    };
    assert!(f.contains(&periodic, 19.0, 5.0));
    assert!(!f.contains(&open, 19.0, 5.0));
    assert!(f.contains(&open, 1.0, 5.0));
    assert!(!f.contains(&periodic, 1.0, 7.0));
    assert!(!f.contains(&periodic, 10.0, 5.0));
    for bad in [3, 0, 128] {
        let text = minimal()
            .merge(&format!(
                "photons = {{ count = 1000, target_split = {bad} }}"
            ))
            .unwrap()
            .text();
        let e = Scene::parse(&text, Path::new("bad.toml"), &Overrides::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("photons.target_split"), "{e}");
    }
}
