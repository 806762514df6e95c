#!/usr/bin/env bash
# The atmosphere against DISORT at many photons, and the built-in scene seen
# from a satellite.
# Usage: benches/scripts/atmosphere.sh [OUTDIR] [SKY_PHOTONS]
# 1. A Rayleigh + aerosol column (tau(550) 0.3, g 0.7, albedo 0.9, 1.5 km
#    scale height; sun 30 degrees; 412, 490, 560 and 670 nm): the sky's and
#    the top's radiance per cell and the irradiances against DISORT
#    (nanodisort from PyPI, tests/clients/disort_atmosphere.py), and the
#    path radiance seen from 3 km and from 700 km, 30 degrees off nadir
#    (over a black surface, as DISORT: sea_coupling = false).
# 2. The built-in scene (maritime aerosol tau(550) 0.1, seen from 3 km
#    with the domain's mean around it) rendered as it is, with
#    --no-atmosphere (from just above the surface), from 700 km, and
#    without its air (the G173 sun and sky): times, and the deep-water
#    pixel noise of L_t and L_w (pixel against its 7 x 7 mean, 160-185 m
#    by 92-152 m) and the standard-error cube's median there.
# Needs python3 with numpy and nanodisort (tools/test.sh installs them in .venv).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-atmosphere}
photons=${2:-1000000}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
py=${PYTHON:-python3}
aerosol='atmosphere.aerosol={model="custom", tau_550=0.3, angstrom=1.0, ssa=0.9, phase={kind="henyey-greenstein", g=0.7}, scale_height_km=1.5}'
"$bin" scene set tests/scenes/minimal.toml 'spectral={centers_nm=[412.0, 490.0, 560.0, 670.0], fwhm_nm=[10.0, 10.0, 10.0, 10.0]}' \
  'sun={zenith_deg=30.0, spectrum="extraterrestrial"}' "atmosphere.sky_photons=$photons" atmosphere.sea_coupling=false "$aerosol" > "$out/column.toml"
for view in "3000.0 30.0" "700000.0 30.0"; do
  set -- $view
  "$bin" scene set "$out/column.toml" "sensor={pixels=[4, 4], gsd_m=1.0, altitude_m=$1, view_zenith_deg=$2, view_azimuth_deg=120.0}" > "$out/view-$1.toml"
  "$bin" scene atmosphere "$out/view-$1.toml" --toa > "$out/view-$1.json"
  "$py" tests/clients/disort_atmosphere.py "$out/view-$1.json" > "$out/view-$1-disort.json"
  "$py" - "$out/view-$1.json" "$out/view-$1-disort.json" <<'PY'
import json, sys
a = json.load(open(sys.argv[1])); d = json.load(open(sys.argv[2]))
v = a["view"]
print(f"sensor at {v['altitude_m']:.0f} m, {v['view_zenith_deg']:.0f} deg off nadir")
for b, x in zip(a["bands"], d):
    bb = b["band"]
    ratio = lambda ours, theirs: [o / t for o, t in zip(ours, theirs) if t > 0]
    sky = ratio(b["sky_radiance"], x["sky"])
    top = ratio(b["toa_radiance"][: 12 * 18], x["toa"][: 12 * 18])
    print(f"  {bb['nm']:.0f} nm: diffuse {bb['diffuse'] / x['diffuse'] - 1:+.2%}, flux {bb['diffuse_flux'] / x['diffuse'] - 1:+.2%}"
          f" (se {bb['diffuse_flux_se'] / x['diffuse']:.2%}), up at top {bb['up_at_top'] / x['up_at_top'] - 1:+.2%};"
          f" sky cells {min(sky) - 1:+.2%} to {max(sky) - 1:+.2%}, top cells to 60 deg {min(top) - 1:+.2%} to {max(top) - 1:+.2%};"
          f" path radiance {v['path_radiance'][a['bands'].index(b)] / x['path_radiance'] - 1:+.2%}"
          f" (se {v['path_radiance_se'][a['bands'].index(b)] / x['path_radiance']:.2%})")
PY
done
"$bin" scene default > "$out/airborne.toml"
"$bin" scene set "$out/airborne.toml" sensor.altitude_m=700000.0 > "$out/satellite.toml"
# The built-in scene without air: the G173 sun and sky, seen from just above the surface.
"$py" - "$out/airborne.toml" > "$out/no-air.toml" <<'PY'
import re, sys
t = open(sys.argv[1]).read()
t = t.replace('spectrum = "extraterrestrial"', 'spectrum = "astm-g173-direct"\n\n[sky]\nspectrum = "astm-g173-diffuse"')
t = re.sub(r"\[atmosphere\]\n(?:[^\[\n][^\n]*\n|\n)*?(?=\[)", "", t)
t = re.sub(r"\[surroundings\]\n[^\[]*", "", t)
t = re.sub(r"altitude_m = [0-9.]+\n", "", t)
sys.stdout.write(t)
PY
"$bin" render "$out/airborne.toml" --out "$out/airborne" --quiet 2>/dev/null
"$bin" render "$out/airborne.toml" --no-atmosphere --out "$out/surface" --quiet 2>/dev/null
"$bin" render "$out/satellite.toml" --out "$out/satellite" --quiet 2>/dev/null
"$bin" render "$out/no-air.toml" --out "$out/no-air" --quiet 2>/dev/null
"$py" - "$out" <<'PY'
import json, os, re, sys
import numpy as np
out = sys.argv[1]
def cube(p):
    return np.fromfile(p, dtype="<f4").reshape(128, 256, 256).astype(float)
hdr = open(f"{out}/airborne/coastal.hdr").read()
wl = np.array([float(x) for x in re.search(r"wavelength = \{([^}]*)\}", hdr).group(1).split(",")])
# Deep water, 160-185 m by 92-152 m: each pixel against its 7 x 7 mean,
# and the median of the standard-error cube.
x0, x1, y0, y1 = int(160 / 0.75), int(185 / 0.75), int(92 / 0.75), int(152 / 0.75)
def noise(w):
    from numpy.lib.stride_tricks import sliding_window_view
    m = sliding_window_view(w, (7, 7)).mean(axis=(2, 3))
    return (w[3:-3, 3:-3] - m).std() * np.sqrt(49 / 48) / w.mean()
for v in ["no-air", "surface", "airborne", "satellite"]:
    r = json.load(open(f"{out}/{v}/coastal.json"))
    print(v, "timings", r["timings_s"])
    for nm in [413, 526, 671]:
        b = int(np.argmin(abs(wl - nm)))
        lt = cube(f"{out}/{v}/coastal.bsq")[b][y0:y1, x0:x1]
        lw = cube(f"{out}/{v}/coastal.lw.bsq")[b][y0:y1, x0:x1]
        se = cube(f"{out}/{v}/coastal.stderr.bsq")[b][y0:y1, x0:x1]
        print(f"  {wl[b]:.0f} nm: L_t {lt.mean():.5f} noise {noise(lt):.2%} (standard error, median {np.median(se / lt):.2%});"
              f" L_w {lw.mean():.5f} noise {noise(lw):.2%}")
PY
