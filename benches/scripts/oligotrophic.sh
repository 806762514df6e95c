#!/usr/bin/env bash
# Water Raman scattering in clear oligotrophic water against a published
# empirical model. Chl 0.05 mg m^-3, no floor, flat surface, sun at 30
# degrees (ASTM G173 direct spectrum), no sky, 36 bands 350-700 nm (data
# tables clamped below their first wavelength: a_w at 380 nm, a_phi at
# 400 nm), 16 M photons. The
# photon map reads R_rs from a nadir radiometer 1 m above the water (no
# sky and no glint in a nadir view: its radiance is L_w) with Raman
# scattering on and off. Prints the Raman share of R_rs, (on - off) / on,
# at 443, 490 and 550 nm, beside the share Lee et al. (2013, JGR 118,
# 4241, Eq. 11) predict from the run's own R_rs(443) / R_rs(550) and
# R_rs(550): RF = alpha R_rs443/R_rs550 + beta0 R_rs550^beta1, share =
# RF / (1 + RF), with the coefficients of NASA's l2gen Raman correction
# (McKinna et al. 2016) at 443, 488 and 551 nm.
# Usage: benches/scripts/oligotrophic.sh [OUTDIR] [PHOTONS]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/bench-oligotrophic}
photons=${2:-16000000}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/littoral
cat > "$out/clear.toml" <<TOML
name = "clear"
[spectral]
start_nm = 350.0
end_nm = 700.0
bands = 36
out_of_range = "clamp"
[sun]
zenith_deg = 30.0
spectrum = "astm-g173-direct"
[domain]
size_m = [40.0, 40.0]
[sensor]
pixels = [1, 1]
[water]
chl = 0.05
raman = true
[photons]
count = $photons
[[radiometer]]
depth_m = -1.0
view = "nadir"
position_m = [20.0, 20.0]
TOML
for light in on off; do
  "$bin" render "$out/clear.toml" --out "$out/$light" --inelastic "$light" --quiet
done
python3 - "$out" <<'PY'
import json, math, sys
out = sys.argv[1]
read = lambda d: json.load(open(f"{out}/{d}/clear.json"))
on, off = read("on"), read("off")
nm = on["bands_nm"]
ed = on["Ed_above_surface"]
band = lambda w: min(range(len(nm)), key=lambda i: abs(nm[i] - w))
r_on, r_off = on["radiometers"][0], off["radiometers"][0]
rrs = lambda r, b: r["L"][b] / ed[b]
b443, b550 = band(443), band(550)
ratio, r550 = rrs(r_on, b443) / rrs(r_on, b550), rrs(r_on, b550)
print(f"R_rs(443) = {rrs(r_on, b443):.5f}, R_rs(550) = {r550:.5f} sr^-1, ratio {ratio:.2f}")
print("| band | Raman share of R_rs, photon map | Lee et al. 2013 |")
print("|---|---|---|")
for w, (alpha, beta0, beta1) in ((443, (0.004, 0.015, -0.023)), (490, (0.011, 0.010, -0.051)), (550, (0.017, 0.010, -0.080))):
    b = band(w)
    share = (r_on["L"][b] - r_off["L"][b]) / r_on["L"][b]
    se = math.hypot(r_on["stderr"][b], r_off["stderr"][b]) / r_on["L"][b]
    rf = alpha * ratio + beta0 * r550 ** beta1
    print(f"| {nm[b]:.0f} nm | {share * 100:.1f} % ± {se * 100:.1f} % | {rf / (1 + rf) * 100:.1f} % |")
PY
