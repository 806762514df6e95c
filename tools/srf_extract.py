#!/usr/bin/env python3
"""Extract sensor relative spectral responses (RSR/SRF) from PyPI packages.

Writes the files in ``data/srf/`` of littoral:

* tabulated RSR files (multispectral sensors), taken verbatim from
  ``pyrsr`` 0.8.0 (Apache-2.0):
  ``sentinel2a-msi.csv``, ``sentinel2b-msi.csv``, ``landsat8-oli.csv``,
  ``landsat9-oli.csv``;
* a Gaussian centre/FWHM file (hyperspectral sensor), taken verbatim from
  ``isofit`` 4.1.5 (Apache-2.0): ``aviris-ng.csv``;
* Gaussian centre/FWHM files for EnMAP and PRISMA, taken from ``hgrs``
  (hGRS) 1.1.2 (Apache-2.0): ``enmap.csv`` (its ``prisma_rsr.csv``, whose
  centres are checked here against EnMAP's pre-launch channel centres in
  ``enpt`` 1.5.0, which identifies the table; nothing is copied from enpt)
  and ``prisma.csv`` (its ``prisma_fwhm.nc``, read by a small HDF5 reader
  below);
* ``README.md``, the index of these files, including the sensor that no
  reachable package provides (PACE OCI) and why.

No number is computed or estimated here: response values are copied as the
package's own decimal strings; the only changes are the unit conversion of
wavelengths from micrometres to nanometres (exact, in decimal arithmetic),
negative responses (detector noise in the Landsat lab data, all |x| < 4e-4)
set to 0, zeros written where a band has no tabulated value on the common
grid, and the restriction to 350-2600 nm (which drops only the thermal TIRS
bands 10 and 11 of Landsat 8/9). hGRS's PRISMA table is stored as binary
float32 (netCDF-4/HDF5); each value is written as the shortest decimal that
reads back to the identical float32, i.e. exactly the stored number.

Reproduce
---------
Only the Python standard library is needed (no numpy, no h5py). Download
the four packages' source distributions into one directory, then run::

    pip download --no-deps --no-binary :all: -d /tmp/srfpkg \
        pyrsr==0.8.0 isofit==4.1.5 hgrs==1.1.2 enpt==1.5.0
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

one row per channel, as tabulated by the source (no fitting), in the
source's order (EnMAP lists its VNIR then its SWIR detector, whose ranges
overlap, so its centres are not monotonic there).
"""

from __future__ import annotations

import argparse
import hashlib
import io
import os
import re
import struct
import sys
import tarfile
import zipfile
from decimal import Decimal
from email.parser import HeaderParser

WL_MIN_NM = Decimal(350)
WL_MAX_NM = Decimal(2600)

TESTED_VERSIONS = {"pyrsr": "0.8.0", "isofit": "4.1.5", "hgrs": "1.1.2", "enpt": "1.5.0"}


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
        return self.read_bytes(member).decode("utf-8")

    def read_bytes(self, member: str) -> bytes:
        if self.kind == "tar":
            return self._tar.extractfile(member).read()
        if self.kind == "whl":
            return self._zip.read(member)
        with open(os.path.join(self.path, member), "rb") as fh:
            return fh.read()

    def rel(self, member: str) -> str:
        """Member path without an sdist's leading ``<name>-<version>/``."""
        return member.split("/", 1)[1] if self.kind == "tar" else member

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
# minimal HDF5 reader (netCDF-4 files), standard library only
# --------------------------------------------------------------------------
class Hdf5Small:
    """Reads 1-D floating-point datasets linked from the root group of a small
    HDF5 file: superblock version 2/3, version-2 object headers, compact
    links, contiguous or compact storage. Anything else is refused with an
    error rather than guessed at (the archive's SHA-256 pins the bytes)."""

    def __init__(self, data: bytes, what: str):
        self.b, self.what = data, what
        if data[:8] != b"\x89HDF\r\n\x1a\n":
            self._fail("not an HDF5 file")
        if data[8] not in (2, 3):
            self._fail(f"superblock version {data[8]} (only 2 and 3 are read)")
        self.so, self.sl = data[9], data[10]
        base, _ext, _eof, root = (self._u(12 + i * self.so, self.so) for i in range(4))
        if base != 0:
            self._fail("non-zero base address")
        self.links = {}
        for mtype, body in self._messages(root):
            if mtype == 6:
                name, addr = self._link(body)
                self.links[name] = addr

    def _fail(self, why: str):
        raise ValueError(f"{self.what}: {why}")

    def _u(self, off: int, size: int) -> int:
        return int.from_bytes(self.b[off:off + size], "little")

    def _messages(self, addr: int):
        """(type, body) of every message of the object header at addr."""
        b = self.b
        if b[addr:addr + 4] != b"OHDR" or b[addr + 4] != 2:
            self._fail(f"object header at {addr} is not a version-2 OHDR")
        flags = b[addr + 5]
        p = addr + 6 + (16 if flags & 0x20 else 0) + (4 if flags & 0x10 else 0)
        n = 1 << (flags & 3)
        blocks = [(p + n, p + n + self._u(p, n))]
        hdr = 6 if flags & 0x04 else 4
        while blocks:
            p, end = blocks.pop(0)
            while p + hdr <= end:
                mtype, size = b[p], self._u(p + 1, 2)
                body = b[p + hdr:p + hdr + size]
                if mtype == 0x10:  # continuation: OCHK block
                    caddr, clen = self._u(p + hdr, self.so), self._u(p + hdr + self.so, self.sl)
                    if b[caddr:caddr + 4] != b"OCHK":
                        self._fail(f"continuation at {caddr} is not OCHK")
                    blocks.append((caddr + 4, caddr + clen - 4))
                elif mtype != 0:
                    yield mtype, body
                p += hdr + size

    def _link(self, m: bytes):
        if m[0] != 1:
            self._fail(f"link message version {m[0]}")
        flags, p = m[1], 2
        ltype = 0
        if flags & 0x08:
            ltype, p = m[p], p + 1
        if flags & 0x04:
            p += 8
        if flags & 0x10:
            p += 1
        n = 1 << (flags & 3)
        ln = int.from_bytes(m[p:p + n], "little")
        p += n
        name = m[p:p + ln].decode("utf-8")
        if ltype != 0:
            self._fail(f"link {name!r} is not a hard link")
        return name, int.from_bytes(m[p + ln:p + ln + self.so], "little")

    def dataset(self, name: str):
        """The dataset's values as (float, raw bytes, struct format) triples."""
        if name not in self.links:
            self._fail(f"no dataset {name!r} in the root group (has {sorted(self.links)})")
        dims = fmt = raw = None
        for mtype, m in self._messages(self.links[name]):
            if mtype == 1:  # dataspace
                if m[0] == 1:
                    rank, p = m[1], 8
                elif m[0] == 2:
                    rank, p = m[1], 4
                else:
                    self._fail(f"{name}: dataspace version {m[0]}")
                dims = [int.from_bytes(m[p + i * self.sl:p + (i + 1) * self.sl], "little")
                        for i in range(rank)]
            elif mtype == 3:  # datatype
                cls, size = m[0] & 0x0F, int.from_bytes(m[4:8], "little")
                if cls != 1 or size not in (4, 8) or m[1] & 1:
                    self._fail(f"{name}: not a little-endian float32/float64 (class {cls}, size {size})")
                fmt = "<f" if size == 4 else "<d"
            elif mtype == 8:  # data layout
                if m[0] not in (3, 4):
                    self._fail(f"{name}: layout message version {m[0]}")
                if m[1] == 1:  # contiguous
                    addr = int.from_bytes(m[2:2 + self.so], "little")
                    size = int.from_bytes(m[2 + self.so:2 + self.so + self.sl], "little")
                    raw = self.b[addr:addr + size]
                elif m[1] == 0:  # compact
                    size = int.from_bytes(m[2:4], "little")
                    raw = m[4:4 + size]
                else:
                    self._fail(f"{name}: chunked storage is not read here")
            elif mtype == 0x0B:
                self._fail(f"{name}: has a filter pipeline")
        if dims is None or fmt is None or raw is None or len(dims) != 1:
            self._fail(f"{name}: not a 1-D dataset with a datatype and contiguous data")
        width = struct.calcsize(fmt)
        if len(raw) != dims[0] * width:
            self._fail(f"{name}: {len(raw)} bytes of data for {dims[0]} values")
        return [(struct.unpack(fmt, raw[i:i + width])[0], raw[i:i + width], fmt)
                for i in range(0, len(raw), width)]


def shortest_decimal(value: float, raw: bytes, fmt: str) -> Decimal:
    """The shortest decimal that packs back to exactly ``raw`` (the stored float)."""
    for digits in range(1, 18):
        s = f"{value:.{digits}g}"
        if struct.pack(fmt, float(s)) == raw:
            return Decimal(s).normalize()
    raise ValueError(f"no round-trip decimal for {value!r}")


# --------------------------------------------------------------------------
# Gaussian centre/FWHM sensors (hGRS): EnMAP and PRISMA
# --------------------------------------------------------------------------
def enmap_prelaunch_centres(enpt: Package):
    """EnMAP's pre-launch channel centres in enpt (VNIR list, SWIR list), as Decimals."""
    member = enpt.member("enpt/resources/EnMAP_Sensor/EnMAP_Level_1B_SNR.zip")
    zf = zipfile.ZipFile(io.BytesIO(enpt.read_bytes(member)))
    out = []
    dates = sorted({"%04d-%02d-%02d" % zf.getinfo(h).date_time[:3] for h in ("SNR_D1.hdr", "SNR_D2.hdr")})
    for hdr in ("SNR_D1.hdr", "SNR_D2.hdr"):
        text = zf.read(hdr).decode("ascii")
        m = re.search(r"wavelength\s*=\s*\{([^}]*)\}", text)
        if not m:
            raise ValueError(f"{member}/{hdr}: no wavelength list")
        out.append([Decimal(v.strip()) for v in m.group(1).split(",") if v.strip()])
    return out, enpt.rel(member), ", ".join(dates)


def write_enmap(hgrs: Package, enpt: Package, outdir: str) -> dict:
    member = hgrs.member("hgrs/data/aux/prisma_rsr.csv")
    lines = [ln.strip() for ln in hgrs.read(member).splitlines() if ln.strip()]
    if lines[0].replace(" ", "") != "wavelength,fwhm":
        raise ValueError(f"{member}: expected header 'wavelength,fwhm', found {lines[0]!r}")
    rows = [ln.split(",") for ln in lines[1:]]
    if any(len(r) != 2 for r in rows):
        raise ValueError(f"{member}: expected 2 columns")
    cen = [to_nm(r[0], False) for r in rows]
    fwhm = [to_nm(r[1], False) for r in rows]
    (vnir, swir), enpt_member, enpt_date = enmap_prelaunch_centres(enpt)
    ref = vnir + swir
    if len(ref) != len(cen):
        raise ValueError(f"{member}: {len(cen)} rows, but enpt lists {len(vnir)} + {len(swir)} EnMAP channels")
    diff = max(abs(a - b) for a, b in zip(cen, ref))
    if diff > Decimal("0.001"):
        raise ValueError(f"{member}: centres differ from enpt's EnMAP centres by up to {diff} nm")
    if not all(f > 0 for f in fwhm) or not all(WL_MIN_NM <= c <= WL_MAX_NM for c in cen):
        raise ValueError(f"{member}: FWHM not positive or centre outside {WL_MIN_NM}-{WL_MAX_NM} nm")
    nv, n = len(vnir), len(cen)
    fv, fs = fwhm[:nv], fwhm[nv:]
    rel = hgrs.rel(member)
    path = os.path.join(outdir, "enmap.csv")
    with open(path, "w", newline="\n") as fh:
        fh.write("# EnMAP HSI (Environmental Mapping and Analysis Program hyperspectral imager) channel centres"
                 " and FWHM, for Gaussian spectral response functions.\n")
        fh.write(f"# Source: {hgrs.label()}\n")
        fh.write(f"#   file {rel} (columns: wavelength nm, fwhm nm; {n} rows; hGRS's code does not read it).\n")
        fh.write("# Identification: despite the file's name these are EnMAP's channels, not PRISMA's: its centres\n"
                 f"#   are EnMAP's pre-launch channel centres, {nv} VNIR {fmt_dec(vnir[0])}-{fmt_dec(vnir[-1])} nm"
                 f" then {len(swir)} SWIR\n"
                 f"#   {fmt_dec(swir[0])}-{fmt_dec(swir[-1])} nm, equal within {fmt_dec(diff)} nm (float32 rounding)"
                 " to the wavelength lists\n"
                 f"#   of SNR_D1.hdr and SNR_D2.hdr in {enpt.label()},\n"
                 f"#   {enpt_member} (EnMAP Processing Tool; headers dated {enpt_date}),\n"
                 "#   as tools/srf_extract.py checks. enpt gives no FWHM: the FWHMs are hGRS's alone, not cross-checked.\n")
        fh.write("# Calibration: pre-launch. EnMAP products carry in-flight centres and FWHMs per scene"
                 " (METADATA.XML), which\n"
                 "#   differ by a few nm; fine for simulation, not for processing a particular scene.\n")
        fh.write(f"# Licence: hgrs is {hgrs.licence()}.\n")
        fh.write("# Values: centre and FWHM in nm as written in the package (its strings are float32 printouts,"
                 " e.g. 428.799988;\n"
                 "#   trailing zeros dropped); nothing fitted or estimated. Response model: Gaussian,"
                 " exp(-4 ln2 (lambda-center)^2 / fwhm^2), peak 1.\n")
        fh.write(f"# Bands: b001..b{n:03d} = source row 1..{n}, in the source's order: b001-b{nv:03d} VNIR"
                 f" (FWHM {fmt_dec(min(fv))}-{fmt_dec(max(fv))}),\n"
                 f"#   b{nv + 1:03d}-b{n:03d} SWIR (FWHM {fmt_dec(min(fs))}-{fmt_dec(max(fs))}); the detectors overlap"
                 f" at {fmt_dec(swir[0])}-{fmt_dec(vnir[-1])} nm,\n"
                 "#   so centres are not monotonic there. All lie in 350-2600 nm.\n")
        fh.write("# Extracted by tools/srf_extract.py.\n")
        fh.write("band,center_nm,fwhm_nm\n")
        for i in range(n):
            fh.write(f"b{i + 1:03d},{fmt_dec(cen[i])},{fmt_dec(fwhm[i])}\n")
    return {"file": path, "bands": n,
            "range": f"{fmt_dec(min(cen))}-{fmt_dec(max(cen))} (centres); "
                     f"FWHM {fmt_dec(min(fwhm))}-{fmt_dec(max(fwhm))}",
            "member": rel, "format": "Gaussian centre/FWHM (tabulated by source)",
            "nv": nv, "ns": len(swir), "diff": fmt_dec(diff), "enpt_member": enpt_member,
            "enpt_date": enpt_date, "overlap": f"{fmt_dec(swir[0])}-{fmt_dec(vnir[-1])}"}


def write_prisma(hgrs: Package, outdir: str) -> dict:
    member = hgrs.member("hgrs/data/aux/prisma_fwhm.nc")
    rel = hgrs.rel(member)
    h5 = Hdf5Small(hgrs.read_bytes(member), rel)
    wl, fw = h5.dataset("wl"), h5.dataset("fwhm")
    if len(wl) != len(fw):
        raise ValueError(f"{rel}: {len(wl)} wavelengths but {len(fw)} FWHMs")
    fmts = {f for _v, _r, f in wl + fw}
    cen = [shortest_decimal(*t) for t in wl]
    fwhm = [shortest_decimal(*t) for t in fw]
    if any(b <= a for a, b in zip(cen, cen[1:])):
        raise ValueError(f"{rel}: centres not ascending")
    if not all(f > 0 for f in fwhm) or not all(WL_MIN_NM <= c <= WL_MAX_NM for c in cen):
        raise ValueError(f"{rel}: FWHM not positive or centre outside {WL_MIN_NM}-{WL_MAX_NM} nm")
    n = len(cen)
    gap, a, b = min((b - a, a, b) for a, b in zip(cen, cen[1:]))
    dtype = "float32" if fmts == {"<f"} else "float64" if fmts == {"<d"} else "mixed float"
    path = os.path.join(outdir, "prisma.csv")
    with open(path, "w", newline="\n") as fh:
        fh.write("# PRISMA HSI (PRecursore IperSpettrale della Missione Applicativa, ASI) channel centres and FWHM,"
                 " for Gaussian spectral response functions.\n")
        fh.write(f"# Source: {hgrs.label()}\n")
        fh.write(f"#   file {rel} (netCDF-4/HDF5: {dtype} variables wl and fwhm, nm, on dimension wl; {n} channels).\n")
        fh.write("# Identification: the file names no scene. hGRS builds this table from a PRISMA L1 product's"
                 " attributes\n"
                 "#   (hgrs/driver.py, Driver.read_l1c_prisma: List_Cw_Vnir[5:] + List_Cw_Swir[:-2] and the matching\n"
                 "#   List_Fwhm_*, sorted by wavelength), and hgrs/lut_maker.py takes the PRISMA FWHMs from the L1 product\n"
                 "#   PRS_L1_STD_OFFL_20210906103712_20210906103717_0001 (6 Sep 2021); so this is one scene's calibration,\n"
                 "#   probably that one. PRISMA's centres and FWHMs vary slightly from scene to scene: fine for\n"
                 "#   simulation, not for processing a particular scene.\n")
        fh.write(f"# Licence: hgrs is {hgrs.licence()}.\n")
        fh.write(f"# Values: each stored {dtype} written as the shortest decimal that reads back to the identical"
                 " value (so exactly\n"
                 "#   the package's numbers); nothing fitted or estimated. Response model: Gaussian,"
                 " exp(-4 ln2 (lambda-center)^2 / fwhm^2), peak 1.\n")
        fh.write(f"# Bands: b001..b{n:03d} = the file's channels in its (ascending) order. The file does not say"
                 " which detector\n"
                 "#   each channel is from; where the detectors overlap, VNIR and SWIR channels interleave"
                 f" (closest pair {a:.2f} and\n#   {b:.2f} nm). All lie in 350-2600 nm.\n")
        fh.write("# Extracted by tools/srf_extract.py.\n")
        fh.write("band,center_nm,fwhm_nm\n")
        for i in range(n):
            fh.write(f"b{i + 1:03d},{fmt_dec(cen[i])},{fmt_dec(fwhm[i])}\n")
    return {"file": path, "bands": n,
            "range": f"{fmt_dec(cen[0])}-{fmt_dec(cen[-1])} (centres); "
                     f"FWHM {fmt_dec(min(fwhm))}-{fmt_dec(max(fwhm))}",
            "member": rel, "format": "Gaussian centre/FWHM (tabulated by source)"}


# --------------------------------------------------------------------------
# README
# --------------------------------------------------------------------------
NOT_FOUND = [
    ("pace-oci", "PACE Ocean Color Instrument",
     "Not written. No package reachable here ships OCI's spectral responses or a channel centre/FWHM table. "
     "Checked: pyrsr 0.8.0 (multispectral sensors only); Py6S 1.9.2 (no OCI); isofit 4.1.5 (neither its "
     "sdist nor its wheel has an OCI file: isofit reads `data/oci/pace_oci_rsr.nc` from its extra data, which "
     "`isofit download data` fetches from GitHub, not from a registry; its GitHub repository's `data/oci_noise.txt` lists OCI "
     "wavelengths without FWHM); hyperproc 0.1.2 (reads OCI centres from each granule, assumes its own nominal "
     "5 nm FWHM below 900 nm and uses isofit's data bundle for the responses); hypercoast 0.27.0, "
     "nasa-pace-data-reader 0.0.5.0, o25 0.1.9 (readers and algorithms, no band tables); pyspectral 0.14.3 "
     "(downloads its responses at run time, and lists no OCI); rsrf 0.3.1 (code only: its curated responses "
     "are fetched from its GitHub releases at run time); gee-acolite 1.2.1 (no ACOLITE data files; ACOLITE "
     "itself is not on PyPI); hgrs 1.1.2, sicor 0.20.5, smartg 2.0.6, hygeos-core 1.3.2 (no OCI data)."),
]


def write_readme(outdir: str, pyrsr: Package, isofit: Package, hgrs: Package, enpt: Package,
                 results: dict) -> None:
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
        for name in ["sentinel2a-msi", "sentinel2b-msi", "landsat8-oli", "landsat9-oli", "aviris-ng",
                     "enmap", "prisma"]:
            r = results[name]
            pkg = {"aviris-ng": isofit, "enmap": hgrs, "prisma": hgrs}.get(name, pyrsr)
            fh.write(f"| {name} | `{os.path.basename(r['file'])}` | {r['format']} | {r['bands']} | "
                     f"{r['range']} | {pkg.name} {pkg.version} | `{r['member']}` | {pkg.licence()} |\n")
        for name, _title, _why in NOT_FOUND:
            fh.write(f"| {name} | — (not available) | — | — | — | — | — | — |\n")
        ne, nv = results["enmap"]["bands"], results["enmap"]["nv"]
        fh.write("\nBand columns: Sentinel-2 `B1..B8,B8A,B9..B12`; Landsat OLI `B1..B9` (B8 panchromatic, "
                 "B9 cirrus; the TIRS thermal bands 10-11 are outside 350-2600 nm and omitted); "
                 f"AVIRIS-NG `b001..b{results['aviris-ng']['bands']:03d}` (source channel index + 1); "
                 f"EnMAP `b001..b{ne:03d}` (source row: b001-b{nv:03d} VNIR, b{nv + 1:03d}-b{ne:03d} SWIR, "
                 f"overlapping at {results['enmap']['overlap']} nm, so not in wavelength order there); "
                 f"PRISMA `b001..b{results['prisma']['bands']:03d}` (the source's ascending order).\n\n")
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
        e = results["enmap"]
        fh.write(f"* EnMAP: {hgrs.label()}, `{e['member']}`. Despite its name the file holds EnMAP's channels: "
                 f"its {e['nv']} + {e['ns']} centres equal (within {e['diff']} nm, float32 rounding) EnMAP's "
                 f"pre-launch channel centres in the ENVI headers SNR_D1.hdr/SNR_D2.hdr of {enpt.label()}, "
                 f"`{e['enpt_member']}` (dated {e['enpt_date']}), which the script checks; enpt (GPL-3.0-or-later) "
                 "is used only for that check, no number is taken from it. The FWHMs are hGRS's alone (enpt has "
                 "none). Pre-launch values: EnMAP products carry 224 channels whose centres and FWHMs, given per "
                 "scene in METADATA.XML, are a few nm off these (e.g. enfrosp 0.3.2's `enfrosp/data/index.dat` "
                 "lists 224 EnMAP centres starting at 418.42 nm); fine for simulation, not for processing a "
                 "scene.\n")
        fh.write(f"* PRISMA: {hgrs.label()}, `{results['prisma']['member']}` (netCDF-4; read with the "
                 "script's own small HDF5 reader, values written as the shortest decimals that read back to the "
                 "stored float32s). One scene's centres and FWHMs as hGRS's PRISMA reader takes them from an L1 "
                 "product's `List_Cw_*`/`List_Fwhm_*` attributes (5 VNIR and 2 SWIR entries left out, sorted by "
                 "wavelength); the file names no scene (hGRS's `lut_maker.py` uses L1 product "
                 "PRS_L1_STD_OFFL_20210906103712). PRISMA's calibration varies slightly per scene.\n")
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
                    help="directory holding the pip-downloaded pyrsr, isofit, hgrs and enpt distributions")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "..", "data", "srf"),
                    help="output directory (default: <repo>/data/srf)")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)

    pyrsr = Package(args.pkgdir, "pyrsr")
    isofit = Package(args.pkgdir, "isofit")
    hgrs = Package(args.pkgdir, "hgrs")
    enpt = Package(args.pkgdir, "enpt")
    results = {}
    for name, datadir, bands, title in PYRSR_SENSORS:
        results[name] = write_tabulated(pyrsr, args.out, name, datadir, bands, title)
    results["aviris-ng"] = write_aviris_ng(isofit, args.out)
    results["enmap"] = write_enmap(hgrs, enpt, args.out)
    results["prisma"] = write_prisma(hgrs, args.out)
    write_readme(args.out, pyrsr, isofit, hgrs, enpt, results)
    for name, r in results.items():
        size = os.path.getsize(r["file"])
        extra = f"{r['bands']} bands, {r['range']} nm" if "bands" in r else ""
        print(f"{name:16s} {os.path.relpath(r['file'])}  {size} bytes  {extra}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
