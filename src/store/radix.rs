//! Least-significant-digit radix sorting by the low bits of an integer key,
//! for the writer's two sorts: a tile's records by Morton code, a spill
//! frame's photons by the Morton code of their grid offsets.
//!
//! Both sorted with the standard library's pattern-defeating quicksort
//! before, about 7 % of a spilling emission's samples: keys of 16 or 32
//! bytes compared as pairs of words, 16 levels deep for a tile. A radix
//! sort counts every digit in one read of the keys, then moves each key
//! once per 8-bit digit of the code (6 passes for a tile's 48-bit codes),
//! skipping a digit every key shares.
//!
//! Not for: sorting by a whole record (a tile's ties on the code are put in
//! order afterwards by a comparison sort of each run, see `codec`).

/// Bits sorted per pass.
const DIGIT_BITS: u32 = 8;
const BUCKETS: usize = 1 << DIGIT_BITS;

/// Sort `items` stably by the low `bits` bits of `key` (at most 128),
/// through `spare` (any contents; left holding scratch). Items whose keys
/// agree in those bits keep their order.
pub fn sort_by_low_bits<T: Copy>(
    items: &mut Vec<T>,
    spare: &mut Vec<T>,
    bits: u32,
    key: impl Fn(&T) -> u128,
) {
    let n = items.len();
    if n < 2 {
        return;
    }
    spare.clear();
    spare.resize(n, items[0]);
    let bits = bits.min(128);
    let passes = bits.div_ceil(DIGIT_BITS) as usize;
    let mask = |pass: usize| (1usize << (bits - pass as u32 * DIGIT_BITS).min(DIGIT_BITS)) - 1;
    // Every pass's digit counts from one read of the keys.
    let mut counts = [[0usize; BUCKETS]; (128 / DIGIT_BITS) as usize];
    for x in items.iter() {
        let k = key(x);
        for (pass, count) in counts[..passes].iter_mut().enumerate() {
            count[(k >> (pass as u32 * DIGIT_BITS)) as usize & mask(pass)] += 1;
        }
    }
    for (pass, start) in counts[..passes].iter_mut().enumerate() {
        // A digit every key shares leaves the order as it is.
        if start.contains(&n) {
            continue;
        }
        let mut sum = 0;
        for s in start.iter_mut() {
            let count = *s;
            *s = sum;
            sum += count;
        }
        let (shift, mask) = (pass as u32 * DIGIT_BITS, mask(pass));
        for x in items.iter() {
            let d = (key(x) >> shift) as usize & mask;
            spare[start[d]] = *x;
            start[d] += 1;
        }
        std::mem::swap(items, spare);
    }
}

#[cfg(test)]
mod tests;
