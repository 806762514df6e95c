#!/usr/bin/env bash
# Submerged boxes of 0.5, 1, 2 and 4 m at three depths: the photon map at
# the built-in scene's photon density (100 traced photons per m^2 of
# domain) against the path integrator, through nadir radiometers 1 m above
# the water over the box's centre and over the sand 8 m away.
# Usage: benches/scripts/targets.sh [OUTDIR] [PHOTONS_PER_M2] [SPP] [GATHER_RAYS] [WIND_M_S]
# (WIND_M_S 0: a flat surface; default 5, Cox-Munk)
# Prints one markdown row per box: band-mean R_rs difference with the
# combined standard error of the band means, the worst band against its
# 3 sigma + 2 % allowance, and the box/sand contrast of both integrators.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-targets}
density=${2:-100}
spp=${3:-256}
gather=${4:-32}
wind=${5:-5}
if [ "$wind" = 0 ]; then
  surface=(surface.kind='"flat"')
else
  surface=(surface.kind='"cox-munk"' "surface.wind_speed=$wind")
fi
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
domain=40
photons=$((density * domain * domain))
echo "| box | top depth | box: photon map - path | sand: photon map - path | worst band / allowance | contrast photon map | contrast path |"
echo "|---|---|---|---|---|---|---|"
for size in 0.5 1 2 4; do
  for depth in 1.5 3 6; do
    name="box-${size}m-${depth}m"
    floor=$(python3 -c "print($depth + 0.5)")
    centre=$(python3 -c "print(-($depth + 0.25))")
    "$bin" scene set tests/scenes/box.toml "name=\"$name\"" "${surface[@]}" \
      "domain.size_m=[$domain.0, $domain.0]" "bottom.depth_m=$floor" \
      "target=[{ kind = \"box\", center_m = [20.0, 20.0, $centre], size_m = [$size, $size, 0.5], reflectance = 0.5 }]" \
      "photons.count=$photons" "estimate.gather_rays=$gather" > "$out/$name.toml"
    "$bin" render "$out/$name.toml" --out "$out/$name-pm" --quiet 2>/dev/null
    "$bin" render "$out/$name.toml" --out "$out/$name-path" --integrator path --spp "$spp" --quiet 2>/dev/null
    python3 - "$out/$name-pm/$name.json" "$out/$name-path/$name.json" "$size" "$depth" <<'PY'
import json, sys
pm, pa = json.load(open(sys.argv[1]))["radiometers"], json.load(open(sys.argv[2]))["radiometers"]
size, depth = sys.argv[3], sys.argv[4]
mean = lambda v: sum(v) / len(v)
box, sand = (pm[0], pa[0]), (pm[1], pa[1])
def diff(a, b):
    m_a, m_b = mean(a["L"]), mean(b["L"])
    s = (a["band_mean_stderr"] ** 2 + b["band_mean_stderr"] ** 2) ** 0.5
    return f"{(m_a / m_b - 1) * 100:+.1f} % ± {s / m_b * 100:.1f} %"
worst = max(abs(x - y) / (3 * (sa * sa + sb * sb) ** 0.5 + 0.02 * y)
            for a, b in (box, sand)
            for x, y, sa, sb in zip(a["L"], b["L"], a["stderr"], b["stderr"]))
c = [mean(box[i]["L"]) / mean(sand[i]["L"]) - 1 for i in (0, 1)]
rel = lambda r: r["band_mean_stderr"] / mean(r["L"])
c_se = [(1 + c[i]) * (rel(box[i]) ** 2 + rel(sand[i]) ** 2) ** 0.5 for i in (0, 1)]
print(f"| {size} m | {depth} m | {diff(*box)} | {diff(*sand)} | {worst:.2f} | {c[0] * 100:.0f} % ± {c_se[0] * 100:.0f} % | {c[1] * 100:.0f} % ± {c_se[1] * 100:.0f} % |")
PY
  done
done
