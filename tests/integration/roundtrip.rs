//! Round trip: every generated photon comes back from `littoral map dump`
//! within the documented quantisation error, and nothing else does.

use crate::common::*;
use glam::Vec3;
use littoral::photon::{oct_encode, OCT_MAX_ANGLE_ERROR_RAD};
use littoral::store::MapFile;
use littoral::synth::Distribution;

#[test]
fn dump_returns_every_photon_within_quantisation_error() {
    let dir = tempdir();
    for (d, name) in [
        (Distribution::Uniform, "u.map"),
        (Distribution::Water, "w.map"),
    ] {
        let n = 20_000u64;
        let src = source(n, 64, 5, d);
        let (path, _) = synth_map(dir.path(), name, &src, Some(1500), 2, 64 * MIB);
        let out = littoral(&["map", "dump", p(&path)]);
        assert!(out.status.success());
        let text = String::from_utf8(out.stdout).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("x,y,z,dx,dy,dz,band,power"));
        let dumped: Vec<(Vec3, Vec3, u16, f32)> = lines
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                assert_eq!(f.len(), 8, "{l}");
                let v = |i: usize| f[i].parse::<f32>().unwrap();
                (
                    Vec3::new(v(0), v(1), v(2)),
                    Vec3::new(v(3), v(4), v(5)),
                    f[6].parse().unwrap(),
                    v(7),
                )
            })
            .collect();
        assert_eq!(dumped.len() as u64, n);

        // The largest quantum of any tile bounds the position error.
        let map = MapFile::open(&path).unwrap();
        let step = map
            .tiles()
            .iter()
            .map(|t| (t.quant.max - t.quant.min) / 65535.0)
            .fold(Vec3::ZERO, Vec3::max);
        let tol = step * 0.5 + Vec3::splat(2e-5);

        let points: Vec<[f32; 3]> = dumped.iter().map(|d| d.0.to_array()).collect();
        let tree: kiddo::ImmutableKdTree<f32, 3> =
            kiddo::ImmutableKdTree::new_from_slice(&points).unwrap();
        let mut used = vec![false; dumped.len()];
        for i in 0..n {
            let p = src.photon(i);
            let near = tree
                .query(&p.position.to_array())
                .nearest_n::<kiddo::SquaredEuclidean<f32>>(std::num::NonZeroUsize::new(4).unwrap())
                .execute();
            // The match is the nearest unused dumped photon with the same band and power.
            let hit = near
                .iter()
                .map(|r| r.item as usize)
                .find(|&j| !used[j] && dumped[j].2 == p.band && dumped[j].3 == p.power)
                .unwrap_or_else(|| panic!("photon {i} not found in the dump"));
            used[hit] = true;
            let (pos, dir, _, _) = dumped[hit];
            let err = (pos - p.position).abs();
            assert!(
                err.cmple(tol).all(),
                "photon {i}: position error {err} > {tol}"
            );
            let angle = p.direction.cross(dir).length().asin();
            assert!(
                angle <= OCT_MAX_ANGLE_ERROR_RAD + 1e-6
                    || oct_encode(dir) == oct_encode(p.direction),
                "photon {i}: direction error {angle} rad"
            );
        }
        assert!(used.iter().all(|&u| u));
    }
}
