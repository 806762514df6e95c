#!/usr/bin/env bash
# Submerged boxes of 0.5, 1, 2 and 4 m at three depths: the photon map at
# the built-in scene's photon density (100 traced photons per m^2 of
# domain) against the path integrator, through nadir radiometers 1 m above
# the water over the box's centre and over the sand 8 m from it in four
# directions (the sand's reading is the four positions' mean).
# Usage: benches/scripts/targets.sh [OUTDIR] [PHOTONS_PER_M2] [SPP] [GATHER_RAYS] [WIND_M_S] [SEEDS]
# (WIND_M_S 0: a flat surface; default 5, Cox-Munk. SEEDS: the photon map's
# seeds, e.g. "1 2 3 4"; default "1".) TARGET_SPLIT in the environment
# sets `[photons] target_split` (default: the scene's, 16); SIZES and
# DEPTHS pick boxes and depths (default "0.5 1 2 4" and "1.5 3 6").
# Prints one markdown row per box: band-mean R_rs difference with the
# combined standard error of the band means, the worst band against its
# 3 sigma + 2 % allowance, and the box/sand contrast of both integrators.
# With more than two seeds the photon map's error bars are the standard
# error of the seeds' mean from their spread (its own estimate otherwise);
# the path integrator's are its own.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-targets}
density=${2:-100}
spp=${3:-256}
gather=${4:-32}
wind=${5:-5}
seeds=${6:-1}
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
rad() { echo "{ depth_m = -1.0, view = \"nadir\", position_m = [$1, $2] }"; }
radiometers="radiometer=[$(rad 20.0 20.0), $(rad 28.0 20.0), $(rad 12.0 20.0), $(rad 20.0 28.0), $(rad 20.0 12.0)]"
echo "| box | top depth | box: photon map - path | sand: photon map - path | worst band / allowance | contrast photon map | contrast path |"
echo "|---|---|---|---|---|---|---|"
for size in ${SIZES:-0.5 1 2 4}; do
  for depth in ${DEPTHS:-1.5 3 6}; do
    name="box-${size}m-${depth}m"
    floor=$(python3 -c "print($depth + 0.5)")
    centre=$(python3 -c "print(-($depth + 0.25))")
    "$bin" scene set tests/scenes/box.toml "name=\"$name\"" "${surface[@]}" \
      "domain.size_m=[$domain.0, $domain.0]" "bottom.depth_m=$floor" \
      "target=[{ kind = \"box\", center_m = [20.0, 20.0, $centre], size_m = [$size, $size, 0.5], reflectance = 0.5 }]" \
      "$radiometers" "photons.count=$photons" "estimate.gather_rays=$gather" \
      ${TARGET_SPLIT:+"photons.target_split=$TARGET_SPLIT"} > "$out/$name.toml"
    pm=()
    for seed in $seeds; do
      "$bin" render "$out/$name.toml" --out "$out/$name-pm-$seed" --seed "$seed" --quiet 2>/dev/null
      pm+=("$out/$name-pm-$seed/$name.json")
    done
    "$bin" render "$out/$name.toml" --out "$out/$name-path" --integrator path --spp "$spp" --quiet 2>/dev/null
    python3 - "$size" "$depth" "$out/$name-path/$name.json" "${pm[@]}" <<'PY'
import json, math, sys
size, depth, path_json, *pm_json = sys.argv[1:]
mean = lambda v: sum(v) / len(v)

def reading(radiometers):
    """Box and sand (four positions' mean): per-band L and stderr, band-mean stderr."""
    box, sands = radiometers[0], radiometers[1:]
    n = len(sands)
    sand_l = [mean(b) for b in zip(*(r["L"] for r in sands))]
    sand_s = [math.sqrt(sum(s * s for s in b)) / n for b in zip(*(r["stderr"] for r in sands))]
    sand_bm = math.sqrt(sum(r["band_mean_stderr"] ** 2 for r in sands)) / n
    return [(box["L"], box["stderr"], box["band_mean_stderr"]), (sand_l, sand_s, sand_bm)]

path = reading(json.load(open(path_json))["radiometers"])
runs = [reading(json.load(open(p))["radiometers"]) for p in pm_json]
k = len(runs)
pm = []
for i in (0, 1):
    l = [mean(b) for b in zip(*(r[i][0] for r in runs))]
    if k > 2:
        # Standard error of the seeds' mean from their spread.
        se = [math.sqrt(sum((x - m) ** 2 for x in b) / (k - 1) / k)
              for b, m in zip(zip(*(r[i][0] for r in runs)), l)]
        bms = [mean(r[i][0]) for r in runs]
        bm_se = math.sqrt(sum((x - mean(bms)) ** 2 for x in bms) / (k - 1) / k)
    else:
        se = [math.sqrt(sum(s * s for s in b)) / k for b in zip(*(r[i][1] for r in runs))]
        bm_se = math.sqrt(sum(r[i][2] ** 2 for r in runs)) / k
    pm.append((l, se, bm_se))

def diff(a, b):
    m_a, m_b = mean(a[0]), mean(b[0])
    s = math.hypot(a[2], b[2])
    return f"{(m_a / m_b - 1) * 100:+.1f} % ± {s / m_b * 100:.1f} %"

worst = max(abs(x - y) / (3 * math.hypot(sa, sb) + 0.02 * y)
            for a, b in zip(pm, path)
            for x, y, sa, sb in zip(a[0], b[0], a[1], b[1]))
def contrast(r):
    c = mean(r[0][0]) / mean(r[1][0]) - 1
    se = (1 + c) * math.hypot(r[0][2] / mean(r[0][0]), r[1][2] / mean(r[1][0]))
    return f"{c * 100:.0f} % ± {se * 100:.0f} %"
print(f"| {size} m | {depth} m | {diff(pm[0], path[0])} | {diff(pm[1], path[1])} | {worst:.2f} | {contrast(pm)} | {contrast(path)} |")
PY
  done
done
