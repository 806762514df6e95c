#!/usr/bin/env bash
# Quality per time against the peers, in one run.
#
# 1. Deep water whose 128 bands (400-700 nm) all have the same IOPs and sun
#    (tests/scenes/identical_bands.toml: a 0.1, b 0.4 m^-1, Fournier-Forand
#    b_b/b 0.0183, sun 30 degrees, flat surface; 48 x 48 nadir pixels of
#    0.5 m), so every (pixel, band) has the same radiance and the spread of
#    the values around their mean is each method's error. Rendered by:
#    - the photon map (4 M photons, emission included);
#    - littoral's path integrator at PATH_SPP and 4 x PATH_SPP samples per
#      pixel (every band in one path);
#    - Mitsuba 3 (`volpath`, LLVM, one band: the 128 bands are 128 renders)
#      at MI_SPP and 4 x MI_SPP, the water a homogeneous medium with the
#      Fournier-Forand phase function tabulated (`tabphase`) under a flat
#      dielectric. Mitsuba cannot connect a point in the water to a
#      directional sun through the refracting surface, so the sun is an
#      azimuthal ring 1 degree wide at its zenith angle carrying its
#      horizontal irradiance: exact for a nadir view over horizontally
#      uniform water (the radiance does not depend on the sun's azimuth),
#      which is why this scene and no other is compared with it.
#    For each: the per-(pixel, band) error against the exact answer (the
#    path integrator's 8 M-path reading, +- 0.21 %), the wall time, the error's fall
#    from the lower count to the higher (0.5 when it falls as 1/sqrt(N)),
#    and the time it needs to reach the photon map's error, by 1/sqrt(N)
#    from the higher count.
# 2. The built-in scene, photon map (emission included) against the path
#    integrator at BUILTIN_SPP, each with its standard-error cube: the
#    median relative standard error per (pixel, band) over the whole cube,
#    deep water, the shallow sand by the beach, the panel and the dark box,
#    and the time the path integrator needs to match the photon map there.
#
# Usage: benches/scripts/peers.sh [OUTDIR] [PATH_SPP] [MI_SPP] [BUILTIN_SPP]
# (defaults 4096, 256, 16). Needs python3 with numpy and Mitsuba 3:
# `pip install numpy mitsuba==3.5.2` (its wheels' LLVM variant runs on the
# system's LLVM 15; newer Mitsuba emits code LLVM 15 cannot compile).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-peers}
pspp=${2:-4096}
mspp=${3:-256}
bspp=${4:-16}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
seconds() { local t0; t0=$(date +%s.%N); "$@" >/dev/null; echo "$(date +%s.%N) - $t0" | bc; }
spread() {
  python3 - "$1" <<'PY'
import re, sys, numpy as np
hdr = sys.argv[1]; t = open(hdr).read()
g = lambda k: int(re.search(k + r'\s*=\s*(\d+)', t).group(1))
d = np.fromfile(hdr[:-4] + '.bsq', dtype='<f4').astype(float)
print(f"{d.mean():.6g} {d.std() / d.mean():.6g}")
PY
}
scene="$out/deep.toml"
"$bin" scene set tests/scenes/identical_bands.toml spectral.start_nm=400.0 spectral.end_nm=700.0 \
  spectral.bands=128 'domain.size_m=[60.0, 60.0]' photons.count=4000000 'sensor.pixels=[48, 48]' \
  sensor.gsd_m=0.5 > "$scene"
rm -rf "$out/pm.map"
t_pm=$(seconds "$bin" render "$scene" --out "$out/pm" --map "$out/pm.map" --quiet)
pm=$(spread "$out/pm/ident.hdr")
rows="photon-map 0 $t_pm $pm 0"
for n in "$pspp" $((4 * pspp)); do
  t=$(seconds "$bin" render "$scene" --out "$out/path-$n" --integrator path --spp "$n" --quiet)
  rows+=$'\n'"path $n $t $(spread "$out/path-$n/ident.hdr") 0"
done
cat > "$out/mitsuba_deep.py" <<'PY'
import sys, time, math, numpy as np
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
spp = int(sys.argv[1])
# Deep water of identical_bands.toml: a 0.1, b 0.4 m^-1, Fournier-Forand b_b/b 0.0183,
# flat surface (n 1.34), sun 30 deg of 1 W m^-2 nm^-1 beam-normal irradiance.
a, b, n_w, sun_zen, e_sun = 0.1, 0.4, 1.34, 30.0, 1.0
def ff(mu, bb=0.0183):
    # Fournier-Forand with n = 1.10 and mu from b_b/b (Mobley et al. 2002 form).
    # Solve for the slope mu (Junge exponent) by bisection on the backscatter fraction.
    n = 1.10
    def parts(m, psi):
        nu = (3 - m) / 2
        d = 4 * np.sin(psi / 2) ** 2 / (3 * (n - 1) ** 2)
        d180 = 4 / (3 * (n - 1) ** 2)
        p = (1 / (4 * np.pi * (1 - d) ** 2 * d ** nu) * (nu * (1 - d) - (1 - d ** nu)
             + (d * (1 - d ** nu) - nu * (1 - d)) / np.sin(psi / 2) ** 2)
             + (1 - d180 ** nu) / (16 * np.pi * (d180 - 1) * d180 ** nu) * (3 * np.cos(psi) ** 2 - 1))
        return p
    def back(m):
        nu = (3 - m) / 2
        d90 = 4 * np.sin(np.pi / 4) ** 2 / (3 * (n - 1) ** 2)
        return 1 - (1 - d90 ** (nu + 1) - 0.5 * (1 - d90 ** nu)) / ((1 - d90) * d90 ** nu)
    lo, hi = 3.0001, 5.0
    for _ in range(100):
        m = 0.5 * (lo + hi)
        if back(m) < bb: lo = m
        else: hi = m
    psi = np.maximum(np.arccos(np.clip(mu, -1, 1 - 1e-12)), 1e-6)
    p = parts(m, psi)
    # The form is 0/0 where delta = 1 (psi near 10 degrees): there, the
    # line between the nodes either side.
    d = 4 * np.sin(psi / 2) ** 2 / (3 * (n - 1) ** 2)
    bad = np.abs(1 - d) < 5e-3
    p[bad] = np.interp(mu[bad], mu[~bad], p[~bad])
    # The last interval holds the peak, whose values no line between
    # nodes follows: its node is set so that the interval carries the
    # probability the distribution function gives it.
    nu = (3 - m) / 2
    d180 = 4 / (3 * (n - 1) ** 2)
    h = mu[-1] - mu[-2]
    psi_h = np.arccos(1 - h)
    dh = 4 * np.sin(psi_h / 2) ** 2 / (3 * (n - 1) ** 2)
    cdf = ((1 - dh ** (nu + 1)) - np.sin(psi_h / 2) ** 2 * (1 - dh ** nu)) / ((1 - dh) * dh ** nu) \
        + 0.125 * (1 - d180 ** nu) / ((d180 - 1) * d180 ** nu) * np.cos(psi_h) * np.sin(psi_h) ** 2
    p[-1] = cdf / (np.pi * h) - p[-2]
    return p
nodes = 200001
mu = np.linspace(-1.0, 1.0, nodes)
vals = ff(mu)
# The sun as an azimuthal ring at its zenith angle, one 1-degree row of a
# lat-long map, carrying the beam's horizontal irradiance: for a nadir view
# over horizontally uniform water the radiance does not depend on the sun's
# azimuth, so the ring gives the sun's answer (it would not over a floor or
# a target, or off nadir). The ring is 1 degree wide: its spread of sun
# zeniths changes the answer in second order only, and a narrower one
# would only be hit less often.
rows, cols = 360, 8
env = np.zeros((rows, cols, 3), dtype=np.float32)
row0, row1 = round((sun_zen - 0.5) * 2), round((sun_zen + 0.5) * 2)
theta0, theta1 = math.radians(row0 / 2), math.radians(row1 / 2)
# The integral of cos(theta) over the ring's solid angle.
omega_cos = np.pi * (math.sin(theta1) ** 2 - math.sin(theta0) ** 2)
env[row0:row1, :, :] = e_sun * math.cos(math.radians(sun_zen)) / omega_cos
scene = mi.load_dict({
    "type": "scene",
    "integrator": {"type": "volpath", "max_depth": -1, "rr_depth": 20},
    "sensor": {
        "type": "orthographic",
        "to_world": mi.ScalarTransform4f.look_at(origin=[0, 1, 0], target=[0, 0, 0], up=[0, 0, 1])
                    @ mi.ScalarTransform4f.scale([12.0, 12.0, 1.0]),
        "film": {"type": "hdrfilm", "width": 48, "height": 48, "rfilter": {"type": "box"},
                 "pixel_format": "rgb"},
        "sampler": {"type": "independent", "sample_count": spp},
    },
    "sky": {"type": "envmap", "bitmap": mi.Bitmap(env), "scale": 1.0},
    "water": {
        "type": "cube",
        "to_world": mi.ScalarTransform4f.translate([0, -100, 0]) @ mi.ScalarTransform4f.scale([200, 100, 200]),
        "bsdf": {"type": "dielectric", "int_ior": n_w, "ext_ior": 1.0},
        "interior": {"type": "homogeneous", "sigma_t": a + b, "albedo": b / (a + b),
                     "phase": {"type": "tabphase", "values": ",".join(f"{v:.8g}" for v in vals)}},
    },
})
t0 = time.time()
img = np.array(mi.render(scene, spp=spp))[:, :, 0]
seconds = time.time() - t0
ok = np.isfinite(img)
# Pixels Mitsuba leaves NaN (a few in 2304) are left out and counted.
v = img[ok]
print(f"{spp} {seconds:.3f} {v.mean():.6g} {v.std() / v.mean():.6g} {int((~ok).sum())}")
PY
for n in "$mspp" $((4 * mspp)); do
  rows+=$'\n'"mitsuba $(python3 "$out/mitsuba_deep.py" "$n" 2>/dev/null | tail -1)"
done
echo "$rows" > "$out/deep.txt"
python3 - "$out/deep.txt" <<'PY'
import math, sys
# The exact answer: the path integrator's nadir radiance above the water
# for this water and sun, 0.0028482 W m^-2 sr^-1 nm^-1 +- 0.21 % (four
# radiometers of 2 M paths; benches/README, "Per-band noise").
ref = 0.0028482
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
def error(r):
    # rms of value / ref - 1 over the (pixel, band) values, from their mean and spread
    m, s = float(r[3]), float(r[4])
    return math.hypot(s * m, m - ref) / ref
pm = next(r for r in rows if r[0] == "photon-map")
t_pm, e_pm = float(pm[2]), error(pm)
print("| method | samples per pixel | wall time | mean against the exact answer | error per (pixel, band) | fall from N/4 | time to the photon map's error | x the photon map |")
print("|---|---|---|---|---|---|---|---|")
print(f"| photon map, 4 M photons | — | {t_pm:.1f} s | {(float(pm[3]) / ref - 1) * 100:+.2f} % | {e_pm*100:.2f} % | — | {t_pm:.1f} s | 1 |")
for name, bands in (("path", 1), ("mitsuba", 128)):
    rs = [r for r in rows if r[0] == name]
    lo, hi = rs[0], rs[-1]
    n, t, e = int(hi[1]), float(hi[2]), error(hi)
    fall = e / error(lo)
    need = t * (e / e_pm) ** 2 * bands
    label = "littoral path integrator" if name == "path" else "Mitsuba 3 volpath, ring sun, x 128 bands"
    nan = f" ({hi[5]} NaN pixels left out)" if int(hi[5]) else ""
    print(f"| {label} | {n} | {t:.1f} s | {(float(hi[3]) / ref - 1) * 100:+.1f} % | {e*100:.1f} %{nan} | {fall:.2f} | {need:.3g} s | {need / t_pm:.3g} |")
PY
# 2. The built-in scene.
t_bpm=$(seconds "$bin" render --out "$out/builtin-pm" --map "$out/builtin.map" --quiet)
t_bpath=$(seconds "$bin" render --out "$out/builtin-path" --integrator path --spp "$bspp" --quiet)
python3 - "$out" "$bspp" "$t_bpm" "$t_bpath" <<'PY'
import json, re, sys, numpy as np
out, spp, t_pm, t_path = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
def load(hdr):
    t = open(hdr).read()
    g = lambda k: int(re.search(k + r'\s*=\s*(\d+)', t).group(1))
    return np.fromfile(hdr[:-4] + '.bsq', dtype='<f4').reshape(g('bands'), g('lines'), g('samples')).astype(float)
# Regions by the image's geotransform (x = x0 + col dx, y = y0 + row dy).
gt = json.load(open(f"{out}/builtin-pm/coastal.json"))["sensor"]["geotransform"]
def window(x0, x1, y0, y1):
    c0, c1 = sorted(((x0 - gt[0]) / gt[1], (x1 - gt[0]) / gt[1]))
    r0, r1 = sorted(((y0 - gt[3]) / gt[5], (y1 - gt[3]) / gt[5]))
    return np.s_[:, int(np.ceil(r0)):int(np.floor(r1)), int(np.ceil(c0)):int(np.floor(c1))]
regions = [
    ("whole cube", np.s_[:, :, :]),
    ("deep water (x 154-191 m, y 8-121 m)", window(154.0, 191.5, 8.0, 121.0)),
    ("shallow sand by the beach (x 20-40 m, 0.6-2.2 m deep)", window(20.0, 40.0, 8.0, 121.0)),
    ("the 2 m panel at (66, 140) m", window(65.0, 67.0, 139.0, 141.0)),
    ("the 3 m dark box at (114, 150) m", window(112.5, 115.5, 148.5, 151.5)),
]
print(f"built-in scene: photon map (emission included) {t_pm:.1f} s, path integrator at {spp} spp {t_path:.1f} s")
print("| region | photon map error per (pixel, band) | path integrator's | path time to match | x the photon map |")
print("|---|---|---|---|---|")
for name, win in regions:
    e = {}
    for k in ("pm", "path"):
        l, se = load(f"{out}/builtin-{k}/coastal.hdr")[win], load(f"{out}/builtin-{k}/coastal.stderr.hdr")[win]
        ok = l > 0
        e[k] = np.median(se[ok] / l[ok])
    t_equal = t_path * (e["path"] / e["pm"]) ** 2
    print(f"| {name} | {e['pm']*100:.2f} % | {e['path']*100:.1f} % | {t_equal:.3g} s | {t_equal / t_pm:.0f} |")
PY
