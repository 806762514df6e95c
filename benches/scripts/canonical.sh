#!/usr/bin/env bash
# Mobley et al. (1993) canonical Problem 2: infinitely deep homogeneous
# water (c = 1 /m, so optical depth = metres), the Petzold average-particle
# phase function, single-scattering albedo 0.9 or 0.2, a flat surface
# (n = 1.34), black sky, sun at 60 degrees with 1 W m^-2 nm^-1 on a plane
# normal to it. Compares the emission tallies' E_d and E_ou at optical
# depths 1, 5 and 10 with the mean of the paper's seven models (Table 5;
# their spread s/mean in brackets). Each albedo runs once per seed; the
# error bar is the standard error of the seeds' mean from their spread
# (deep in absorbing water E_ou rests on few photons, and one run's own
# standard error is itself uncertain).
# Usage: benches/scripts/canonical.sh [OUTDIR] [PHOTONS_AT_0.9] [PHOTONS_AT_0.2] [SEEDS]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-canonical}
photons_09=${2:-20000000}
photons_02=${3:-200000000}
seeds=${4:-"1 2 3 4"}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
for albedo in 0.9 0.2; do
  name="problem2-w$albedo"
  a=$(python3 -c "print(1 - $albedo)")
  photons=$photons_09
  [ "$albedo" = 0.2 ] && photons=$photons_02
  "$bin" scene set tests/scenes/minimal.toml "name=\"$name\"" \
    "spectral={ start_nm = 550.0, end_nm = 550.0, bands = 1 }" sun.zenith_deg=60.0 sky.radiance=0.0 \
    "surface={ kind = \"flat\", refractive_index = 1.34 }" "domain.size_m=[20.0, 20.0]" \
    "water={ iop = { a = $a, b = $albedo }, phase = { kind = \"petzold\" } }" \
    "bottom={ depth_m = 60.0, reflectance = 0.0 }" photons.count=$photons "sensor.pixels=[2, 2]" \
    "tally.depths_m=[1.0, 5.0, 10.0]" > "$out/$name.toml"
  csvs=()
  for seed in $seeds; do
    "$bin" render "$out/$name.toml" --seed "$seed" --out "$out/$name-s$seed" --mem-budget 1GiB --quiet
    csvs+=("$out/$name-s$seed/$name.profiles.csv")
  done
  python3 - "$albedo" "${csvs[@]}" <<'PY'
import csv, math, sys
# Table 5 of Mobley et al. 1993: tau -> (E_d, spread, E_ou, spread).
table = {
    "0.9": {1: (4.13e-1, 0.001, 9.31e-2, 0.021), 5: (1.87e-1, 0.005, 4.63e-2, 0.017),
            10: (6.85e-2, 0.010, 1.65e-2, 0.014)},
    "0.2": {1: (1.62e-1, 0.000, 9.66e-4, 0.023), 5: (2.27e-3, 0.002, 1.37e-5, 0.063),
            10: (1.30e-5, 0.047, 7.28e-8, 0.187)},
}[sys.argv[1]]
runs = [{round(float(r["depth_m"])): (float(r["Ed_W_m2_nm"]), float(r["Eou_W_m2_nm"]),
                                     float(r["Eou_stderr"]))
         for r in csv.DictReader(open(path))} for path in sys.argv[2:]]
n = len(runs)
def mean_se(xs):
    m = sum(xs) / len(xs)
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1)) if len(xs) > 1 else float("nan")
    return m, sd / math.sqrt(len(xs))
for tau, t in sorted(table.items()):
    ed, _ = mean_se([r[tau][0] for r in runs])
    eou, se = mean_se([r[tau][1] for r in runs])
    own = math.sqrt(sum(r[tau][2] ** 2 for r in runs)) / n
    print(f"| {sys.argv[1]} | {tau} | {(ed / t[0] - 1) * 100:+.1f} % ({t[1] * 100:.1f} %) "
          f"| {(eou / t[2] - 1) * 100:+.1f} % ± {se / eou * 100:.1f} % "
          f"(runs' own: {own / eou * 100:.1f} %) ({t[3] * 100:.1f} %) |")
PY
done
