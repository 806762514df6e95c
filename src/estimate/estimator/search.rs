//! The searches of an estimate and its sums: the photons found around a
//! point (k nearest, wrapped at periodic edges), the region the boundaries
//! leave of the search, and the local, expanded and coarse band sums
//! combined by the spectral mode.

use super::*;
use crate::estimate::boundary::vertical_linear_factor;
use crate::scene::settings::POLICY_K_MIN;

/// The two searches of one estimate: the local one and the expanded one.
/// A share s of the scene's searches takes s times their photons within
/// s^(1/3) times their radii (the largest of a nearest search, or the
/// fixed one), the same density of photons in a smaller sphere.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sizes {
    pub(super) local: Search,
    pub(super) big: Search,
    /// Whether the estimate has an expanded search of its own size.
    pub(super) two_sizes: bool,
}

impl Estimator<'_> {
    /// The sizes of an estimate's searches: the scene's, times `share` (in
    /// (0, 1]; exactly the scene's at 1), no count below the search-size
    /// policy's least ([`POLICY_K_MIN`]) unless the scene's is. Without
    /// `two_sizes` the expanded search is the local one.
    pub(super) fn sizes(&self, share: f64, two_sizes: bool) -> Sizes {
        let s = &self.scene.estimate;
        let of = |n: usize| ((n as f64 * share).round() as usize).max(n.min(POLICY_K_MIN));
        let k = of(s.k);
        let k_big = if two_sizes {
            of(s.k_expanded.max(s.k)).max(k)
        } else {
            k
        };
        let reach = share.cbrt() as f32;
        // The expanded search of a fixed radius holds k_big / k times the
        // local one's volume.
        let search = |n: usize| match s.radius_m {
            Some(r) => Search::Radius {
                radius: r as f32 * (n as f32 / k as f32).cbrt() * reach,
            },
            None => Search::Nearest {
                k: n,
                max_radius: Some(s.max_radius_m as f32 * reach),
            },
        };
        Sizes {
            local: search(k),
            big: search(k_big),
            two_sizes,
        }
    }

    /// The radius of the region of `search` of which `found` were found:
    /// the fixed radius, or the farthest photon — or the maximum radius
    /// when fewer than k photons lie within it.
    pub(super) fn region_radius(found: &[Neighbour], search: Search) -> f32 {
        match search {
            Search::Radius { radius } => radius,
            Search::Nearest { k, max_radius } if found.len() < k => max_radius.unwrap_or(f32::MAX),
            Search::Nearest { .. } => found
                .iter()
                .fold(0.0f32, |m, n| m.max(n.distance_sq))
                .sqrt()
                .max(1e-6),
        }
    }

    /// Photons of `layers` for `search` around `x`, in any order,
    /// continued across periodic edges, appended to `found`: with several
    /// layers, the search over their union.
    pub(super) fn find(
        &self,
        x: Vec3,
        layers: &[u16],
        search: Search,
        found: &mut Vec<Neighbour>,
        part: &mut Vec<Neighbour>,
        extra: &mut Vec<Neighbour>,
    ) -> Result<()> {
        let start = found.len();
        for &layer in layers {
            self.map
                .query_any_order_into(x, Some(layer), search, part)?;
            if self.scene.domain.periodic {
                self.wrap_search(x, layer, search, part, extra)?;
            }
            found.extend_from_slice(part);
        }
        let ours = &mut found[start..];
        if let (Search::Nearest { k, .. }, true) = (search, layers.len() > 1) {
            if ours.len() > k {
                ours.select_nth_unstable_by(k - 1, |a, b| a.distance_sq.total_cmp(&b.distance_sq));
                found.truncate(start + k);
            }
        }
        Ok(())
    }

    /// Move the photons of the local search `search` (the k nearest, or
    /// those within its fixed radius) to the front of `found`; returns
    /// their count.
    pub(super) fn take_local(found: &mut [Neighbour], search: Search) -> usize {
        match search {
            Search::Radius { radius } => {
                let r_sq = radius * radius;
                let mut n = 0;
                for i in 0..found.len() {
                    if found[i].distance_sq <= r_sq {
                        found.swap(i, n);
                        n += 1;
                    }
                }
                n
            }
            Search::Nearest { k, .. } => {
                if found.len() > k {
                    found.select_nth_unstable_by(k - 1, |a, b| {
                        a.distance_sq.total_cmp(&b.distance_sq)
                    });
                }
                found.len().min(k)
            }
        }
    }

    /// With periodic domain edges a search sphere that crosses an edge
    /// continues on the far side: the periodic images of `x` are searched
    /// too and their photons merged, moved by the period so that offsets
    /// stay relative to x.
    pub(super) fn wrap_search(
        &self,
        x: Vec3,
        layer: u16,
        search: Search,
        found: &mut Vec<Neighbour>,
        extra: &mut Vec<Neighbour>,
    ) -> Result<()> {
        let r = Self::region_radius(found, search);
        let [lx, ly] = self.scene.domain.size_m.map(|v| v as f32);
        let shift = |c: f32, l: f32| -> f32 {
            if c < r {
                l
            } else if c > l - r {
                -l
            } else {
                0.0
            }
        };
        let (ox, oy) = (shift(x.x, lx), shift(x.y, ly));
        let mut offsets = Vec::with_capacity(3);
        if ox != 0.0 {
            offsets.push(Vec3::new(ox, 0.0, 0.0));
        }
        if oy != 0.0 {
            offsets.push(Vec3::new(0.0, oy, 0.0));
        }
        if ox != 0.0 && oy != 0.0 {
            offsets.push(Vec3::new(ox, oy, 0.0));
        }
        if offsets.is_empty() {
            return Ok(());
        }
        for offset in offsets {
            self.map
                .query_any_order_into(x + offset, Some(layer), search, extra)?;
            found.extend(extra.iter().map(|n| {
                let mut n = *n;
                n.photon.position -= offset;
                n
            }));
        }
        if let Search::Nearest { k, .. } = search {
            if found.len() > k {
                found.select_nth_unstable_by(k - 1, |a, b| a.distance_sq.total_cmp(&b.distance_sq));
                found.truncate(k);
            }
        }
        Ok(())
    }

    /// The searches of an estimate into `found`: the local search is
    /// `found[..n_local]`, of radius `r_local`; the expanded search, of
    /// radius `r_big`, is all of `found` (one search) or `found[n_local..]`
    /// (two layers; `sizes` then has two). Returns (n_local, r_local,
    /// r_big).
    pub(super) fn searches(
        &self,
        x: Vec3,
        classes: Classes,
        sizes: Sizes,
        found: &mut Vec<Neighbour>,
        part: &mut Vec<Neighbour>,
        extra: &mut Vec<Neighbour>,
    ) -> Result<(usize, f32, f32)> {
        let Sizes { local, big, .. } = sizes;
        found.clear();
        Ok(match classes {
            Classes::Union(layers) => {
                self.find(x, layers, big, found, part, extra)?;
                let r_big = Self::region_radius(found, big);
                let n_local = if sizes.two_sizes {
                    Self::take_local(found, local)
                } else {
                    found.len()
                };
                let r_local = if sizes.two_sizes {
                    Self::region_radius(&found[..n_local], local)
                } else {
                    r_big
                };
                (n_local, r_local, r_big)
            }
            Classes::Split { light, heavy } => {
                self.find(x, &[light], local, found, part, extra)?;
                let n_local = found.len();
                let r_local = Self::region_radius(found, local);
                self.find(x, &[heavy], big, found, part, extra)?;
                (
                    n_local,
                    r_local,
                    Self::region_radius(&found[n_local..], big),
                )
            }
        })
    }

    /// The squared distances from which photons are left out of the local
    /// and the expanded sums: a search that stopped at its k-th photon has
    /// that photon on its edge, and the k - 1 inside it are what its volume
    /// holds. With Poisson-distributed photons of density λ the volume V of
    /// the k-th neighbour's sphere is Gamma(k, 1/λ) distributed, so that
    /// E[(k - 1)/V] = λ while counting all k gives λ k/(k - 1): +3 % at
    /// k = 32. A search that reached its radius (fixed, or the maximum with
    /// fewer than k found) has no photon on its edge and keeps all.
    fn search_edges(
        &self,
        found: &[Neighbour],
        n_local: usize,
        sizes: Sizes,
        by_layer: bool,
    ) -> (f32, f32) {
        let (Search::Nearest { k, .. }, Search::Nearest { k: k_big, .. }) =
            (sizes.local, sizes.big)
        else {
            return (f32::INFINITY, f32::INFINITY);
        };
        let edge = |set: &[Neighbour], k: usize| {
            if set.len() >= k {
                set.iter().fold(0.0f32, |m, n| m.max(n.distance_sq))
            } else {
                f32::INFINITY
            }
        };
        let local = edge(&found[..n_local], k);
        let big = if by_layer {
            edge(&found[n_local..], k_big)
        } else {
            edge(found, k_big)
        };
        (local, big)
    }

    /// The search region around `x` out to `r_outer`, cut by the boundaries
    /// as the compensation mode says: a volume's axial distances, or on a
    /// surface the disc's.
    pub(super) fn region(
        &self,
        x: Vec3,
        surface: Option<(Vec3, SurfaceId)>,
        r_outer: f32,
    ) -> Region {
        let mode = self.boundary;
        match surface {
            None => Region::Volume(match (mode, &self.grid) {
                (BoundaryMode::None, _) => AxialDistances::unbounded(r_outer),
                (_, Some(grid)) => grid.distances(x, r_outer),
                (_, None) => boundary::axial_distances_traced(self.scene, x, r_outer),
            }),
            Some((normal, id)) => Region::Disc(match mode {
                BoundaryMode::None => DiscDistances::unbounded(r_outer, normal),
                _ => boundary::disc_distances_traced(self.scene, x, normal, id, r_outer),
            }),
        }
    }

    /// The searches of one estimate and its sums. With [`Classes::Union`]
    /// one search serves both sizes: the expanded search (or the local one
    /// alone when only one size is needed) is found, its nearest photons
    /// are the local search, and volume estimates count the photons
    /// travelling toward the viewer's hemisphere (`weight` returns them as
    /// heavy) at the expanded scale. With [`Classes::Split`] the two
    /// classes are two layers, each searched for its own count. Either way
    /// the boundaries are traced once, at the larger radius: through the
    /// phase function's forward lobe a few photons travelling toward the
    /// viewer carry most of the in-scatter (upwelling light seen looking
    /// down rests on the few photons travelling up), and a local search of
    /// k holds too few of them for a steady estimate. The searches take
    /// `share` of the scene's ([`Sizes`]).
    ///
    /// One function of about 150 lines, the estimator's inner loop: one
    /// pass over the neighbours feeds six sums held in the scratch (local,
    /// coarse and expanded, each per band and per photon group), which the
    /// combination then reads; split apart, each piece would take the same
    /// dozen buffers.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn estimate(
        &self,
        x: Vec3,
        classes: Classes,
        weight: &impl PhotonWeight,
        surface: Option<(Vec3, SurfaceId)>,
        view: Option<ShapeView>,
        share: f64,
        scratch: &mut Scratch,
        out: &mut [f64],
    ) -> Result<()> {
        let Scratch {
            found,
            part,
            extra,
            local,
            expanded,
            coarse,
            shape,
            group_local,
            group_coarse,
            group_expanded,
            shape_groups,
            bin_sums,
            bin_views,
            bin_shape,
            inelastic,
            phase_density,
            elastic_density,
            ..
        } = scratch;
        // Inelastic weights for volume estimates of a scene with inelastic
        // light.
        let with_inelastic = self.inelastic.is_some() && surface.is_none();
        if with_inelastic {
            inelastic.iter_mut().for_each(BandSums::clear);
        }
        let nb = self.scene.bands.len();
        debug_assert!(out.len() == nb || out.len() == CHANNELS * nb);
        let with_groups = out.len() == CHANNELS * nb;
        let (out, out_groups) = out.split_at_mut(nb);
        out_groups.iter_mut().for_each(|o| *o = 0.0);
        let compensated = self.spectral != SpectralMode::Naive;
        let split = surface.is_none();
        let by_layer = matches!(classes, Classes::Split { .. });
        let two_sizes = compensated || split;
        let sizes = self.sizes(share, two_sizes);
        let (n_local, r_local, r_big) = self.searches(x, classes, sizes, found, part, extra)?;
        let (local_edge, big_edge) = self.search_edges(found, n_local, sizes, by_layer);
        if found.is_empty() {
            out.iter_mut().for_each(|o| *o = 0.0);
            return Ok(());
        }
        let mode = self.boundary;
        let r_outer = r_local.max(r_big);
        let outer = self.region(x, surface, r_outer);
        let small = outer.capped(r_local);
        let big = outer.capped(r_big);
        // The band shape from the grid, where the grid mode has one here:
        // a fixed view's now; the direction bins' once their weights are
        // summed below.
        let binned = self.shapes.is_some() && matches!(view, Some(ShapeView::Binned));
        let mut has_shape = match (&self.shapes, view) {
            (Some(grid), Some(ShapeView::Fixed(view))) => grid.shape_and_groups_at(
                x,
                view,
                shape,
                with_groups.then_some(&mut shape_groups[..]),
            ),
            _ => false,
        };
        if binned {
            *bin_sums = [[0.0; DIRECTION_BINS]; 2];
        }
        // Group sums: totals always, per band where the combination reads
        // bands (naive: local and coarse; compensated: expanded, unless a
        // shape is found).
        if with_groups {
            group_local.clear(!compensated);
            group_coarse.clear(!compensated);
            group_expanded.clear(compensated && !has_shape);
        }
        // Photons on other surfaces (a target's side, the far side of a thin
        // panel) are not on this one; they still bound the search, whose
        // radius comes from every photon found.
        let plane = surface.map(|(normal, _)| (normal, PLANE_TOLERANCE * r_outer + 0.005));
        local.clear();
        expanded.clear();
        coarse.clear();
        // The weight and its vertical first moment at each scale, for the
        // local-linear level (`vertical_linear_factor`).
        let (mut moments_local, mut moments_big) = ([0.0f64; 2], [0.0f64; 2]);
        for (i, n) in found.iter().enumerate() {
            let offset = n.photon.position - x;
            if plane.is_some_and(|(normal, tol)| offset.dot(normal).abs() > tol) {
                continue;
            }
            let is_local = i < n_local;
            let in_local =
                is_local && n.distance_sq < local_edge && small.accepts(mode, offset, r_local);
            let in_big = n.distance_sq < big_edge
                && if by_layer {
                    !is_local && big.accepts(mode, offset, r_big)
                } else {
                    two_sizes && big.accepts(mode, offset, r_big)
                };
            if !(in_local || in_big) {
                continue;
            }
            let (w, toward, w_phases) = weight(n);
            // Counted at the expanded scale: the heavy layer's photons, or
            // in one search those travelling toward the viewer.
            let heavy = if by_layer { !is_local } else { split && toward };
            let (band, group) = (n.photon.band, n.photon.group);
            if with_inelastic {
                // [Raman, isotropic, elastic] local, then expanded.
                let at = if in_local && !heavy {
                    Some(0)
                } else if in_big && heavy {
                    Some(INELASTIC_SLOTS)
                } else {
                    None
                };
                if let Some(k) = at {
                    inelastic[k].add(band, w_phases[0]);
                    inelastic[k + 1].add(band, w_phases[1]);
                    inelastic[k + 2].add(band, w);
                }
            }
            // An oblique estimate's weights per direction bin: [local,
            // expanded], as the level counts them.
            let counted = [in_local && !heavy, in_big && heavy];
            if binned && (counted[0] || counted[1]) {
                let scale = usize::from(!counted[0]);
                bin_sums[scale][direction_bin(n.photon.direction, self.sun_w)] += w;
            }
            if in_local && !heavy {
                moments_local[0] += w;
                moments_local[1] += w * f64::from(offset.z);
                local.add(band, w);
                if with_groups {
                    group_local.add(group, band, w);
                }
            }
            // Two layers: the expanded band sums (a shape where the grid
            // has none) take every photon counted.
            if in_big || by_layer {
                moments_big[0] += w;
                moments_big[1] += w * f64::from(offset.z);
                expanded.add(band, w);
                if with_groups {
                    group_expanded.add(group, band, w);
                }
            }
            if in_big && heavy {
                coarse.add(band, w);
                if with_groups {
                    group_coarse.add(group, band, w);
                }
            }
        }
        // The clipped sphere's volume, over the local-linear factor where
        // a vertical boundary cuts it.
        let size = |region: &Region, r: f32, [s0, s1]: [f64; 2]| {
            let v = region.size(mode, r);
            match (mode, region) {
                (BoundaryMode::ClippedSphere, Region::Volume(b)) if s0 > 0.0 => {
                    v / vertical_linear_factor(f64::from(r), b, s1 / s0)
                }
                _ => v,
            }
        };
        let v_local = size(&small, r_local, moments_local);
        if v_local <= 0.0 {
            out.iter_mut().for_each(|o| *o = 0.0);
            return Ok(());
        }
        let v_big = if two_sizes {
            size(&big, r_big, moments_big)
        } else {
            0.0
        };
        if with_inelastic {
            // Each scale's sums over its own volume, as the naive estimate
            // counts them.
            let v_big = if v_big > 0.0 { v_big } else { f64::INFINITY };
            let [rl, il, el, rb, ib, eb] = inelastic.each_ref().map(BandSums::sums);
            let [raman_density, iso_density] = phase_density;
            for e in 0..nb {
                raman_density[e] = rl[e] / v_local + rb[e] / v_big;
                iso_density[e] = il[e] / v_local + ib[e] / v_big;
                elastic_density[e] = el[e] / v_local + eb[e] / v_big;
            }
        }
        if binned {
            // Each bin weighs in as its photons' density toward the viewer.
            let v_big = if v_big > 0.0 { v_big } else { f64::INFINITY };
            let base = Self::fixed_views(self.scene);
            bin_views.clear();
            bin_views.extend(
                (0..DIRECTION_BINS)
                    .map(|d| (base + d, bin_sums[0][d] / v_local + bin_sums[1][d] / v_big)),
            );
            has_shape = self.shapes.as_ref().is_some_and(|g| {
                g.mixed_shape_and_groups_at(
                    x,
                    bin_views,
                    shape,
                    with_groups.then_some(&mut shape_groups[..]),
                    bin_shape,
                )
            });
        }
        let groups = with_groups.then_some(Groups {
            local: group_local,
            coarse: group_coarse,
            expanded: group_expanded,
            out: out_groups,
        });
        if has_shape {
            combine_with_shape(
                local,
                v_local,
                coarse,
                expanded,
                v_big,
                Some(&shape[..]),
                out,
            );
            if let Some(g) = groups {
                g.shape(v_local, v_big, shape, shape_groups, out);
            }
        } else if split {
            // Without a grid shape here, `grid` combines as `compensated`.
            combine_with_coarse(self.spectral, local, v_local, coarse, expanded, v_big, out);
            if let Some(g) = groups {
                g.ratio(self.spectral, v_local, v_big, true, expanded, out);
            }
        } else {
            combine(self.spectral, local, v_local, expanded, v_big, out);
            if let Some(g) = groups {
                g.ratio(self.spectral, v_local, v_big, false, expanded, out);
            }
        }
        Ok(())
    }
}
