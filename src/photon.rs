//! The photon and its packed on-disk form.
//!
//! A photon is a position (m), the direction it was travelling when stored
//! (unit vector, pointing along the flight, i.e. *incoming* to the site), a
//! band index and a power (W per photon in its band). On disk a photon is a
//! 16-byte record: position quantised to 16 bits per axis inside its tile's
//! box, direction octahedral-encoded in 2 x 16 bits, band and photon group
//! in one u16 (band in the low [`BAND_BITS`] bits), power as f32. See
//! `store::codec` for the tile layout.
//!
//! The group ([`GROUPS`] of them) is drawn per emitted path, so that the
//! photons of one path share it: the groups are independent subsets of the
//! map, from which the renderer estimates its own photon noise
//! (`estimate::groups`).
//!
//! Quantisation error (tested in this module and in the round-trip tests):
//! - position: at most half a quantum per axis, `extent / (2 * 65535)`, plus
//!   f32 rounding (a few ulp of the coordinate);
//! - direction: at most [`OCT_MAX_ANGLE_ERROR_RAD`];
//! - band and power: exact.

use glam::Vec3;

/// A stored photon, decoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Position in scene coordinates (m, z up, sea surface at z = 0).
    pub position: Vec3,
    /// Unit direction of flight when the photon was stored.
    pub direction: Vec3,
    /// Index into the map's band grid.
    pub band: u16,
    /// Power carried, W (spectral power integrated over the band).
    pub power: f32,
    /// The independent photon subset the photon's path belongs to, below [`GROUPS`].
    pub group: u8,
}

/// Bits of the packed band field that hold the band index.
pub const BAND_BITS: u32 = 12;
/// Photon groups: independent subsets of a map (one per emitted path).
pub const GROUPS: usize = 16;
const _: () = assert!(GROUPS <= 1 << (16 - BAND_BITS));
/// Most bands a map can hold.
pub const MAX_BANDS: usize = 1 << BAND_BITS;

/// The group of emitted path `index`: the top bits of a hash of the index,
/// so that groups are independent of how paths were numbered.
#[inline]
pub fn group_of_path(index: u64) -> u8 {
    (crate::rng::mix64(index ^ 0x6772_6f75_7073) >> 60) as u8 & (GROUPS as u8 - 1)
}

/// Band and group packed into one u16 (band low).
#[inline]
pub fn pack_band_group(band: u16, group: u8) -> u16 {
    debug_assert!((band as usize) < MAX_BANDS && (group as usize) < GROUPS);
    band | (group as u16) << BAND_BITS
}

/// A photon as held in memory by the tile cache: position decoded, direction
/// still octahedral-coded (decoded on use by [`PackedPhoton::unpack`]), so a
/// cached photon costs 24 bytes instead of 32 and decoding a tile skips the
/// normalisation of every direction.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PackedPhoton {
    pub position: [f32; 3],
    pub oct: [u16; 2],
    /// Band and group ([`pack_band_group`]), as stored on disk.
    pub band_group: u16,
    /// The map layer the photon belongs to (`LAYER_*`).
    pub layer: u16,
    pub power: f32,
}

const _: () = assert!(std::mem::size_of::<PackedPhoton>() == 24);

/// Layer of photons stored at scattering events in the water while
/// travelling down or level (see [`volume_layer`]).
pub const LAYER_VOLUME: u16 = 0;
/// Layer of photons stored where light meets the floor or a target.
pub const LAYER_SURFACE: u16 = 1;
/// Layer of photons stored at scattering events in the water while
/// travelling up.
pub const LAYER_VOLUME_UP: u16 = 2;
/// Number of layers a map holds.
pub const LAYERS: usize = 3;
/// The layers of volume photons: down (or level), then up.
pub const VOLUME_LAYERS: [u16; 2] = [LAYER_VOLUME, LAYER_VOLUME_UP];

/// The layer of a volume photon travelling along `direction`.
///
/// Volume photons are kept apart by the sign of their vertical travel so
/// that an estimate can search the few photons travelling toward a viewer
/// looking down (through the phase function's forward lobe they carry most
/// of the upwelling in-scatter) without visiting the many travelling down
/// (`estimate::estimator`).
#[inline]
pub fn volume_layer(direction: Vec3) -> u16 {
    if direction.z > 0.0 {
        LAYER_VOLUME_UP
    } else {
        LAYER_VOLUME
    }
}

impl PackedPhoton {
    /// Pack a photon of `layer` (encodes its direction).
    pub fn pack(p: &Photon, layer: u16) -> Self {
        PackedPhoton {
            position: p.position.to_array(),
            oct: oct_encode(p.direction),
            band_group: pack_band_group(p.band, p.group),
            layer,
            power: p.power,
        }
    }

    /// The photon with its direction decoded.
    #[inline]
    pub fn unpack(&self) -> Photon {
        Photon {
            position: self.pos(),
            direction: oct_decode(self.oct),
            band: self.band(),
            power: self.power,
            group: self.group(),
        }
    }

    /// The band index.
    #[inline]
    pub fn band(&self) -> u16 {
        self.band_group & (MAX_BANDS as u16 - 1)
    }

    /// The photon group.
    #[inline]
    pub fn group(&self) -> u8 {
        (self.band_group >> BAND_BITS) as u8
    }

    /// Position as a vector.
    #[inline]
    pub fn pos(&self) -> Vec3 {
        Vec3::from_array(self.position)
    }
}

/// Worst-case angle between a unit vector and its 2 x 16-bit octahedral code.
pub const OCT_MAX_ANGLE_ERROR_RAD: f32 = 5.0e-5;

/// Octahedral encoding of a unit vector into two 16-bit snorm values
/// (Cigolle et al. 2014, "A Survey of Efficient Representations for
/// Independent Unit Vectors"), choosing among the four neighbouring codes
/// the one that decodes closest to `d` ("precise" variant).
#[inline]
pub fn oct_encode(d: Vec3) -> [u16; 2] {
    let codes = oct_candidates(d);
    // Compare by squared chord: a dot product near 1 has no f32 resolution
    // left. The first candidate (the floor) stands when no error is below
    // infinity (a NaN direction).
    let mut best = codes[0];
    let mut best_err = f32::INFINITY;
    for (code, err) in codes.into_iter().zip(oct_errors(codes, d)) {
        if err < best_err {
            best_err = err;
            best = code;
        }
    }
    best
}

/// The four codes around `d`'s octahedral point, the floor first.
#[inline]
fn oct_candidates(d: Vec3) -> [[u16; 2]; 4] {
    let l1 = d.x.abs() + d.y.abs() + d.z.abs();
    let (mut u, mut v) = if l1 > 0.0 {
        (d.x / l1, d.y / l1)
    } else {
        (0.0, 0.0)
    };
    if d.z < 0.0 {
        let (pu, pv) = (u, v);
        u = (1.0 - pv.abs()) * sign_not_zero(pu);
        v = (1.0 - pu.abs()) * sign_not_zero(pv);
    }
    let (fu, fv) = (snorm16_floor(u) as i32, snorm16_floor(v) as i32);
    OCT_STEPS.map(|(du, dv)| {
        [
            (fu + du).min(32767) as i16 as u16,
            (fv + dv).min(32767) as i16 as u16,
        ]
    })
}

/// The four neighbouring codes [`oct_encode`] chooses among.
const OCT_STEPS: [(i32, i32); 4] = [(0, 0), (1, 0), (0, 1), (1, 1)];

/// Squared distance from `d` to each code's [`oct_decode`].
#[cfg(not(target_arch = "x86_64"))]
#[inline]
fn oct_errors(codes: [[u16; 2]; 4], d: Vec3) -> [f32; 4] {
    codes.map(|c| (oct_decode(c) - d).length_squared())
}

/// Squared distance from `d` to each code's [`oct_decode`], the four
/// decodes in the lanes of SSE registers: the same IEEE operations in the
/// same order as the scalar decode (glam's `normalize` is `v * (1 /
/// sqrt(x x + y y + z z))`, and SSE's square root and division are
/// correctly rounded), so the same bits (tested against the scalar form).
#[cfg(target_arch = "x86_64")]
#[inline]
fn oct_errors(codes: [[u16; 2]; 4], d: Vec3) -> [f32; 4] {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of the x86-64 baseline.
    unsafe {
        let lanes = |k: usize| {
            let q = codes.map(|c| c[k] as i16 as i32);
            let f = _mm_cvtepi32_ps(_mm_setr_epi32(q[0], q[1], q[2], q[3]));
            _mm_max_ps(_mm_div_ps(f, _mm_set1_ps(32767.0)), _mm_set1_ps(-1.0))
        };
        let (u, v) = (lanes(0), lanes(1));
        let sign = _mm_set1_ps(-0.0);
        let abs = |x: __m128| _mm_andnot_ps(sign, x);
        let z = _mm_sub_ps(_mm_sub_ps(_mm_set1_ps(1.0), abs(u)), abs(v));
        let t = _mm_max_ps(_mm_xor_ps(z, sign), _mm_setzero_ps());
        let copysign = |m: __m128, s: __m128| _mm_or_ps(abs(m), _mm_and_ps(s, sign));
        let x = _mm_sub_ps(u, copysign(t, u));
        let y = _mm_sub_ps(v, copysign(t, v));
        let dot = _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(x, x), _mm_mul_ps(y, y)),
            _mm_mul_ps(z, z),
        );
        let r = _mm_div_ps(_mm_set1_ps(1.0), _mm_sqrt_ps(dot));
        let ex = _mm_sub_ps(_mm_mul_ps(x, r), _mm_set1_ps(d.x));
        let ey = _mm_sub_ps(_mm_mul_ps(y, r), _mm_set1_ps(d.y));
        let ez = _mm_sub_ps(_mm_mul_ps(z, r), _mm_set1_ps(d.z));
        let err = _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(ex, ex), _mm_mul_ps(ey, ey)),
            _mm_mul_ps(ez, ez),
        );
        let mut out = [0f32; 4];
        _mm_storeu_ps(out.as_mut_ptr(), err);
        out
    }
}

/// Inverse of [`oct_encode`]; returns a unit vector. Branch-free (the
/// lower-hemisphere fold is a subtraction), since stored directions point
/// up or down at random and a branch would mispredict half the time.
#[inline]
pub fn oct_decode(code: [u16; 2]) -> Vec3 {
    let u = unsnorm16(code[0]);
    let v = unsnorm16(code[1]);
    let z = 1.0 - u.abs() - v.abs();
    let t = (-z).max(0.0);
    let x = u - t.copysign(u);
    let y = v - t.copysign(v);
    Vec3::new(x, y, z).normalize()
}

#[inline]
fn sign_not_zero(x: f32) -> f32 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

#[inline]
fn snorm16_floor(x: f32) -> i16 {
    (x.clamp(-1.0, 1.0) * 32767.0).floor() as i16
}

#[inline]
fn unsnorm16(q: u16) -> f32 {
    (q as i16 as f32 / 32767.0).max(-1.0)
}

/// Quantisation of one axis of a tile box to 16 bits.
///
/// `q = round((p - min) / step)` with `step = (max - min) / 65535`, and the
/// decoded value is `min + q * step` in f32. A degenerate axis (max == min)
/// encodes every value as 0 and decodes to `min`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisQuantizer {
    min: f32,
    step: f32,
    inv_step: f64,
}

impl AxisQuantizer {
    /// A quantiser for values in `[min, max]`.
    pub fn new(min: f32, max: f32) -> Self {
        let step = (max - min) / 65535.0;
        let inv_step = if step > 0.0 { 1.0 / step as f64 } else { 0.0 };
        AxisQuantizer {
            min,
            step,
            inv_step,
        }
    }

    /// 16-bit code of `p` (clamped into the box).
    #[inline]
    pub fn encode(&self, p: f32) -> u16 {
        ((p as f64 - self.min as f64) * self.inv_step)
            .round()
            .clamp(0.0, 65535.0) as u16
    }

    /// Decoded value of code `q`.
    #[inline]
    pub fn decode(&self, q: u16) -> f32 {
        self.min + q as f32 * self.step
    }

    /// Quantum size (m).
    pub fn step(&self) -> f32 {
        self.step
    }
}

#[cfg(test)]
mod tests;
