use super::*;
use crate::rng::Pcg32;

#[test]
fn box_index_visits_boxes_nearest_first_and_finds_every_box_in_range() {
    let mut rng = Pcg32::new(3, 3);
    let boxes: Vec<Aabb> = (0..500)
        .map(|_| {
            let c = Vec3::new(rng.uniform_f32(), rng.uniform_f32(), rng.uniform_f32()) * 10.0;
            let h = Vec3::new(rng.uniform_f32(), rng.uniform_f32(), rng.uniform_f32());
            Aabb {
                min: c - h,
                max: c + h,
            }
        })
        .collect();
    let tree = BoxTree::over_boxes(&boxes);
    let mut heap = Vec::new();
    for _ in 0..100 {
        let q = Vec3::new(rng.uniform_f32(), rng.uniform_f32(), rng.uniform_f32()) * 12.0;
        let r_sq = 4.0;
        let mut got = Vec::new();
        tree.nearest_leaves::<()>(&q.to_array(), r_sq, &mut heap, |d, i| {
            got.push((d, i));
            Ok(r_sq)
        })
        .unwrap();
        assert!(got.windows(2).all(|w| w[0].0 <= w[1].0), "nearest first");
        let mut ids: Vec<u32> = got.iter().map(|x| x.1).collect();
        ids.sort_unstable();
        let want: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| boxes[i as usize].distance_sq(q) <= r_sq)
            .collect();
        assert_eq!(ids, want);
    }
}
