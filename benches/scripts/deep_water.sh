#!/usr/bin/env bash
# Deep, uniform water band by band against the path integrator: the
# built-in scene's water (Chl 1, CDOM 0.05 m^-1, NAP 0.01, Fournier-Forand
# b_b/b 0.0183) without its gradient, floor 30 m down (sand), Cox-Munk
# 3 m/s, sun 35 degrees (G173 direct and sky), 128 bands 400-800 nm, water
# Raman on, the built-in estimate settings (5 m searches, 0.75 m steps,
# `spectral = "grid"`). Nothing varies across the domain, so the photon
# map's band shapes meet light that falls with depth at each band's own
# rate and nothing else.
#
# Read: nadir radiometers at 0.5 m and 2 m (the centre of the domain) and
# the 4 x 4 pixel camera's water-leaving radiance just above the surface.
# The photon map (PHOTONS, once per seed) against the path integrator
# (SPP paths per pixel, SPP x 1024 per radiometer), per 50 nm of bands:
# the ratio of band sums - 1, with the standard error of the seeds' mean
# combined with the reference's own (its heavy tails make that uncertain
# in the red at 2 m, where it warns).
#
# Usage: benches/scripts/deep_water.sh [OUTDIR] [PHOTONS] [SPP] [SEEDS]
# (defaults: target/bench-deep-water, 4000000, 8192, "1 2 3 4"; about 8
# minutes on two cores; needs python3 with numpy).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-deep-water}
photons=${2:-4000000}
spp=${3:-8192}
seeds=${4:-1 2 3 4}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral

cat > "$out/deep.toml" <<EOF
name = "deep"
seed = 1

[spectral]
start_nm = 400.0
end_nm = 800.0
bands = 128
out_of_range = "clamp"

[sun]
zenith_deg = 35.0
azimuth_deg = 0.0
spectrum = "astm-g173-direct"

[surface]
kind = "cox-munk"
wind_speed = 3.0
refractive_index = 1.34

[domain]
size_m = [200.0, 200.0]
edges = "periodic"

[water]
chl = 1.0
cdom_440 = 0.05
cdom_slope = 0.015
nap_440 = 0.01
nap_slope = 0.011
phase = { kind = "fournier-forand", bb_ratio = 0.0183 }

[bottom]
depth_m = 30.0
reflectance = "sand"

[photons]
count = $photons

[sensor]
kind = "orthographic"
pixels = [4, 4]
gsd_m = 0.75
samples_per_pixel = 1

[estimate]
max_radius_m = 5.0
boundary = "clipped-sphere"
spectral = "grid"
step_m = 0.75

[[radiometer]]
depth_m = 0.5
view = "nadir"
position_m = [100.0, 100.0]

[[radiometer]]
depth_m = 2.0
view = "nadir"
position_m = [100.0, 100.0]
EOF

"$bin" render "$out/deep.toml" --integrator path --spp "$spp" --out "$out/path" 2> "$out/path.log" >&2
runs=()
for seed in $seeds; do
  "$bin" render "$out/deep.toml" --seed "$seed" --out "$out/pm-$seed" 2>> "$out/pm.log" >&2
  runs+=("$out/pm-$seed")
done

python3 - "$out/path" "${runs[@]}" <<'PY'
import json, re, sys
import numpy as np
ref, runs = sys.argv[1], sys.argv[2:]
report = lambda d: json.load(open(f"{d}/deep.json"))
hdr = open(f"{ref}/deep.hdr").read()
wl = np.array([float(x) for x in re.search(r"wavelength = \{([^}]*)\}", hdr).group(1).split(",")])
groups = [(lo, lo + 50) for lo in range(400, 800, 50)]
def line(name, m, sm, r, sr):
    cells = []
    for lo, hi in groups:
        sel = (wl >= lo) & (wl < hi)
        d = m[sel].sum() / r[sel].sum() - 1
        se = np.sqrt((sm[sel] ** 2).sum() + (sr[sel] ** 2).sum()) / r[sel].sum()
        cells.append(f"{d:+.1%} ± {se:.1%}")
    print(f"| {name} | " + " | ".join(cells) + " |")
print("| reading | " + " | ".join(f"{lo}-{hi}" for lo, hi in groups) + " |")
print("|---" * (len(groups) + 1) + "|")
path = report(ref)
n = len(runs)
for i, r in enumerate(path["radiometers"]):
    m = np.array([report(d)["radiometers"][i]["L"] for d in runs])
    sm = m.std(0, ddof=1) / np.sqrt(n) if n > 1 else np.zeros(m.shape[1])
    line(f"nadir radiance {r['depth_m']} m deep", m.mean(0), sm, np.array(r["L"]), np.array(r["stderr"]))
pixels = lambda d, name: np.fromfile(f"{d}/deep.{name}.bsq", dtype="<f4").reshape(len(wl), -1).astype(float)
m = np.array([pixels(d, "lw").mean(1) for d in runs])
sm = m.std(0, ddof=1) / np.sqrt(n) if n > 1 else np.zeros(m.shape[1])
# The reference's L_t standard error stands for its L_w's: the surface's
# reflected sky, the difference, is the same in every path.
se = pixels(ref, "stderr")
line("camera L_w (16 pixels)", m.mean(0), sm, pixels(ref, "lw").mean(1), np.sqrt((se ** 2).sum(1)) / se.shape[1])
PY
