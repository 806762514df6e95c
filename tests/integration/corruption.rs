//! Corruption: every flipped byte of a map's header, metadata, index and footer, a
//! sample of flipped blob bytes, and truncation at every section boundary
//! give a clean error naming the file (and the tile, for blobs) — never a
//! panic, never silent success.

use crate::common::*;
use littoral::progress::Silent;
use littoral::store::format::{FOOTER_LEN, INDEX_ENTRY_LEN};
use littoral::store::MapFile;
use littoral::synth::Distribution;
use std::path::Path;

struct Layout {
    bytes: Vec<u8>,
    header_len: usize,
    index_offset: usize,
    blobs: Vec<(usize, usize)>,
}

fn small_map(dir: &Path) -> Layout {
    let src = source(3_000, 8, 3, Distribution::Water);
    let (path, summary) = synth_map(dir, "good.map", &src, Some(500), 1, 64 * MIB);
    assert!(summary.tiles >= 5);
    let map = MapFile::open(&path).unwrap();
    let blobs: Vec<(usize, usize)> = map
        .tiles()
        .iter()
        .map(|t| (t.offset as usize, t.offset as usize + t.length as usize))
        .collect();
    let bytes = std::fs::read(&path).unwrap();
    let index_offset = bytes.len() - FOOTER_LEN - map.tiles().len() * INDEX_ENTRY_LEN;
    Layout {
        header_len: blobs[0].0,
        index_offset,
        blobs,
        bytes,
    }
}

fn open_err(path: &Path) -> String {
    match MapFile::open(path) {
        Ok(_) => panic!("{} opened", path.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn every_flipped_metadata_byte_is_caught_at_open() {
    let dir = tempdir();
    let l = small_map(dir.path());
    let path = dir.path().join("bad.map");
    let blobs_end = l.blobs.last().unwrap().1;
    assert!(
        l.index_offset > blobs_end,
        "the synthetic map records metadata"
    );
    let metadata = (0..l.header_len).chain(blobs_end..l.bytes.len());
    let mut checked = 0;
    for i in metadata {
        for mask in [0x01u8, 0x80] {
            let mut b = l.bytes.clone();
            b[i] ^= mask;
            std::fs::write(&path, &b).unwrap();
            let e = open_err(&path);
            assert!(e.contains("bad.map"), "byte {i}: {e}");
            assert!(!e.contains('\n'), "byte {i}: multi-line error {e}");
            checked += 1;
        }
    }
    assert!(checked > 2 * (l.header_len + FOOTER_LEN));
}

#[test]
fn flipped_blob_bytes_are_caught_naming_the_tile() {
    let dir = tempdir();
    let l = small_map(dir.path());
    let path = dir.path().join("bad.map");
    for (t, &(start, end)) in l.blobs.iter().enumerate() {
        let step = ((end - start) / 23).max(1);
        for i in (start..end).step_by(step).chain([end - 1]) {
            let mut b = l.bytes.clone();
            b[i] ^= 0x10;
            std::fs::write(&path, &b).unwrap();
            let map = MapFile::open(&path).expect("blob damage is found on decode, not at open");
            let e = map.verify(&Silent).unwrap_err().to_string();
            assert!(
                e.contains("bad.map") && e.contains(&format!("tile {t}")),
                "byte {i}: {e}"
            );
        }
    }
}

#[test]
fn truncation_at_every_section_boundary() {
    let dir = tempdir();
    let l = small_map(dir.path());
    let path = dir.path().join("short.map");
    let mut cuts = vec![
        0,
        1,
        8,
        16,
        l.header_len - 1,
        l.header_len,
        l.header_len + 1,
    ];
    for &(s, e) in &l.blobs {
        cuts.extend([s, s + 1, e - 1, e]);
    }
    cuts.extend([
        l.index_offset,
        l.index_offset + 1,
        l.bytes.len() - FOOTER_LEN,
        l.bytes.len() - 1,
    ]);
    for cut in cuts {
        std::fs::write(&path, &l.bytes[..cut]).unwrap();
        let e = open_err(&path);
        assert!(e.contains("short.map"), "cut {cut}: {e}");
    }
    // Extra bytes appended are caught as well.
    let mut long = l.bytes.clone();
    long.extend_from_slice(&[0u8; 7]);
    std::fs::write(&path, &long).unwrap();
    open_err(&path);
}

#[test]
fn empty_file_directory_missing_file_and_foreign_files() {
    let dir = tempdir();
    let empty = dir.path().join("empty.map");
    std::fs::write(&empty, b"").unwrap();
    assert!(open_err(&empty).contains("0 bytes"));
    assert!(open_err(dir.path()).contains("directory"));
    assert!(open_err(&dir.path().join("missing.map")).contains("missing.map"));
    let foreign = dir.path().join("foreign.map");
    std::fs::write(&foreign, vec![b'x'; 4096]).unwrap();
    assert!(open_err(&foreign).contains("magic"));
}

/// A well-formed file of a newer format version (all checksums valid) is
/// refused with a message saying so.
#[test]
fn newer_format_version_is_refused() {
    let dir = tempdir();
    let l = small_map(dir.path());
    let mut b = l.bytes.clone();
    let newer = littoral::store::format::FORMAT_VERSION + 1;
    b[8..12].copy_from_slice(&newer.to_le_bytes());
    let crc = crc32fast::hash(&b[..l.header_len - 4]);
    b[l.header_len - 4..l.header_len].copy_from_slice(&crc.to_le_bytes());
    let f = b.len() - FOOTER_LEN;
    b[f + 24..f + 28].copy_from_slice(&newer.to_le_bytes());
    let crc = crc32fast::hash(&b[f..f + 28]);
    b[f + 28..f + 32].copy_from_slice(&crc.to_le_bytes());
    let path = dir.path().join("newer.map");
    std::fs::write(&path, &b).unwrap();
    let e = open_err(&path);
    assert!(
        e.contains(&format!("version {newer}")) && e.contains("newer"),
        "{e}"
    );
}
