#!/usr/bin/env bash
# Radiometers of the photon map (default settings) against the path
# integrator in small scenes: deep, shallow with a floor, layered, a
# target, a rough surface, and a radiometer 0.1 mm above the floor.
# Usage: benches/scripts/against_path.sh [OUTDIR] [PHOTONS] [SPP]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-against-path}
photons=${2:-4000000}
spp=${3:-1024}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
# The scenes are tests/scenes/against_path/, shared with the test.
scenes=tests/scenes/against_path
for f in deep shallow layered target rough near_floor; do
  "$bin" render "$scenes/$f.toml" --out "$out/$f-pm" --photons "$photons" --quiet
  "$bin" render "$scenes/$f.toml" --out "$out/$f-path" --integrator path --spp "$spp" --quiet
  python3 - "$out/$f-pm/$f.json" "$out/$f-path/$f.json" "$f" <<'PY'
import json, sys
pm, pa, name = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), sys.argv[3]
for a, b in zip(pm["radiometers"], pa["radiometers"]):
    l = sum(b["L"]) / len(b["L"]); se = (sum(s * s for s in b["stderr"]) ** 0.5) / len(b["L"])
    m = sum(a["L"]) / len(a["L"])
    worst = max(abs(x / y - 1) for x, y in zip(a["L"], b["L"]))
    # Per band: the photon map's relative error, and the largest
    # difference in combined standard errors.
    pse = max(s / x for s, x in zip(a["stderr"], a["L"]))
    z = max(abs(x - y) / (sa * sa + sb * sb) ** 0.5
            for x, y, sa, sb in zip(a["L"], b["L"], a["stderr"], b["stderr"]))
    print(f"| {name} | {a['depth_m']} | {l:.5g} ± {se / l * 100:.1f} % | {m / l - 1:+.3f} | {worst:.3f} | {pse * 100:.1f} % | {z:.1f} |")
PY
done
