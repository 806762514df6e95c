#!/usr/bin/env python3
"""Mie tables of the 6S "continental", "maritime" and "urban" aerosol models.

What it computes
----------------
For each of the three standard aerosol models of the 6S radiative-transfer
code (iaer = 1, 2, 3), at the 14 6S wavelengths from 0.35 to 0.86 um:

* ``ext_rel_550``: extinction coefficient divided by its value at 550 nm;
* ``ssa``: single-scattering albedo;
* ``g``: asymmetry parameter (Mie, <cos theta>);
* ``phase``: the scattering phase function P(theta) on ANGLES_DEG below,
  normalised so that its mean over the sphere is 1:
  (1 / 4 pi) * integral P dOmega = (1/2) * integral_0^pi P(theta) sin(theta) dtheta = 1,
  i.e. the integral over 4 pi steradians is 4 pi (the 6S convention).

and writes ``data/aerosol_models.csv`` (model, wavelength_nm, ext_rel_550,
ssa, g) and ``data/aerosol_phase.csv`` (model, wavelength_nm, angle_deg,
phase).

Method
------
1. Four basic components (dust-like, water-soluble, oceanic, soot), each a
   log-normal number size distribution written exactly as 6S writes it
   (6SV1.0B MIE.f, lines 95-98):
       dN/dr = exp(-(log10(r/r_m))^2 / (2 log10(s)^2)) / (sqrt(2 pi) ln(10) r log10(s)),
   r_m the number median radius ("Rmean"), s the geometric standard
   deviation ("Sigma"), truncated to RMIN <= r <= RMAX = 0.001 .. 20 um.
   Within that range each component is normalised to one particle
   (6S divides by the in-range number, MIE.f lines 136, 217-218).
2. Mie theory (miepython; homogeneous spheres, m = n - i k) for every radius:
   Q_ext, Q_sca, g and the unpolarised intensity i(theta) normalised to
   Q_sca over 4 pi. Size integration: trapezoidal rule in ln r on a uniform
   grid of 0.005 decades (861 radii over 0.001-20 um; 0.0025 decades, 1721
   radii, for the non-absorbing oceanic component, whose Mie resonance
   ripple converges slowly); radii whose weight r^2 dN/dln r is below 1e-16
   of the maximum are skipped. Per particle:
       <C_ext> = sum w_k pi r_k^2 Q_ext(r_k) / sum w_k, likewise <C_sca>,
       <C_sca g>, and d<C_sca>/dOmega = sum w_k pi r_k^2 i(theta; r_k) / sum w_k.
   ``--convergence`` repeats this with half the step. Result: extinction,
   scattering and g change by <= 8e-5; the phase function by <= 0.4 %
   (dust-like), 0.05 % (water-soluble), 1e-7 (soot) and, for oceanic, up
   to 1.2-2.7 % at single backward angles where P ~ 0.1-0.7 (resonance
   ripple; the forward lobe and the integrals are converged).
   ``--validate-6sv`` repeats it with 6S's own scheme (left rectangles,
   dlog10 r = 0.011, MIE.f lines 34, 81-82, 157-160) and compares with the
   numbers tabulated in 6S (see Sources). That coarse scheme is itself the
   main difference between 6S's tables and ours: 6S's oceanic extinction
   carries +/-4e-3 of resonance-ripple noise from wavelength to wavelength
   (dust-like 1.4e-3, water-soluble 1e-4), which is why e.g. the maritime
   Angstrom exponent differs by 0.005.
3. Mixing, as 6S AEROSO.f does it (lines 205-240): the model's volume
   fractions c_j are turned into number fractions
       n_j = (c_j / v_j) / sum_k (c_k / v_k),
   v_j the mean particle volume (4/3) pi <r^3> of component j over the same
   truncated, number-normalised distribution; then
       ext = sum n_j <C_ext>_j,  sca = sum n_j <C_sca>_j,
       g = sum n_j <C_sca g>_j / sca,
       P(theta) = 4 pi sum n_j d<C_sca>_j/dOmega / sca.
   (6S's own v_j is not divided by the in-range number, 1.0126-1.0128 for
   the four components, and its last radius rectangle reaches 20.5 um; with
   our self-consistent v_j the number fractions differ from 6S's by <= 0.3 %
   relative.)

Angle grid (ANGLES_DEG, 164 angles): 0 to 1 deg every 0.05; 1.1 to 3 every 0.1;
3.25 to 10 every 0.25; 11 to 30 every 1; 32 to 180 every 2. The run checks that
the trapezoidal integral of every tabulated P over this grid is 1 to 1e-3
and that g recomputed from the table matches the Mie g.

Sources
-------
* The models, the mixing rule, the wavelengths and the integration scheme:
  the 6S code, Vermote, Tanre, Deuze, Herman & Morcrette (1997), "Second
  Simulation of the Satellite Signal in the Solar Spectrum, 6S: an overview",
  IEEE Trans. Geosci. Remote Sens. 35(3):675-686, doi:10.1109/36.581987;
  version 6SV1.0B as vendored by the Orfeo ToolBox,
  github.com/orfeotoolbox/OTB at commit cbc8644dfc17ccbde94f13c8fd88f3e3a81be8a8
  (the 6SV1.0B Fortran files last changed in 18e581f4ff4b9c01e247be9b86d8fd62c49753a4,
  main.f in 7408396bb99b3aa450e4d62ed31b759a4cd1d5fc):
    - Modules/ThirdParty/6S/src/main.f lines 329-331 (the 20 wavelengths,
      ``data wldisc``) and 859-872 (volume fractions of iaer = 1, 2, 3);
    - Modules/ThirdParty/6S/src/6SV1.0B/AEROSO.f lines 205-240 (mixing);
    - Modules/ThirdParty/6S/src/6SV1.0B/MIE.f lines 34, 81-99, 136-160,
      171-177, 217-218 (size distribution, radius scheme, normalisation);
    - Modules/ThirdParty/6S/src/6SV1.0B/{DUST,WATE,OCEA,SOOT}.f: the
      components' tabulated Mie results (lines 22-24 asymmetry, 26-36
      extinction and scattering, 164-181 the 550 nm phase function on 83
      angles, ``vi_m`` mean particle volume at line 1121/1123/1123/1122).
      Their comment (lines 16-19) gives the origin of the component data:
      "Parameters and refractive indices - G.A. d'Almeida, 'Atmospheric
      aerosols. Global climatology and radiative characteristics', 1991"
      (d'Almeida, Koepke & Shettle 1991, A. Deepak Publishing, Hampton VA).
* The size parameters (r_m, s), the radius range and the refractive indices
  are NOT written in the 6SV source (it ships only their Mie results). They
  were recovered from those results and are verified against them:
    - RMIN, RMAX and (r_m, s) of all four components reproduce the four
      tabulated vi_m to 1e-7 relative with 6S's radius scheme
      (other radius ranges tried, 0.0001-20, 0.0005-20, 0.002-20, 0.005-20,
      0.001-19.9 and 0.001-25 um, miss by 0.08-3.5 %; any RMAX in
      (19.9986, 20.507] um gives 6S the same radius points, 20 is assumed);
    - each refractive index is the value (3 decimals in n, 2-4 significant
      digits in k) with which 6S's scheme reproduces the tabulated extinction
      AND scattering of that component at that wavelength to <= 1.5e-5
      (most to ~1e-7, the precision of the 6S tables); for dust-like and
      oceanic, whose extinction depends least on n, n +/- 0.001 misses by
      1e-5 to 1e-3;
    - as an independent check (not used in the recovery), the same numbers
      reproduce 6S's tabulated asymmetry parameters (all 14 wavelengths,
      to the 3 printed decimals: max difference 0.0005) and 550 nm phase
      functions on 6S's 83 angles (rms 1.0-1.5e-4, max 4.5e-4 relative, the
      4 printed digits); run ``--validate-6sv``.
  For oceanic at 0.40-0.694 um the tables fix k only within a factor ~2
  (1 - ssa is 3e-7..2e-6 there, the last digit of the tables); any such k
  changes ssa by < 1e-6.
  Cross-reference: the older 6S v4.1 (github.com/mottus/6S_python at commit
  d07a07e3dc8715db93dc42f911116e11e56ff190, sixs_fortran77/main.f lines
  672-680) lists WCP-112 component data (dust-like 0.5 um / 2.99 with
  1.53-0.008i, water-soluble 0.005 um / 2.99, soot 0.0118 um / 2.00 with
  1.75-0.44..0.46i); 6SV changed the dust-like and water-soluble size
  distributions to those below (its vi_m differ), kept soot's.

How to run
----------
    python3 -m venv /tmp/mievenv && /tmp/mievenv/bin/pip install numpy miepython
    /tmp/mievenv/bin/python tools/aerosol_tables.py            # write the CSVs, print checks
    /tmp/mievenv/bin/python tools/aerosol_tables.py --check    # recompute, compare to the CSVs
    /tmp/mievenv/bin/python tools/aerosol_tables.py --validate-6sv   # 6S scheme vs 6S tables
    /tmp/mievenv/bin/python tools/aerosol_tables.py --convergence    # radius-step check
Tested with Python 3, numpy 2.4, miepython 3.3 (pure-Python mode; a full
run takes a few minutes on one core).
"""

import argparse
import pathlib
import sys
import time

import numpy as np
import miepython

ROOT = pathlib.Path(__file__).resolve().parent.parent
MODELS_CSV = ROOT / "data" / "aerosol_models.csv"
PHASE_CSV = ROOT / "data" / "aerosol_phase.csv"

# ---------------------------------------------------------------------------
# 6S constants
# ---------------------------------------------------------------------------

# The 20 wavelengths of 6S (um), main.f lines 329-331 (OTB commit above).
WAVELENGTHS_6S = [0.350, 0.400, 0.412, 0.443, 0.470, 0.488, 0.515, 0.550,
                  0.590, 0.633, 0.670, 0.694, 0.760, 0.860, 1.240, 1.536,
                  1.650, 1.950, 2.250, 3.750]
# The tables cover the first 14 (0.35-0.86 um); 550 nm is index 7.
WAVELENGTHS = WAVELENGTHS_6S[:14]
I550 = 7

# Radius range of the 6S basic components (um): recovered, see docstring.
RMIN, RMAX = 0.001, 20.0
# 6S radius step (decades), MIE.f line 34 (rlogpas=0.011); ours is per
# component ("h" below, decades of r per trapezoid step).
STEP_6S = 0.011

# Components: number median radius r_m (um), geometric standard deviation s,
# refractive index m = n - i k at WAVELENGTHS. Values recovered from, and
# verified against, 6SV1.0B's tabulated Mie results (see docstring); the
# 6SV code attributes the data to d'Almeida, Koepke & Shettle (1991).
COMPONENTS = {
    "dust_like": {
        "file": "DUST.f", "h": 0.005,
        "rm": 0.471, "sigma": 2.512,
        "n": [1.530] * 12 + [1.528, 1.520],
        "k": [0.008] * 14,
    },
    "water_soluble": {
        "file": "WATE.f", "h": 0.005,
        "rm": 0.0285, "sigma": 2.239,
        "n": [1.530] * 12 + [1.528, 1.520],
        "k": [0.005, 0.005, 0.005, 0.005, 0.005, 0.005, 0.0053, 0.006,
              0.006, 0.0067, 0.007, 0.007, 0.0088, 0.0109],
    },
    "oceanic": {
        "file": "OCEA.f", "h": 0.0025,
        "rm": 0.3, "sigma": 2.51,
        "n": [1.390, 1.385, 1.385, 1.383, 1.383, 1.382, 1.382, 1.381,
              1.379, 1.378, 1.377, 1.376, 1.375, 1.373],
        # 0.35-0.694 um: order of magnitude only (see docstring).
        "k": [1.2e-7, 8.7e-9, 8.1e-9, 7.6e-9, 5.2e-9, 5.1e-9, 7.0e-9,
              5.1e-9, 3.0e-9, 1.2e-8, 2.8e-8, 4.7e-8, 1.29e-5, 3.25e-5],
    },
    "soot": {
        "file": "SOOT.f", "h": 0.005,
        "rm": 0.0118, "sigma": 2.0,
        "n": [1.750] * 14,
        "k": [0.465, 0.46, 0.4588, 0.4557, 0.453, 0.4512, 0.447, 0.44,
              0.436, 0.435, 0.433, 0.4306, 0.43, 0.433],
    },
}
ORDER = ["dust_like", "water_soluble", "oceanic", "soot"]

# Volume fractions (dust-like, water-soluble, oceanic, soot): 6S main.f
# lines 859-872 (iaer = 1 continental, 2 maritime, 3 urban).
MODELS = {
    "continental": [0.70, 0.29, 0.00, 0.01],
    "maritime": [0.00, 0.05, 0.95, 0.00],
    "urban": [0.17, 0.61, 0.00, 0.22],
}


def _angles():
    a = [np.arange(0, 1.0001, 0.05), np.arange(1.1, 3.0001, 0.1),
         np.arange(3.25, 10.0001, 0.25), np.arange(11, 30.0001, 1.0),
         np.arange(32, 180.0001, 2.0)]
    return np.round(np.concatenate(a), 6)


ANGLES_DEG = _angles()

# 6SV1.0B's tabulated Mie results for the components at the 14 wavelengths
# (DUST.f/WATE.f/OCEA.f/SOOT.f, OTB commit above): vi_m (um^3; lines
# 1121/1123/1123/1122), ext_m and sca_m (lines 26-36; per particle, um^2,
# labelled "km-1" in the code), asy_m (lines 22-24) and the phase function
# at 550 nm on 6S's 83 angles (lines 164-181; mu = -1, 40 Gauss points, 0,
# 40 Gauss points, +1, i.e. from 180 deg to 0 deg). Used only to validate.
REF_6SV = {
    "dust_like": {
        "vi_um3": 18.2859898,
        "ext": [8.2303880e+00, 8.3057230e+00, 8.3288830e+00, 8.3683960e+00, 8.4159680e+00, 8.4286500e+00, 8.4678640e+00, 8.5199620e+00, 8.5832420e+00, 8.6328670e+00, 8.6890270e+00, 8.7043090e+00, 8.8034380e+00, 8.9246360e+00],
        "sca": [5.5657000e+00, 5.7441320e+00, 5.7869490e+00, 5.8880610e+00, 5.9760420e+00, 6.0288080e+00, 6.1127330e+00, 6.2150030e+00, 6.3332350e+00, 6.4501230e+00, 6.5479410e+00, 6.6037940e+00, 6.7717050e+00, 7.0024200e+00],
        "asy": [0.846, 0.838, 0.836, 0.832, 0.827, 0.826, 0.822, 0.817, 0.812, 0.807, 0.802, 0.800, 0.792, 0.785],
        "phase_550": [
            4.9600e-01, 4.7240e-01, 4.8680e-01, 4.7220e-01, 4.3660e-01, 3.9420e-01, 3.5180e-01,
            3.2190e-01, 2.9460e-01, 2.5650e-01, 2.0720e-01, 1.6790e-01, 1.4150e-01, 1.2050e-01,
            1.0190e-01, 8.8370e-02, 7.9630e-02, 7.3000e-02, 6.9250e-02, 6.6320e-02, 6.3390e-02,
            6.1030e-02, 5.9950e-02, 6.0340e-02, 5.9950e-02, 6.0750e-02, 6.1060e-02, 6.1740e-02,
            6.3490e-02, 6.6210e-02, 6.8580e-02, 7.1110e-02, 7.4850e-02, 7.9020e-02, 8.4000e-02,
            8.8980e-02, 9.4500e-02, 1.0060e-01, 1.0810e-01, 1.1610e-01, 1.2380e-01, 1.2830e-01,
            1.3290e-01, 1.4440e-01, 1.5910e-01, 1.7310e-01, 1.8600e-01, 2.0230e-01, 2.2160e-01,
            2.4140e-01, 2.6620e-01, 2.9080e-01, 3.1900e-01, 3.4950e-01, 3.8120e-01, 4.2040e-01,
            4.5770e-01, 5.0390e-01, 5.5000e-01, 6.0280e-01, 6.5930e-01, 7.2940e-01, 8.0730e-01,
            8.8430e-01, 9.6820e-01, 1.0730e+00, 1.1790e+00, 1.3070e+00, 1.4560e+00, 1.6210e+00,
            1.8210e+00, 2.0710e+00, 2.3990e+00, 2.8440e+00, 3.5030e+00, 4.5280e+00, 6.2740e+00,
            9.6200e+00, 1.6800e+01, 3.5290e+01, 9.7250e+01, 4.4130e+02, 2.0960e+03],
    },
    "water_soluble": {
        "vi_um3": 0.00182737305,
        "ext": [1.6682020e-02, 1.4854270e-02, 1.4447050e-02, 1.3442780e-02, 1.2632200e-02, 1.2118810e-02, 1.1397590e-02, 1.0539510e-02, 9.6463740e-03, 8.7918110e-03, 8.1289740e-03, 7.7296470e-03, 6.7401320e-03, 5.4556050e-03],
        "sca": [1.6116820e-02, 1.4369330e-02, 1.3977800e-02, 1.3012390e-02, 1.2230160e-02, 1.1735500e-02, 1.1018100e-02, 1.0144930e-02, 9.2848520e-03, 8.4244270e-03, 7.7724480e-03, 7.3890770e-03, 6.3635830e-03, 5.0647770e-03],
        "asy": [0.663, 0.657, 0.655, 0.651, 0.648, 0.645, 0.642, 0.638, 0.633, 0.628, 0.623, 0.620, 0.613, 0.605],
        "phase_550": [
            3.2490e-01, 3.2140e-01, 3.0830e-01, 2.8940e-01, 2.6970e-01, 2.5250e-01, 2.3950e-01,
            2.3090e-01, 2.2530e-01, 2.2140e-01, 2.1810e-01, 2.1470e-01, 2.1080e-01, 2.0660e-01,
            2.0210e-01, 1.9740e-01, 1.9290e-01, 1.8870e-01, 1.8480e-01, 1.8140e-01, 1.7850e-01,
            1.7620e-01, 1.7450e-01, 1.7340e-01, 1.7290e-01, 1.7310e-01, 1.7400e-01, 1.7560e-01,
            1.7800e-01, 1.8110e-01, 1.8520e-01, 1.9010e-01, 1.9600e-01, 2.0280e-01, 2.1080e-01,
            2.2000e-01, 2.3060e-01, 2.4250e-01, 2.5610e-01, 2.7140e-01, 2.8860e-01, 2.9800e-01,
            3.0790e-01, 3.2970e-01, 3.5420e-01, 3.8160e-01, 4.1220e-01, 4.4650e-01, 4.8500e-01,
            5.2810e-01, 5.7640e-01, 6.3050e-01, 6.9120e-01, 7.5930e-01, 8.3560e-01, 9.2130e-01,
            1.0170e+00, 1.1250e+00, 1.2460e+00, 1.3820e+00, 1.5350e+00, 1.7070e+00, 1.8990e+00,
            2.1150e+00, 2.3560e+00, 2.6260e+00, 2.9280e+00, 3.2660e+00, 3.6410e+00, 4.0570e+00,
            4.5180e+00, 5.0270e+00, 5.5850e+00, 6.1940e+00, 6.8550e+00, 7.5650e+00, 8.3190e+00,
            9.1070e+00, 9.9090e+00, 1.0690e+01, 1.1380e+01, 1.1870e+01, 1.2000e+01],
    },
    "oceanic": {
        "vi_um3": 4.99809027,
        "ext": [3.4921340e+00, 3.5558350e+00, 3.5774400e+00, 3.6019850e+00, 3.6258010e+00, 3.6280890e+00, 3.6582860e+00, 3.6587470e+00, 3.6965270e+00, 3.7306090e+00, 3.7366550e+00, 3.7635600e+00, 3.7767310e+00, 3.8131610e+00],
        "sca": [3.4921000e+00, 3.5558330e+00, 3.5774380e+00, 3.6019830e+00, 3.6257990e+00, 3.6280880e+00, 3.6582840e+00, 3.6587460e+00, 3.6965260e+00, 3.7306070e+00, 3.7366500e+00, 3.7635520e+00, 3.7749580e+00, 3.8091290e+00],
        "asy": [0.790, 0.787, 0.785, 0.784, 0.782, 0.784, 0.781, 0.784, 0.781, 0.780, 0.780, 0.779, 0.779, 0.778],
        "phase_550": [
            5.8890e-01, 4.9930e-01, 4.7270e-01, 4.1280e-01, 3.7370e-01, 3.6000e-01, 3.5340e-01,
            3.3820e-01, 3.1670e-01, 2.9880e-01, 2.8740e-01, 2.9580e-01, 2.9780e-01, 2.8690e-01,
            2.8340e-01, 2.5250e-01, 2.0300e-01, 1.6630e-01, 1.3630e-01, 1.1440e-01, 1.0050e-01,
            8.5130e-02, 7.8000e-02, 7.4460e-02, 7.0290e-02, 6.7240e-02, 6.6570e-02, 6.8440e-02,
            6.8370e-02, 7.0440e-02, 7.2750e-02, 7.1420e-02, 7.4330e-02, 7.6820e-02, 7.9810e-02,
            8.2210e-02, 8.4150e-02, 8.9190e-02, 9.5470e-02, 1.0070e-01, 1.0600e-01, 1.0930e-01,
            1.1500e-01, 1.2280e-01, 1.3370e-01, 1.4330e-01, 1.5900e-01, 1.7570e-01, 1.9470e-01,
            2.1500e-01, 2.4450e-01, 2.7360e-01, 3.0740e-01, 3.3710e-01, 3.8630e-01, 4.4320e-01,
            4.9450e-01, 5.6060e-01, 6.4520e-01, 7.2560e-01, 8.2690e-01, 9.3820e-01, 1.0740e+00,
            1.2320e+00, 1.4020e+00, 1.5900e+00, 1.8250e+00, 2.0990e+00, 2.4150e+00, 2.7510e+00,
            3.1630e+00, 3.6640e+00, 4.2660e+00, 5.0230e+00, 5.9560e+00, 7.2700e+00, 9.3730e+00,
            1.2850e+01, 1.9240e+01, 3.3830e+01, 7.4270e+01, 2.3900e+02, 7.4010e+02],
    },
    "soot": {
        "vi_um3": 6.05630412e-05,
        "ext": [1.0177240e-03, 8.6147330e-04, 8.2915640e-04, 7.5345580e-04, 6.9556190e-04, 6.6058080e-04, 6.1152990e-04, 5.5415740e-04, 5.0075400e-04, 4.5424660e-04, 4.1890210e-04, 3.9754660e-04, 3.5079390e-04, 2.9845240e-04],
        "sca": [2.9568080e-04, 2.3011830e-04, 2.1705540e-04, 1.8719830e-04, 1.6512210e-04, 1.5212930e-04, 1.3480110e-04, 1.1565990e-04, 9.7746790e-05, 8.2185600e-05, 7.1114100e-05, 6.4860940e-05, 5.0938260e-05, 3.6212590e-05],
        "asy": [0.423, 0.397, 0.391, 0.377, 0.365, 0.358, 0.348, 0.337, 0.324, 0.310, 0.299, 0.293, 0.276, 0.253],
        "phase_550": [
            6.0660e-01, 6.0640e-01, 6.0570e-01, 6.0430e-01, 6.0240e-01, 6.0000e-01, 5.9700e-01,
            5.9350e-01, 5.8950e-01, 5.8510e-01, 5.8030e-01, 5.7530e-01, 5.6990e-01, 5.6430e-01,
            5.5850e-01, 5.5270e-01, 5.4670e-01, 5.4090e-01, 5.3510e-01, 5.2940e-01, 5.2400e-01,
            5.1890e-01, 5.1430e-01, 5.1000e-01, 5.0640e-01, 5.0340e-01, 5.0110e-01, 4.9970e-01,
            4.9920e-01, 4.9980e-01, 5.0150e-01, 5.0440e-01, 5.0880e-01, 5.1460e-01, 5.2200e-01,
            5.3110e-01, 5.4220e-01, 5.5520e-01, 5.7030e-01, 5.8770e-01, 6.0750e-01, 6.1840e-01,
            6.2990e-01, 6.5500e-01, 6.8290e-01, 7.1380e-01, 7.4780e-01, 7.8510e-01, 8.2590e-01,
            8.7020e-01, 9.1820e-01, 9.7010e-01, 1.0260e+00, 1.0860e+00, 1.1500e+00, 1.2180e+00,
            1.2900e+00, 1.3670e+00, 1.4480e+00, 1.5340e+00, 1.6230e+00, 1.7170e+00, 1.8140e+00,
            1.9150e+00, 2.0190e+00, 2.1260e+00, 2.2360e+00, 2.3480e+00, 2.4600e+00, 2.5740e+00,
            2.6860e+00, 2.7970e+00, 2.9060e+00, 3.0100e+00, 3.1100e+00, 3.2020e+00, 3.2860e+00,
            3.3600e+00, 3.4230e+00, 3.4730e+00, 3.5080e+00, 3.5280e+00, 3.5330e+00],
    },
}

# ---------------------------------------------------------------------------
# Size distribution and Mie integration
# ---------------------------------------------------------------------------


def dn_dlnr(r, rm, sigma):
    """Log-normal number density per unit ln r, 6S's form (MIE.f 95-98) times r."""
    ls = np.log10(sigma)
    return np.exp(-0.5 * (np.log10(r / rm) / ls) ** 2) / (np.sqrt(2.0 * np.pi) * np.log(10.0) * ls)


def radius_grid(rm, sigma, scheme="trapezoid", h=0.005):
    """Radii (um) and quadrature weights w_k so that sum w_k f(r_k) ~ int f dN.

    ``trapezoid``: uniform in ln r from RMIN to RMAX, about ``h`` decades apart.
    ``6s``: 6S's MIE.f scheme, r_{k+1} = r_k 10^0.011 from RMIN while r_k < RMAX,
    left rectangles w_k = dN/dr(r_k) (r_{k+1} - r_k).
    """
    if scheme == "trapezoid":
        n = int(round(np.log10(RMAX / RMIN) / h))
        lr = np.linspace(np.log(RMIN), np.log(RMAX), n + 1)
        r = np.exp(lr)
        w = dn_dlnr(r, rm, sigma) * (lr[1] - lr[0])
        w[0] *= 0.5
        w[-1] *= 0.5
        return r, w
    if scheme == "6s":
        rs, ws = [], []
        r = RMIN
        while True:
            dr = r * (10.0 ** STEP_6S - 1.0)
            rs.append(r)
            ws.append(dn_dlnr(r, rm, sigma) / r * dr)
            r = r + dr
            if r >= RMAX:
                break
        return np.array(rs), np.array(ws)
    raise ValueError(scheme)


def component_optics(name, il, mu=None, scheme="trapezoid", h=None):
    """Per-particle optics of one component at WAVELENGTHS[il].

    ``h``: radius step in decades (default: the component's "h").

    Returns N (in-range number, ~1), v (mean particle volume, um^3),
    v6s (6S's vi: the same sum not divided by N), cext, csca, cscag (um^2,
    per in-range particle) and, if ``mu`` is given, dcsca (dC_sca/dOmega,
    um^2/sr, at mu = cos theta).
    """
    c = COMPONENTS[name]
    r, w = radius_grid(c["rm"], c["sigma"], scheme, h or c["h"])
    wl = WAVELENGTHS[il]
    m = complex(c["n"][il], -c["k"][il])
    N = w.sum()
    vol = (4.0 / 3.0 * np.pi * r ** 3 * w).sum()
    out = {"N": N, "v": vol / N, "v6s": vol}
    area = w * r ** 2
    keep = area >= 1e-16 * area.max()
    r, w = r[keep], w[keep]
    x = 2.0 * np.pi * r / wl
    cs = np.pi * r ** 2 * w
    qe, qs, _, g = miepython.efficiencies_mx(m, x)
    out["cext"] = (cs * qe).sum() / N
    out["csca"] = (cs * qs).sum() / N
    out["cscag"] = (cs * qs * g).sum() / N
    if mu is not None:
        mu = np.asarray(mu, dtype=float)
        acc = np.zeros(mu.size)
        for xk, ck in zip(x, cs):
            acc += ck * miepython.i_unpolarized(m, xk, mu, norm="qsca")
        out["dcsca"] = acc / N
    return out


def number_fractions(fractions, vols):
    """6S AEROSO.f: c_j / v_j normalised (volume -> number fractions)."""
    c = np.asarray(fractions, dtype=float)
    v = np.asarray(vols, dtype=float)
    q = c / v
    return q / q.sum()


def mix(fractions, comps):
    """External mixture of the four components (list in ORDER) at one wavelength."""
    nf = number_fractions(fractions, [cp["v"] for cp in comps])
    ext = sum(n * cp["cext"] for n, cp in zip(nf, comps))
    sca = sum(n * cp["csca"] for n, cp in zip(nf, comps))
    scag = sum(n * cp["cscag"] for n, cp in zip(nf, comps))
    res = {"ext": ext, "ssa": sca / ext, "g": scag / sca, "nf": nf}
    if "dcsca" in comps[0]:
        res["phase"] = 4.0 * np.pi * sum(n * cp["dcsca"] for n, cp in zip(nf, comps)) / sca
    return res


def trapz(y, x):
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def phase_moments(p, angles_deg):
    """(1/2) int P sin, (1/2) int P cos sin, by the trapezoidal rule in theta."""
    th = np.radians(angles_deg)
    return trapz(p * np.sin(th), th) / 2.0, trapz(p * np.cos(th) * np.sin(th), th) / 2.0


def angstrom(e1, l1, e2, l2):
    return -np.log(e1 / e2) / np.log(l1 / l2)


def selftest_normalisation():
    """i_unpolarized(norm='qsca') must integrate to Q_sca over 4 pi."""
    m, x = complex(1.5, -0.01), 7.3
    mu, wt = np.polynomial.legendre.leggauss(600)
    tot = 2.0 * np.pi * np.sum(wt * miepython.i_unpolarized(m, x, mu, norm="qsca"))
    qsca = miepython.efficiencies_mx(m, x)[1]
    if abs(tot / qsca - 1.0) > 1e-6:
        sys.exit(f"miepython normalisation unexpected: {tot} vs Qsca {qsca}")


# ---------------------------------------------------------------------------
# Tables
# ---------------------------------------------------------------------------


def compute_all(progress=True):
    """Component optics at all WAVELENGTHS on ANGLES_DEG, then the three models."""
    mu = np.cos(np.radians(ANGLES_DEG))
    comps = {}
    for name in ORDER:
        t = time.time()
        comps[name] = [component_optics(name, il, mu) for il in range(len(WAVELENGTHS))]
        if progress:
            print(f"  {name:14s} {time.time() - t:6.1f} s", flush=True)
    models = {}
    for mname, frac in MODELS.items():
        models[mname] = [mix(frac, [comps[n][il] for n in ORDER]) for il in range(len(WAVELENGTHS))]
    return comps, models


def header(kind):
    common = [
        "# 6S standard aerosol models (continental, maritime, urban) computed by Mie theory.",
        "# Source: 6S, Vermote, Tanre, Deuze, Herman & Morcrette (1997) IEEE TGRS 35(3):675-686, version",
        "#   6SV1.0B as vendored in github.com/orfeotoolbox/OTB @ cbc8644dfc17ccbde94f13c8fd88f3e3a81be8a8",
        "#   (Modules/ThirdParty/6S/src): volume fractions main.f lines 859-872 -- continental 0.70 dust-like",
        "#   + 0.29 water-soluble + 0.01 soot; maritime 0.05 water-soluble + 0.95 oceanic; urban 0.17",
        "#   dust-like + 0.61 water-soluble + 0.22 soot -- and mixing rule 6SV1.0B/AEROSO.f. Component data after",
        "#   d'Almeida, Koepke & Shettle (1991) as used by 6SV; their log-normal parameters and refractive",
        "#   indices are not printed in the 6SV source and were recovered from, and checked against, 6SV's",
        "#   tabulated component Mie results (6SV1.0B/DUST.f, WATE.f, OCEA.f, SOOT.f); see the script.",
        "# Method: log-normal number distributions truncated to 0.001-20 um (dust-like 0.471 um/2.512,",
        "#   water-soluble 0.0285/2.239, oceanic 0.3/2.51, soot 0.0118/2.0: median radius/geometric s.d.);",
        "#   Mie theory (miepython 3.3) integrated by the trapezoidal rule in ln r, steps of 0.005 decade",
        "#   (oceanic 0.0025); volume fractions -> number fractions n_j = (c_j/v_j)/sum(c_k/v_k), v_j = mean",
        "#   particle volume of component j; external mixture.",
    ]
    if kind == "models":
        return common + [
            "# Columns: model; wavelength_nm (the 6S wavelengths from 350 to 860 nm); ext_rel_550 = extinction",
            "#   coefficient / its value at 550 nm; ssa = single-scattering albedo; g = asymmetry parameter (Mie).",
            "# Generated by tools/aerosol_tables.py; verify with: python3 tools/aerosol_tables.py --check",
            "model,wavelength_nm,ext_rel_550,ssa,g",
        ]
    return common + [
        "# Columns: model; wavelength_nm; angle_deg = scattering angle; phase = phase function P(theta),",
        "#   normalised to mean 1 over the sphere: (1/2) integral_0^180deg P sin(theta) dtheta = 1, i.e. the",
        "#   integral over 4 pi sr is 4 pi. Angle grid: 0-1 deg by 0.05, 1.1-3 by 0.1, 3.25-10 by 0.25,",
        "#   11-30 by 1, 32-180 by 2 (164 angles); the trapezoidal integral on this grid is 1 within 1e-3.",
        "# Generated by tools/aerosol_tables.py; verify with: python3 tools/aerosol_tables.py --check",
        "model,wavelength_nm,angle_deg,phase",
    ]


def fmt(v):
    return f"{v:.6g}"


def table_rows(models):
    mrows, prows = [], []
    for mname, res in models.items():
        e550 = res[I550]["ext"]
        for il, wl in enumerate(WAVELENGTHS):
            r = res[il]
            wnm = int(round(wl * 1000))
            mrows.append([mname, str(wnm), fmt(r["ext"] / e550), fmt(r["ssa"]), fmt(r["g"])])
            for a, p in zip(ANGLES_DEG, r["phase"]):
                prows.append([mname, str(wnm), f"{a:g}", fmt(p)])
    return mrows, prows


def write_csv(path, head, rows):
    path.write_text("\n".join(head + [",".join(r) for r in rows]) + "\n")


def read_csv(path):
    rows = []
    for line in path.read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        rows.append(line.split(","))
    return rows[0], rows[1:]


def compare(path, rows, rtol=1e-5):
    hdr, old = read_csv(path)
    if len(old) != len(rows):
        return False, f"{path.name}: {len(old)} rows on disk, {len(rows)} recomputed"
    worst = 0.0
    for a, b in zip(old, rows):
        for u, v in zip(a, b):
            try:
                fu, fv = float(u), float(v)
            except ValueError:
                if u != v:
                    return False, f"{path.name}: '{u}' vs '{v}'"
                continue
            d = abs(fu - fv) / max(abs(fv), 1e-30)
            worst = max(worst, d)
    return worst <= rtol, f"{path.name}: {len(rows)} rows, max relative difference {worst:.2e}"


def sixs_reference_models():
    """The three models mixed from 6SV's own component tables (AEROSO.f rule)."""
    out = {}
    for mname, frac in MODELS.items():
        vi = [REF_6SV[n]["vi_um3"] for n in ORDER]
        nf = number_fractions(frac, vi)
        ext = sum(n * np.array(REF_6SV[c]["ext"]) for n, c in zip(nf, ORDER))
        sca = sum(n * np.array(REF_6SV[c]["sca"]) for n, c in zip(nf, ORDER))
        scag = sum(n * np.array(REF_6SV[c]["sca"]) * np.array(REF_6SV[c]["asy"]) for n, c in zip(nf, ORDER))
        out[mname] = {"ext": ext, "ssa": sca / ext, "g": scag / sca}
    return out


def report(models):
    """Print the sanity checks; return False if a check fails."""
    ok = True
    i443, i860 = WAVELENGTHS.index(0.443), WAVELENGTHS.index(0.860)
    ref = sixs_reference_models()
    print("\nSanity checks (Angstrom exponent from extinction at 443 and 860 nm, the 6S wavelengths")
    print("nearest 440/870; '6SV' = the same quantity mixed from 6SV1.0B's tabulated components,")
    print("whose g is 6S's 83-angle Gauss-quadrature asymmetry):")
    print(f"{'model':12s} {'alpha':>7s} {'6SV':>6s} {'ssa550':>7s} {'6SV':>7s} {'g550':>6s} {'6SV':>6s}"
          f" {'max|int-1|':>10s} {'max|g_tab-g|':>12s}")
    for mname, res in models.items():
        a = angstrom(res[i443]["ext"], 0.443, res[i860]["ext"], 0.860)
        a6 = angstrom(ref[mname]["ext"][i443], 0.443, ref[mname]["ext"][i860], 0.860)
        nerr = gerr = 0.0
        for r in res:
            s0, s1 = phase_moments(r["phase"], ANGLES_DEG)
            nerr = max(nerr, abs(s0 - 1.0))
            gerr = max(gerr, abs(s1 - r["g"]))
        ok &= nerr < 1e-3 and gerr < 2e-3
        r5 = res[I550]
        print(f"{mname:12s} {a:7.3f} {a6:6.3f} {r5['ssa']:7.4f} {ref[mname]['ssa'][I550]:7.4f}"
              f" {r5['g']:6.3f} {ref[mname]['g'][I550]:6.3f} {nerr:10.1e} {gerr:12.1e}")
        print(f"{'':12s} number fractions (dust, w-s, ocean, soot): "
              + ", ".join(f"{v:.4g}" for v in r5["nf"]))
    print("phase normalisation (|int - 1| < 1e-3) and g from the table (|dg| < 2e-3):",
          "pass" if ok else "FAIL")
    return ok


def validate_6sv():
    """Redo the components with 6S's radius scheme and compare with 6S's tables."""
    mu83 = np.polynomial.legendre.leggauss(80)
    nodes, wts = mu83
    cg = np.concatenate([[-1.0], nodes[:40], [0.0], nodes[40:], [1.0]])
    pw = np.concatenate([[0.0], wts[:40], [0.0], wts[40:], [0.0]])
    print("6S scheme (0.001-20 um, left rectangles, dlog10 r = 0.011) vs 6SV1.0B tables:")
    print(f"{'component':14s} {'vi ratio':>10s} {'max|dext|':>10s} {'max|dsca|':>10s}"
          f" {'max|dasy|':>10s} {'P550 rms':>9s} {'P550 max':>9s}  (relative; asy absolute)")
    for name in ORDER:
        ref = REF_6SV[name]
        de = ds = da = 0.0
        for il in range(len(WAVELENGTHS)):
            o = component_optics(name, il, cg, scheme="6s")
            de = max(de, abs(o["cext"] / ref["ext"][il] - 1))
            ds = max(ds, abs(o["csca"] / ref["sca"][il] - 1))
            ph = o["dcsca"] / o["csca"] * 4 * np.pi
            asy = np.sum(cg * ph * pw) / np.sum(ph * pw)
            da = max(da, abs(asy - ref["asy"][il]))
            if il == I550:
                rel = ph / np.array(ref["phase_550"]) - 1
                prms, pmax = np.sqrt(np.mean(rel ** 2)), np.max(np.abs(rel))
                vr = o["v6s"] / ref["vi_um3"]
        print(f"{name:14s} {vr:10.7f} {de:10.1e} {ds:10.1e} {da:10.4f} {prms:9.1e} {pmax:9.1e}")
    s = np.sum(np.array(REF_6SV["oceanic"]["phase_550"]) * pw)
    print(f"(6S's own 550 nm oceanic phase function sums to {s:.4f} with its Gauss weights: mean 1 <=> 2)")


def convergence():
    """Each component's radius step against half of it."""
    mu = np.cos(np.radians(ANGLES_DEG))
    print("radius step h vs h/2 (relative differences; g absolute):")
    for name in ORDER:
        h = COMPONENTS[name]["h"]
        for il in (0, I550, len(WAVELENGTHS) - 1):
            a = component_optics(name, il, mu, h=h)
            b = component_optics(name, il, mu, h=h / 2)
            dp = np.max(np.abs(a["dcsca"] / b["dcsca"] - 1))
            print(f"  {name:14s} h={h}  {WAVELENGTHS[il]:.3f} um: ext {abs(a['cext'] / b['cext'] - 1):.1e}"
                  f"  sca {abs(a['csca'] / b['csca'] - 1):.1e}"
                  f"  g {abs(a['cscag'] / a['csca'] - b['cscag'] / b['csca']):.1e}  phase max {dp:.1e}",
                  flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--check", action="store_true", help="recompute and compare with the shipped CSVs")
    g.add_argument("--validate-6sv", action="store_true", help="6S scheme vs 6S's tabulated components")
    g.add_argument("--convergence", action="store_true", help="radius-step convergence")
    args = ap.parse_args()
    t0 = time.time()
    selftest_normalisation()
    if args.validate_6sv:
        validate_6sv()
    elif args.convergence:
        convergence()
    else:
        print("computing components (14 wavelengths, 164 angles):")
        _, models = compute_all()
        mrows, prows = table_rows(models)
        ok = report(models)
        if args.check:
            for path, rows in ((MODELS_CSV, mrows), (PHASE_CSV, prows)):
                good, msg = compare(path, rows)
                print(("ok   " if good else "DIFF ") + msg)
                ok &= good
        else:
            write_csv(MODELS_CSV, header("models"), mrows)
            write_csv(PHASE_CSV, header("phase"), prows)
            print(f"wrote {MODELS_CSV.relative_to(ROOT)} ({len(mrows)} rows), "
                  f"{PHASE_CSV.relative_to(ROOT)} ({len(prows)} rows)")
        print(f"run time {time.time() - t0:.0f} s")
        if not ok:
            sys.exit(1)
        return
    print(f"run time {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
