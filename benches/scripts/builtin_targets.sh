#!/usr/bin/env bash
# The built-in scene's submerged targets: the 2 m grey panel (top 3.95 m
# deep) and the dark 3 m box (top 7.15 m deep), read by nadir radiometers
# 1 m above the water over each one's centre and 3.5 m (panel) / 4.5 m
# (box) north of it over the sand, the photon map at the default 4 M
# photons against the path integrator.
# Usage: benches/scripts/builtin_targets.sh [OUTDIR] [SPP] [SEEDS]
# (SPP: the path integrator's samples per pixel; each radiometer reads
# 1024 x SPP paths. Default 1024: at 128 its heavy tails left a run's
# box reading 1.8 % below that of 1024. SEEDS: the photon map's seeds,
# default 1-12: four seeds' spread, with 3 degrees of freedom, put the
# box's contrast 3.4 standard errors off where twelve put it 1.1.) Prints one markdown row per target: the band-mean L
# difference with its combined standard error and the target/sand
# contrast of both integrators. With more than two seeds the photon map's
# error bars are the standard error of the seeds' mean from their spread.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-builtin-targets}
spp=${2:-1024}
seeds=${3:-1 2 3 4 5 6 7 8 9 10 11 12}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
"$bin" scene default > "$out/base.toml"
rad() { echo "{ depth_m = -1.0, view = \"nadir\", position_m = [$1, $2] }"; }
# The image is cut to one tile: the radiometers are what is measured.
"$bin" scene set "$out/base.toml" \
  "radiometer=[$(rad 66.0 140.0), $(rad 66.0 143.5), $(rad 114.0 150.0), $(rad 114.0 154.5)]" \
  "sensor.pixels=[16, 16]" > "$out/coastal.toml"
pm=()
for seed in $seeds; do
  "$bin" render "$out/coastal.toml" --out "$out/pm-$seed" --seed "$seed" --quiet 2>/dev/null
  pm+=("$out/pm-$seed/coastal.json")
done
"$bin" render "$out/coastal.toml" --out "$out/path" --integrator path --spp "$spp" --quiet 2>/dev/null
python3 - "$out/path/coastal.json" "${pm[@]}" <<'PY'
import json, math, sys
path_json, *pm_json = sys.argv[1:]
mean = lambda v: sum(v) / len(v)
load = lambda p: json.load(open(p))["radiometers"]
path = load(path_json)
runs = [load(p) for p in pm_json]
k = len(runs)

def pm_reading(i):
    """Band mean of radiometer i over the seeds and its standard error."""
    bms = [mean(r[i]["L"]) for r in runs]
    if k > 2:
        se = math.sqrt(sum((x - mean(bms)) ** 2 for x in bms) / (k - 1) / k)
    else:
        se = math.sqrt(sum(r[i]["band_mean_stderr"] ** 2 for r in runs)) / k
    return mean(bms), se

def path_reading(i):
    return mean(path[i]["L"]), path[i]["band_mean_stderr"]

def contrast(t, s):
    c = t[0] / s[0] - 1
    return c, (1 + c) * math.hypot(t[1] / t[0], s[1] / s[0])

print("| target | target: photon map - path | sand: photon map - path | contrast photon map | contrast path |")
print("|---|---|---|---|---|")
for name, (t, s) in (("2 m panel, top 3.95 m", (0, 1)), ("3 m dark box, top 7.15 m", (2, 3))):
    cells = []
    for i in (t, s):
        a, b = pm_reading(i), path_reading(i)
        cells.append(f"{(a[0] / b[0] - 1) * 100:+.1f} % ± {math.hypot(a[1], b[1]) / b[0] * 100:.1f} %")
    cp = contrast(pm_reading(t), pm_reading(s))
    cq = contrast(path_reading(t), path_reading(s))
    print(f"| {name} | {cells[0]} | {cells[1]} | {cp[0] * 100:.1f} % ± {cp[1] * 100:.1f} % | {cq[0] * 100:.1f} % ± {cq[1] * 100:.1f} % |")
PY
