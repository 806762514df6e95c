//! One memory budget (`--mem-budget`) split between the stages that hold
//! memory: the sort writer while emitting; the renderer's own buffers (the
//! reserve), the boundary-distance grid and the tile cache while rendering.
//!
//! **Emission.** The sort writer gets the whole budget; its fixed needs
//! (zstd contexts, I/O buffers, channel, spill metadata) are inside it
//! (`store::writer::WRITER_FIXED_BYTES`). The map's tile layout depends on
//! this share, so it is the budget itself, as it always was.
//!
//! **Rendering.** The reserve is computed from what the renderer allocates
//! besides the cache and the grid, not guessed:
//! - the geometry (BVH and triangle tables), which lives through the run;
//! - the image-sized buffers: the quicklook's RGB image and the RGB tiles
//!   collected for it (2 x 12 bytes per pixel);
//! - the spectral OpenEXR, written as tiles finish: its tiles
//!   (`cube::exr::tile_px`) of every band of every layer (radiance,
//!   standard error, products) in progress or finished ahead of a slower
//!   one (those meeting the `render::dispatch_window` image tiles past the
//!   oldest unfinished one, one more at each end), those waiting for the
//!   writer (`cube::exr::CHANNEL_TILES`), and per worker the chunks of one
//!   being compressed; no more than the image has;
//! - per worker: one 16 x 16 image tile of every band (f32), the
//!   estimator's neighbour lists (two of `k_expanded` neighbours of 36
//!   bytes) and the query's packed candidates (28 bytes each), and three
//!   band accumulators;
//! - a fixed [`RUNTIME_RESERVE`] for what no buffer size shows: the
//!   process baseline (binary, libc, allocator metadata) and the per-thread
//!   allocator arenas and stacks. Measured as the peak anonymous resident
//!   memory (RssAnon, sampled every 0.5 ms from outside the process) of
//!   `littoral render` of a 16 x 16 pixel, 128-band scene from a 1-photon
//!   map, where every other term is negligible: 1.2 MiB with one or two
//!   threads. 4 MiB leaves room for allocator fragmentation.
//!
//! Check of the whole reserve (built-in scene at 64 x 64 pixels of 3 m,
//! 128 bands, 300 k photons, 2 threads, `--mem-budget 64MiB`, map reused):
//! peak RssAnon 26.0 MiB, of which the tile cache held at most 18.0 MiB;
//! the other 8.0 MiB are inside the computed reserve of 10.7 MiB.
//!
//! The rest goes to the boundary grid (when the scene asks for one) and
//! then the tile cache; a budget that leaves the cache nothing is refused
//! before any photon is traced.

use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::store::BuildOptions;

const MIB: u64 = 1 << 20;

/// Process baseline and per-thread allocator overhead (see the module notes).
pub const RUNTIME_RESERVE: u64 = 4 * MIB;

/// A run's memory budget in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    total: u64,
}

/// How a render's budget is shared out (bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct RenderShares {
    /// The whole budget.
    pub budget_bytes: u64,
    /// The renderer's own buffers, the geometry and the runtime.
    pub reserve_bytes: u64,
    /// The boundary-distance grid (0 without one).
    pub boundary_grid_bytes: u64,
    /// The band-shape grid of `spectral = "grid"` (0 without one; sized
    /// once the map's photon count is known, and taken from the tile cache).
    #[serde(default)]
    pub band_shape_grid_bytes: u64,
    /// The tile cache: everything left.
    pub tile_cache_bytes: u64,
}

impl RenderShares {
    /// Take `bytes` for the band-shape grid from the tile cache's share.
    pub fn take_band_shape_grid(&mut self, bytes: u64) -> Result<()> {
        if bytes >= self.tile_cache_bytes {
            return Err(Error::Budget {
                budget: self.budget_bytes,
                what: format!(
                    "the band-shape grid ([estimate] spectral = \"grid\") needs {bytes} bytes, leaving nothing for the tile cache"
                ),
            });
        }
        self.band_shape_grid_bytes = bytes;
        self.tile_cache_bytes -= bytes;
        Ok(())
    }
}

impl MemoryBudget {
    /// A budget of `total` bytes.
    pub fn new(total: u64) -> Self {
        MemoryBudget { total }
    }

    /// Parse a size such as `512MiB` given for the flag or key `field`.
    pub fn parse(field: &str, text: &str) -> Result<Self> {
        Ok(Self::new(crate::size::parse_size(field, text)?))
    }

    /// The whole budget in bytes.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// Build options of the sort writer: the whole budget.
    pub fn emission(&self, threads: usize) -> BuildOptions {
        BuildOptions {
            threads,
            ..BuildOptions::with_budget(self.total)
        }
    }

    /// The renderer's own needs for `scene` with `threads` workers (0 = one
    /// per core), in bytes: under an atmosphere its sky and columns, and
    /// with a sensor above the surface the air view's tables and shared
    /// paths, among them.
    pub fn render_reserve(scene: &Scene, threads: usize) -> u64 {
        let nb = scene.bands.len() as u64;
        let [w, h] = scene.sensor.pixels.map(|p| p as u64);
        let image = 2 * 12 * w * h;
        let tile = (crate::render::TILE_PX * crate::render::TILE_PX) as u64 * nb * 4;
        let k = scene.estimate.k_expanded.max(scene.estimate.k) as u64;
        let neighbours = k * (2 * 36 + 28);
        let sums = 3 * nb * 16;
        let workers = crate::parallel::workers(threads) as u64;
        let layers = 2 + crate::render::products(scene).len() as u64;
        let side = crate::cube::exr::tile_px(scene.render.exr_compression) as u64;
        let per_exr_tile = (side / crate::render::TILE_PX as u64).pow(2);
        let window = crate::render::dispatch_window(workers as usize) as u64;
        let exr_tiles =
            (window.div_ceil(per_exr_tile) + 2 + crate::cube::exr::CHANNEL_TILES as u64 + workers)
                .min(w.div_ceil(side) * h.div_ceil(side));
        let exr_px = side * side;
        let exr = exr_tiles * layers * exr_px * nb * 4;
        RUNTIME_RESERVE
            + scene.geometry.heap_bytes()
            + crate::render::air::AirView::reserve_bytes(scene)
            + scene.atmosphere.as_ref().map_or(0, |a| a.heap_bytes())
            + image
            + exr
            + workers * (tile + neighbours + sums)
    }

    /// Shares of a render of `scene` with `threads` workers; an error if the
    /// budget cannot hold the reserve and the grid with room for a cache.
    pub fn render(&self, scene: &Scene, threads: usize) -> Result<RenderShares> {
        let reserve = Self::render_reserve(scene, threads);
        let grid = crate::estimate::Estimator::grid_bytes(scene)?;
        let fixed = reserve.saturating_add(grid);
        if fixed >= self.total {
            return Err(Error::Budget {
                budget: self.total,
                what: if grid > 0 {
                    format!(
                        "the renderer needs {reserve} bytes and the boundary grid ([estimate] boundary_grid_m) {grid}, leaving nothing for the tile cache"
                    )
                } else {
                    format!(
                        "the renderer needs {reserve} bytes for its buffers, leaving nothing for the tile cache"
                    )
                },
            });
        }
        Ok(RenderShares {
            budget_bytes: self.total,
            reserve_bytes: reserve,
            boundary_grid_bytes: grid,
            band_shape_grid_bytes: 0,
            tile_cache_bytes: self.total - fixed,
        })
    }
}

#[cfg(test)]
mod tests;
