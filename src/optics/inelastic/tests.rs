use super::*;
use crate::rng::Pcg32;

#[test]
fn the_coefficient_follows_bartlett() {
    assert!((raman_coefficient(488.0) - 2.6e-4).abs() < 1e-12);
    // (488 / 400)^5.5 = 2.9848...
    let r = raman_coefficient(400.0) / raman_coefficient(488.0);
    assert!((r - (488.0f64 / 400.0).powf(5.5)).abs() < 1e-12);
    assert!((r - 2.9848).abs() < 1e-3, "{r}");
}

#[test]
fn the_phase_function_is_the_published_one_and_normalised() {
    let rho = RAMAN_DEPOLARISATION;
    let p = raman_phase();
    let published = |mu: f64| {
        3.0 / (16.0 * std::f64::consts::PI) * (1.0 + 3.0 * rho) / (1.0 + 2.0 * rho)
            * (1.0 + (1.0 - rho) / (1.0 + 3.0 * rho) * mu * mu)
    };
    let n = 20_000;
    let mut integral = 0.0;
    for i in 0..n {
        let mu = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
        assert!((p.eval(mu) - published(mu)).abs() < 1e-12 * published(mu).max(1.0));
        integral += 2.0 * std::f64::consts::PI * p.eval(mu) * 2.0 / n as f64;
    }
    assert!((integral - 1.0).abs() < 1e-6, "{integral}");
}

#[test]
fn the_shift_density_is_normalised_and_sampled_as_it_reads() {
    // Integral over 2000..5000 cm^-1 and the mean 3383.75 cm^-1.
    let (mut total, mut first) = (0.0, 0.0);
    let step = 0.5;
    let mut dk = 2000.0;
    while dk < 5000.0 {
        let f = shift_density(dk + 0.5 * step);
        total += f * step;
        first += f * (dk + 0.5 * step) * step;
        dk += step;
    }
    assert!((total - 1.0).abs() < 1e-9, "{total}");
    let mean: f64 = WALRAFEN.iter().map(|&(w, mu, _)| w * mu).sum();
    assert!((mean - 3383.75).abs() < 1e-9);
    assert!((first - mean).abs() < 1e-6, "{first}");
    // Samples: histogram against the density, chi-square over 30 bins.
    let mut rng = Pcg32::new(7, 0);
    let n = 200_000;
    let (lo, hi, bins) = (2800.0, 4000.0, 30);
    let mut counts = vec![0u64; bins];
    for _ in 0..n {
        let x = sample_shift(rng.uniform_f64(), rng.normal());
        if (lo..hi).contains(&x) {
            counts[((x - lo) / (hi - lo) * bins as f64) as usize] += 1;
        }
    }
    let w = (hi - lo) / bins as f64;
    let mut chi2 = 0.0;
    for (i, &c) in counts.iter().enumerate() {
        // Expected count by Simpson's rule over the bin.
        let a = lo + i as f64 * w;
        let p =
            w / 6.0 * (shift_density(a) + 4.0 * shift_density(a + 0.5 * w) + shift_density(a + w));
        let e = p * n as f64;
        chi2 += (c as f64 - e).powi(2) / e;
    }
    // 30 degrees of freedom: the 0.999 quantile is 59.7.
    assert!(chi2 < 59.7, "chi2 {chi2}");
}

/// The closed-form transfer against drawing photons: λ' uniform in the
/// excitation band's cell, Δk from Walrafen's sum, each landing photon
/// weighted by λ'/λ (its energy) times Δ_e / Δ_m.
#[test]
fn the_band_transfer_matches_drawn_photons() {
    let bands = BandGrid::even(400.0, 700.0, 31).unwrap();
    let all = Inelastic::raman(&bands);
    let r = &all.processes[0];
    let cells = &all.cells;
    let nb = bands.len();
    let mut rng = Pcg32::new(11, 0);
    let n = 100_000;
    for e in [0usize, 9, 20] {
        let (lo, hi) = cells[e];
        let mut sum = vec![0.0; nb];
        let mut sum2 = vec![0.0; nb];
        let mut out = 0u64;
        for _ in 0..n {
            let nm = lo + (hi - lo) * rng.uniform_f64();
            let em = emission_nm(nm, sample_shift(rng.uniform_f64(), rng.normal()));
            match cells.iter().position(|&(a, b)| em >= a && em < b) {
                Some(m) => {
                    let x = nm / em * (hi - lo) / (cells[m].1 - cells[m].0);
                    sum[m] += x;
                    sum2[m] += x * x;
                }
                None => out += 1,
            }
        }
        for m in 0..nb {
            let mean = sum[m] / n as f64;
            let se = ((sum2[m] / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
            let t = r.transfer(e, m);
            assert!(
                (t - mean).abs() <= 4.0 * se + 1e-4 * t + 2e-5,
                "e {e} m {m}: closed form {t}, drawn {mean} +- {se}"
            );
        }
        let lost = out as f64 / n as f64;
        let se = (lost * (1.0 - lost) / n as f64).sqrt().max(1.0 / n as f64);
        assert!(
            (r.lost[e] - lost).abs() <= 4.0 * se,
            "e {e}: lost {} against drawn {lost}",
            r.lost[e]
        );
    }
    // 400 nm light lands near 463 nm; 600 nm light near 759 nm, beyond the grid.
    assert!(r.lost[0] < 1e-6 && r.lost[20] > 0.99, "{:?}", r.lost);
}

#[test]
fn bands_fed_from_below_the_grid_say_so() {
    let bands = BandGrid::even(400.0, 700.0, 31).unwrap();
    let all = Inelastic::raman(&bands);
    let r = &all.processes[0];
    // 420 nm is excited near 366 nm, 600 nm near 494 nm.
    assert!(r.missing[2] > 0.999, "{}", r.missing[2]);
    assert!(r.missing[20] < 1e-9, "{}", r.missing[20]);
    // The gain of a band fed from within the grid: b_R at the mean
    // excitation wavelength (498.7 nm for 600 nm), times (λ'/λ)^3: λ'/λ
    // for the energy, (λ'/λ)^2 for the excitation interval that maps onto
    // the band's cell (dλ/dλ' = (λ/λ')^2).
    let ex = 1e7 / (1e7 / 600.0 + 3383.75);
    let expected = raman_coefficient(ex) * (ex / 600.0f64).powi(3);
    let g = r.gain_bound[20];
    assert!((g / expected - 1.0).abs() < 0.03, "{g} against {expected}");
    // The run says which bands lack Raman light.
    let w = all.missing_warnings(bands.centers_nm()).remove(0);
    assert!(
        w.starts_with("water.raman: ")
            && w.contains("from 400.0 to ")
            && w.contains("of their Raman light")
            && w.contains("below the grid's first band, at 395.0 nm"),
        "{w}"
    );
    // A grid that starts low enough lacks nothing it shows.
    let wide = BandGrid::even(350.0, 700.0, 36).unwrap();
    let r = &Inelastic::raman(&wide).processes[0];
    assert!(r.missing[15] < 0.01, "{}", r.missing[15]);
}

#[test]
fn overlapping_bands_share_their_overlap() {
    let bands = BandGrid::explicit(vec![500.0, 505.0, 530.0], vec![10.0, 10.0, 4.0]).unwrap();
    let c = band_cells(&bands);
    assert_eq!(c[0], (495.0, 502.5));
    assert_eq!(c[1], (502.5, 510.0));
    assert_eq!(c[2], (528.0, 532.0));
}

/// Every process's transfer against drawing its events: λ' uniform in
/// the excitation band's cell, the emission drawn by `Kind::sample`, each
/// landing photon weighted by its count times λ'/λ times Δ_e / Δ_m over
/// the band's nominal yield. Bands: 64 from 360 to 800 nm, so that
/// chlorophyll (370-690 nm) and CDOM (310-550 nm) are excited inside and
/// at the ends of their ranges.
#[test]
fn every_process_transfers_what_its_drawn_events_carry() {
    let bands = BandGrid::even(360.0, 800.0, 64).unwrap();
    let all = Inelastic::new(
        &bands,
        &[Kind::Raman, Kind::Chlorophyll, Kind::Cdom],
        CHL_QUANTUM_YIELD,
    );
    let cells = &all.cells;
    let nb = bands.len();
    let mut rng = Pcg32::new(5, 0);
    let n = 100_000;
    for p in &all.processes {
        for e in [1usize, 13, 27, 45] {
            let (lo, hi) = cells[e];
            let nominal = p.nominal[e];
            let mut sum = vec![0.0; nb];
            let mut sum2 = vec![0.0; nb];
            for _ in 0..n {
                let nm = lo + (hi - lo) * rng.uniform_f64();
                let Some((em, count)) = p.kind.sample(nm, &mut rng) else {
                    continue;
                };
                if let Some(m) = cells.iter().position(|&(a, b)| em >= a && em < b) {
                    let x = count * nm / em * (hi - lo) / (cells[m].1 - cells[m].0) / nominal;
                    sum[m] += x;
                    sum2[m] += x * x;
                }
            }
            for m in 0..nb {
                let mean = sum[m] / n as f64;
                // Rare landings (a far tail) may draw no photon at all: the
                // standard error is at least that of a Poisson count of
                // photons of weight about 1.
                let t = p.transfer(e, m);
                let se = ((sum2[m] / n as f64 - mean * mean).max(0.0) / n as f64)
                    .sqrt()
                    .max((t / n as f64).sqrt());
                assert!(
                    (t - mean).abs() <= 4.0 * se + 3e-3 * t,
                    "{:?} e {e} m {m}: closed form {t}, drawn {mean} +- {se}",
                    p.kind
                );
            }
        }
    }
    let chl = all.process(Kind::Chlorophyll).unwrap();
    // The first cell excited only above 370 nm: its share of the cell.
    let (lo, hi) = cells[1];
    assert!((chl.nominal[1] - (hi - 370.0) / (hi - lo)).abs() < 1e-12);
    // Hawes' mean quantum yield over a cell: 1-2 %.
    let cdom = all.process(Kind::Cdom).unwrap();
    assert!(
        cdom.nominal[13] > 0.01 && cdom.nominal[13] < 0.02,
        "{}",
        cdom.nominal[13]
    );
    // Not excited above 690 nm; at 450 nm nearly all of it lands in the grid.
    assert!(chl.scale[50] == 0.0 && chl.scale[13] == CHL_QUANTUM_YIELD);
    // (Only what falls in the f32 rounding gaps between cells is lost.)
    assert!(chl.lost[13] < 1e-5, "{}", chl.lost[13]);
    // The energy of a 450 nm photon's fluorescence: 450 / 685 of it, to
    // within the Gaussian's spread (E[1/λ] = 1/685 (1 + (10.6/685)^2)).
    let (lo, hi) = cells[13];
    let mid = 0.5 * (lo + hi);
    let energy: f64 = (0..nb)
        .map(|m| chl.transfer(13, m) * (cells[m].1 - cells[m].0))
        .sum();
    let expected = mid / 685.0 * (1.0 + (10.6f64 / 685.0).powi(2)) * (hi - lo);
    assert!(
        (energy / expected - 1.0).abs() < 1e-3,
        "{energy} against {expected}"
    );
}

/// Hawes' fulvic acid: its quantum yield at 450 nm is 1.93 % and its
/// emission (per nm) peaks near 1 / (A1/λ' + B1) = 540 nm; it is zero
/// outside 310-550 nm.
#[test]
fn cdom_fluorescence_follows_hawes() {
    let y = Kind::Cdom.photon_yield(450.0);
    assert!((y - 0.0193).abs() < 2e-4, "{y}");
    let peak = (400..700)
        .map(|nm| {
            (
                nm,
                Kind::Cdom
                    .into_interval(450.0, nm as f64, nm as f64 + 1.0)
                    .0,
            )
        })
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a })
        .0;
    assert!((535..=545).contains(&peak), "{peak}");
    assert_eq!(Kind::Cdom.photon_yield(300.0), 0.0);
    assert_eq!(Kind::Cdom.photon_yield(551.0), 0.0);
    // Emission at or below the excitation wavelength is not made.
    assert_eq!(Kind::Cdom.into_interval(450.0, 400.0, 450.0), (0.0, 0.0));
}
