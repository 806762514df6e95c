//! The ground's classes within the domain for the air view's control
//! variate: the land, and the water by the depth of the floor under it.
//!
//! Each class has its own table of the mean radiance leaving it, so what
//! a path meeting the ground adds by an integrator call is its difference
//! from a table of ground like its own. In the red, water over sand half a
//! metre down leaves ten times the radiance of water 4 m deep and a
//! hundred times that of deep water, so the water's classes double in
//! depth: their floors lie between `FIRST_EDGE_M` × 2^k metres. An edge
//! is kept only where both sides hold at least [`MIN_SHARE`] of the water.

use super::Class;
use crate::scene::Scene;
use glam::DVec3;
use rayon::prelude::*;

/// Cells per side of the grid of classes over the domain.
const GRID: usize = 512;

/// The shallowest floor depth between two water classes (m); each next
/// one is twice as deep.
const FIRST_EDGE_M: f32 = 0.5;

/// Edges between water classes, at most (0.5 m to 64 m).
const EDGES: i32 = 8;

/// The least share of the water a class keeps.
const MIN_SHARE: f64 = 0.02;

/// The code of the land in the grid.
const LAND: u8 = u8::MAX;

/// Bins of floor depth within each water class, of equal shares of it:
/// the control's table for a class is scaled per bin and band by what the
/// table's calls met there (`render::air`, "Water by the depth of its
/// floor").
pub(super) const BINS: usize = 8;

/// The classes of the ground within the domain, on a grid of `GRID`^2
/// cells: the class of a point is its cell's, taken at the cell's centre.
pub(super) struct Classes {
    size_m: [f64; 2],
    /// Per cell (rows of increasing y): the water's class, or `LAND`.
    grid: Vec<u8>,
    /// Per cell: its depth bin within its water class (0 on land).
    bins: Vec<u8>,
    /// Per water class: its share of the domain.
    pub water_share: Vec<f64>,
    /// The land's share of the domain (0 without land).
    pub land_share: f64,
}

impl Classes {
    /// The classes of `scene`'s domain.
    pub fn new(scene: &Scene) -> Classes {
        let [sx, sy] = scene.domain.size_m;
        let n = GRID;
        // The floor's depth at each cell's centre (+inf without a floor),
        // -inf on land.
        let depths: Vec<f32> = (0..n * n)
            .into_par_iter()
            .map(|k| {
                let x = (((k % n) as f64 + 0.5) * sx / n as f64) as f32;
                let y = (((k / n) as f64 + 0.5) * sy / n as f64) as f32;
                match scene.geometry.floor_depth_at(x, y) {
                    Some(d) if d < 0.0 && scene.land.is_some() => f32::NEG_INFINITY,
                    Some(d) => d,
                    None => f32::INFINITY,
                }
            })
            .collect();
        let water: Vec<f32> = depths
            .iter()
            .copied()
            .filter(|d| *d > f32::NEG_INFINITY)
            .collect();
        let count = |lo: f32, hi: f32| water.iter().filter(|&&d| d >= lo && d < hi).count();
        // Edges doubling in depth, each kept where the class above it (since
        // the last kept edge) and all the water below it hold enough.
        let least = (MIN_SHARE * water.len() as f64).max(1.0) as usize;
        let mut edges: Vec<f32> = Vec::new();
        for k in 0..EDGES {
            let e = FIRST_EDGE_M * 2f32.powi(k);
            let lo = edges.last().copied().unwrap_or(f32::NEG_INFINITY);
            if count(lo, e) >= least && count(e, f32::INFINITY) >= least {
                edges.push(e);
            }
        }
        let cell = |d: f32| -> u8 {
            if d == f32::NEG_INFINITY {
                LAND
            } else {
                edges.partition_point(|&e| e <= d) as u8
            }
        };
        let grid: Vec<u8> = depths.iter().map(|&d| cell(d)).collect();
        // Each class's depths at the quantiles that split it into `BINS`.
        let mut by_class: Vec<Vec<f32>> = vec![Vec::new(); edges.len() + 1];
        for (&c, &d) in grid.iter().zip(&depths) {
            if c != LAND {
                by_class[usize::from(c)].push(d);
            }
        }
        let quantiles: Vec<Vec<f32>> = by_class
            .into_iter()
            .map(|mut v| {
                v.sort_by(f32::total_cmp);
                (1..BINS)
                    .map(|j| v.get(j * v.len() / BINS).copied().unwrap_or(f32::INFINITY))
                    .collect()
            })
            .collect();
        let bins: Vec<u8> = grid
            .iter()
            .zip(&depths)
            .map(|(&c, &d)| match c {
                LAND => 0,
                k => quantiles[usize::from(k)].partition_point(|&e| e <= d) as u8,
            })
            .collect();
        let unit = 1.0 / (n * n) as f64;
        let mut water_share = vec![0.0; edges.len() + 1];
        let mut land_share = 0.0;
        for &c in &grid {
            match c {
                LAND => land_share += unit,
                k => water_share[k as usize] += unit,
            }
        }
        Classes {
            size_m: [sx, sy],
            grid,
            bins,
            water_share,
            land_share,
        }
    }

    /// The class of the ground at `p` (within the domain; outside it, the
    /// nearest cell's).
    pub fn of(&self, p: DVec3) -> Class {
        self.at(p).0
    }

    /// The class of the ground at `p` as [`Classes::of`] gives it, and its
    /// depth bin within a water class (0 on land).
    pub fn at(&self, p: DVec3) -> (Class, usize) {
        let n = GRID;
        let i = ((p.x / self.size_m[0] * n as f64) as isize).clamp(0, n as isize - 1) as usize;
        let j = ((p.y / self.size_m[1] * n as f64) as isize).clamp(0, n as isize - 1) as usize;
        let bin = usize::from(self.bins[j * n + i]);
        match self.grid[j * n + i] {
            LAND => (Class::Land, 0),
            k => (Class::Water(usize::from(k)), bin),
        }
    }

    /// The bytes of the grids.
    pub fn bytes(&self) -> u64 {
        (self.grid.len() + self.bins.len()) as u64
    }

    /// The number of water classes.
    pub fn waters(&self) -> usize {
        self.water_share.len()
    }
}
