use super::*;
use crate::scene::Overrides;

#[test]
fn render_shares_add_up_and_grow_with_the_scene() {
    let scene = Scene::coastal(&Overrides::default()).unwrap();
    let b = MemoryBudget::new(512 * MIB);
    let s = b.render(&scene, 2).unwrap();
    assert_eq!(
        s.reserve_bytes + s.boundary_grid_bytes + s.tile_cache_bytes,
        512 * MIB
    );
    assert!(s.reserve_bytes > RUNTIME_RESERVE);
    // 256 x 256 pixels: 1.5 MiB of image buffers; 128 bands: 4 MiB of EXR tile.
    assert!(s.reserve_bytes >= RUNTIME_RESERVE + 1_572_864 + 4 * MIB);
    assert!(s.reserve_bytes < 32 * MIB, "{s:?}");
    let more = MemoryBudget::render_reserve(&scene, 8);
    assert!(more > s.reserve_bytes);
}

#[test]
fn a_budget_without_room_for_a_cache_is_refused() {
    let scene = Scene::coastal(&Overrides::default()).unwrap();
    let e = MemoryBudget::new(4 * MIB).render(&scene, 1).unwrap_err();
    assert!(matches!(e, Error::Budget { .. }), "{e}");
    assert!(e.to_string().contains("tile cache"), "{e}");
}
