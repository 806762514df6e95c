use super::*;
use crate::rng::Pcg32;
use crate::testing::{chi_square_critical, simpson};
use std::f64::consts::FRAC_PI_2;
use std::sync::OnceLock;

/// Samples per Monte Carlo check.
const SAMPLES: usize = 200_000;
/// Quadrature grid in x = 1 - mu: nodes 2^(j/40 - 50), j = 0..=2040, so
/// x = 1 (mu = 0) is node 2000 and the forward peaks are resolved down to
/// x = 2^-50.
const GRID_PER_OCTAVE: usize = 40;
const GRID_OCTAVES_BELOW_ONE: usize = 50;
const GRID_INTERVALS: usize = GRID_PER_OCTAVE * (GRID_OCTAVES_BELOW_ONE + 1);
const GRID_MU_ZERO: usize = GRID_PER_OCTAVE * GRID_OCTAVES_BELOW_ONE;

fn cases() -> Vec<(&'static str, PhaseFunction)> {
    let hg = |g| PhaseFunction::henyey_greenstein(g).unwrap();
    let ff = |b| PhaseFunction::fournier_forand(b).unwrap();
    vec![
        ("isotropic", PhaseFunction::isotropic()),
        ("HG g=0", hg(0.0)),
        ("HG g=1e-4", hg(1e-4)),
        ("HG g=0.5", hg(0.5)),
        ("HG g=0.9", hg(0.9)),
        ("HG g=-0.3", hg(-0.3)),
        ("HG g=-0.8", hg(-0.8)),
        (
            "Rayleigh q=0.835",
            PhaseFunction::rayleigh(RAYLEIGH_Q_WATER).unwrap(),
        ),
        ("FF B=0.0183", ff(0.0183)),
        ("FF B=0.01", ff(0.01)),
        ("FF B=0.1", ff(0.1)),
        ("FF B=0.001", ff(0.001)),
        ("FF B=1e-4", ff(1e-4)),
        ("Petzold", PhaseFunction::petzold()),
        (
            "user table",
            PhaseFunction::tabulated(
                &[0.0, 30.0, 90.0, 150.0, 180.0],
                &[10.0, 4.0, 1.0, 0.5, 0.8],
                "t",
            )
            .unwrap(),
        ),
        (
            "user table, partial range",
            PhaseFunction::tabulated(&[10.0, 45.0, 170.0], &[5.0, 1.0, 2.0], "t").unwrap(),
        ),
    ]
}

/// The density integrated independently of the samplers: over the grid
/// intervals in w = ln(1 - mu) (where forward peaks are smooth), plus
/// the cap x < 2^-50 as the power law p ~ x^s fitted to p at 2^-50 and 2^-49.
struct Profile {
    /// x = 1 - mu at the grid nodes, increasing from 2^-50 to 2.
    x: Vec<f64>,
    /// 2 pi int p dmu over each interval.
    mass: Vec<f64>,
    /// 2 pi int mu p dmu over each interval.
    moment: Vec<f64>,
    /// Mass of the cap x < 2^-50.
    cap: f64,
}

impl Profile {
    fn new(pf: &PhaseFunction) -> Self {
        let x: Vec<f64> = (0..=GRID_INTERVALS)
            .map(|j| 2f64.powf(j as f64 / GRID_PER_OCTAVE as f64 - GRID_OCTAVES_BELOW_ONE as f64))
            .collect();
        let integrate = |weight: &dyn Fn(f64) -> f64| -> Vec<f64> {
            // dmu = -x dw. p is evaluated at x itself: a cosine near 1 would
            // round to a staircase in x that biases the sum by ~1e-8.
            let f = |w: f64| {
                let x = w.exp();
                TWO_PI * pf.eval_one_minus_cos(x) * weight(1.0 - x) * x
            };
            x.windows(2)
                .map(|pair| simpson(&f, pair[0].ln(), pair[1].ln(), 1e-16))
                .collect()
        };
        let mass = integrate(&|_| 1.0);
        let moment = integrate(&|mu| mu);
        let x0 = x[0];
        let (p0, p1) = (pf.eval_one_minus_cos(x0), pf.eval_one_minus_cos(2.0 * x0));
        let s = (p1 / p0).log2();
        let cap = TWO_PI * p0 * x0 / (s + 1.0);
        Profile {
            x,
            mass,
            moment,
            cap,
        }
    }

    fn total(&self) -> f64 {
        self.mass.iter().sum::<f64>() + self.cap
    }

    fn mean_cos(&self) -> f64 {
        // In the cap mu = 1 to within 2^-50.
        self.moment.iter().sum::<f64>() + self.cap
    }

    fn backscatter(&self) -> f64 {
        self.mass[GRID_MU_ZERO..].iter().sum()
    }
}

fn profiles() -> &'static [(&'static str, PhaseFunction, Profile)] {
    static PROFILES: OnceLock<Vec<(&'static str, PhaseFunction, Profile)>> = OnceLock::new();
    PROFILES.get_or_init(|| {
        cases()
            .into_iter()
            .map(|(name, pf)| {
                let profile = Profile::new(&pf);
                (name, pf, profile)
            })
            .collect()
    })
}

/// Pearson chi-square of SAMPLES draws of `sample_cos` against the density.
/// Bins hold about 1/100 of the probability each: grid intervals are
/// gathered from the back (x = 2) forward until each bin reaches 1/100;
/// the last bin takes the rest and the cap (every draw that rounds to
/// mu = 1). Bins expecting fewer than 5 draws are merged. Returns
/// (chi2, degrees of freedom).
fn chi_square(pf: &PhaseFunction, profile: &Profile, seed: u64) -> (f64, usize) {
    const TARGET: f64 = 0.01;
    let total = profile.total();
    // Bin b holds x in [edges[b+1], edges[b]); edges decrease from 2 to 0.
    let mut edges = vec![2.0];
    let mut probs = Vec::new();
    let mut acc = 0.0;
    for j in (0..GRID_INTERVALS).rev() {
        acc += profile.mass[j] / total;
        if acc >= TARGET {
            edges.push(profile.x[j]);
            probs.push(acc);
            acc = 0.0;
        }
    }
    probs.push(acc + profile.cap / total);
    edges.push(0.0);
    // Merge bins expecting fewer than 5 draws into their backward neighbour.
    let min_prob = 5.0 / SAMPLES as f64;
    let mut b = probs.len();
    while b > 1 {
        b -= 1;
        if probs[b] < min_prob {
            probs[b - 1] += probs[b];
            probs.remove(b);
            edges.remove(b);
        }
    }
    let mut counts = vec![0u64; probs.len()];
    let mut rng = Pcg32::new(seed, 0);
    for _ in 0..SAMPLES {
        let x = 1.0 - pf.sample_cos(rng.uniform_f64());
        let bin = edges[1..].partition_point(|&e| e > x).min(probs.len() - 1);
        counts[bin] += 1;
    }
    let chi2 = counts
        .iter()
        .zip(&probs)
        .map(|(&c, &p)| {
            let e = p * SAMPLES as f64;
            (c as f64 - e).powi(2) / e
        })
        .sum();
    (chi2, probs.len() - 1)
}

/// Physical fact: every phase function integrates to 1 over the sphere.
/// The quadrature is independent of the closed forms used for sampling
/// and good to about 1e-14 on the grid; the power-law fit of the cap below
/// 2^-50 adds up to 8e-10 (FF at B = 1e-4, whose cap holds 37 % of the
/// probability), hence the tolerance of 2e-9.
#[test]
fn every_phase_function_integrates_to_one() {
    for (name, _, profile) in profiles() {
        let total = profile.total();
        eprintln!("{name}: integral {total:.15}");
        assert!((total - 1.0).abs() < 2e-9, "{name}: integral {total}");
    }
}

/// Chi-square goodness of fit of `sample_cos` against the density, at the
/// p = 0.001 critical value: a correct sampler fails one case in 1000.
#[test]
fn samplers_pass_chi_square() {
    let mut failures = Vec::new();
    for (i, (name, pf, profile)) in profiles().iter().enumerate() {
        let (chi2, dof) = chi_square(pf, profile, 1000 + i as u64);
        let critical = chi_square_critical(dof);
        eprintln!("{name}: chi2 {chi2:.1} dof {dof} critical {critical:.1}");
        if chi2 >= critical {
            failures.push(format!("{name}: chi2 {chi2} >= {critical} (dof {dof})"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The sample mean of sample_cos agrees with mean_cosine() within 4
/// standard errors (sample standard deviation / sqrt(N)), and
/// mean_cosine() agrees with the independent quadrature.
#[test]
fn sample_mean_cosine_within_four_standard_errors() {
    for (i, (name, pf, profile)) in profiles().iter().enumerate() {
        let g = pf.mean_cosine();
        let quadrature = profile.mean_cos();
        assert!(
            (g - quadrature).abs() < 1e-9,
            "{name}: mean_cosine {g} vs quadrature {quadrature}"
        );
        let mut rng = Pcg32::new(77, i as u64);
        let (mut sum, mut sum_sq) = (0.0, 0.0);
        for _ in 0..SAMPLES {
            let mu = pf.sample_cos(rng.uniform_f64());
            sum += mu;
            sum_sq += mu * mu;
        }
        let n = SAMPLES as f64;
        let mean = sum / n;
        let se = ((sum_sq / n - mean * mean) / (n - 1.0)).sqrt();
        eprintln!(
            "{name}: g {g:.9}, sample mean {mean:.6}, {:.2} se",
            (mean - g) / se
        );
        assert!(
            (mean - g).abs() < 4.0 * se,
            "{name}: {mean} vs {g}, se {se}"
        );
    }
}

/// backscatter_fraction() agrees with the independent quadrature over mu < 0.
#[test]
fn backscatter_fraction_matches_quadrature() {
    for (name, pf, profile) in profiles() {
        let (b, quadrature) = (pf.backscatter_fraction(), profile.backscatter());
        assert!(
            (b - quadrature).abs() < 1e-10,
            "{name}: {b} vs quadrature {quadrature}"
        );
    }
}

/// sample_cos is non-decreasing in u and stays in [-1, 1], from u = 0 to
/// the largest u below 1 that uniform_f64 produces.
#[test]
fn samplers_are_monotone_and_in_range() {
    let mut us: Vec<f64> = (0..=4000).map(|i| i as f64 / 4001.0).collect();
    us.extend([1.0 - 1e-9, 1.0 - 1e-12, 1.0 - f64::EPSILON / 2.0]);
    for (name, pf) in cases() {
        let mut prev = -1.0;
        for &u in &us {
            let mu = pf.sample_cos(u);
            assert!((-1.0..=1.0).contains(&mu), "{name}: u {u} gave {mu}");
            assert!(mu >= prev - 1e-12, "{name}: not monotone at u {u}");
            prev = mu;
        }
    }
}

/// The two exact HG inversions agree where they meet.
#[test]
fn hg_inversions_agree() {
    for g in [0.2, 0.5, 0.7, -0.5] {
        for i in 0..=100 {
            let u = i as f64 / 100.0;
            let (a, b) = (hg_sample_cos_expanded(g, u), hg_sample_cos_classic(g, u));
            assert!((a - b).abs() < 1e-13, "g {g} u {u}: {a} vs {b}");
        }
    }
}

/// Pure water (OPTICS.md): q = 0.835 gives p(90°) = 0.06225 sr^-1.
#[test]
fn rayleigh_water_value() {
    let p = PhaseFunction::rayleigh(RAYLEIGH_Q_WATER).unwrap().eval(0.0);
    assert!((p - 0.06225).abs() < 5e-6, "{p}");
}

/// eval and eval_one_minus_cos agree wherever the cosine is exact.
#[test]
fn eval_forms_agree() {
    for (name, pf) in cases() {
        for i in 0..=200 {
            let mu = -1.0 + i as f64 / 100.0;
            let (a, b) = (pf.eval(mu), pf.eval_one_minus_cos(1.0 - mu));
            assert!((a / b - 1.0).abs() < 1e-12, "{name} mu {mu}: {a} vs {b}");
        }
    }
}

/// `scatter` returns unit vectors at the requested cosine to w, for w
/// anywhere including the poles the basis construction must survive.
#[test]
fn scatter_returns_unit_vector_at_requested_cosine() {
    let mut rng = Pcg32::new(5, 0);
    let mut ws = vec![
        Vec3::Z,
        -Vec3::Z,
        Vec3::X,
        Vec3::new(1e-7, 0.0, -1.0).normalize(),
    ];
    for _ in 0..1000 {
        let z = 2.0 * rng.uniform_f32() - 1.0;
        let phi = std::f32::consts::TAU * rng.uniform_f32();
        let r = (1.0 - z * z).max(0.0).sqrt();
        ws.push(Vec3::new(r * phi.cos(), r * phi.sin(), z));
    }
    for w in ws {
        for _ in 0..20 {
            let cos = 2.0 * rng.uniform_f32() - 1.0;
            let phi = std::f32::consts::TAU * rng.uniform_f32();
            let d = scatter(w, cos, phi);
            assert!(
                (d.length() - 1.0).abs() < 1e-5,
                "{w} {cos}: |d| {}",
                d.length()
            );
            assert!((d.dot(w) - cos).abs() < 1e-5, "{w} {cos}: {}", d.dot(w));
        }
        for cos in [1.0, -1.0] {
            let d = scatter(w, cos, 0.3);
            assert!((d.dot(w) - cos).abs() < 1e-6);
        }
    }
    // sample_direction keeps the sampled cosine.
    let pf = PhaseFunction::henyey_greenstein(0.8).unwrap();
    for i in 0..100 {
        let u = [i as f64 / 100.0, 0.37];
        let d = pf.sample_direction(Vec3::Y, u);
        assert!((d.dot(Vec3::Y) as f64 - pf.sample_cos(u[0])).abs() < 1e-5);
    }
}

fn field_of(result: Result<PhaseFunction>) -> String {
    match result {
        Err(Error::Invalid { field, .. }) => field,
        other => panic!("expected an invalid-field error, got {other:?}"),
    }
}

/// Bad parameters are errors naming the field, not panics.
#[test]
fn bad_parameters_name_the_field() {
    for g in [1.0, -1.0, 1.5, f64::NAN, f64::INFINITY] {
        assert_eq!(field_of(PhaseFunction::henyey_greenstein(g)), "g");
    }
    for q in [-0.1, 1.5, f64::NAN] {
        assert_eq!(field_of(PhaseFunction::rayleigh(q)), "q");
    }
    for bb in [0.0, 5e-5, 0.2, -0.01, f64::NAN] {
        assert_eq!(field_of(PhaseFunction::fournier_forand(bb)), "bb_ratio");
    }
    let ff = |n, mu| FournierForand::new(n, mu).map(PhaseFunction::FournierForand);
    assert_eq!(field_of(ff(1.0, 3.5)), "n");
    assert_eq!(field_of(ff(f64::NAN, 3.5)), "n");
    assert_eq!(field_of(ff(1.1, 3.0)), "mu");
    assert_eq!(field_of(ff(1.1, 5.5)), "mu");
    let table = |a: &[f64], v: &[f64]| PhaseFunction::tabulated(a, v, "water.phase_table");
    let bad: [(&[f64], &[f64]); 10] = [
        (&[0.0, 180.0], &[1.0]),
        (&[90.0], &[1.0]),
        (&[], &[]),
        (&[0.0, 90.0, 45.0], &[1.0, 1.0, 1.0]),
        (&[0.0, 90.0, 90.0], &[1.0, 1.0, 1.0]),
        (&[0.0, 181.0], &[1.0, 1.0]),
        (&[-1.0, 180.0], &[1.0, 1.0]),
        (&[0.0, f64::NAN], &[1.0, 1.0]),
        (&[0.0, 180.0], &[1.0, -0.5]),
        (&[0.0, 180.0], &[0.0, 0.0]),
    ];
    for (angles, values) in bad {
        assert_eq!(field_of(table(angles, values)), "water.phase_table");
    }
    assert_eq!(
        field_of(table(&[0.0, 180.0], &[1.0, f64::NAN])),
        "water.phase_table"
    );
    let message = table(&[0.0, 181.0], &[1.0, 1.0]).unwrap_err().to_string();
    assert!(message.starts_with("water.phase_table: "), "{message}");
}

/// Henyey–Greenstein p(psi) = (1 - g^2) / (4 pi D^(3/2)), D = 1 + g^2 -
/// 2 g cos psi, and a bound on |p''| over [lo, hi] for g > 0: p'' = -3 K g
/// (cos psi D^-5/2 - 5 g sin^2 psi D^-7/2), K = (1 - g^2) / (4 pi), with D
/// increasing in psi, so |p''| <= 3 K g (D(lo)^-5/2 + 5 g s^2 D(lo)^-7/2),
/// s the largest sine on the interval.
fn hg_and_curvature_bound(g: f64) -> (impl Fn(f64) -> f64, impl Fn(f64, f64) -> f64) {
    let k = (1.0 - g * g) / (4.0 * std::f64::consts::PI);
    let d = move |psi: f64| 1.0 + g * g - 2.0 * g * psi.cos();
    let p = move |psi: f64| k * d(psi).powf(-1.5);
    let bound = move |lo: f64, hi: f64| {
        let s = if lo <= FRAC_PI_2 && hi >= FRAC_PI_2 {
            1.0
        } else {
            lo.sin().max(hi.sin())
        };
        let dl = d(lo);
        3.0 * k * g * (dl.powf(-2.5) + 5.0 * g * s * s * dl.powf(-3.5))
    };
    (p, bound)
}

/// A tabulated phase function's integrals against closed forms: HG
/// tabulated every 0.25 degrees integrates to 1 and has mean cosine g and
/// backscatter fraction B = (1 - g) / (2 g) ((1 + g) / sqrt(1 + g^2) - 1)
/// analytically. The table is the linear interpolant of HG, whose
/// pointwise error is at most h^2 / 8 max |p''| per piece, so each
/// integral of the table is within E = 2 pi sum_pieces h^2 / 8 max |p''|
/// int sin psi of HG's (|cos| <= 1 for the moment); after normalising by
/// the table's own integral, 1 + e0, mean cosine and B are within (E +
/// |value| E) / (1 - E). Those bounds (2e-6 to 6e-4, about five times
/// the errors measured) are the tolerances, plus 1e-12 for rounding.
#[test]
fn tabulated_henyey_greenstein_has_the_analytic_moments() {
    for g in [0.3, 0.6, 0.85] {
        let (p, curvature) = hg_and_curvature_bound(g);
        let nodes = 720;
        let angles: Vec<f64> = (0..=nodes)
            .map(|i| 180.0 * i as f64 / nodes as f64)
            .collect();
        let values: Vec<f64> = angles.iter().map(|a| p(a.to_radians())).collect();
        let pf = PhaseFunction::tabulated(&angles, &values, "hg table").unwrap();
        let PhaseFunction::Tabulated(t) = &pf else {
            unreachable!()
        };
        let (mut e_all, mut e_back) = (0.0, 0.0);
        for w in angles.windows(2) {
            let (lo, hi) = (w[0].to_radians(), w[1].to_radians());
            let h = hi - lo;
            let e = TWO_PI * h * h / 8.0 * curvature(lo, hi) * (lo.cos() - hi.cos());
            e_all += e;
            if lo >= FRAC_PI_2 - 1e-12 {
                e_back += e;
            }
        }
        let b_hg = (1.0 - g) / (2.0 * g) * ((1.0 + g) / (1.0 + g * g).sqrt() - 1.0);
        let tol_norm = e_all + 1e-12;
        let tol_g = (e_all + g * e_all) / (1.0 - e_all) + 1e-12;
        let tol_b = (e_back + b_hg * e_all) / (1.0 - e_all) + 1e-12;
        let (norm, mean, back) = (
            t.raw_integral(),
            pf.mean_cosine(),
            pf.backscatter_fraction(),
        );
        eprintln!(
            "HG {g} tabulated: integral {norm:.9} (bound {tol_norm:.1e}), \
             g {mean:.9} (bound {tol_g:.1e}), B {back:.9} vs {b_hg:.9} (bound {tol_b:.1e})"
        );
        assert!(e_all < 1e-3, "bound {e_all} too loose to test much");
        assert!((norm - 1.0).abs() <= tol_norm, "g {g}: integral {norm}");
        assert!((mean - g).abs() <= tol_g, "g {g}: mean cosine {mean}");
        assert!((back - b_hg).abs() <= tol_b, "g {g}: B {back} vs {b_hg}");
        // The density is the interpolant, normalised: at a node it is HG
        // over the table's integral.
        let at = 30f64.to_radians();
        assert!((pf.eval(at.cos()) * norm / p(at) - 1.0).abs() < 1e-9);
    }
}

/// The Petzold table's raw integral, backscatter and mean cosine from the
/// data file by a route independent of `tabulated.rs`: the file read
/// here, each linear piece's 2 pi int p sin psi (and p cos psi sin psi)
/// by adaptive Simpson, and the power law below 0.12589 degrees by the
/// substitution u = psi^(2 - alpha), under which int psi^-alpha sin psi
/// dpsi = int sinc(psi(u)) du / (2 - alpha) is smooth. Simpson runs to
/// 1e-15 absolute per piece, so 1e-11 relative is allowed. This pins the
/// figures `tabulated/tests.rs` states (integral 1.01798, unnormalised B
/// 0.018142) to an integral the code did not compute.
#[test]
fn petzold_integrals_match_an_independent_quadrature() {
    let text = include_str!("../../../data/petzold_avg_particle_mobley1993.csv");
    let mut lines = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header
        .iter()
        .position(|h| h.trim() == "beta_corrected_per_sr")
        .unwrap();
    let (alpha, first_deg) = (1.346, 0.12589);
    let rows: Vec<(f64, f64)> = lines
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|x| x.trim().parse().unwrap()).collect();
            (f[0], f[col])
        })
        .filter(|&(a, _)| a >= first_deg)
        .collect();
    assert_eq!(rows[0].0, first_deg);
    assert_eq!(rows.last().unwrap().0, 180.0);
    // Power-law head.
    let (psi0, p0) = (first_deg.to_radians(), rows[0].1);
    let e = 2.0 - alpha;
    let psi_of = |u: f64| u.powf(1.0 / e);
    let sinc = |x: f64| if x == 0.0 { 1.0 } else { x.sin() / x };
    let head_mass = TWO_PI * p0 * psi0.powf(alpha) / e
        * simpson(&|u| sinc(psi_of(u)), 0.0, psi0.powf(e), 1e-18);
    let head_moment = TWO_PI * p0 * psi0.powf(alpha) / e
        * simpson(
            &|u| sinc(psi_of(u)) * psi_of(u).cos(),
            0.0,
            psi0.powf(e),
            1e-18,
        );
    let (mut mass, mut moment, mut back) = (head_mass, head_moment, 0.0);
    for w in rows.windows(2) {
        let ((a0, v0), (a1, v1)) = (w[0], w[1]);
        let (lo, hi) = (a0.to_radians(), a1.to_radians());
        let lin = move |psi: f64| v0 + (v1 - v0) * (psi - lo) / (hi - lo);
        let m = TWO_PI * simpson(&|psi| lin(psi) * psi.sin(), lo, hi, 1e-15);
        mass += m;
        moment += TWO_PI * simpson(&|psi| lin(psi) * psi.sin() * psi.cos(), lo, hi, 1e-15);
        if a0 >= 90.0 {
            back += m;
        }
    }
    assert!(rows.iter().any(|r| r.0 == 90.0), "90 degrees is a node");
    let pf = PhaseFunction::petzold();
    let PhaseFunction::Tabulated(t) = &pf else {
        unreachable!()
    };
    eprintln!(
        "Petzold by independent quadrature: integral {mass:.9}, unnormalised B {back:.9}, \
         g {:.9}; the code: {:.9}, {:.9}, {:.9}",
        moment / mass,
        t.raw_integral(),
        pf.backscatter_fraction() * t.raw_integral(),
        pf.mean_cosine()
    );
    assert!((t.raw_integral() / mass - 1.0).abs() < 1e-11);
    assert!((pf.backscatter_fraction() / (back / mass) - 1.0).abs() < 1e-11);
    assert!((pf.mean_cosine() / (moment / mass) - 1.0).abs() < 1e-11);
    // The figures the tabulated tests pin.
    assert!((mass - 1.01798).abs() < 5e-6, "{mass}");
    assert!((back - 0.018142).abs() < 5e-7, "{back}");
}

/// `cosine_hemisphere` draws Lambertian directions around any normal: in
/// the normal's frame, cos^2(theta) is uniform on [0, 1] and the azimuth
/// uniform, independently. Pearson chi-square over 10 x 8 bins of equal
/// probability (an independent frame for the azimuth, since any azimuth
/// origin serves) at p = 0.001, for normals up, down, oblique and a
/// hair off straight down (where an orthonormal basis is easily lost);
/// every direction is a unit vector in the normal's hemisphere.
#[test]
fn cosine_hemisphere_passes_chi_square() {
    const MU_BINS: usize = 10;
    const PHI_BINS: usize = 8;
    let normals = [
        Vec3::Z,
        Vec3::NEG_Z,
        Vec3::new(1.0, 1.0, 1.0).normalize(),
        Vec3::new(0.0, 1e-4, -1.0).normalize(),
    ];
    for (i, n) in normals.into_iter().enumerate() {
        // A frame of our own: any vector not along n, made orthogonal.
        let helper = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
        let t1 = (helper - n * n.dot(helper)).normalize();
        let t2 = n.cross(t1);
        let mut counts = [0u64; MU_BINS * PHI_BINS];
        let mut rng = Pcg32::new(77, i as u64);
        for _ in 0..SAMPLES {
            let d = cosine_hemisphere(n, &mut rng);
            assert!((d.length() - 1.0).abs() < 1e-5, "{d}");
            let mu = d.dot(n) as f64;
            assert!(mu >= -1e-6, "normal {n}: direction {d} below the surface");
            let u = (mu * mu).clamp(0.0, 1.0 - 1e-12);
            let phi = (d.dot(t2) as f64).atan2(d.dot(t1) as f64) + std::f64::consts::PI;
            let p = ((phi / std::f64::consts::TAU * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
            counts[(u * MU_BINS as f64) as usize * PHI_BINS + p] += 1;
        }
        let e = SAMPLES as f64 / counts.len() as f64;
        let chi2: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        let critical = chi_square_critical(counts.len() - 1);
        assert!(chi2 < critical, "normal {n}: chi2 {chi2} >= {critical}");
    }
}
