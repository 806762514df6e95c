#!/usr/bin/env bash
# Chlorophyll fluorescence line height against the relation it follows.
#
# Deep homogeneous water of Chl 1, 2, 5 and 10 mg m^-3 (no CDOM, no NAP,
# no floor), a flat surface (n = 1.34), the sun at 30 degrees with the
# ASTM G173 direct spectrum and no sky; 40 bands of 10 nm from 367 to 757
# nm (data tables clamped outside their range), so that 667, 677 and 747
# nm stand for MODIS's FLH bands (667, 678, 748 nm). Each water renders
# twice on its own map, elastic only and with chlorophyll fluorescence at
# phi = 0.01 (Raman off in both), and reads L_w from a nadir radiometer
# 1 m above the water (no sky, no glint in a nadir view).
#
# The fluorescence line height FLH = L(677) - [L(667) + (L(747) - L(667))
# (677 - 667) / (747 - 667)], divided by E_d(0+) (sr^-1), of the
# fluorescence alone (with - without) is compared with the single-emission
# relation of Gordon (1979) that Huot et al. (2005) and Behrenfeld et al.
# (2009) build on: isotropic emission phi a_phi(l') E_o(z, l') (l'/l) g(l)
# / 4pi per unit volume, carried to the surface along nadir and attenuated
# by the absorption a(l) only,
#   L_f(0-, l) = (1/4pi) Sum_l' phi a_phi(l') D_l' (l'/l) g(l)
#                  Int_0^inf E_o(z, l') exp(-a(l) z) dz,
#   L_f(0+, l) = L_f(0-, l) t / n^2        (t = 1 - r_F(0) = 0.979),
# with E_o(z, l') from the run's own scalar-irradiance tallies (integrated
# between the tally depths as piecewise exponentials), a_phi and a_w from
# the tables littoral reads (band-averaged with its Gaussian responses),
# g the emission Gaussian (685 nm, sigma 10.6 nm) over each band's cell,
# excitation 370-690 nm, emission only to l > l'. The relation neglects
# the scattering of the emitted light; its departure from the full
# transport is what this measures. Both runs of a seed share their random
# numbers until a photon fluoresces, so their difference is far less noisy
# than either; the error bars are the standard errors of the seeds' mean
# from their spread.
# Usage: benches/scripts/flh.sh [OUTDIR] [PHOTONS] [SEEDS]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-flh}
photons=${2:-4000000}
seeds=${3:-"1 2 3"}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
for chl in 1 2 5 10; do
  for light in off on; do
    fl=""
    [ "$light" = on ] && fl=$'[water.fluorescence]\nchl_quantum_yield = 0.01'
    cat > "$out/chl$chl-$light.toml" <<TOML
name = "chl$chl-$light"
[spectral]
start_nm = 367.0
end_nm = 757.0
bands = 40
out_of_range = "clamp"
[sun]
zenith_deg = 30.0
spectrum = "astm-g173-direct"
[surface]
kind = "flat"
refractive_index = 1.34
[domain]
size_m = [40.0, 40.0]
[sensor]
pixels = [1, 1]
[water]
chl = $chl.0
cdom_440 = 0.0
nap_440 = 0.0
raman = false
$fl
[photons]
count = $photons
[tally]
depths_m = [0.02, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 13.0, 16.0, 20.0]
[[radiometer]]
depth_m = -1.0
view = "nadir"
position_m = [20.0, 20.0]
TOML
    for seed in $seeds; do
      "$bin" render "$out/chl$chl-$light.toml" --seed "$seed" --out "$out/chl$chl-$light-s$seed" --quiet
    done
  done
done
python3 - "$out" $seeds <<'PY'
import csv, json, math, sys

out, seeds = sys.argv[1], sys.argv[2:]
DATA = "data"
PHI, MU, SIGMA, N = 0.01, 685.0, 10.6, 1.34
T_N2 = (1 - ((N - 1) / (N + 1)) ** 2) / N ** 2


def table(name, cols):
    rows = [r for r in open(f"{DATA}/{name}") if not r.startswith("#")]
    rd = list(csv.DictReader(rows))
    key = next(k for k in rd[0] if k.startswith("wavelength"))
    return [float(r[key]) for r in rd], [[float(r[c]) for r in rd] for c in cols]


def lerp(xs, ys, x):
    x = min(max(x, xs[0]), xs[-1])
    for i in range(len(xs) - 1):
        if xs[i] <= x <= xs[i + 1]:
            t = (x - xs[i]) / (xs[i + 1] - xs[i]) if xs[i + 1] > xs[i] else 0.0
            return ys[i] + t * (ys[i + 1] - ys[i])
    return ys[-1]


def band_avg(xs, ys, c, fwhm):
    # littoral's Gaussian band response, +-3 sigma, clamped to the table.
    s = fwhm / 2.3548
    num = den = 0.0
    for k in range(601):
        x = c - 3 * s + 6 * s * k / 600
        w = math.exp(-0.5 * ((x - c) / s) ** 2)
        num += w * lerp(xs, ys, x)
        den += w
    return num / den


def gauss_cell(lo, hi, above):
    # Int over [lo, hi] and above `above` of g(l) / l dl, g normalised.
    lo = max(lo, above)
    if hi <= lo:
        return 0.0
    n, acc = 400, 0.0
    for k in range(n):
        l = lo + (hi - lo) * (k + 0.5) / n
        acc += math.exp(-0.5 * ((l - MU) / SIGMA) ** 2) / (SIGMA * math.sqrt(2 * math.pi)) / l
    return acc * (hi - lo) / n


def depth_integral(zs, s, a):
    # Int_0^inf S(z) exp(-a z) dz, S piecewise exponential between tallies
    # (extended to z = 0 and beyond the last depth by its end segments).
    def seg(z0, z1, s0, k):
        r = k + a
        return s0 * math.exp(-a * z0) * (1 - math.exp(-r * (z1 - z0))) / r
    ks = [math.log(s[i] / s[i + 1]) / (zs[i + 1] - zs[i]) for i in range(len(zs) - 1)]
    total = seg(0.0, zs[0], s[0] * math.exp(ks[0] * zs[0]), ks[0])
    for i in range(len(zs) - 1):
        total += seg(zs[i], zs[i + 1], s[i], ks[i])
    return total + s[-1] * math.exp(-a * zs[-1]) / (ks[-1] + a)


aw_x, (aw,) = table("aw_composite_380_1000.csv", ["aw_per_m"])
ap_x, (A, E) = table("aph_bricaud1998.csv", ["A_phi", "E_phi"])



def mean_se(xs):
    m = sum(xs) / len(xs)
    if len(xs) < 2:
        return m, float("nan")
    return m, math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1) / len(xs))


print("| Chl | FLH elastic (sr^-1) | FLH of the fluorescence, littoral | Gordon relation | littoral / relation, FLH | 677 nm | 687 nm |")
print("|---|---|---|---|---|---|---|")
for chl in (1, 2, 5, 10):
    rows = []
    for seed in seeds:
        rep = {l: json.load(open(f"{out}/chl{chl}-{l}-s{seed}/chl{chl}-{l}.json")) for l in ("off", "on")}
        nm = rep["on"]["bands_nm"]
        fwhm = 10.0
        ed = rep["on"]["Ed_above_surface"]
        L = {l: rep[l]["radiometers"][0]["L"] for l in rep}
        prof = list(csv.DictReader(open(f"{out}/chl{chl}-on-s{seed}/chl{chl}-on.profiles.csv")))
        zs = sorted({float(r["depth_m"]) for r in prof})
        eo = {(float(r["depth_m"]), float(r["wavelength_nm"])): float(r["Eod_W_m2_nm"]) + float(r["Eou_W_m2_nm"]) for r in prof}
        aphi = [band_avg(ap_x, A, c, fwhm) * chl ** band_avg(ap_x, E, c, fwhm) for c in nm]
        a = [band_avg(aw_x, aw, c, fwhm) + aphi[i] for i, c in enumerate(nm)]
        pred = []
        for m, lm in enumerate(nm):
            lo, hi = lm - fwhm / 2, lm + fwhm / 2
            acc = 0.0
            for e, le in enumerate(nm):
                if not (370.0 <= le <= 690.0):
                    continue
                w = gauss_cell(lo, hi, le)
                s = [eo[(z, le)] for z in zs]
                if w == 0.0 or min(s) <= 0.0:
                    continue
                acc += PHI * aphi[e] * fwhm * le * w * depth_integral(zs, s, a[m])
            pred.append(acc / (4 * math.pi) / fwhm * T_N2)
        band = lambda w: min(range(len(nm)), key=lambda i: abs(nm[i] - w))
        b1, b2, b3 = band(667), band(677), band(747)
        f = (nm[b2] - nm[b1]) / (nm[b3] - nm[b1])
        flh = lambda v: (v[b2] - (v[b1] + (v[b3] - v[b1]) * f)) / ed[b2]
        fl = [L["on"][i] - L["off"][i] for i in range(len(nm))]
        rows.append((flh(L["off"]), flh(fl), flh(pred), flh(fl) / flh(pred),
                     fl[b2] / pred[b2], fl[band(687)] / pred[band(687)]))
    cols = [mean_se([r[i] for r in rows]) for i in range(6)]
    print(f"| {chl} | {cols[0][0]:.2e} | {cols[1][0]:.3e} ± {cols[1][1]:.1e} | {cols[2][0]:.3e} "
          + " ".join(f"| {m:.3f} ± {e:.3f}" for m, e in cols[3:]) + " |")
PY
