#!/usr/bin/env bash
# The path integrator at 10^6 paths against the emission's Lu tally, an
# independent forward Monte Carlo of the same radiance, in three clear-water
# scenes: Fournier-Forand water (a = 0.05, b = 0.3 /m, b_b/b = 0.0183), a flat
# surface (n = 1.34), sun at 30 degrees, black sky, one band; a Lambertian
# floor of reflectance 0.3 at 3 m, the same floor at 10 m, and deep water
# (a black floor at 60 m). Both read the upwelling radiance 10 cm below the
# surface averaged over the tally's 10-degree cone with the same cosine
# weight (a radiometer with `half_angle_deg = 10`), so they estimate the same
# number and R_rs, which is t / n^2 times it over E_d, agrees as they do.
# The last column is the photon map's radiometer (same field of view, the
# map of the same emission) against the path integrator.
# Usage: benches/scripts/path_reference.sh [OUTDIR] [PHOTONS] [SPP]
# (SPP x 1024 paths; 977 gives 1 000 448.)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-path-reference}
photons=${2:-60000000}
spp=${3:-977}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
echo "| scene | path (10^6 paths) | tally ($photons photons) | path / tally | combined SE | z | photon map vs path |"
echo "|---|---|---|---|---|---|---|"
for case in "floor3 3.0 0.3" "floor10 10.0 0.3" "deep 60.0 0.0"; do
  set -- $case
  name=$1 depth=$2 rho=$3
  "$bin" scene set tests/scenes/minimal.toml "name=\"$name\"" \
    "spectral={ start_nm = 550.0, end_nm = 550.0, bands = 1 }" sun.zenith_deg=30.0 sky.radiance=0.0 \
    "surface={ kind = \"flat\", refractive_index = 1.34 }" "domain={ size_m = [20.0, 20.0] }" \
    "water={ iop = { a = 0.05, b = 0.3 }, phase = { kind = \"fournier-forand\", bb_ratio = 0.0183 } }" \
    "bottom={ depth_m = $depth, reflectance = $rho }" photons.count=$photons "sensor.pixels=[1, 1]" \
    "tally.depths_m=[0.1]" \
    "radiometer=[{ depth_m = 0.1, view = \"nadir\", half_angle_deg = 10.0 }]" > "$out/$name.toml"
  "$bin" render "$out/$name.toml" --out "$out/$name-map" --mem-budget 1GiB --quiet
  "$bin" render "$out/$name.toml" --integrator path --spp "$spp" --out "$out/$name-path" --quiet
  python3 - "$name" "$out/$name-map/$name.json" "$out/$name-path/$name.json" <<'PY'
import json, math, sys
name, map_json, path_json = sys.argv[1:]
pm = json.load(open(map_json))
tally = pm["tally"][0]
lu, lu_se = tally["Lu"][0], tally["Lu_stderr"][0]
r = json.load(open(path_json))["radiometers"][0]
l, l_se = r["L"][0], r["stderr"][0]
m, m_se = pm["radiometers"][0]["L"][0], pm["radiometers"][0]["stderr"][0]
se = math.hypot(l_se / lu, l * lu_se / lu ** 2)
print(f"| {name} | {l:.5g} ± {100 * l_se / l:.2f} % | {lu:.5g} ± {100 * lu_se / lu:.2f} % "
      f"| {l / lu:.4f} | {100 * se:.2f} % | {(l / lu - 1) / se:+.1f} "
      f"| {m / l - 1:+.2%} ± {100 * m_se / l:.2f} % |")
PY
done
