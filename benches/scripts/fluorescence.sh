#!/usr/bin/env bash
# Inelastic light in the built-in scene: the photon map with every process
# the water supports on (water Raman scattering, chlorophyll and CDOM
# fluorescence; `--inelastic on`) and off, on one photon map each. Prints
# the runs' wall and CPU times (the render stage alone: the report's
# timings), and per band of interest the deep-water noise (a pixel's
# relative deviation from its 7 x 7 neighbourhood's mean, rms over
# columns 200-250, rows 100-250, as "Rendering" measures it) and the
# inelastic share of the deep-water radiance ((on - off) / on).
# Usage: benches/scripts/fluorescence.sh [OUTDIR]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-fluorescence}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
for light in off on; do
  /usr/bin/time -f "inelastic $light: %e s wall, %U s user + %S s system" \
    "$bin" render --out "$out/$light" --map "$out/$light.map" --inelastic "$light" --quiet
done
python3 - "$out" <<'PY'
import array, json, math, sys
out = sys.argv[1]
def cube(d):
    hdr = open(f"{out}/{d}/coastal.hdr").read()
    get = lambda k: int(hdr.split(f"{k} = ")[1].split()[0])
    return get("samples"), get("lines"), get("bands")
def band(d, b):
    w, h, nb = cube(d)
    a = array.array("f")
    with open(f"{out}/{d}/coastal.bsq", "rb") as f:
        f.seek(4 * w * h * b)
        a.fromfile(f, w * h)
    return w, h, a
report = json.load(open(f"{out}/on/coastal.json"))
nm = report["bands_nm"]
for label in ("off", "on"):
    r = json.load(open(f"{out}/{label}/coastal.json"))
    print(f"inelastic {label}: render stage {r['timings_s']['render']:.1f} s")
print("| band | deep-water noise, off / on | inelastic share of deep-water radiance |")
print("|---|---|---|")
for want in (443, 526, 560, 620, 670, 685, 700):
    b = min(range(len(nm)), key=lambda i: abs(nm[i] - want))
    row = []
    means = {}
    for label in ("off", "on"):
        w, h, a = band(label, b)
        dev, tot = [], []
        for y in range(100, 251):
            for x in range(200, 251):
                nb = [a[yy * w + xx] for yy in range(y - 3, y + 4) for xx in range(x - 3, x + 4)]
                m = sum(nb) / len(nb)
                dev.append((a[y * w + x] / m - 1) ** 2)
                tot.append(a[y * w + x])
        row.append(math.sqrt(sum(dev) / len(dev)) * 100)
        means[label] = sum(tot) / len(tot)
    share = (means["on"] - means["off"]) / means["on"] * 100
    print(f"| {nm[b]:.1f} nm | {row[0]:.2f} % / {row[1]:.2f} % | {share:+.1f} % |")
PY
