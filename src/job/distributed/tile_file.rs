//! A part's tile file (`PARTDIR/tiles/CCCCC-RRRRR.tile`): one finished
//! image tile, written whole under a temporary name. Layout: the magic
//! `LTTILE01`, the scene digest (64 hex bytes), i, j, w, h, bands and the
//! error flag (u32 LE each), then the f32 LE arrays (the radiance, its
//! standard error when flagged, each product of `render::products` in
//! order, the quicklook's RGB), and the CRC-32 of all before it. Sizes
//! follow from the header and the product list, so a file of another
//! layout is an error naming it, never a panic.

use crate::error::{Error, Result};
use crate::render::TileResult;
use crate::scene::Scene;
use std::path::{Path, PathBuf};

const TILE_MAGIC: &[u8; 8] = b"LTTILE01";
/// The directory of a part's tile files.
pub(super) const TILES_DIR: &str = "tiles";

pub(super) fn tile_path(dir: &Path, (i, j): (usize, usize)) -> PathBuf {
    dir.join(TILES_DIR).join(format!("{i:05}-{j:05}.tile"))
}

/// A tile's file: magic, scene digest (64 hex bytes), i, j, w, h, bands,
/// error flag (u32 LE each), the f32 LE arrays, CRC-32 of all before it.
pub(super) fn tile_bytes(t: &TileResult, digest: &str, bands: usize) -> Vec<u8> {
    let arrays = 2 + t.products.len();
    let mut b = Vec::with_capacity(128 + 4 * (t.values.len() * arrays + t.rgb.len()));
    b.extend_from_slice(TILE_MAGIC);
    b.extend_from_slice(digest.as_bytes());
    for v in [t.i, t.j, t.w, t.h, bands, !t.errors.is_empty() as usize] {
        b.extend_from_slice(&(v as u32).to_le_bytes());
    }
    let arrays = std::iter::once(&t.values)
        .chain(std::iter::once(&t.errors))
        .chain(t.products.iter())
        .chain(std::iter::once(&t.rgb));
    for a in arrays {
        for v in a {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    let crc = crc32fast::hash(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

/// Read the tile file at `path`, which must be tile `(i, j)` of the scene
/// with `digest`, `bands` bands, the error flag `errors` and `products`
/// product arrays.
pub(super) fn read_tile(
    path: &Path,
    digest: &str,
    (i, j): (usize, usize),
    (w, h): (usize, usize),
    bands: usize,
    errors: bool,
    products: usize,
) -> Result<TileResult> {
    let bad = |what: &str| Error::data(path, None, "tile", what.to_string());
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, "read", e))?;
    let head = 8 + 64 + 6 * 4;
    if bytes.len() < head + 4 || &bytes[..8] != TILE_MAGIC {
        return Err(bad("not a littoral tile file (or truncated)"));
    }
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    if crc32fast::hash(body) != u32::from_le_bytes(crc.try_into().expect("4 bytes")) {
        return Err(bad("corrupt tile (CRC mismatch)"));
    }
    if &body[8..72] != digest.as_bytes() {
        return Err(bad("a tile of another render (scene digest differs)"));
    }
    let u = |k: usize| {
        let o = 72 + 4 * k;
        u32::from_le_bytes(body[o..o + 4].try_into().expect("4 bytes")) as usize
    };
    if [u(0), u(1), u(2), u(3), u(4), u(5)] != [i, j, w, h, bands, errors as usize] {
        return Err(bad("tile position, size or bands do not match the scene"));
    }
    // The radiance, its standard error (or nothing), each product, the
    // quicklook's RGB: sized from the product list, so a tile of another
    // product count is refused by its length.
    let n = w * h * bands;
    let sizes: Vec<usize> = [n, if errors { n } else { 0 }]
        .into_iter()
        .chain(std::iter::repeat_n(n, products))
        .chain([w * h * 3])
        .collect();
    if body.len() != head + 4 * sizes.iter().sum::<usize>() {
        return Err(bad("tile length does not match its size"));
    }
    let mut at = head;
    let mut arrays = sizes.iter().map(|&len| {
        let a: Vec<f32> = body[at..at + 4 * len]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect();
        at += 4 * len;
        a
    });
    let values = arrays.next().expect("values");
    let errors = arrays.next().expect("errors");
    let products = (0..products)
        .map(|_| arrays.next().expect("product"))
        .collect();
    let rgb = arrays.next().expect("rgb");
    Ok(TileResult {
        i,
        j,
        w,
        h,
        values,
        errors,
        products,
        rgb,
    })
}

/// Width and height of tile `(i, j)`.
pub(super) fn tile_size(scene: &Scene, (i, j): (usize, usize)) -> (usize, usize) {
    let t = crate::render::TILE_PX;
    let [w, h] = scene.sensor.pixels;
    (t.min(w - i * t), t.min(h - j * t))
}

/// A part's finished tiles, one file each, written whole.
pub(super) struct TileFiles<'a> {
    pub(super) dir: &'a Path,
    pub(super) digest: &'a str,
    pub(super) bands: usize,
}

impl crate::render::TileSink for TileFiles<'_> {
    fn write(&self, t: &TileResult) -> Result<()> {
        crate::output::write_atomic(
            &tile_path(self.dir, (t.i, t.j)),
            &tile_bytes(t, self.digest, self.bands),
        )
    }
}
