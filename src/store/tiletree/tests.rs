use super::*;
use crate::morton::{demorton3, morton3};
use crate::rng::Pcg32;
use crate::store::codec::BoxQuantizer;
use glam::Vec3;

/// Photons on a 16-bit grid in the unit cube, a third of them on one
/// plane and some exact duplicates, sorted by Morton code as a tile is.
const UNIT: Aabb = Aabb {
    min: Vec3::ZERO,
    max: Vec3::ONE,
};

/// Photons and their codes, as a tile decodes them.
fn tile(n: usize, seed: u64) -> (Vec<u64>, Vec<PackedPhoton>) {
    let mut rng = Pcg32::new(seed, 1);
    let q = BoxQuantizer::new(&UNIT);
    let mut v: Vec<(u64, PackedPhoton)> = Vec::with_capacity(n);
    for i in 0..n {
        let p = if i % 17 == 5 && i > 0 {
            v[i / 2].1.position
        } else {
            let z = if rng.uniform_f32() < 0.3 {
                0.25
            } else {
                rng.uniform_f32()
            };
            [rng.uniform_f32(), rng.uniform_f32(), z]
        };
        let code = morton3(q.encode(p));
        let position = q.decode(demorton3(code)).to_array();
        v.push((
            code,
            PackedPhoton {
                position,
                power: i as f32,
                ..Default::default()
            },
        ));
    }
    v.sort_by_key(|x| x.0);
    v.into_iter().unzip()
}

fn cells(codes: &[u64]) -> Vec<[u16; 3]> {
    codes.iter().map(|&c| demorton3(c)).collect()
}

fn brute(photons: &[PackedPhoton], q: &[f32; 3]) -> Vec<f32> {
    let mut d: Vec<f32> = photons
        .iter()
        .map(|p| point_distance_sq(&p.position, q))
        .collect();
    d.sort_by(f32::total_cmp);
    d
}

#[test]
fn nearest_equals_brute_force() {
    for (n, seed) in [(1, 1), (LEAF, 2), (LEAF + 1, 3), (1000, 4), (20_000, 5)] {
        let (codes, photons) = tile(n, seed);
        let tree = TileTree::from_morton(&codes, &cells(&codes), &UNIT);
        let mut rng = Pcg32::new(seed, 9);
        let mut nearest = Nearest::default();
        for _ in 0..200 {
            let q = [
                rng.uniform_f32() * 1.4 - 0.2,
                rng.uniform_f32() * 1.4 - 0.2,
                rng.uniform_f32() * 1.4 - 0.2,
            ];
            let all = brute(&photons, &q);
            for (k, limit) in [(1, f32::INFINITY), (50, f32::INFINITY), (200, 0.01)] {
                nearest.reset(k, limit);
                tree.nearest(&photons, &q, &mut nearest);
                let got: Vec<f32> = nearest.results(true).map(|x| x.0).collect();
                let want: Vec<f32> = all
                    .iter()
                    .copied()
                    .filter(|&d| d <= limit)
                    .take(k)
                    .collect();
                assert_eq!(got, want, "n {n} k {k} limit {limit} at {q:?}");
                // Each photon is taken once.
                let mut ids: Vec<u32> = nearest.results(false).map(|x| x.1.power as u32).collect();
                ids.sort_unstable();
                ids.dedup();
                assert_eq!(ids.len(), got.len());
            }
            let r_sq = 0.02;
            let mut out = Vec::new();
            tree.within(&photons, &q, r_sq, &mut out);
            let mut got: Vec<f32> = out.iter().map(|x| x.0).collect();
            got.sort_by(f32::total_cmp);
            let want: Vec<f32> = all.iter().copied().filter(|&d| d <= r_sq).collect();
            assert_eq!(got, want, "radius, n {n} at {q:?}");
        }
    }
}

#[test]
fn leaves_cover_each_photon_once_and_planes_separate_the_sides() {
    let (codes, photons) = tile(5000, 7);
    let tree = TileTree::from_morton(&codes, &cells(&codes), &UNIT);
    let mut seen = vec![0u8; photons.len()];
    /// The items under node `i`, checking each plane against them.
    fn walk(
        t: &TileTree,
        i: usize,
        photons: &[PackedPhoton],
        seen: &mut [u8],
    ) -> (usize, Vec<usize>) {
        let n = t.nodes[i];
        if n.count > 0 {
            assert!(n.count as usize <= LEAF);
            let items: Vec<usize> = (n.link as usize..(n.link + n.count as u32) as usize).collect();
            for &j in &items {
                seen[j] += 1;
                let (lo, count) = (n.link as usize, n.count as usize);
                assert_eq!(t.position(lo, count, j), photons[j].position);
            }
            return (1, items);
        }
        let (cl, left) = walk(t, i + 1, photons, seen);
        let (cr, right) = walk(t, n.link as usize, photons, seen);
        let a = n.axis as usize;
        assert!(left.iter().all(|&j| photons[j].position[a] <= n.split));
        assert!(right.iter().all(|&j| photons[j].position[a] >= n.split));
        (1 + cl + cr, left.into_iter().chain(right).collect())
    }
    let (count, _) = walk(&tree, 0, &photons, &mut seen);
    assert_eq!(count, tree.len(), "every node is reachable once");
    assert!(seen.iter().all(|&s| s == 1));
}
