//! Morton (Z-order) codes: the order photons take inside a tile, queries
//! take through a batch, and the renderer takes through its image tiles, so
//! that neighbours in the order are neighbours in space.

/// Spread the low 21 bits of `v` to every third bit (21-bit to 63-bit
/// Morton spread).
#[inline]
fn part1by2(v: u32) -> u64 {
    let mut x = (v & 0x1f_ffff) as u64;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Inverse of [`part1by2`].
#[inline]
fn compact1by2(mut x: u64) -> u32 {
    x &= 0x1249_2492_4924_9249;
    x = (x ^ (x >> 2)) & 0x10c3_0c30_c30c_30c3;
    x = (x ^ (x >> 4)) & 0x100f_00f0_0f00_f00f;
    x = (x ^ (x >> 8)) & 0x001f_0000_ff00_00ff;
    x = (x ^ (x >> 16)) & 0x001f_0000_0000_ffff;
    x = (x ^ (x >> 32)) & 0x001f_ffff;
    x as u32
}

/// 48-bit Morton code of a quantised position (x in the lowest bit).
#[inline]
pub fn morton3(q: [u16; 3]) -> u64 {
    part1by2(q[0] as u32) | (part1by2(q[1] as u32) << 1) | (part1by2(q[2] as u32) << 2)
}

/// Inverse of [`morton3`].
#[inline]
pub fn demorton3(m: u64) -> [u16; 3] {
    [
        compact1by2(m) as u16,
        compact1by2(m >> 1) as u16,
        compact1by2(m >> 2) as u16,
    ]
}

/// Bits per axis of [`morton3_wide`].
pub const WIDE_BITS: u32 = 42;

/// 126-bit Morton code of three 42-bit coordinates (x in the lowest bit;
/// higher bits of the coordinates are ignored).
#[inline]
pub fn morton3_wide(q: [u64; 3]) -> u128 {
    let half = |shift: u32| {
        part1by2((q[0] >> shift) as u32)
            | (part1by2((q[1] >> shift) as u32) << 1)
            | (part1by2((q[2] >> shift) as u32) << 2)
    };
    ((half(21) as u128) << 63) | half(0) as u128
}

/// Inverse of [`morton3_wide`].
#[inline]
pub fn demorton3_wide(m: u128) -> [u64; 3] {
    let (lo, hi) = (m as u64 & ((1 << 63) - 1), (m >> 63) as u64);
    let axis = |k: u32| (compact1by2(hi >> k) as u64) << 21 | compact1by2(lo >> k) as u64;
    [axis(0), axis(1), axis(2)]
}

#[cfg(test)]
mod tests;
