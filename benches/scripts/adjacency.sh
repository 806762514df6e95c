#!/usr/bin/env bash
# The adjacency effect: a bay of deep water 2 km across in land of
# reflectance 0.3 (`[surroundings] kind = "lambertian"`), seen from 700 km
# at nadir through a maritime-like aerosol (tau(550) 0.2, Angstrom 0.5,
# albedo 0.98, g 0.75) of scale height 1 km and 3 km; sun 30 degrees;
# 443, 555 and 670 nm; 64 x 64 pixels of 31.25 m.
# For each: the reflectance at the sensor rho_t against the distance from
# the shore (mean over the pixels at that distance from the nearest edge of
# the domain) and its excess over the bay's centre (pixels 750 m or more
# from the shore), by the photon map (4 M photons, 4 samples per pixel) and
# by the path integrator (256 paths per pixel), with standard errors from
# the pixels' spread. Also OUTDIR/adjacency.svg: the excess of every ring
# of pixels against its distance from the shore, both integrators, both
# heights, the three bands (benches/adjacency.svg is the one measured).
# Usage: benches/scripts/adjacency.sh [OUTDIR]
# Needs python3 with numpy (tools/test.sh installs it in .venv).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-adjacency}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
py=${PYTHON:-python3}
for h in 1.0 3.0; do
  for integrator in photon-map path; do
    spp=4; [ "$integrator" = path ] && spp=256
    cat > "$out/bay-$h-$integrator.toml" <<TOML
name = "bay"
seed = 1
[spectral]
centers_nm = [443.0, 555.0, 670.0]
fwhm_nm = [10.0, 10.0, 10.0]
[sun]
zenith_deg = 30.0
spectrum = "extraterrestrial"
[domain]
size_m = [2000.0, 2000.0]
[water]
iop = { a = 0.05, b = 0.3 }
phase = { kind = "fournier-forand", bb_ratio = 0.0183 }
[photons]
count = 4000000
[sensor]
pixels = [64, 64]
gsd_m = 31.25
samples_per_pixel = $spp
altitude_m = 700000.0
[render]
integrator = "$integrator"
[atmosphere]
sky_photons = 50000
[atmosphere.aerosol]
model = "custom"
tau_550 = 0.2
angstrom = 0.5
ssa = 0.98
phase = { kind = "henyey-greenstein", g = 0.75 }
scale_height_km = $h
[surroundings]
kind = "lambertian"
reflectance = 0.3
TOML
    /usr/bin/time -f "%e s wall" "$bin" render "$out/bay-$h-$integrator.toml" --out "$out/$h-$integrator" --quiet
  done
  "$py" - "$out/$h-photon-map/bay" "$out/$h-path/bay" "$h" "$out/rings-$h.json" <<'PY'
import json
import sys
import numpy as np

def cube(path):
    h = open(path + ".hdr").read()
    get = lambda k: int([l for l in h.splitlines() if l.strip().startswith(k)][0].split("=")[1])
    s, l, b = get("samples"), get("lines"), get("bands")
    return np.fromfile(path + ".bsq", dtype="<f4").reshape(b, l, s).astype(np.float64)

gsd = 31.25
runs = [cube(p + ".rhot") for p in sys.argv[1:3]]
nb, ny, nx = runs[0].shape
yy, xx = np.mgrid[0:ny, 0:nx]
d = np.minimum.reduce([xx + 0.5, nx - xx - 0.5, yy + 0.5, ny - yy - 0.5]) * gsd
centre = d >= 750.0
bins = [0, 62.5, 125, 187.5, 250, 375, 500, 750]
print(f"\naerosol scale height {sys.argv[3]} km: rho_t and its excess over the bay's centre, photon map | path integrator")
print("distance (m) | " + " | ".join(f"{n} nm" for n in (443, 555, 670)))
for lo, hi in zip(bins[:-1], bins[1:]):
    m = (d >= lo) & (d < hi)
    cells = []
    for b in range(nb):
        parts = []
        for r in runs:
            v, c = r[b][m], r[b][centre]
            ex = v.mean() - c.mean()
            se = np.sqrt(v.var(ddof=1) / v.size + c.var(ddof=1) / c.size)
            parts.append(f"{v.mean():.4f} {ex:+.4f} ± {se:.4f}")
        cells.append(" / ".join(parts))
    print(f"{lo:.0f}-{hi:.0f} | " + " | ".join(cells))
c = [[r[b][centre].mean() for b in range(nb)] for r in runs]
print("centre (>= 750 m) | " + " | ".join(f"{c[0][b]:.4f} / {c[1][b]:.4f}" for b in range(nb)))
# Each ring of pixels (its distance from the shore), for the plot.
rings = sorted(set(d[~centre].ravel()))
json.dump(
    {
        "distance_m": rings,
        "excess": [[[float(r[b][d == x].mean() - r[b][centre].mean()) for x in rings] for b in range(nb)] for r in runs],
    },
    open(sys.argv[4], "w"),
)
PY
done
"$py" - "$out" <<'PY'
# The rings' excess against distance as an SVG, drawn by hand (no plotting
# package needed): a panel per aerosol height, a colour per band, the
# photon map solid and the path integrator dashed.
import json
import sys

out = sys.argv[1]
W, H, pad = 360, 260, 48
colours = {"443 nm": "#1f5fbf", "555 nm": "#2a9d3f", "670 nm": "#c0392b"}
xmax, ymax = 750.0, 0.016
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{2 * W}" height="{H + 30}" font-family="sans-serif" font-size="11">']
for k, h in enumerate(("1.0", "3.0")):
    data = json.load(open(f"{out}/rings-{h}.json"))
    x0 = k * W + pad
    px = lambda d: x0 + (W - pad - 12) * d / xmax
    py = lambda e: 12 + (H - pad) * (1 - e / ymax)
    svg.append(f'<text x="{x0 + 60}" y="{H + 22}">distance from the shore (m); aerosol {h} km</text>')
    svg.append(f'<line x1="{px(0)}" y1="{py(0)}" x2="{px(xmax)}" y2="{py(0)}" stroke="black"/>')
    svg.append(f'<line x1="{px(0)}" y1="{py(0)}" x2="{px(0)}" y2="{py(ymax)}" stroke="black"/>')
    for t in range(0, 751, 250):
        svg.append(f'<text x="{px(t) - 8}" y="{py(0) + 14}">{t}</text>')
    for t in (0.0, 0.004, 0.008, 0.012, 0.016):
        svg.append(f'<text x="{x0 - 44}" y="{py(t) + 4}">{t:.3f}</text>')
    svg.append(f'<text x="{x0 + 4}" y="{py(ymax) + 10}">excess of rho_t over the centre</text>')
    for run, dash in ((0, ""), (1, ' stroke-dasharray="4 3"')):
        for b, (name, colour) in enumerate(colours.items()):
            pts = " ".join(f"{px(d):.1f},{py(e):.1f}" for d, e in zip(data["distance_m"], data["excess"][run][b]))
            svg.append(f'<polyline points="{pts}" fill="none" stroke="{colour}"{dash}/>')
    if k == 1:
        for b, (name, colour) in enumerate(colours.items()):
            svg.append(f'<text x="{x0 + 180}" y="{py(ymax) + 26 + 14 * b}" fill="{colour}">{name}</text>')
        svg.append(f'<text x="{x0 + 180}" y="{py(ymax) + 26 + 42}">solid: photon map; dashed: path</text>')
svg.append("</svg>")
open(f"{out}/adjacency.svg", "w").write("\n".join(svg) + "\n")
print(f"\nplot: {out}/adjacency.svg")
PY
