#!/usr/bin/env bash
# Mobley et al. (1993) canonical Problem 2: infinitely deep homogeneous
# water (c = 1 /m, so optical depth = metres), the Petzold average-particle
# phase function, single-scattering albedo 0.9 or 0.2, a flat surface
# (n = 1.34), black sky, sun at 60 degrees with 1 W m^-2 nm^-1 on a plane
# normal to it. Compares the emission tallies' E_d and E_ou at optical
# depths 1, 5 and 10 with the mean of the paper's seven models (Table 5;
# their spread s/mean in brackets).
# Usage: benches/scripts/canonical.sh [OUTDIR] [PHOTONS]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-canonical}
photons=${2:-100000000}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
for albedo in 0.9 0.2; do
  name="problem2-w$albedo"
  a=$(python3 -c "print(1 - $albedo)")
  cat > "$out/$name.toml" <<TOML
name = "$name"
[spectral]
start_nm = 550.0
end_nm = 550.0
bands = 1
[sun]
zenith_deg = 60.0
irradiance = 1.0
[sky]
radiance = 0.0
[surface]
kind = "flat"
refractive_index = 1.34
[domain]
size_m = [20.0, 20.0]
[water]
iop = { a = $a, b = $albedo }
phase = { kind = "petzold" }
[bottom]
depth_m = 60.0
reflectance = 0.0
[photons]
count = $photons
[sensor]
pixels = [2, 2]
[tally]
depths_m = [1.0, 5.0, 10.0]
TOML
  "$bin" render "$out/$name.toml" --out "$out/$name" --mem-budget 1GiB --quiet
  python3 - "$out/$name/$name.profiles.csv" "$albedo" <<'PY'
import csv, sys
# Table 5 of Mobley et al. 1993: tau -> (E_d, spread, E_ou, spread).
table = {
    "0.9": {1: (4.13e-1, 0.001, 9.31e-2, 0.021), 5: (1.87e-1, 0.005, 4.63e-2, 0.017),
            10: (6.85e-2, 0.010, 1.65e-2, 0.014)},
    "0.2": {1: (1.62e-1, 0.000, 9.66e-4, 0.023), 5: (2.27e-3, 0.002, 1.37e-5, 0.063),
            10: (1.30e-5, 0.047, 7.28e-8, 0.187)},
}[sys.argv[2]]
for r in csv.DictReader(open(sys.argv[1])):
    tau = round(float(r["depth_m"]))
    ed, eou, se = float(r["Ed_W_m2_nm"]), float(r["Eou_W_m2_nm"]), float(r["Eou_stderr"])
    t = table[tau]
    print(f"| {sys.argv[2]} | {tau} | {(ed / t[0] - 1) * 100:+.1f} % ({t[1] * 100:.1f} %) "
          f"| {(eou / t[2] - 1) * 100:+.1f} % ± {se / eou * 100:.1f} % ({t[3] * 100:.1f} %) |")
PY
done
