#!/usr/bin/env bash
# Radiometers of the photon map (default settings) against the path
# integrator in small scenes: deep, shallow with a floor, layered, a
# target, a rough surface, and a radiometer 0.1 mm above the floor.
# Usage: benches/scripts/against_path.sh [OUTDIR] [PHOTONS] [SPP]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-against-path}
photons=${2:-4000000}
spp=${3:-1024}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
base() {
cat <<TOML
name = "$1"
[spectral]
start_nm = 450.0
end_nm = 650.0
bands = 8
[sun]
zenith_deg = 30.0
irradiance = 1.0
[sky]
radiance = 0.02
[domain]
size_m = [40.0, 40.0]
[photons]
count = $photons
[sensor]
pixels = [1, 1]
[estimate]
max_radius_m = 2.0
step_m = 0.25
TOML
}
radiometers() {
  for d in "$@"; do
    printf '[[radiometer]]\ndepth_m = %s\nview = "nadir"\nposition_m = [20.0, 20.0]\n' "$d"
  done
}
write() { # name, extra TOML, radiometer depths...
  local name=$1 extra=$2; shift 2
  { base "$name"; printf '%s\n' "$extra"; radiometers "$@"; } > "$out/$name.toml"
}
write deep '[water]
chl = 1.0
cdom_440 = 0.05' 1.0 3.0 -1.0
write shallow '[water]
chl = 1.0
cdom_440 = 0.05
[bottom]
depth_m = 4.0
reflectance = "sand"' 1.0 3.9 -1.0
write layered '[water]
chl = 0.5
cdom_440 = 0.05
[[water.layer]]
top_m = 2.0
bottom_m = 4.0
chl = 8.0
cdom_440 = 0.2
nap_440 = 0.1
[bottom]
depth_m = 8.0
reflectance = 0.2' 1.0 3.0 -1.0
write target '[water]
chl = 1.0
cdom_440 = 0.05
[bottom]
depth_m = 6.0
reflectance = 0.1
[[target]]
kind = "panel"
center_m = [20.0, 20.0, -3.0]
size_m = [4.0, 4.0]
reflectance = 0.5' 1.0 2.5 -1.0
write rough '[surface]
kind = "cox-munk"
wind_speed = 8.0
[water]
chl = 1.0
cdom_440 = 0.05
[bottom]
depth_m = 5.0
reflectance = "sand"' 1.0 4.0 -1.0
write near_floor '[water]
chl = 1.0
cdom_440 = 0.05
[bottom]
depth_m = 3.0
reflectance = 0.3' 2.9999 2.99 1.5
for f in deep shallow layered target rough near_floor; do
  "$bin" render "$out/$f.toml" --out "$out/$f-pm" --quiet
  "$bin" render "$out/$f.toml" --out "$out/$f-path" --integrator path --spp "$spp" --quiet
  python3 - "$out/$f-pm/$f.json" "$out/$f-path/$f.json" "$f" <<'PY'
import json, sys
pm, pa, name = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), sys.argv[3]
for a, b in zip(pm["radiometers"], pa["radiometers"]):
    l = sum(b["L"]) / len(b["L"]); se = (sum(s * s for s in b["stderr"]) ** 0.5) / len(b["L"])
    m = sum(a["L"]) / len(a["L"])
    worst = max(abs(x / y - 1) for x, y in zip(a["L"], b["L"]))
    # Per band: the photon map's relative error, and the largest
    # difference in combined standard errors.
    pse = max(s / x for s, x in zip(a["stderr"], a["L"]))
    z = max(abs(x - y) / (sa * sa + sb * sb) ** 0.5
            for x, y, sa, sb in zip(a["L"], b["L"], a["stderr"], b["stderr"]))
    print(f"| {name} | {a['depth_m']} | {l:.5g} ± {se / l * 100:.1f} % | {m / l - 1:+.3f} | {worst:.3f} | {pse * 100:.1f} % | {z:.1f} |")
PY
done
