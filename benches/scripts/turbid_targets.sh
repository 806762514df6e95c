#!/usr/bin/env bash
# Submerged boxes in turbid water, the CI test's scene
# (tests/integration/against_path.rs: 1 m boxes with tops at 3 m and 1.5
# m, a 2 m box at 5.5 m, reflectance 0.5, sand at 6 m; Chl 10, CDOM 0.1,
# NAP 0.05, flat surface, sun 30 degrees, 32 bands 400-720 nm, 40 m
# domain) with a 0.5 m box at 1.5 m added at (20, 20) m:
# - the downwelling radiance just above the boxes, which the final gather
#   rays off a top face see: zenith radiometers 5 cm above each of the
#   three boxes' tops, over the centre, a quarter of the box's width off
#   it, and over the sand 5 m away at the same depth;
# - each of the four boxes and the sand at (30, 30) m from the air (nadir
#   radiometers 1 m above the water);
# - the sun's aureole 3 m deep at (20, 30) m: 5 degrees from the refracted
#   sun toward the zenith and away from it (1-degree fields).
# The photon map (default settings, PHOTONS, once per seed) against the
# path integrator (SPP x 1024 paths per radiometer).
# Usage: benches/scripts/turbid_targets.sh [OUTDIR] [PHOTONS] [SPP] [SEEDS]
# (defaults: target/bench-turbid-targets, 4000000, 512, "1 2 3 4"; 10
# minutes on two cores). Prints each radiometer's band-mean difference
# with the standard error of the seeds' mean (with one seed: its own),
# combined with the path integrator's own, and three single bands.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-turbid-targets}
photons=${2:-4000000}
spp=${3:-512}
seeds=${4:-1 2 3 4}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
boxes="(30.0, 10.0, 1.0, 3.0), (10.0, 30.0, 2.0, 5.5), (10.0, 10.0, 1.0, 1.5)"
python3 - "$out/above.toml" "$boxes" <<'PY'
import sys
dst, boxes = sys.argv[1], eval("[" + sys.argv[2] + "]")
text = open("tests/scenes/box.toml").read()
head = text[: text.index("[[target]]")]
for a, b in (('name = "box"', 'name = "above"'), ("chl = 2.0", "chl = 10.0"),
             ("cdom_440 = 0.05", "cdom_440 = 0.1"), ("nap_440 = 0.02", "nap_440 = 0.05"),
             ("depth_m = 2.0", "depth_m = 6.0")):
    assert a in head, a
    head = head.replace(a, b)
out = [head]
for x, y, s, top in boxes:
    out.append(f'[[target]]\nkind = "box"\ncenter_m = [{x}, {y}, {-(top + 0.25)}]\n'
               f"size_m = [{s}, {s}, 0.5]\nreflectance = 0.5\n")
out.append('[[target]]\nkind = "box"\ncenter_m = [20.0, 20.0, -1.75]\nsize_m = [0.5, 0.5, 0.5]\nreflectance = 0.5\n')
out.append("[photons]\ncount = 4000000\n[sensor]\npixels = [1, 1]\n")
for x, y, s, top in boxes:
    for px, py in ((x, y), (x + 0.25 * s, y), (x, y + 5.0)):
        out.append(f'[[radiometer]]\ndepth_m = {top - 0.05}\nview = "zenith"\nposition_m = [{px}, {py}]\n')
for x, y in [(b[0], b[1]) for b in boxes] + [(20.0, 20.0), (30.0, 30.0)]:
    out.append(f'[[radiometer]]\ndepth_m = -1.0\nview = "nadir"\nposition_m = [{x}, {y}]\n')
# The sun (azimuth 0: toward +x) refracted into the water, 5 degrees off.
import math
theta_w = math.asin(math.sin(math.radians(30.0)) / 1.34)
for off in (-5.0, 5.0):
    t = theta_w + math.radians(off)
    out.append(f'[[radiometer]]\ndepth_m = 3.0\nview = [{math.sin(t):.6f}, 0.0, {math.cos(t):.6f}]\n'
               'position_m = [20.0, 30.0]\nhalf_angle_deg = 1.0\n')
open(dst, "w").write("".join(out))
PY
"$bin" render "$out/above.toml" --out "$out/path" --integrator path --spp "$spp" --quiet 2>/dev/null
pm=()
for seed in $seeds; do
  "$bin" render "$out/above.toml" --out "$out/pm-$seed" --photons "$photons" --seed "$seed" --quiet 2>/dev/null
  pm+=("$out/pm-$seed/above.json")
done
python3 - "$out/path/above.json" "${pm[@]}" <<'PY'
import json, math, sys
path = json.load(open(sys.argv[1]))
runs = [json.load(open(p)) for p in sys.argv[2:]]
mean = lambda v: sum(v) / len(v)
nm = path["bands_nm"]
picks = [3, 13, 25]
print("| radiometer | position (m) | path (± its error) | photon map − path | "
      + " | ".join(f"{nm[b]:.0f} nm" for b in picks) + " |")
print("|---|---|---|---|" + "---|" * len(picks))
kinds = [f"5 cm above the {k}, top {t} m" for t in ("3", "5.5", "1.5")
         for k in ("box's centre", "box, off centre", "sand 5 m away")]
kinds += ["from the air: 1 m box, top 3 m", "from the air: 2 m box, top 5.5 m",
          "from the air: 1 m box, top 1.5 m", "from the air: 0.5 m box, top 1.5 m",
          "from the air: sand", "3 m deep, 5° from the refracted sun toward the zenith",
          "3 m deep, 5° from the refracted sun away from the zenith"]
for i, r in enumerate(path["radiometers"]):
    p, p_se = mean(r["L"]), r["band_mean_stderr"]
    ms = [mean(x["radiometers"][i]["L"]) for x in runs]
    k = len(ms)
    m_se = (math.sqrt(sum((v - mean(ms)) ** 2 for v in ms) / (k - 1) / k) if k > 1
            else runs[0]["radiometers"][i]["band_mean_stderr"])
    bands = " | ".join(f"{(mean([x['radiometers'][i]['L'][b] for x in runs]) / r['L'][b] - 1) * 100:+.1f} %"
                       for b in picks)
    print(f"| {kinds[i]} | {r['position_m']} | {p:.5g} ± {p_se / p * 100:.2f} % "
          f"| {(mean(ms) / p - 1) * 100:+.2f} % ± {math.hypot(m_se, p_se) / p * 100:.2f} % | {bands} |")
PY
