#!/usr/bin/env bash
# A billion stored photons on this machine: the built-in coastal scene (128
# bands) at PHOTONS traced photons (default 690 M, about 1.0e9 stored),
# emitted and rendered within --mem-budget 256MiB, next to the 4 M-photon
# default. The image is 64 x 64 pixels of 3 m (the built-in footprint at a
# quarter of the resolution), and the searches are k = 1000 and 5000
# instead of the policy's 3800 and 38000 at this count, to bound the
# render's time ([estimate] is not an emission input: the map is reused).
# Usage: benches/scripts/billion.sh [OUTDIR] [PHOTONS]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-billion}
photons=${2:-690000000}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
"$bin" scene set default "sensor.pixels=[64, 64]" sensor.gsd_m=3.0 > "$out/coastal64.toml"
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
