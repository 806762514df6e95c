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
# Read: nadir radiance 0.5 m and 2 m deep and the 4 x 4 pixel camera's
# water-leaving radiance just above the surface. The photon map (PHOTONS,
# once per seed) reads the radiance at nine positions 67 m apart and
# averages them: its error is correlated over its searches (5 m), and one
# position's reading strays by about 4 % from map to map, in every band
# alike. The path integrator (SPP paths per pixel, SPP x 1024 per
# radiometer at the centre, once per seed) is the reference. Per 50 nm of
# bands: the ratio of band sums - 1, with the standard error of the photon
# map's seeds' mean combined with that of the reference's. The
# reference's error comes from the spread of its seeds, not from its own
# standard error: its samples are heavy-tailed (it warns in the red at 2
# m), and two runs of 8192 paths per pixel differed by 3-4 % in L_w where
# each claimed 1 %.
#
# Usage: benches/scripts/deep_water.sh [OUTDIR] [PHOTONS] [SPP] [SEEDS]
# (defaults: target/bench-deep-water, 4000000, 2048, "1 2 3 4"; about 8
# minutes on two cores; needs python3 with numpy).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-deep-water}
photons=${2:-4000000}
spp=${3:-2048}
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
EOF

cp "$out/deep.toml" "$out/deep-path.toml"
for depth in 0.5 2.0; do
  printf '\n[[radiometer]]\ndepth_m = %s\nview = "nadir"\nposition_m = [100.0, 100.0]\n' \
    "$depth" >> "$out/deep-path.toml"
  for x in 33.0 100.0 167.0; do
    for y in 33.0 100.0 167.0; do
      printf '\n[[radiometer]]\ndepth_m = %s\nview = "nadir"\nposition_m = [%s, %s]\n' \
        "$depth" "$x" "$y" >> "$out/deep.toml"
    done
  done
done
refs=()
runs=()
for seed in $seeds; do
  "$bin" render "$out/deep-path.toml" --integrator path --spp "$spp" --seed "$seed" \
    --out "$out/path-$seed" 2>> "$out/path.log" >&2
  "$bin" render "$out/deep.toml" --seed "$seed" --map "$out/map-$seed" --out "$out/pm-$seed" \
    2>> "$out/pm.log" >&2
  refs+=("$out/path-$seed")
  runs+=("$out/pm-$seed")
done

python3 - "${#refs[@]}" "${refs[@]}" "${runs[@]}" <<'PY'
import json, re, sys
import numpy as np
n_ref = int(sys.argv[1])
refs, runs = sys.argv[2:2 + n_ref], sys.argv[2 + n_ref:]
report = lambda d: json.load(open(f"{d}/deep.json"))
hdr = open(f"{refs[0]}/deep.hdr").read()
wl = np.array([float(x) for x in re.search(r"wavelength = \{([^}]*)\}", hdr).group(1).split(",")])
groups = [(lo, lo + 50) for lo in range(400, 800, 50)]
def sums(values, sel):
    """Each seed's band sum over `sel`: its mean and standard error."""
    v = np.array(values)[:, sel].sum(1)
    return v.mean(), (v.std(ddof=1) / np.sqrt(len(v)) if len(v) > 1 else 0.0)
def line(name, pm, ref):
    cells = []
    for lo, hi in groups:
        sel = (wl >= lo) & (wl < hi)
        (m, sm), (r, sr) = sums(pm, sel), sums(ref, sel)
        cells.append(f"{m / r - 1:+.1%} ± {np.hypot(sm, sr) / r:.1%}")
    print(f"| {name} | " + " | ".join(cells) + " |")
print("| reading | " + " | ".join(f"{lo}-{hi} nm" for lo, hi in groups) + " |")
print("|---" * (len(groups) + 1) + "|")
def reading(d, depth):
    """The mean over a run's radiometers at `depth`."""
    return np.mean([r["L"] for r in report(d)["radiometers"] if r["depth_m"] == depth], axis=0)
for depth in (0.5, 2.0):
    line(f"nadir radiance {depth} m deep", [reading(d, depth) for d in runs],
         [reading(d, depth) for d in refs])
lw = lambda d: np.fromfile(f"{d}/deep.lw.bsq", dtype="<f4").reshape(len(wl), -1).astype(float).mean(1)
line("camera L_w (16 pixels)", [lw(d) for d in runs], [lw(d) for d in refs])
PY
