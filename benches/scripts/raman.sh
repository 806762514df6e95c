#!/usr/bin/env bash
# Water Raman scattering in the built-in scene: both integrators with
# Raman scattering on and off (`--inelastic`), read by nadir radiometers
# 1 m above the water at four deep-water points. Prints, per radiometer,
# the Raman share of the reading ((on - off) / on) by both integrators
# over 450-600 nm and 600-800 nm, and the photon map against the path
# integrator with Raman on: the band mean over 530-800 nm (the bands the
# grid's own light excites) with its combined standard error.
# Usage: benches/scripts/raman.sh [OUTDIR] [SPP]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-raman}
spp=${2:-256}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
rad() { echo "{ depth_m = -1.0, view = \"nadir\", position_m = [$1, $2] }"; }
"$bin" scene set default 'name="raman"' 'water.raman=true' 'sensor.pixels=[8, 8]' \
  "radiometer=[$(rad 160.0 50.0), $(rad 170.0 80.0), $(rad 180.0 40.0), $(rad 185.0 100.0)]" > "$out/raman.toml"
for light in on off; do
  /usr/bin/time -f "photon map, Raman $light: %e s" "$bin" render "$out/raman.toml" --out "$out/pm-$light" --inelastic "$light" --quiet
  /usr/bin/time -f "path, Raman $light: %e s" "$bin" render "$out/raman.toml" --out "$out/path-$light" --integrator path --spp "$spp" --inelastic "$light" --quiet
done
python3 - "$out" <<'PY'
import json, math, sys
out = sys.argv[1]
read = lambda d: json.load(open(f"{out}/{d}/raman.json"))
runs = {k: read(k) for k in ("pm-on", "pm-off", "path-on", "path-off")}
nm = runs["pm-on"]["bands_nm"]
def mean(v, lo, hi):
    sel = [x for x, w in zip(v, nm) if lo <= w <= hi]
    return sum(sel) / len(sel)
def se(s, lo, hi):
    sel = [x for x, w in zip(s, nm) if lo <= w <= hi]
    return sum(sel) / len(sel)   # bands correlated: the plain mean bounds it
print("| radiometer | Raman share 450-600 nm, photon map / path | 600-800 nm, photon map / path | photon map - path, 530-800 nm (Raman on) |")
print("|---|---|---|---|")
for i, r in enumerate(runs["pm-on"]["radiometers"]):
    row = []
    for lo, hi in ((450, 600), (600, 800)):
        share = lambda a, b: (mean(a["L"], lo, hi) - mean(b["L"], lo, hi)) / mean(a["L"], lo, hi) * 100
        pm = share(runs["pm-on"]["radiometers"][i], runs["pm-off"]["radiometers"][i])
        pa = share(runs["path-on"]["radiometers"][i], runs["path-off"]["radiometers"][i])
        row.append(f"{pm:.1f} % / {pa:.1f} %")
    a, b = runs["pm-on"]["radiometers"][i], runs["path-on"]["radiometers"][i]
    m_a, m_b = mean(a["L"], 530, 800), mean(b["L"], 530, 800)
    s = math.hypot(se(a["stderr"], 530, 800), se(b["stderr"], 530, 800))
    print(f"| {r['position_m']} | {row[0]} | {row[1]} | {(m_a / m_b - 1) * 100:+.1f} % ± {s / m_b * 100:.1f} % |")
PY
