#!/usr/bin/env python3
"""Extract sensor relative spectral responses (RSR/SRF) from PyPI packages.

Writes the files in ``data/srf/`` of littoral:

* tabulated RSR files (multispectral sensors), taken verbatim from
  ``pyrsr`` 0.8.0 (Apache-2.0):
  ``sentinel2a-msi.csv``, ``sentinel2b-msi.csv``, ``landsat8-oli.csv``,
  ``landsat9-oli.csv``;
* a Gaussian centre/FWHM file (hyperspectral sensor), taken verbatim from
  ``isofit`` 4.1.5 (Apache-2.0): ``aviris-ng.csv``;
* ``README.md``, the index of these files, including the sensors that no
  reachable package provides (PACE OCI, EnMAP, PRISMA) and why.

No number is computed or estimated here: response values are copied as the
package's own decimal strings; the only changes are the unit conversion of
wavelengths from micrometres to nanometres (exact, in decimal arithmetic),
negative responses (detector noise in the Landsat lab data, all |x| < 4e-4)
set to 0, zeros written where a band has no tabulated value on the common
grid, and the restriction to 350-2600 nm (which drops only the thermal TIRS
bands 10 and 11 of Landsat 8/9).

Reproduce
---------
Only the Python standard library is needed (no numpy). Download the two
packages' source distributions into one directory, then run::

    pip download --no-deps --no-binary :all: -d /tmp/srfpkg pyrsr==0.8.0 isofit==4.1.5
    python3 tools/srf_extract.py --pkgdir /tmp/srfpkg --out data/srf

The archives are read in place (``.tar.gz`` sdists or ``.whl`` wheels; an
unpacked directory of the same name also works). Other versions are accepted
with a warning; the versions and the archive's SHA-256 are written into
every file's header, so a change of source is visible in the diff.

Output formats
--------------
Tabulated RSR::

    # comment lines
    wavelength_nm,B1,B2,...
    412,0.001775742,0,...

ascending 1 nm grid (the packages' own grid: every pyrsr band used here is
tabulated at integer nanometres), peak-normalised responses (max 1) as
published, 0 outside a band's tabulated support.

Gaussian centre/FWHM::

    # comment lines
    band,center_nm,fwhm_nm
    b001,376.86,5.57

one row per channel, as tabulated by the source (no fitting).
"""

from __future__ import annotations

import argparse
import hashlib
import io
import os
import re
import sys
import tarfile
import zipfile
from decimal import Decimal
from email.parser import HeaderParser

WL_MIN_NM = Decimal(350)
WL_MAX_NM = Decimal(2600)

TESTED_VERSIONS = {"pyrsr": "0.8.0", "isofit": "4.1.5"}


# --------------------------------------------------------------------------
# package access
# --------------------------------------------------------------------------
class Package:
    """Read-only view of one downloaded distribution (sdist, wheel or dir)."""

    def __init__(self, pkgdir: str, name: str):
        self.name = name
        self.path = self._find(pkgdir, name)
        self.kind = ("dir" if os.path.isdir(self.path)
                     else "whl" if self.path.endswith(".whl") else "tar")
        if self.kind == "tar":
            self._tar = tarfile.open(self.path)
            self.members = [m.name for m in self._tar.getmembers() if m.isfile()]
        elif self.kind == "whl":
            self._zip = zipfile.ZipFile(self.path)
            self.members = [n for n in self._zip.namelist() if not n.endswith("/")]
        else:
            self.members = []
            for root, _dirs, files in os.walk(self.path):
                for f in files:
                    self.members.append(os.path.relpath(os.path.join(root, f), self.path))
        self.sha256 = (self._sha256(self.path) if self.kind != "dir" else "n/a (unpacked directory)")
        self.meta = self._metadata()
        self.version = self.meta.get("Version", "?")
        if self.version != TESTED_VERSIONS.get(name):
            print(f"warning: {name} {self.version} found, this script was checked against "
                  f"{TESTED_VERSIONS.get(name)}", file=sys.stderr)

    @staticmethod
    def _find(pkgdir: str, name: str) -> str:
        pat = re.compile(rf"^{re.escape(name)}-[0-9][^/]*?(\.tar\.gz|\.whl)?$", re.IGNORECASE)
        hits = []
        for root, dirs, files in os.walk(pkgdir):
            for entry in files + dirs:
                if pat.match(entry):
                    hits.append(os.path.join(root, entry))
        # prefer archives (exact bytes, hashable) over unpacked directories
        hits.sort(key=lambda p: (os.path.isdir(p), p))
        if not hits:
            sys.exit(f"error: no {name}-<version> archive or directory under {pkgdir}; run\n"
                     f"  pip download --no-deps --no-binary :all: -d {pkgdir} "
                     f"{name}=={TESTED_VERSIONS[name]}")
        return hits[0]

    @staticmethod
    def _sha256(path: str) -> str:
        h = hashlib.sha256()
        with open(path, "rb") as fh:
            for chunk in iter(lambda: fh.read(1 << 20), b""):
                h.update(chunk)
        return h.hexdigest()

    def member(self, suffix: str) -> str:
        """Archive member whose path ends with ``suffix`` (exactly one)."""
        hits = [m for m in self.members if m.replace(os.sep, "/").endswith(suffix)]
        # an sdist may carry both PKG-INFO and <pkg>.egg-info/PKG-INFO: take the shortest
        if not hits:
            raise FileNotFoundError(f"{suffix} not in {self.path}")
        return min(hits, key=len)

    def read(self, member: str) -> str:
        if self.kind == "tar":
            return self._tar.extractfile(member).read().decode("utf-8")
        if self.kind == "whl":
            return self._zip.read(member).decode("utf-8")
        with open(os.path.join(self.path, member), encoding="utf-8") as fh:
            return fh.read()

    def _metadata(self) -> dict:
        for suffix in ("/PKG-INFO", ".dist-info/METADATA", "PKG-INFO"):
            try:
                text = self.read(self.member(suffix))
                break
            except FileNotFoundError:
                continue
        else:
            return {}
        msg = HeaderParser().parsestr(text)
        out = {k: msg.get(k, "") for k in ("Name", "Version", "License", "License-Expression")}
        out["classifiers"] = [c for c in msg.get_all("Classifier", []) if c.startswith("License")]
        return out

    def licence(self) -> str:
        """Licence as declared in the metadata, checked against the LICENSE file."""
        decl = self.meta.get("License-Expression") or ""
        if not decl:
            cls = self.meta.get("classifiers") or []
            decl = cls[0].split("::")[-1].strip() if cls else ""
        if not decl or len(decl) > 80:
            decl = (self.meta.get("License") or "").strip().splitlines()[0] if self.meta.get("License") else ""
        try:
            lic_text = self.read(self.member("/LICENSE"))
        except FileNotFoundError:
            lic_text = ""
        if "Apache License" in lic_text and "Version 2.0" in lic_text:
            file_says = "Apache-2.0"
        elif "GNU GENERAL PUBLIC LICENSE" in lic_text.upper():
            file_says = "GPL"
        else:
            file_says = "?"
        if file_says == "Apache-2.0" and decl in ("Apache-2.0", "Apache Software License"):
            return "Apache-2.0 (METADATA and LICENSE file)"
        return f"{decl or '?'} (METADATA); LICENSE file: {file_says}"

    def label(self) -> str:
        return f"PyPI {self.name} {self.version} ({os.path.basename(self.path)}, sha256 {self.sha256})"


def to_nm(value: str, micrometres: bool) -> Decimal:
    d = Decimal(value)
    return (d * 1000).normalize() if micrometres else d.normalize()


def fmt_dec(d: Decimal) -> str:
    s = format(d, "f")
    return s.rstrip("0").rstrip(".") if "." in s else s


# --------------------------------------------------------------------------
# tabulated sensors (pyrsr)
# --------------------------------------------------------------------------
PYRSR_SENSORS = [
    # output name, pyrsr data dir, [(pyrsr band id, output column)], title
    ("sentinel2a-msi", "Sentinel-2A/MSI",
     [(b, "B" + b) for b in ["1", "2", "3", "4", "5", "6", "7", "8", "8A", "9", "10", "11", "12"]],
     "Sentinel-2A MultiSpectral Instrument (MSI)"),
    ("sentinel2b-msi", "Sentinel-2B/MSI",
     [(b, "B" + b) for b in ["1", "2", "3", "4", "5", "6", "7", "8", "8A", "9", "10", "11", "12"]],
     "Sentinel-2B MultiSpectral Instrument (MSI)"),
    ("landsat8-oli", "Landsat-8/OLI_TIRS",
     [(str(i), f"B{i}") for i in range(1, 10)],
     "Landsat 8 Operational Land Imager (OLI), bands 1-9 (B8 = panchromatic, B9 = cirrus)"),
    ("landsat9-oli", "Landsat-9/OLI_TIRS",
     [(str(i), f"B{i}") for i in range(1, 10)],
     "Landsat 9 Operational Land Imager 2 (OLI-2), bands 1-9 (B8 = panchromatic, B9 = cirrus)"),
]


def read_pyrsr_band(pkg: Package, rel: str):
    """Parse a pyrsr band file: first line '<n> <name>', then '<wl> <rsr>' rows."""
    text = pkg.read(pkg.member(rel))
    lines = [ln for ln in text.splitlines() if ln.strip()]
    head = lines[0].split()
    declared = int(head[0])
    rows = [ln.split() for ln in lines[1:]]
    wls = [r[0] for r in rows]
    micrometres = max(Decimal(w) for w in wls) < 100  # pyrsr's own unit test (rsr.py)
    out = []
    for w, v in rows:
        nm = to_nm(w, micrometres)
        out.append((nm, v))
    return out, declared, micrometres, " ".join(head[1:])


def write_tabulated(pkg: Package, outdir: str, name: str, datadir: str, bands, title: str) -> dict:
    ref = pkg.read(pkg.member(f"pyrsr/data/{datadir}/reference")).strip().splitlines()
    cols = {}
    notes = []
    n_neg = 0
    max_neg = Decimal(0)
    any_um = False
    for bid, col in bands:
        rel = f"pyrsr/data/{datadir}/band_{bid}"
        rows, declared, um, hdrname = read_pyrsr_band(pkg, rel)
        any_um |= um
        if declared != len(rows):
            notes.append(f"{rel}: header declares {declared} rows, file has {len(rows)} "
                         f"(contiguous {fmt_dec(rows[0][0])}-{fmt_dec(rows[-1][0])} nm; all rows used)")
        series = {}
        for nm, v in rows:
            if nm != nm.to_integral_value():
                raise ValueError(f"{rel}: {nm} nm is not on a 1 nm grid")
            if not (WL_MIN_NM <= nm <= WL_MAX_NM):
                continue
            dv = Decimal(v)
            if dv < 0:
                n_neg += 1
                max_neg = max(max_neg, -dv)
                v = "0"
            if int(nm) in series:
                raise ValueError(f"{rel}: duplicate wavelength {nm}")
            series[int(nm)] = v
        if not series:
            raise ValueError(f"{rel}: no samples within {WL_MIN_NM}-{WL_MAX_NM} nm")
        peak = max(Decimal(x) for x in series.values())
        if not (Decimal("0.99") <= peak <= Decimal("1.01")):
            raise ValueError(f"{rel}: peak {peak} is not ~1 (not peak-normalised?)")
        cols[col] = series
    lo = min(min(s) for s in cols.values())
    hi = max(max(s) for s in cols.values())
    names = [c for _b, c in bands]
    path = os.path.join(outdir, name + ".csv")
    with open(path, "w", newline="\n") as fh:
        fh.write(f"# Relative spectral response (RSR) of the {title}.\n")
        fh.write(f"# Source: {pkg.label()}\n")
        fh.write(f"#   files pyrsr/data/{datadir}/band_<id> for band ids "
                 f"{', '.join(b for b, _c in bands)}; provenance file pyrsr/data/{datadir}/reference says:\n")
        for ln in ref:
            fh.write(f"#     {ln.strip()}\n")
        fh.write(f"# Licence: pyrsr is {pkg.licence()}; the underlying "
                 f"response data were published by the agency named above (see the URL).\n")
        fh.write("# Values: peak-normalised relative response (max 1), copied verbatim from the package;"
                 " 0 where a band has no tabulated value.\n")
        conv = "converted from micrometres to nm exactly, " if any_um else ""
        fh.write(f"# Grid: wavelength_nm {lo}-{hi} step 1 ({hi - lo + 1} rows), {conv}the package's native "
                 f"1 nm sampling; restricted to {WL_MIN_NM}-{WL_MAX_NM} nm.\n")
        if n_neg:
            fh.write(f"# Changed: {n_neg} negative response values (largest magnitude {fmt_dec(max_neg)}, "
                     "measurement noise in the source) set to 0.\n")
        if datadir.startswith("Landsat"):
            fh.write("# Omitted: TIRS thermal bands 10 and 11 (10.6-12.5 um), outside 350-2600 nm.\n")
        for n in notes:
            fh.write(f"# Note: {n}\n")
        fh.write("# Extracted by tools/srf_extract.py.\n")
        fh.write("wavelength_nm," + ",".join(names) + "\n")
        for wl in range(lo, hi + 1):
            fh.write(str(wl) + "," + ",".join(cols[c].get(wl, "0") for c in names) + "\n")
    # support = first..last non-zero sample, for the README
    supp = {}
    for c in names:
        nz = [w for w, v in cols[c].items() if Decimal(v) > 0]
        supp[c] = (min(nz), max(nz))
    return {"file": path, "bands": len(names), "range": f"{lo}-{hi}", "supp": supp,
            "member": f"pyrsr/data/{datadir}/band_*", "format": "tabulated RSR, 1 nm"}


# --------------------------------------------------------------------------
# Gaussian centre/FWHM sensors (isofit)
# --------------------------------------------------------------------------
def write_aviris_ng(pkg: Package, outdir: str) -> dict:
    member = pkg.member("isofit/test/data/wavelengths.txt")
    rows = [ln.split() for ln in pkg.read(member).splitlines() if ln.strip()]
    if any(len(r) != 3 for r in rows):
        raise ValueError(f"{member}: expected 3 columns (index, centre um, FWHM um)")
    idx = [int(r[0]) for r in rows]
    if idx != list(range(len(rows))):
        raise ValueError(f"{member}: channel indices are not 0..{len(rows) - 1}")
    cen = [to_nm(r[1], True) for r in rows]
    fwhm = [to_nm(r[2], True) for r in rows]
    if any(b <= a for a, b in zip(cen, cen[1:])):
        raise ValueError(f"{member}: centres not ascending")
    keep = [i for i, c in enumerate(cen) if WL_MIN_NM <= c <= WL_MAX_NM]
    path = os.path.join(outdir, "aviris-ng.csv")
    with open(path, "w", newline="\n") as fh:
        fh.write("# AVIRIS-NG (Airborne Visible/InfraRed Imaging Spectrometer - Next Generation) channel centres"
                 " and FWHM, for Gaussian spectral response functions.\n")
        fh.write(f"# Source: {pkg.label()}\n")
        fh.write(f"#   file {member.split('/', 1)[1] if pkg.kind == 'tar' else member}"
                 " (ISOFIT's instrument wavelength file; columns: channel index, centre um, FWHM um).\n")
        fh.write("# Identification: the package does not name the instrument in this file. It is the isofit test\n"
                 "#   instrument (isofit's docs pair 'wavelengths.txt' with the AVIRIS-NG noise model), and its\n"
                 "#   centres match the wavelength column of the AVIRIS-NG radiance spectra\n"
                 "#   ang20171108t184227_rdn_v2p11_*.txt in isofit's repository (examples/20171108_Pasadena/remote,\n"
                 "#   'remote AVIRIS-NG observations'): both have 425 channels, 376.86 ... 2500.54 nm, and 15 channels\n"
                 "#   spot-checked across the range agree to 0.01 nm. AVIRIS-NG's calibration is per flight\n"
                 "#   campaign; this is one (2017-era) calibration, with ~5.01 nm sampling.\n")
        fh.write(f"# Licence: isofit is {pkg.licence()} (Copyright California Institute of Technology).\n")
        fh.write("# Values: centre and FWHM converted from micrometres to nm exactly (x1000); nothing fitted or"
                 " estimated. Response model: Gaussian, exp(-4 ln2 (lambda-center)^2 / fwhm^2), peak 1.\n")
        fh.write(f"# Bands: b001..b{len(rows):03d} = source channel index 0..{len(rows) - 1};"
                 f" {len(keep)} of {len(rows)} centres lie in {WL_MIN_NM}-{WL_MAX_NM} nm (only those are listed).\n")
        fh.write("# Extracted by tools/srf_extract.py.\n")
        fh.write("band,center_nm,fwhm_nm\n")
        for i in keep:
            fh.write(f"b{i + 1:03d},{fmt_dec(cen[i])},{fmt_dec(fwhm[i])}\n")
    return {"file": path, "bands": len(keep),
            "range": f"{fmt_dec(cen[keep[0]])}-{fmt_dec(cen[keep[-1]])} (centres); "
                     f"FWHM {fmt_dec(min(fwhm))}-{fmt_dec(max(fwhm))}",
            "member": member.split("/", 1)[1] if pkg.kind == "tar" else member,
            "format": "Gaussian centre/FWHM (tabulated by source)"}


# --------------------------------------------------------------------------
# README
# --------------------------------------------------------------------------
NOT_FOUND = [
    ("pace-oci", "PACE Ocean Color Instrument",
     "Not written. No package reachable here ships OCI's spectral responses or channel centre/FWHM table. "
     "Checked: pyrsr 0.8.0 (multispectral sensors only), Py6S 1.9.2 (no OCI), isofit 4.1.5 (its PyPI "
     "distribution has no OCI file; isofit's GitHub repository has `data/oci_noise.txt`, a noise model whose "
     "first column lists OCI wavelengths, but no FWHM, and it is not in the PyPI package)."),
    ("enmap", "EnMAP HSI",
     "Not written. No package reachable here ships EnMAP responses or FWHMs. enpt 1.5.0 (EnMAP Processing "
     "Tool, GPL-3.0-or-later) ships only pre-launch channel centres (ENVI headers SNR_D1.hdr, 88 VNIR channels "
     "423.03-985.21 nm, and SNR_D2.hdr, 154 SWIR channels 904.78-2438.60 nm, inside "
     "`enpt/resources/EnMAP_Sensor/EnMAP_Level_1B_SNR.zip`, dated 2017) without FWHM; EnPT reads the real "
     "centres and FWHMs from each scene's L1B metadata XML. acwater 0.3.2 has none either. A Gaussian file "
     "would need invented FWHMs, so none was made."),
    ("prisma", "PRISMA HSI (ASI)",
     "Not written. No package reachable here (pyrsr, Py6S, isofit, enpt, acwater) ships PRISMA channel "
     "centres, FWHM or responses; PRISMA's per-scene centres/FWHM are in each L1/L2 product's HDF5 attributes."),
]


def write_readme(outdir: str, pyrsr: Package, isofit: Package, results: dict) -> None:
    path = os.path.join(outdir, "README.md")
    with open(path, "w", newline="\n") as fh:
        fh.write("# Sensor spectral response functions\n\n")
        fh.write("Relative spectral responses of imaging sensors, for band-integrating simulated spectra.\n"
                 "Every number is copied from a PyPI package (named per file below and in each file's `#` "
                 "header, which is the authority). Regenerate with `tools/srf_extract.py` (its docstring "
                 "gives the `pip download` line); do not edit the numbers by hand.\n\n")
        fh.write("Two formats:\n\n"
                 "* **tabulated RSR**: `wavelength_nm,<band>,...`; ascending 1 nm grid, "
                 "peak-normalised response (max 1), 0 outside a band's support. Integrate as "
                 "`sum(R(l) x(l)) / sum(R(l))` on the grid.\n"
                 "* **Gaussian centre/FWHM**: `band,center_nm,fwhm_nm`, one row per channel; response "
                 "`exp(-4 ln2 (l - center)^2 / fwhm^2)`. Used where the source gives only centres and "
                 "FWHMs (a dense table would be large and add nothing).\n\n")
        fh.write("| sensor | file | format | bands | wavelength range, nm | source package | file inside package | licence |\n")
        fh.write("|---|---|---|---|---|---|---|---|\n")
        for name in ["sentinel2a-msi", "sentinel2b-msi", "landsat8-oli", "landsat9-oli", "aviris-ng"]:
            r = results[name]
            pkg = isofit if name == "aviris-ng" else pyrsr
            fh.write(f"| {name} | `{os.path.basename(r['file'])}` | {r['format']} | {r['bands']} | "
                     f"{r['range']} | {pkg.name} {pkg.version} | `{r['member']}` | {pkg.licence()} |\n")
        for name, _title, _why in NOT_FOUND:
            fh.write(f"| {name} | — (not available) | — | — | — | — | — | — |\n")
        fh.write("\nBand columns: Sentinel-2 `B1..B8,B8A,B9..B12`; Landsat OLI `B1..B9` (B8 panchromatic, "
                 "B9 cirrus; the TIRS thermal bands 10-11 are outside 350-2600 nm and omitted); "
                 "AVIRIS-NG `b001..b425` (source channel index + 1).\n\n")
        fh.write("## Provenance and caveats\n\n")
        fh.write(f"* Multispectral: {pyrsr.label()}. Sentinel-2A/2B from ESA's S2 SRF document "
                 "COPE-GSEG-EOPG-TN-15-0007 v3.0 (19 Dec 2017); Landsat 8 OLI from NASA/Ball "
                 "`Ball_BA_RSR.v1.2` (2014); Landsat 9 OLI-2 from NASA `L9_OLI2_Ball_BA_RSR.v1.0` "
                 "(2021), as recorded in pyrsr's `reference` files. pyrsr's band files are already on "
                 "integer nanometres, so no resampling was done; Landsat wavelengths are converted "
                 "from micrometres exactly, and a few tiny negative Landsat values (noise) are set to 0 "
                 "(counted in each header).\n")
        fh.write(f"* AVIRIS-NG: {isofit.label()}, `{results['aviris-ng']['member']}`. The package does "
                 "not label the file; it is isofit's test instrument and its centres match those of the "
                 "AVIRIS-NG radiance spectra in isofit's repository (details in the file header). "
                 "AVIRIS-NG is recalibrated per campaign: this is one 2017-era calibration, fine for "
                 "simulation, not for processing a particular flight line.\n")
        fh.write("* Py6S 1.9.2 (LGPL-3.0) also tabulates Sentinel-2A/2B and Landsat 8 OLI responses, at 2.5 nm "
                 "in `Py6S/Params/wavelength.py`; pyrsr was preferred (1 nm, newer S2 v3.0 SRFs, Apache-2.0, "
                 "and Landsat 9).\n\n")
        fh.write("## Not available\n\n")
        for name, title, why in NOT_FOUND:
            fh.write(f"* **{name}** ({title}): {why}\n")
    results["README"] = {"file": path}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pkgdir", required=True,
                    help="directory holding the pip-downloaded pyrsr and isofit distributions")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "..", "data", "srf"),
                    help="output directory (default: <repo>/data/srf)")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)

    pyrsr = Package(args.pkgdir, "pyrsr")
    isofit = Package(args.pkgdir, "isofit")
    results = {}
    for name, datadir, bands, title in PYRSR_SENSORS:
        results[name] = write_tabulated(pyrsr, args.out, name, datadir, bands, title)
    results["aviris-ng"] = write_aviris_ng(isofit, args.out)
    write_readme(args.out, pyrsr, isofit, results)
    for name, r in results.items():
        size = os.path.getsize(r["file"])
        extra = f"{r['bands']} bands, {r['range']} nm" if "bands" in r else ""
        print(f"{name:16s} {os.path.relpath(r['file'])}  {size} bytes  {extra}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
