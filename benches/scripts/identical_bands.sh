#!/usr/bin/env bash
# Per-pixel, per-band noise of the photon map against photon count and
# spectral mode, in deep water whose 128 bands all have the same IOPs and
# sun (so every band of every pixel has the same radiance).
# Usage: benches/scripts/identical_bands.sh [OUTDIR]   (needs python3 with numpy)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-identical}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
scene="$out/ident.toml"
"$bin" scene set tests/scenes/identical_bands.toml spectral.start_nm=400.0 spectral.end_nm=700.0 \
  spectral.bands=128 'domain.size_m=[60.0, 60.0]' photons.count=4000000 'sensor.pixels=[48, 48]' \
  sensor.gsd_m=0.5 > "$scene"
spread() {
python3 - "$1" <<'PY'
import sys, re, numpy as np
hdr = sys.argv[1]; t = open(hdr).read()
g = lambda k: int(re.search(k + r'\s*=\s*(\d+)', t).group(1))
d = np.fromfile(hdr[:-4] + '.bsq', dtype='<f4').reshape(g('bands'), g('lines'), g('samples')).astype(float)
m = d.mean()
print(f"mean {m:.5g}  pixel-band {d.std()/m*100:.1f} %  pixel (band mean) {d.mean(axis=0).std()/m*100:.1f} %  band (image mean) {d.mean(axis=(1,2)).std()/m*100:.2f} %")
PY
}
for n in 4000000 8000000 16000000 32000000; do
  for mode in grid compensated naive; do
    dir="$out/$n-$mode"
    /usr/bin/time -f "%e s" -o "$dir.time" "$bin" render "$scene" --out "$dir" --photons "$n" \
      --spectral "$mode" --map "$out/$n.map" --quiet
    echo "$n $mode $(cat "$dir.time") $(spread "$dir/ident.hdr")"
  done
done
