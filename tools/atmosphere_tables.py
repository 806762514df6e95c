#!/usr/bin/env python3
"""Extract the atmosphere's tables from PyPI packages into littoral's data/.

Writes two files, copying numbers verbatim (no number is computed here):

* ``data/afgl_profiles.csv``: the six AFGL reference atmospheres (Anderson,
  Clough, Kneizys, Chetwynd & Shettle 1986, "AFGL Atmospheric Constituent
  Profiles (0-120 km)", AFGL-TR-86-0110), 50 levels from 0 to 120 km each:
  altitude, pressure, temperature, air number density and the H2O and O3
  volume mixing ratios, from ``pyrtlib`` 1.2.0 (``climatology/*.dat``,
  "adapted from glatm.dat"). The U.S. Standard profile is the U.S. Standard
  Atmosphere 1976 as AFGL tabulates it.
* ``data/ozone_leckner1978.csv``: ozone absorption coefficients (per cm of
  ozone at STP, i.e. per atm-cm) from 300 to 800 nm, as tabulated in Bird &
  Riordan (1986), "Simple solar spectral model for direct and diffuse
  irradiance on horizontal and tilted planes at the earth's surface for
  cloudless atmospheres", J. Climate Appl. Meteor. 25:87 (SPECTRL2, after
  Leckner 1978, Solar Energy 20:143), from ``pvlib`` 0.16.1
  (``pvlib/spectrum/spectrl2.py``, ``_SPECTRL2_COEFFS``).

Usage: python3 -m pip download --no-deps pyrtlib==1.2.0 pvlib==0.16.1 -d W;
unzip both wheels into W/x; python3 tools/atmosphere_tables.py W/x.
"""

import ast
import pathlib
import sys

PROFILES = [
    ("tropical", "tropical.dat", 15.0),
    ("midlatitude-summer", "midlatitude_summer.dat", 45.0),
    ("midlatitude-winter", "midlatitude_winter.dat", 45.0),
    ("subarctic-summer", "subarctic_summer.dat", 60.0),
    ("subarctic-winter", "subarctic_winter.dat", 60.0),
    ("us-standard-1976", "us_standard.dat", 45.5397),
]


def short(text):
    """The shortest decimal that reads back to the same double."""
    return repr(float(text))


def profiles(root, out):
    src = root / "pyrtlib" / "climatology"
    lines = [
        "# AFGL atmospheric constituent profiles, 0-120 km, 50 levels each.",
        "# Source: Anderson, Clough, Kneizys, Chetwynd & Shettle (1986), AFGL-TR-86-0110",
        "#   (\"glatm.dat\"), as shipped by pyrtlib 1.2.0 (climatology/*.dat); us-standard-1976 is",
        "#   the U.S. Standard Atmosphere 1976. Latitudes (deg): "
        + ", ".join(f"{n} {lat}" for n, _, lat in PROFILES)
        + ".",
        "# Columns: profile, altitude (km), pressure (hPa), temperature (K), air number density",
        "#   (molecules cm^-3), H2O and O3 volume mixing ratios (ppmv). Extracted by",
        "#   tools/atmosphere_tables.py; values verbatim.",
        "profile,z_km,p_hpa,t_k,air_cm3,h2o_ppmv,o3_ppmv",
    ]
    for name, file, _ in PROFILES:
        for row in (src / file).read_text().split("\n"):
            f = row.split()
            if not f:
                continue
            z, p, d, t, h2o, o3 = f[0], f[1], f[2], f[3], f[4], f[6]
            lines.append(",".join([name] + [short(v) for v in (z, p, t, d, h2o, o3)]))
    out.write_text("\n".join(lines) + "\n")


def ozone(root, out):
    text = (root / "pvlib" / "spectrum" / "spectrl2.py").read_text()

    def column(name):
        key = f"_SPECTRL2_COEFFS['{name}'] = ["
        start = text.index(key) + len(key) - 1
        end = text.index("]", start) + 1
        body = "\n".join(l.split("#")[0] for l in text[start:end].split("\n"))
        return ast.literal_eval(body)

    nm = column("wavelength")
    ao = column("ozone_absorption")
    lines = [
        "# Ozone absorption coefficient per atm-cm of ozone (1/cm at STP), 300-800 nm.",
        "# Source: Bird & Riordan (1986) J. Climate Appl. Meteor. 25:87 (SPECTRL2), after Leckner (1978)",
        "#   Solar Energy 20:143; as tabulated in pvlib 0.16.1 (pvlib/spectrum/spectrl2.py). Optical depth",
        "#   = coefficient x column in atm-cm (1000 DU = 1 atm-cm). Extracted by tools/atmosphere_tables.py.",
        "#   The table gives 0 from 360 to 440 nm, where ozone absorbs weakly (the tail of the Huggins",
        "#   bands and the onset of the Chappuis band); it is used as given.",
        "wavelength_nm,k_o3_per_atm_cm",
    ]
    for w, k in zip(nm, ao):
        if w <= 800.0:
            lines.append(f"{w!r},{k!r}")
    out.write_text("\n".join(lines) + "\n")


def main():
    root = pathlib.Path(sys.argv[1])
    data = pathlib.Path(__file__).resolve().parent.parent / "data"
    profiles(root, data / "afgl_profiles.csv")
    ozone(root, data / "ozone_leckner1978.csv")


if __name__ == "__main__":
    main()
