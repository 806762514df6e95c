use super::*;

/// A plan aimed at tiles smaller than the default sizes its chunks for
/// the cells it will have: 8 chunks of every cell fit in the buffers.
/// (Chunks sized for the default tile's 31 cells, 4096 records each,
/// took 768 MB for 7 813 cells of 256 photons against a buffer share of
/// about 170 MB, and the writer spilled frames of one or two photons.)
#[test]
fn chunks_are_sized_for_the_cells_of_the_tile_size() {
    let photons = 2_000_000;
    let plan = WriterPlan::new(256 * MIB, photons).unwrap();
    assert_eq!(plan.chunk_records, 4096);
    let fine = plan.with_tile_photons(256);
    let cells = fine.cells_for(photons) as u64;
    assert_eq!(cells, 7813);
    assert!(fine.chunk_records > 32);
    assert!(8 * cells * (fine.chunk_records * STAGED) as u64 <= fine.buffer_bytes);
    assert!(8 * cells * ((fine.chunk_records + 1) * STAGED) as u64 > fine.buffer_bytes);
    // The cells' bookkeeping came out of the buffers, the same either way.
    let whole = |p: &WriterPlan| p.buffer_bytes + p.cells_for(photons) as u64 * CELL_BYTES;
    assert_eq!(whole(&plan), whole(&fine));
    assert_eq!(plan.buffer_bytes + 31 * CELL_BYTES, whole(&plan));
}

/// Cells' bookkeeping takes at most half the buffers: at the smallest
/// budget, 10^9 photons in tiles of 256 would be 3.9 M cells (2 GB of
/// bookkeeping against a 14 MiB budget); the partition is coarser
/// instead, and the budget's shares still add up to it.
#[test]
fn cells_are_as_many_as_the_buffers_can_keep() {
    let photons = 1_000_000_000;
    for plan in [
        WriterPlan::new(MIN_WRITER_BUDGET, photons).unwrap(),
        WriterPlan::new(MIN_WRITER_BUDGET, photons)
            .unwrap()
            .with_tile_photons(256),
        WriterPlan::new(256 * MIB, photons)
            .unwrap()
            .with_tile_photons(1),
    ] {
        let cells = plan.cells_for(photons) as u64;
        assert_eq!(cells, plan.max_cells, "{plan:?}");
        assert!(cells * CELL_BYTES <= plan.buffer_bytes, "{plan:?}");
        let merge = (plan.budget - WRITER_FIXED_BYTES) / 4;
        assert_eq!(
            WRITER_FIXED_BYTES
                + merge
                + plan.fetch_reserve
                + plan.buffer_bytes
                + cells * CELL_BYTES,
            plan.budget
        );
    }
    // At the default tile and 256 MiB, 10^9 photons keep one cell a tile.
    let plan = WriterPlan::new(256 * MIB, photons).unwrap();
    assert_eq!(plan.cells_for(photons) as u64, photons.div_ceil(65_536));
}
