//! Morton (Z-order) codes: the order photons take inside a tile, queries
//! take through a batch, and the renderer takes through its image tiles, so
//! that neighbours in the order are neighbours in space.

/// Spread the bits of `v` to every third bit (21-bit to 63-bit Morton spread).
#[inline]
fn part1by2(v: u16) -> u64 {
    let mut x = v as u64;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Inverse of [`part1by2`].
#[inline]
fn compact1by2(mut x: u64) -> u16 {
    x &= 0x1249_2492_4924_9249;
    x = (x ^ (x >> 2)) & 0x10c3_0c30_c30c_30c3;
    x = (x ^ (x >> 4)) & 0x100f_00f0_0f00_f00f;
    x = (x ^ (x >> 8)) & 0x001f_0000_ff00_00ff;
    x = (x ^ (x >> 16)) & 0x001f_0000_0000_ffff;
    x = (x ^ (x >> 32)) & 0x001f_ffff;
    x as u16
}

/// 48-bit Morton code of a quantised position (x in the lowest bit).
#[inline]
pub fn morton3(q: [u16; 3]) -> u64 {
    part1by2(q[0]) | (part1by2(q[1]) << 1) | (part1by2(q[2]) << 2)
}

/// Inverse of [`morton3`].
#[inline]
pub fn demorton3(m: u64) -> [u16; 3] {
    [compact1by2(m), compact1by2(m >> 1), compact1by2(m >> 2)]
}

#[cfg(test)]
mod tests;
