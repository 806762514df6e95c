#!/usr/bin/env bash
# In-water views far from the vertical, where the photon map's estimates
# once read low (near-horizontal views) or high (wide-field radiometers):
#
# 1. Near-horizontal views deep in forward-scattering water: a 0.1, b 0.5
#    m^-1 (Fournier-Forand, b_b/b 0.0183), sun 30 degrees, flat surface,
#    one band, a 20 m domain; radiometers 5 m deep with a 3-degree field,
#    looking 5 degrees above the horizon toward +x, +y, -x and -y and
#    straight up, at 9 positions (a 3 x 3 grid 6 m apart). The photon map
#    (PHOTONS, once per seed) against the path integrator (SPP x 1024
#    paths per radiometer); each view's reading is its 9 positions' mean.
#    `FORWARD_PEAK_DEG` in the environment sets `[estimate]
#    forward_peak_deg` (the answer must not depend on it).
# 2. A cosine-weighted radiometer over the lower hemisphere (half-angle
#    89.9 degrees) 1 m deep in turbid case-1 water (Chl 5, CDOM 0.2 m^-1,
#    no floor, flat surface, sun 30 degrees, 8 bands 400-700 nm, 9
#    positions 10 m apart in a 40 m domain) against the emission's own
#    upward irradiance tally at 1 m over pi, per seed.
#
# Usage: benches/scripts/grazing.sh [OUTDIR] [PHOTONS] [SPP] [SEEDS]
# (defaults: target/bench-grazing, 4000000, 512, "1 2 3 4"; 20 minutes on
# two cores). Prints the photon map's band mean against the reference with
# the standard error of the seeds' mean (with one seed: the positions'
# spread), combined with the reference's own.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-grazing}
photons=${2:-4000000}
spp=${3:-512}
seeds=${4:-1 2 3 4}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral

python3 - "$out" "${FORWARD_PEAK_DEG:-}" <<'PY'
import math, sys
out, peak = sys.argv[1], sys.argv[2]
estimate = f"[estimate]\nforward_peak_deg = {peak}\n" if peak else ""
views = []
for px in (4, 10, 16):
    for py in (4, 10, 16):
        for az in (0, 90, 180, 270):
            e, a = math.radians(5), math.radians(az)
            v = [math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)]
            views.append(f"[[radiometer]]\ndepth_m = 5.0\nview = [{v[0]:.6f}, {v[1]:.6f}, {v[2]:.6f}]\n"
                         f"position_m = [{px}.0, {py}.0]\nhalf_angle_deg = 3.0\n")
        views.append(f"[[radiometer]]\ndepth_m = 5.0\nview = \"zenith\"\nposition_m = [{px}.0, {py}.0]\n"
                     "half_angle_deg = 3.0\n")
open(f"{out}/horizontal.toml", "w").write(f'''name = "horizontal"
[spectral]
start_nm = 500.0
end_nm = 510.0
bands = 1
[sun]
zenith_deg = 30.0
irradiance = 1.0
[domain]
size_m = [20.0, 20.0]
[water]
iop = {{ a = 0.1, b = 0.5 }}
phase = {{ kind = "fournier-forand", bb_ratio = 0.0183 }}
[photons]
count = 4000000
[sensor]
pixels = [1, 1]
{estimate}''' + "".join(views))
hemi = [f"[[radiometer]]\ndepth_m = 1.0\nview = \"nadir\"\nposition_m = [{px}.0, {py}.0]\n"
        "half_angle_deg = 89.9\n" for px in (10, 20, 30) for py in (10, 20, 30)]
open(f"{out}/hemisphere.toml", "w").write('''name = "hemisphere"
[spectral]
start_nm = 400.0
end_nm = 700.0
bands = 8
out_of_range = "clamp"
[sun]
zenith_deg = 30.0
spectrum = "astm-g173-direct"
[domain]
size_m = [40.0, 40.0]
[water]
chl = 5.0
cdom_440 = 0.2
[photons]
count = 4000000
[sensor]
pixels = [1, 1]
[tally]
depths_m = [1.0]
''' + "".join(hemi))
PY

"$bin" render "$out/horizontal.toml" --out "$out/horizontal-path" --integrator path --spp "$spp" --quiet 2>/dev/null
h=() u=()
for seed in $seeds; do
  "$bin" render "$out/horizontal.toml" --out "$out/horizontal-pm-$seed" --photons "$photons" --seed "$seed" --quiet 2>/dev/null
  "$bin" render "$out/hemisphere.toml" --out "$out/hemisphere-pm-$seed" --photons "$photons" --seed "$seed" --quiet 2>/dev/null
  h+=("$out/horizontal-pm-$seed/horizontal.json")
  u+=("$out/hemisphere-pm-$seed/hemisphere.json")
done

python3 - "$out/horizontal-path/horizontal.json" "${#h[@]}" "${h[@]}" "${u[@]}" <<'PY'
import json, math, sys
path = json.load(open(sys.argv[1]))
n = int(sys.argv[2])
horizontal = [json.load(open(p)) for p in sys.argv[3:3 + n]]
hemisphere = [json.load(open(p)) for p in sys.argv[3 + n:]]
mean = lambda v: sum(v) / len(v)
def seeds_se(values, fallback):
    k = len(values)
    if k < 2:
        return fallback
    m = mean(values)
    return math.sqrt(sum((x - m) ** 2 for x in values) / (k - 1) / k)

print("| view, 5 m deep | path (± its error) | photon map − path |")
print("|---|---|---|")
names = {"0.996195,0,0.087156": "5° above the horizon, toward +x (the sun's side)",
         "0,0.996195,0.087156": "5° above the horizon, toward +y",
         "-0.996195,0,0.087156": "5° above the horizon, toward −x",
         "-0,-0.996195,0.087156": "5° above the horizon, toward −y",
         "zenith": "zenith"}
groups = {}
for i, r in enumerate(path["radiometers"]):
    groups.setdefault(r["view"], []).append(i)
for view, idx in groups.items():
    p = mean([path["radiometers"][i]["L"][0] for i in idx])
    p_se = math.sqrt(sum(path["radiometers"][i]["band_mean_stderr"] ** 2 for i in idx)) / len(idx)
    per_seed = [mean([r["radiometers"][i]["L"][0] for i in idx]) for r in horizontal]
    spread = [r["radiometers"][i]["L"][0] for r in horizontal for i in idx]
    own = math.sqrt(sum((x - mean(spread)) ** 2 for x in spread) / (len(spread) - 1) / len(spread))
    se = math.hypot(seeds_se(per_seed, own), p_se) / p
    print(f"| {names.get(view, view)} | {p:.5g} ± {p_se / p * 100:.2f} % | {(mean(per_seed) / p - 1) * 100:+.2f} % ± {se * 100:.2f} % |")

print()
print("| band | hemispherical radiometer 1 m deep / (E_u / π) of the tally |")
print("|---|---|")
ratios = []
for r in hemisphere:
    eu = r["tally"][0]["Eu"]
    nb = len(eu)
    l = [mean([x["L"][b] for x in r["radiometers"]]) for b in range(nb)]
    ratios.append([l[b] * math.pi / eu[b] for b in range(nb)] + [sum(l) * math.pi / sum(eu)])
for b in range(len(ratios[0])):
    v = [r[b] for r in ratios]
    t = hemisphere[0]["tally"][0]
    fallback = t["Eu_stderr"][b] / t["Eu"][b] / math.sqrt(len(v)) if b < len(t["Eu"]) else float("nan")
    nm = hemisphere[0]["bands_nm"]
    label = f"{nm[b]:.0f} nm" if b < len(nm) else "band mean"
    print(f"| {label} | {(mean(v) - 1) * 100:+.2f} % ± {seeds_se(v, fallback) * 100:.2f} % |")
PY
