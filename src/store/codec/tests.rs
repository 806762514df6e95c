use super::*;
use crate::rng::Pcg32;

fn staged(n: usize, seed: u64) -> Vec<StagedPhoton> {
    (0..n)
        .map(|i| {
            let mut r = Pcg32::new(seed, i as u64);
            let p = Photon {
                position: Vec3::new(
                    r.uniform_f32() * 10.0,
                    r.uniform_f32() * 10.0,
                    -r.uniform_f32() * 3.0,
                ),
                direction: Vec3::new(r.uniform_f32() - 0.5, 0.3, -1.0).normalize(),
                band: r.below(128) as u16,
                power: 0.25,
                group: (i % 16) as u8,
            };
            StagedPhoton::new(&p, 0)
        })
        .collect()
}

#[test]
fn tile_round_trips_within_quantisation_error() {
    let photons = staged(5000, 3);
    let t = TileEncoder::default().encode(&photons).unwrap();
    let mut out = Vec::new();
    TileDecoder::default()
        .decode(&t.blob, &t.entry(0), &mut out)
        .unwrap();
    assert_eq!(out.len(), photons.len());
    let step = (t.quant.max - t.quant.min) / 65535.0;
    // Match decoded photons to inputs by band, power and nearest position.
    let mut used = vec![false; photons.len()];
    for d in out.iter().map(|p| p.unpack()) {
        assert!(t.bounds.distance_sq(d.position) == 0.0);
        let j = (0..photons.len())
            .filter(|&j| !used[j] && photons[j].photon.band() == d.band)
            .min_by(|&a, &b| {
                let da = photons[a].pos().distance_squared(d.position);
                let db = photons[b].pos().distance_squared(d.position);
                da.total_cmp(&db)
            })
            .unwrap();
        used[j] = true;
        let err = (photons[j].pos() - d.position).abs();
        assert!(err.cmple(step * 0.5 + Vec3::splat(1e-5)).all(), "{err}");
        assert_eq!(photons[j].photon.unpack().direction, d.direction);
        assert_eq!(d.power, photons[j].photon.power);
        assert_eq!(d.group, photons[j].photon.group());
    }
}

#[test]
fn blob_is_independent_of_input_order() {
    let mut photons = staged(3000, 4);
    let a = TileEncoder::default().encode(&photons).unwrap();
    photons.reverse();
    let b = TileEncoder::default().encode(&photons).unwrap();
    assert_eq!(a.blob, b.blob);
    assert_eq!(a.crc, b.crc);
}

#[test]
fn corrupt_blobs_are_rejected() {
    let photons = staged(2000, 5);
    let t = TileEncoder::default().encode(&photons).unwrap();
    let mut dec = TileDecoder::default();
    let mut out = Vec::new();
    let mut bad = t.blob.clone();
    bad[t.blob.len() / 2] ^= 0x40;
    assert!(matches!(
        dec.decode(&bad, &t.entry(0), &mut out),
        Err(DecodeError::Checksum { .. })
    ));
    // A valid frame with the wrong count is caught by its length.
    let e = t.entry(0);
    let fewer = TileEntry {
        count: t.count - 1,
        ..e
    };
    assert!(dec.decode(&t.blob, &fewer, &mut out).is_err());
    let more = TileEntry {
        count: t.count + 1,
        ..e
    };
    assert!(matches!(
        dec.decode(&t.blob, &more, &mut out),
        Err(DecodeError::Length { .. })
    ));
    // A truncated frame (with a matching checksum) is caught by zstd.
    let short = &t.blob[..t.blob.len() - 3];
    let short_entry = TileEntry {
        crc: crc32fast::hash(short),
        ..e
    };
    assert!(dec.decode(short, &short_entry, &mut out).is_err());
}

/// Coincident positions and exact duplicates: the blob is a function of the
/// multiset of records, whatever order they come in.
#[test]
fn blob_is_a_function_of_the_multiset_of_records() {
    let mut photons = staged(2000, 6);
    // Photons sharing a position with different payloads, and exact copies.
    for i in 0..500 {
        let mut p = photons[i % 7];
        p.photon.band_group = (i % 5) as u16;
        p.photon.power = [0.5, 1.0][i % 2];
        photons.push(p);
        photons.push(photons[i]);
    }
    let a = TileEncoder::default().encode(&photons).unwrap();
    let mut r = Pcg32::new(9, 9);
    for k in (1..photons.len()).rev() {
        photons.swap(k, r.below(k as u32 + 1) as usize);
    }
    let b = TileEncoder::default().encode(&photons).unwrap();
    assert_eq!(a.blob, b.blob);
}

/// A blob whose plane table disagrees with its length, or whose raw plane
/// is short, is an error rather than a panic or a wrong tile.
#[test]
fn damaged_plane_tables_are_rejected() {
    let photons = staged(3000, 8);
    let t = TileEncoder::default().encode(&photons).unwrap();
    let raw_mask = u16::from_le_bytes([t.blob[0], t.blob[1]]);
    // Some planes are noise (stored raw), some compress.
    assert!(raw_mask != 0 && raw_mask != u16::MAX, "{raw_mask:016b}");
    let mut dec = TileDecoder::default();
    let mut out = Vec::new();
    let check = |blob: Vec<u8>, dec: &mut TileDecoder, out: &mut Vec<PackedPhoton>| {
        let e = TileEntry {
            crc: crc32fast::hash(&blob),
            ..t.entry(0)
        };
        dec.decode(&blob, &e, out).unwrap_err()
    };
    // A plane's stored length one longer than the blob holds.
    let mut longer = t.blob.clone();
    longer[2] = longer[2].wrapping_add(1);
    assert!(matches!(
        check(longer, &mut dec, &mut out),
        DecodeError::Table
    ));
    // A compressed plane marked raw.
    let k = (0..16).find(|k| raw_mask & (1 << k) == 0).unwrap();
    let mut flipped = t.blob.clone();
    flipped[0..2].copy_from_slice(&(raw_mask | 1 << k).to_le_bytes());
    assert!(matches!(
        check(flipped, &mut dec, &mut out),
        DecodeError::Length { .. }
    ));
    // Shorter than the table.
    assert!(matches!(
        check(t.blob[..20].to_vec(), &mut dec, &mut out),
        DecodeError::Table
    ));
    // The intact blob still decodes.
    dec.decode(&t.blob, &t.entry(0), &mut out).unwrap();
    assert_eq!(out.len(), 3000);
}

/// The SIMD un-shuffle is the byte transpose it stands for, at every
/// offset of planes of odd length.
#[test]
fn unshuffle16_transposes_the_byte_planes() {
    let mut rng = crate::rng::Pcg32::new(11, 3);
    let n = 77;
    let raw: Vec<u8> = (0..RECORD_BYTES * n)
        .map(|_| rng.next_u32() as u8)
        .collect();
    for base in 0..=n - 16 {
        let mut out = [[0u8; RECORD_BYTES]; 16];
        unshuffle16(&raw, n, base, &mut out);
        for (j, rec) in out.iter().enumerate() {
            for (k, &byte) in rec.iter().enumerate() {
                assert_eq!(
                    byte,
                    raw[k * n + base + j],
                    "base {base} record {j} byte {k}"
                );
            }
        }
    }
}
