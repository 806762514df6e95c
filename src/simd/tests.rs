/// The transpose against the byte-by-byte definition.
#[test]
fn transpose16_is_the_transpose() {
    let data: Vec<[u8; 16]> = (0..16u8)
        .map(|k| std::array::from_fn(|j| k.wrapping_mul(31) ^ (j as u8).wrapping_mul(7)))
        .collect();
    let rows: [&[u8; 16]; 16] = std::array::from_fn(|k| &data[k]);
    let mut out = [[0u8; 16]; 16];
    super::transpose16(rows, &mut out);
    for j in 0..16 {
        for k in 0..16 {
            assert_eq!(out[j][k], data[k][j], "({j}, {k})");
        }
    }
}
