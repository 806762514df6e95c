#!/usr/bin/env bash
# A billion stored photons on this machine: the built-in coastal scene (128
# bands) at PHOTONS traced photons (default 690 M, about 1.0e9 stored),
# emitted and rendered within --mem-budget 256MiB, next to the 4 M-photon
# default. The image is 64 x 64 pixels of 3 m (the built-in footprint at a
# quarter of the resolution), and the searches are k = 1000 and 5000
# instead of the policy's 3800 and 38000 at this count, to bound the
# render's time ([estimate] is not an emission input: the map is reused).
# BANDS other than 128 sets that many bands at 1 nm steps from 380 nm
# (400: 380-779 nm) in place of the built-in 128 over 400-800 nm.
# Prints each stage's time and peak RSS, the map's size, and the
# deep-water noise of both renders (columns 50-59, rows 28-59): one
# pixel's band against its 7 x 7 mean, and the median relative standard
# error of the standard-error cube, at 526 and 650 nm, the median band
# and the worst band.
# Usage: benches/scripts/billion.sh [OUTDIR] [PHOTONS] [BANDS]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-billion}
photons=${2:-690000000}
bands=${3:-128}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
spectral=()
if [ "$bands" != 128 ]; then
  spectral=(spectral.start_nm=380.0 "spectral.end_nm=$((380 + bands - 1)).0" "spectral.bands=$bands")
fi
"$bin" scene set default "sensor.pixels=[64, 64]" sensor.gsd_m=3.0 "${spectral[@]}" > "$out/coastal64.toml"
"$bin" scene set "$out/coastal64.toml" estimate.k=1000 estimate.k_expanded=5000 > "$out/coastal64-k.toml"
run() { # name, command...: wall, user and sys time and peak RSS of a stage
  local name=$1; shift
  /usr/bin/time -f "$name: %e s wall, %U s user, %S s sys, %M KiB peak RSS" "$@" 2>>"$out/times.txt"
}
: > "$out/times.txt"
run emit "$bin" emit "$out/coastal64.toml" --photons "$photons" --map "$out/billion.map" \
  --mem-budget 256MiB --report "$out/emit.json" --quiet
run render "$bin" render "$out/coastal64-k.toml" --photons "$photons" --map "$out/billion.map" \
  --mem-budget 256MiB --out "$out/billion" --quiet
run render4m "$bin" render "$out/coastal64.toml" --out "$out/default4m" --mem-budget 256MiB --quiet
ls -l "$out/billion.map" >> "$out/times.txt"
cat "$out/times.txt"
python3 - "$out" <<'PY'
import array, json, math, statistics, sys
out = sys.argv[1]
def noise(d):
    """Per band: the 7 x 7 measure and the median relative standard error."""
    hdr = open(f"{out}/{d}/coastal.hdr").read()
    get = lambda k: int(hdr.split(f"{k} = ")[1].split()[0])
    w, h, nb = get("samples"), get("lines"), get("bands")
    cube, se = array.array("f"), array.array("f")
    with open(f"{out}/{d}/coastal.bsq", "rb") as f:
        cube.fromfile(f, w * h * nb)
    with open(f"{out}/{d}/coastal.stderr.bsq", "rb") as f:
        se.fromfile(f, w * h * nb)
    rows = []
    for b in range(nb):
        a = cube[b * w * h:(b + 1) * w * h]
        s = se[b * w * h:(b + 1) * w * h]
        dev, rel = [], []
        for y in range(28, 60):
            for x in range(50, 60):
                m = sum(a[yy * w + xx] for yy in range(y - 3, y + 4) for xx in range(x - 3, x + 4)) / 49
                dev.append((a[y * w + x] / m - 1) ** 2)
                rel.append(s[y * w + x] / a[y * w + x])
        rows.append((math.sqrt(sum(dev) / len(dev)) * 100, statistics.median(rel) * 100))
    return rows
nm = json.load(open(f"{out}/billion/coastal.json"))["bands_nm"]
at = lambda want: min(range(len(nm)), key=lambda i: abs(nm[i] - want))
print("| run | 526 nm | 650 nm | median band | worst band |")
print("|---|---|---|---|---|")
for label, d in (("4 M photons, default settings", "default4m"), (f"the map above, k = 1000 / 5000", "billion")):
    rows = noise(d)
    med = lambda i: statistics.median(r[i] for r in rows)
    worst = max(range(len(rows)), key=lambda b: rows[b][0])
    cell = lambda b: f"{rows[b][0]:.2f} % ({rows[b][1]:.2f} %)"
    print(f"| {label}: 7 x 7 (median standard error) | {cell(at(526))} | {cell(at(650))} | "
          f"{med(0):.2f} % ({med(1):.2f} %) | {rows[worst][0]:.2f} % ({nm[worst]:.0f} nm) |")
PY
