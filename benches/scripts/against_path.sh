#!/usr/bin/env bash
# Radiometers of the photon map (default settings) against the path
# integrator in small scenes: deep, shallow with a floor, layered, a
# target, a rough surface, and a radiometer 0.1 mm above the floor.
# The photon map runs once per seed; its band mean is the seeds' mean, with
# the standard error of that mean from the seeds' spread (from one run's own
# band-mean standard error with one seed).
# Usage: benches/scripts/against_path.sh [OUTDIR] [PHOTONS] [SPP] [SEEDS]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-against-path}
photons=${2:-4000000}
spp=${3:-1024}
seeds=${4:-1}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
# The scenes are tests/scenes/against_path/, shared with the test.
scenes=tests/scenes/against_path
echo "| scene | depth (m) | path, band mean | photon map − path | ± (band mean) | z (band mean) | worst band | largest per-band z |"
echo "|---|---|---|---|---|---|---|---|"
for f in deep shallow layered target rough near_floor; do
  "$bin" render "$scenes/$f.toml" --out "$out/$f-path" --integrator path --spp "$spp" --quiet
  runs=()
  for seed in $seeds; do
    "$bin" render "$scenes/$f.toml" --out "$out/$f-pm-s$seed" --photons "$photons" --seed "$seed" --quiet
    runs+=("$out/$f-pm-s$seed/$f.json")
  done
  python3 - "$f" "$out/$f-path/$f.json" "${runs[@]}" <<'PY'
import json, math, sys
name, pa = sys.argv[1], json.load(open(sys.argv[2]))
pms = [json.load(open(p)) for p in sys.argv[3:]]
n = len(pms)
for i, b in enumerate(pa["radiometers"]):
    nb = len(b["L"])
    l = sum(b["L"]) / nb
    l_se = b["band_mean_stderr"]
    runs = [pm["radiometers"][i] for pm in pms]
    means = [sum(r["L"]) / nb for r in runs]
    m = sum(means) / n
    if n > 1:
        m_se = math.sqrt(sum((x - m) ** 2 for x in means) / (n - 1) / n)
    else:
        m_se = runs[0]["band_mean_stderr"]
    se = math.hypot(m_se, l_se) / l
    # Per band: the seeds' mean against the path, in combined standard
    # errors (each run's own per-band standard error, pooled).
    band = [sum(r["L"][k] for r in runs) / n for k in range(nb)]
    band_se = [math.sqrt(sum(r["stderr"][k] ** 2 for r in runs)) / n for k in range(nb)]
    worst = max(abs(x / y - 1) for x, y in zip(band, b["L"]))
    z = max(abs(x - y) / math.hypot(sa, sb)
            for x, y, sa, sb in zip(band, b["L"], band_se, b["stderr"]))
    print(f"| {name} | {b['depth_m']} | {l:.5g} ± {l_se / l * 100:.1f} % | {m / l - 1:+.1%} "
          f"| {se * 100:.1f} % | {(m / l - 1) / se:+.1f} | {worst:.1%} | {z:.1f} |")
PY
done
