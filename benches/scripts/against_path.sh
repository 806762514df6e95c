#!/usr/bin/env bash
# Radiometers of the photon map (default settings) against the path
# integrator in small scenes: deep, shallow with a floor, layered, a
# target, a rough surface, and a radiometer 0.1 mm above the floor.
# In the horizontally uniform scenes (all but the target's) each radiometer
# is read at 9 positions 10 m apart (a 3 x 3 grid; the scene file's own
# position is the centre) and the reading is their mean: the standard
# error of each integrator's band mean is then the positions' spread, an
# error bar that does not rest on either integrator's own (the path
# integrator's own band-mean error has read 1.5-2.5 times too small here).
# The photon map runs once per seed; its band mean is the seeds' mean, with
# the standard error of that mean from the seeds' and positions' spread.
# Usage: benches/scripts/against_path.sh [OUTDIR] [PHOTONS] [SPP] [SEEDS]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-against-path}
photons=${2:-4000000}
spp=${3:-128}
seeds=${4:-1}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
# The scenes are tests/scenes/against_path/, shared with the test.
scenes=tests/scenes/against_path
echo "| scene | depth (m) | path, band mean ± its error (its own estimate) | photon map − path | ± (band mean) | z (band mean) | worst band |"
echo "|---|---|---|---|---|---|---|"
for f in deep shallow layered target rough near_floor; do
  # The scene with each radiometer at 9 positions (the target's: as is).
  python3 - "$scenes/$f.toml" "$out/$f.toml" "$f" <<'PY'
import re, sys, tomllib
src, dst, name = sys.argv[1:]
text = open(src).read()
scene = tomllib.loads(text)
rads = scene.get("radiometer", [])
head = text[: text.index("[[radiometer]]")] if rads else text
out = [head]
for r in rads:
    x0, y0 = r.get("position_m", [20.0, 20.0])
    grid = [(0, 0)] if name == "target" else [(dx, dy) for dy in (0, -10, 10) for dx in (0, -10, 10)]
    for dx, dy in grid:
        extra = "".join(f"{k} = {v!r}\n" for k, v in r.items() if k not in ("depth_m", "view", "position_m"))
        out.append(f"[[radiometer]]\ndepth_m = {r['depth_m']}\nview = \"{r.get('view', 'nadir')}\"\n"
                   f"position_m = [{x0 + dx}, {y0 + dy}]\n{extra}")
open(dst, "w").write("".join(out))
PY
  "$bin" render "$out/$f.toml" --out "$out/$f-path" --integrator path --spp "$spp" --quiet 2>/dev/null
  runs=()
  for seed in $seeds; do
    "$bin" render "$out/$f.toml" --out "$out/$f-pm-s$seed" --photons "$photons" --seed "$seed" --quiet 2>/dev/null
    runs+=("$out/$f-pm-s$seed/$f.json")
  done
  python3 - "$f" "$out/$f-path/$f.json" "${runs[@]}" <<'PY'
import json, math, sys
name, pa = sys.argv[1], json.load(open(sys.argv[2]))
pms = [json.load(open(p)) for p in sys.argv[3:]]
# Radiometers in groups of one depth and view (the positions of one).
def groups(report):
    g = {}
    for r in report["radiometers"]:
        g.setdefault((r["depth_m"], r["view"]), []).append(r)
    return g
def mean(v):
    return sum(v) / len(v)
def spread_se(v):
    m = mean(v)
    return math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1) / len(v)) if len(v) > 1 else None
path_groups = groups(pa)
for key, rs in path_groups.items():
    nb = len(rs[0]["L"])
    per_pos = [mean(r["L"]) for r in rs]
    l = mean(per_pos)
    own = math.sqrt(sum(r["band_mean_stderr"] ** 2 for r in rs)) / len(rs)
    l_se = max(own, spread_se(per_pos) or 0.0)
    # The photon map: every seed's every position.
    pm_pos = [mean(r["L"]) for pm in pms for r in groups(pm)[key]]
    m = mean(pm_pos)
    m_se = spread_se(pm_pos) or groups(pms[0])[key][0]["band_mean_stderr"]
    se = math.hypot(m_se, l_se) / l
    band_path = [mean([r["L"][k] for r in rs]) for k in range(nb)]
    band_pm = [mean([r["L"][k] for pm in pms for r in groups(pm)[key]]) for k in range(nb)]
    worst = max(abs(x / y - 1) for x, y in zip(band_pm, band_path))
    print(f"| {name} | {key[0]} | {l:.5g} ± {l_se / l * 100:.2f} % (own {own / l * 100:.2f} %) "
          f"| {m / l - 1:+.1%} | {se * 100:.1f} % | {(m / l - 1) / se:+.1f} | {worst:.1%} |")
PY
done
