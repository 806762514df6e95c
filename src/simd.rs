//! The few hardware hints and vector kernels shared across stages, each
//! with a portable fallback that gives the same bits.
//!
//! Kernels that belong to one structure stay beside their scalar twins and
//! tests: the ceiling's columns (`geometry::ceiling`), the direction codes'
//! decode errors (`photon`).

/// Ask for the cache line holding `p`, without waiting for it. `p` need not
/// point at anything valid (the spare capacity of a buffer, say).
#[inline(always)]
pub(crate) fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint; it reads nothing and cannot fault.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(p.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// The 16 x 16 byte transpose: `out[j][k] = rows[k][j]`. On x86-64, four
/// rounds of interleaving row `i` with row `i + 8` (each round rotates a
/// byte's 8-bit row-and-column address by one bit: four make the
/// transpose), 64 SSE2 unpacks instead of 256 byte moves.
#[inline]
pub(crate) fn transpose16(rows: [&[u8; 16]; 16], out: &mut [[u8; 16]; 16]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{
            __m128i, _mm_loadu_si128, _mm_storeu_si128, _mm_unpackhi_epi8, _mm_unpacklo_epi8,
        };
        // SAFETY: each row is 16 readable bytes; unaligned loads.
        let mut r: [__m128i; 16] =
            std::array::from_fn(|k| unsafe { _mm_loadu_si128(rows[k].as_ptr().cast()) });
        for _ in 0..4 {
            let t = r;
            for k in 0..8 {
                // SAFETY: SSE2 is part of every x86-64 target.
                unsafe {
                    r[2 * k] = _mm_unpacklo_epi8(t[k], t[k + 8]);
                    r[2 * k + 1] = _mm_unpackhi_epi8(t[k], t[k + 8]);
                }
            }
        }
        for (o, v) in out.iter_mut().zip(&r) {
            // SAFETY: `o` is 16 writable bytes; an unaligned store.
            unsafe { _mm_storeu_si128(o.as_mut_ptr().cast(), *v) }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    for (j, o) in out.iter_mut().enumerate() {
        for (k, row) in rows.iter().enumerate() {
            o[k] = row[j];
        }
    }
}

#[cfg(test)]
mod tests;
