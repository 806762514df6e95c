#!/usr/bin/env bash
# Time to equal error, photon map against the path integrator, on the
# built-in scene, for the whole 128-band cube, in one run: both render the
# scene with their standard-error cubes; the path integrator's time is
# scaled to the paths per pixel that reach the photon map's median
# relative error per (pixel, band) over the deep-water region (columns
# 200-250, rows 100-250) and over the whole image.
# Usage: benches/scripts/equal_error.sh [OUTDIR] [PATH_SPP]   (needs python3 with numpy)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-equal-error}
spp=${2:-4}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
t0=$(date +%s.%N)
"$bin" render --out "$out/pm" --map "$out/coastal.map" --quiet
t1=$(date +%s.%N)
"$bin" render --out "$out/path" --integrator path --spp "$spp" --quiet
t2=$(date +%s.%N)
python3 - "$out" "$spp" "$(echo "$t1 - $t0" | bc)" "$(echo "$t2 - $t1" | bc)" <<'PY'
import re, sys, numpy as np
out, spp, t_pm, t_path = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
def load(hdr):
    t = open(hdr).read()
    g = lambda k: int(re.search(k + r'\s*=\s*(\d+)', t).group(1))
    return np.fromfile(hdr[:-4] + '.bsq', dtype='<f4').reshape(g('bands'), g('lines'), g('samples')).astype(float)
print(f"photon map (emission included) {t_pm:.1f} s, path integrator at {spp} spp {t_path:.1f} s")
for name, win in [("deep water", np.s_[:, 100:250, 200:250]), ("whole image", np.s_[:, :, :])]:
    e = {}
    for k in ("pm", "path"):
        l, se = load(f"{out}/{k}/coastal.hdr")[win], load(f"{out}/{k}/coastal.stderr.hdr")[win]
        ok = l > 0
        e[k] = np.median(se[ok] / l[ok])
    need = spp * (e["path"] / e["pm"]) ** 2
    t_equal = t_path * need / spp
    print(f"{name}: median relative error per (pixel, band): photon map {e['pm']*100:.2f} %, "
          f"path {e['path']*100:.1f} % at {spp} spp -> {need:.0f} spp, {t_equal/3600:.2f} h: "
          f"photon map faster by {t_equal / t_pm:.0f}x")
PY
