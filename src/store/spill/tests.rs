use super::frame::{body_crc, JOINED_BELOW};
use super::*;
use crate::bounds::Aabb;
use crate::photon::Photon;
use crate::photon::LAYERS;
use crate::rng::Pcg32;
use glam::Vec3;

fn scene_bounds() -> Aabb {
    Aabb {
        min: Vec3::new(-400.0, -400.0, -20.0),
        max: Vec3::new(400.0, 400.0, 0.5),
    }
}

fn scratch(bounds: &Aabb) -> Scratch {
    let file = tempfile::tempfile().unwrap();
    Scratch::new(file, PathBuf::from("test scratch"), SnapGrid::new(bounds)).unwrap()
}

/// `n` photons of `layer` in a box of `size` metres at `at`, snapped.
fn photons(
    n: usize,
    seed: u64,
    at: Vec3,
    size: f32,
    layer: u16,
    grid: &SnapGrid,
) -> Vec<StagedPhoton> {
    let mut r = Pcg32::new(seed, 9);
    (0..n)
        .map(|i| {
            let p = Photon {
                position: at + Vec3::new(r.uniform_f32(), r.uniform_f32(), r.uniform_f32()) * size,
                direction: Vec3::new(r.uniform_f32() - 0.5, r.uniform_f32() - 0.5, -1.0)
                    .normalize(),
                band: r.below(128) as u16,
                power: [0.5, 0.25, 1.0][i % 3],
                group: (i % 16) as u8,
            };
            let mut s = StagedPhoton::new(&p, layer);
            assert!(grid.snap(&mut s));
            s
        })
        .collect()
}

fn sorted(mut v: Vec<StagedPhoton>) -> Vec<[u64; 3]> {
    let mut k: Vec<[u64; 3]> = v.drain(..).map(|p| p.key()).collect();
    k.sort_unstable();
    k
}

#[test]
fn the_grid_is_the_f32_spacing_at_the_bounds_and_snapping_is_exact() {
    let g = SnapGrid::new(&scene_bounds());
    // 400 m lies in [256, 512): f32 spacing 2^(8-23); 20 m in [16, 32): 2^(4-23).
    assert_eq!(g.step(), [2f64.powi(-15), 2f64.powi(-15), 2f64.powi(-19)]);
    let mut r = Pcg32::new(5, 6);
    for _ in 0..100_000 {
        let x = [
            (r.uniform_f32() - 0.5) * 800.0,
            (r.uniform_f32() - 0.5) * 800.0,
            -r.uniform_f32() * 20.0 * r.uniform_f32().powi(8),
        ];
        let i = g.index(x).unwrap();
        let s = g.position(i);
        for a in 0..3 {
            // Within half a step, and snapping again changes nothing.
            assert!(
                (s[a] as f64 - x[a] as f64).abs() <= g.step()[a] / 2.0,
                "{x:?} {s:?}"
            );
            assert_eq!(s[a] as f64, i[a] as f64 * g.step()[a], "not exact: {x:?}");
        }
        assert_eq!(g.index(s).unwrap(), i);
        assert_eq!(g.position(g.index(s).unwrap()), s);
    }
    // Planes a scene is built on stay exactly where they are.
    for z in [0.0f32, -10.0, -0.5, 0.25, -19.875] {
        assert_eq!(g.position(g.index([1.0, 2.0, z]).unwrap())[2], z);
    }
    // Far beyond the bounds, or not finite: refused rather than wrapped.
    assert!(g.index([1e30, 0.0, 0.0]).is_none());
    assert!(g.index([f32::NAN, 0.0, 0.0]).is_none());
    assert!(g.index([0.0, f32::INFINITY, 0.0]).is_none());
    // Outside the bounds but in range: still exact (the f32 spacing there is
    // a multiple of the step).
    let far = [3000.3f32, -1.0e6, 40.0];
    assert_eq!(g.position(g.index(far).unwrap())[..2], far[..2]);
}

#[test]
fn frames_give_back_every_record_and_link_to_the_cells_previous_frame() {
    let bounds = scene_bounds();
    let mut s = scratch(&bounds);
    let grid = s.grid();
    let a = photons(
        FRAME_PHOTONS * 2 + 77,
        1,
        Vec3::new(-3.0, 5.0, -7.0),
        4.0,
        1,
        &grid,
    );
    let b = photons(1000, 2, Vec3::new(100.0, -300.0, -19.0), 0.01, 1, &grid);
    let mut last = s.spill(a.iter(), None).unwrap();
    assert_eq!(s.frames_written, 3);
    last = s.spill(b.iter(), last).unwrap();
    assert_eq!(s.frames_written, 4);
    let mut back = Vec::new();
    let mut buf = Vec::new();
    let mut counts = Vec::new();
    s.for_each_frame(last, &mut buf, |r| {
        counts.push(r.len());
        back.extend_from_slice(r)
    })
    .unwrap();
    assert_eq!(counts, vec![1000, 77, FRAME_PHOTONS, FRAME_PHOTONS]);
    let mut all = a.clone();
    all.extend_from_slice(&b);
    assert_eq!(sorted(back), sorted(all));
}

#[test]
fn coincident_and_extreme_positions_round_trip() {
    let bounds = scene_bounds();
    let mut s = scratch(&bounds);
    let grid = s.grid();
    let mut v = photons(300, 3, Vec3::new(0.0, 0.0, -5.0), 0.0, 0, &grid);
    v.extend(photons(
        300,
        4,
        Vec3::new(-400.0, 400.0, -20.0),
        800.0,
        0,
        &grid,
    ));
    // A photon far outside the bounds but inside the grid's range.
    let mut far = v[0];
    far.photon.position = [3.0e5, -3.0e5, 900.0];
    assert!(grid.snap(&mut far));
    v.push(far);
    let last = s.spill(v.iter(), None).unwrap();
    let mut back = Vec::new();
    let mut buf = Vec::new();
    s.for_each_frame(last, &mut buf, |r| back.extend_from_slice(r))
        .unwrap();
    assert_eq!(sorted(back), sorted(v));
}

/// Sorted grid deltas cost about 1.44 bits a photon more than log2(box
/// volume in grid cells / photons), the entropy of the gaps of a uniform
/// sorted sample. With the direction (at most 32 bits), band (7 bits) and
/// one of three powers (1.6 bits), a frame must stay within that plus a
/// byte of coding overhead per photon, where 32-byte records with raw f32
/// positions cost over 20.
#[test]
fn a_frame_costs_about_the_entropy_of_its_records() {
    let bounds = scene_bounds();
    let mut s = scratch(&bounds);
    let grid = s.grid();
    let n = FRAME_PHOTONS;
    let size = 8.0f32;
    let v = photons(n, 7, Vec3::new(10.0, 10.0, -12.0), size, 0, &grid);
    s.spill(v.iter(), None).unwrap();
    let step = grid.step();
    let cells: f64 = (0..3).map(|a| size as f64 / step[a]).product();
    let position_bits = (cells / n as f64).log2() + 1.44;
    let entropy_bytes = (position_bits + 32.0 + 7.0 + 1.6) / 8.0;
    let per_photon = s.bytes() as f64 / n as f64;
    assert!(
        per_photon <= entropy_bytes + 1.0,
        "{per_photon:.2} bytes a photon against {entropy_bytes:.2} of entropy"
    );
}

#[test]
fn damaged_frames_are_errors_not_panics() {
    let bounds = scene_bounds();
    let mut s = scratch(&bounds);
    let grid = s.grid();
    let v = photons(500, 8, Vec3::ZERO, 1.0, 2, &grid);
    let f = s.spill(v.iter(), None).unwrap().unwrap();
    // On disk, and bytes of it rewritten below through the page cache.
    s.readable(Some(f)).unwrap();
    s.blocks.buffered(&s.file);
    let mut buf = Vec::new();
    // Width, pad, corner, CRC, a plane's length, plane bytes, the last byte.
    let spots = [16u64, 17, 20, 41, 43, 47, 60, f.len as u64 - 2];
    for (at, byte) in spots
        .into_iter()
        .zip([9u8, 1, 2, 0x80, 4, 0x11, 0xff, 0x55])
    {
        let mut bytes = vec![0u8; f.len as usize];
        crate::output::read_exact_at(&s.file, &mut bytes, f.offset).unwrap();
        let saved = bytes[at as usize];
        bytes[at as usize] ^= byte | 1;
        crate::output::write_all_at(&s.file, &bytes, f.offset).unwrap();
        let e = s.read(f, &mut buf).unwrap_err().to_string();
        assert!(e.contains("test scratch"), "{e}");
        bytes[at as usize] = saved;
        crate::output::write_all_at(&s.file, &bytes, f.offset).unwrap();
    }
    // A frame that claims more photons than it holds.
    let more = Frame {
        count: f.count + 1,
        ..f
    };
    assert!(s.read(more, &mut buf).is_err());
    assert_eq!(s.read(f, &mut buf).unwrap().map(|p| p.count), None);
    assert_eq!(buf.len(), 500);
}

/// A frame's link to the one before it lies outside the body's CRC: a
/// damaged link (to the frame itself or past it, longer than any frame,
/// more photons than a frame holds, or half zero) is an error naming the
/// scratch file, not a loop, a huge read or a chain that quietly ends.
#[test]
fn damaged_links_are_errors() {
    let bounds = scene_bounds();
    let mut s = scratch(&bounds);
    let grid = s.grid();
    let first = s
        .spill(photons(300, 3, Vec3::ZERO, 1.0, 0, &grid).iter(), None)
        .unwrap();
    let f = s
        .spill(photons(300, 4, Vec3::ZERO, 1.0, 0, &grid).iter(), first)
        .unwrap()
        .unwrap();
    s.readable(Some(f)).unwrap();
    s.blocks.buffered(&s.file);
    let mut buf = Vec::new();
    let back = s.read(f, &mut buf).unwrap().unwrap();
    assert_eq!((back.offset, back.count), (first.unwrap().offset, 300));
    let mut link = [0u8; FRAME_LINK];
    crate::output::read_exact_at(&s.file, &mut link, f.offset).unwrap();
    let links: [(u64, u32, u32); 6] = [
        (f.offset, f.len, 300),
        (f.offset + 4096, 100, 300),
        (0, u32::MAX, 300),
        (0, back.len, FRAME_PHOTONS as u32 + 1),
        (0, back.len, 0),
        (0, 0, 300),
    ];
    for (offset, len, count) in links {
        let mut bad = [0u8; FRAME_LINK];
        bad[..8].copy_from_slice(&offset.to_le_bytes());
        bad[8..12].copy_from_slice(&len.to_le_bytes());
        bad[12..].copy_from_slice(&count.to_le_bytes());
        crate::output::write_all_at(&s.file, &bad, f.offset).unwrap();
        let e = s.read(f, &mut buf).unwrap_err().to_string();
        assert!(e.contains("test scratch") && e.contains("link"), "{e}");
    }
    crate::output::write_all_at(&s.file, &link, f.offset).unwrap();
    assert_eq!(s.read(f, &mut buf).unwrap().map(|p| p.count), Some(300));
}

/// Shard frames mix layers; the layer is a record field.
#[test]
fn a_frame_of_mixed_layers_round_trips() {
    let bounds = scene_bounds();
    let mut codec = FrameCodec::new(SnapGrid::new(&bounds)).unwrap();
    let grid = codec.grid();
    let mut v = Vec::new();
    for layer in 0..LAYERS as u16 {
        v.extend(photons(
            700,
            10 + layer as u64,
            Vec3::new(-50.0, 20.0, -9.0),
            30.0,
            layer,
            &grid,
        ));
    }
    let mut body = Vec::new();
    codec.encode(&v, &mut body).unwrap();
    let mut back = Vec::new();
    codec.decode(&body, v.len(), &mut back).unwrap();
    assert_eq!(sorted(back.clone()), sorted(v.clone()));
    // A body decoded with the wrong count, or cut short, is an error.
    assert!(codec.decode(&body, v.len() - 1, &mut back).is_err());
    assert!(codec
        .decode(&body[..body.len() - 1], v.len(), &mut back)
        .is_err());
    assert!(codec.decode(&body[..10], v.len(), &mut back).is_err());
}

/// Fetching a cell's frames on one handle and decoding them on another
/// gives the records `for_each_frame` gives, in the same order, for frames
/// written around the page cache and made readable mid-way; a damaged
/// fetched frame is an error naming the scratch file.
#[test]
fn fetched_frames_decode_to_the_records_read_directly() {
    let bounds = scene_bounds();
    let mut s = scratch(&bounds);
    let grid = s.grid();
    let mut newest = None;
    for (k, n) in [5usize, 900, FRAME_PHOTONS + 3, 1, 4000]
        .into_iter()
        .enumerate()
    {
        let v = photons(n, 10 + k as u64, Vec3::new(-3.0, 5.0, -7.0), 2.0, 0, &grid);
        newest = s.spill(v.iter(), newest).unwrap();
        if k == 2 {
            // Part of the file written, padded, then more gathered.
            s.readable(newest).unwrap();
        }
    }
    s.readable(newest).unwrap();
    let (mut want, mut buf) = (Vec::new(), Vec::new());
    s.for_each_frame(newest, &mut buf, |records| want.extend_from_slice(records))
        .unwrap();
    assert_eq!(want.len(), 5 + 900 + FRAME_PHOTONS + 3 + 1 + 4000);
    let mut fetched = Fetched::default();
    s.fetcher().unwrap().fetch(newest, &mut fetched).unwrap();
    let mut reader = s.decoder().unwrap();
    let mut got = Vec::new();
    reader.decode_fetched(&fetched, &mut got).unwrap();
    assert_eq!(got, want);

    let last = fetched.bytes.len() - 1;
    fetched.bytes[last] ^= 0x5a;
    let e = reader
        .decode_fetched(&fetched, &mut got)
        .unwrap_err()
        .to_string();
    assert!(e.contains("test scratch"), "{e}");
}

/// Small frames store their planes as one zstd frame, large ones one
/// frame a plane. Joined, a frame of a few dozen photons is smaller (each
/// plane's own frame header and tables cost more than the shared table
/// loses) and takes one zstd call instead of about twenty, which cost the
/// spill thread half a core at 10^9 photons; up to the threshold it stays
/// within 10 % of the unjoined size on these uniform records (on the
/// built-in scene's photons, frames below 1024 photons took the same or
/// fewer bytes joined); far above it, joined is larger.
#[test]
fn small_frames_join_their_planes_and_large_ones_do_not() {
    let bounds = scene_bounds();
    let grid = SnapGrid::new(&bounds);
    let mut codec = FrameCodec::new(grid).unwrap();
    let mut size = |n: usize, joined: bool| {
        let v = photons(n, 11, Vec3::new(10.0, 10.0, -12.0), 2.0, 0, &grid);
        let mut out = Vec::new();
        codec.encode_as(&v, joined, &mut out).unwrap();
        let mut back = Vec::new();
        codec.decode(&out, n, &mut back).unwrap();
        assert_eq!(sorted(back), sorted(v));
        out.len()
    };
    for n in [1, 40] {
        let (joined, apart) = (size(n, true), size(n, false));
        assert!(
            joined < apart,
            "{n} photons: joined {joined} bytes, apart {apart}"
        );
    }
    for n in [300, JOINED_BELOW - 1] {
        let (joined, apart) = (size(n, true), size(n, false));
        assert!(
            joined as f64 <= 1.1 * apart as f64,
            "{n} photons: joined {joined} bytes, apart {apart}"
        );
    }
    for n in [4 * JOINED_BELOW, FRAME_PHOTONS] {
        let (joined, apart) = (size(n, true), size(n, false));
        assert!(
            apart < joined,
            "{n} photons: joined {joined} bytes, apart {apart}"
        );
    }
    // What `encode` chooses.
    let v = photons(JOINED_BELOW - 1, 12, Vec3::ZERO, 1.0, 1, &grid);
    let mut out = Vec::new();
    codec.encode(&v, &mut out).unwrap();
    assert_eq!(out[1], 1);
    let v = photons(JOINED_BELOW, 12, Vec3::ZERO, 1.0, 1, &grid);
    out.clear();
    codec.encode(&v, &mut out).unwrap();
    assert_eq!(out[1], 0);
}

/// A body whose checksum still matches but whose bytes say something
/// impossible (an unknown plane mode, lengths past the end or short of
/// it, a damaged zstd frame) is an error, in either plane mode: every
/// byte of a joined and an unjoined body flipped, the checksum recomputed.
#[test]
fn bodies_with_a_matching_checksum_but_wrong_bytes_are_errors_not_panics() {
    let bounds = scene_bounds();
    let grid = SnapGrid::new(&bounds);
    let mut codec = FrameCodec::new(grid).unwrap();
    let mut back = Vec::new();
    for (n, joined) in [(200, true), (200, false), (1500, false)] {
        let v = photons(n, 13, Vec3::new(-5.0, 3.0, -2.0), 3.0, 0, &grid);
        let mut body = Vec::new();
        codec.encode_as(&v, joined, &mut body).unwrap();
        assert_eq!(body[1], joined as u8);
        let (mut errors, mut decoded) = (0, 0);
        for at in (0..body.len()).filter(|&at| !(BODY_HEAD - 4..BODY_HEAD).contains(&at)) {
            for flip in [0x01u8, 0x80, 0xff] {
                let mut bad = body.clone();
                bad[at] ^= flip;
                let crc = body_crc(&bad);
                bad[BODY_HEAD - 4..BODY_HEAD].copy_from_slice(&crc.to_le_bytes());
                match codec.decode(&bad, n, &mut back) {
                    Ok(()) => decoded += 1,
                    Err(_) => errors += 1,
                }
            }
        }
        // The mode byte, the lengths and the zstd frames' headers fail;
        // flipped raw plane bytes decode to other records.
        assert!(
            errors > 0 && decoded > 0,
            "{errors} errors, {decoded} decoded"
        );
        let mut bad = body.clone();
        bad[1] = 2;
        let crc = body_crc(&bad);
        bad[BODY_HEAD - 4..BODY_HEAD].copy_from_slice(&crc.to_le_bytes());
        let e = codec.decode(&bad, n, &mut back).unwrap_err();
        assert!(e.contains("plane mode 2"), "{e}");
        // Cut short, the checksum recomputed.
        let mut short = body[..body.len() - 1].to_vec();
        let crc = body_crc(&short);
        short[BODY_HEAD - 4..BODY_HEAD].copy_from_slice(&crc.to_le_bytes());
        assert!(codec.decode(&short, n, &mut back).is_err());
    }
}
