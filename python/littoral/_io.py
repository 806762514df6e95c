"""A render's outputs as xarray Datasets, read lazily from its directory."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import xarray as xr

from . import _littoral

PathLike = Union[str, "os.PathLike[str]"]

#: Cube files of a run named NAME, by data variable: (file suffix, long
#: name, CF standard name or None, units).
CUBES = {
    "L_t": ("", "total radiance at the sensor", "surface_upwelling_radiance_per_unit_wavelength_in_air", "W m-2 sr-1 nm-1"),
    "L_w": (".lw", "water-leaving radiance", "surface_upwelling_radiance_per_unit_wavelength_in_air_emerging_from_sea_water", "W m-2 sr-1 nm-1"),
    "L_surface": (".surface", "radiance reflected by the sea surface (L_t - L_w)", "surface_upwelling_radiance_per_unit_wavelength_in_air_reflected_by_sea_water", "W m-2 sr-1 nm-1"),
    "R_rs": (".rrs", "remote-sensing reflectance L_w / E_d(0+)", "surface_ratio_of_upwelling_radiance_emerging_from_sea_water_to_downwelling_radiative_flux_in_air", "sr-1"),
    "stderr": (".stderr", "standard error of L_t", None, "W m-2 sr-1 nm-1"),
    # With the sensor above the surface.
    "rho_t": (".rhot", "reflectance at the sensor pi L_t / (E_0 cos theta_s)", None, "1"),
    "L_path": (".lpath", "atmospheric path radiance at the sensor", None, "W m-2 sr-1 nm-1"),
    "t_down": (".tdown", "total transmittance of the air from its top to the surface", None, "1"),
    "t_up": (".tup", "total transmittance of the air from the ground to the sensor", None, "1"),
}


class Result:
    """What a render gives: the image cube and the point readings.

    - ``cube``: dims ``wavelength``, ``y``, ``x``; ``L_t``, ``L_w``,
      ``L_surface``, ``R_rs`` and ``stderr``; with the sensor above the
      surface (``sensor.altitude_m``) also ``rho_t``, ``L_path``, ``t_down``
      and ``t_up``.
    - ``radiometers``: dims ``radiometer``, ``wavelength`` (``None``
      without radiometers).
    - ``profiles``: E_d, E_u, E_od, E_ou, L_u, L_d against ``depth`` and
      ``wavelength`` and K_d per ``layer`` (``None`` without tally depths
      or with the path integrator).
    - ``report``: the run's JSON report as a dict
      (``littoral::job::report::RunReport``).
    - ``path``: the directory the outputs are in, or ``None`` when the
      render wrote to a temporary one (the data are then in memory).
    """

    def __init__(
        self,
        cube: xr.Dataset,
        radiometers: Optional[xr.Dataset],
        profiles: Optional[xr.Dataset],
        report: Dict[str, Any],
        path: Optional[Path],
    ) -> None:
        self.cube = cube
        self.radiometers = radiometers
        self.profiles = profiles
        self.report = report
        self.path = path

    def load(self) -> "Result":
        """Read every array into memory (off the files); returns self."""
        for ds in (self.cube, self.radiometers, self.profiles):
            if ds is not None:
                ds.load()
        return self

    def __repr__(self) -> str:
        where = self.path if self.path is not None else "memory"
        return f"<littoral.Result of scene '{self.report.get('scene')}' in {where}>\n{self.cube!r}"


def open(path: PathLike) -> Result:  # noqa: A001 - the package's verb
    """A render's outputs, memory-mapped (no copy, nothing read yet).

    ``path`` is the output directory of one render, or its cube header
    ``NAME.hdr``. Cubes written by ``littoral-cube`` (no JSON report beside
    them) open as a ``cube`` of their one variable.
    """
    path = Path(path)
    hdr = _find_header(path)
    name = hdr.name[: -len(".hdr")]
    folder = hdr.parent
    # A product's header (NAME.rrs.hdr) opens its whole run.
    for suffix, *_ in CUBES.values():
        run = name[: -len(suffix)] if suffix and name.endswith(suffix) else None
        if run and (folder / f"{run}.json").is_file() and (folder / f"{run}.hdr").is_file():
            name, hdr = run, folder / f"{run}.hdr"
            break
    report_path = folder / f"{name}.json"
    report: Dict[str, Any] = {}
    if report_path.is_file():
        try:
            report = json.loads(report_path.read_text())
        except (OSError, ValueError) as e:
            raise _littoral.LittoralError(f"{report_path}: not a littoral report: {e}") from e
    cube = _cube(folder, name, hdr, report)
    bands = _band_coords(report, cube)
    return Result(cube, _radiometers(report, bands), _profiles(report, bands), report, folder)


def _find_header(path: Path) -> Path:
    if path.suffix == ".hdr":
        if not path.is_file():
            raise _littoral.LittoralError(f"{path}: no such cube header")
        return path
    if not path.is_dir():
        raise _littoral.LittoralError(f"{path}: neither an output directory nor a .hdr file")
    runs = sorted(
        p.with_suffix(".hdr")
        for p in path.glob("*.json")
        if p.with_suffix(".hdr").is_file()
    )
    if len(runs) == 1:
        return runs[0]
    if not runs:
        raise _littoral.LittoralError(f"{path}: holds no render's outputs (NAME.json beside NAME.hdr)")
    names = ", ".join(p.name for p in runs)
    raise _littoral.LittoralError(f"{path}: holds several renders ({names}); open one by its .hdr")


def read_envi_header(path: PathLike) -> Dict[str, str]:
    """An ENVI header's fields as text (braces kept off), keys lower case."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise _littoral.LittoralError(f"{path}: read: {e.strerror or e}") from e
    if not text.startswith("ENVI"):
        raise _littoral.LittoralError(f"{path}: not an ENVI header (no 'ENVI' on its first line)")
    fields: Dict[str, str] = {}
    for m in re.finditer(r"^\s*([^=\n]+?)\s*=\s*(\{[^}]*\}|[^\n]*)", text[4:], re.M):
        value = m.group(2).strip()
        if value.startswith("{"):
            value = value[1:-1].strip()
        fields[m.group(1).strip().lower()] = value
    return fields


def _numbers(text: str) -> List[float]:
    return [float(v) for v in text.split(",") if v.strip()]


def _field(h: Dict[str, str], key: str, hdr: Path) -> str:
    if key not in h:
        raise _littoral.LittoralError(f"{hdr}: the header has no '{key}'")
    return h[key]


def _envi_array(hdr: Path) -> Tuple[np.ndarray, Dict[str, str]]:
    """The cube of ``hdr`` as a read-only memory map, (bands, lines, samples)."""
    h = read_envi_header(hdr)
    shape = tuple(int(_field(h, k, hdr)) for k in ("bands", "lines", "samples"))
    if h.get("data type", "4") != "4" or h.get("interleave", "bsq").lower() != "bsq":
        raise _littoral.LittoralError(f"{hdr}: only float32 BSQ cubes are read (data type 4, interleave bsq)")
    dtype = np.dtype(">f4" if h.get("byte order", "0") == "1" else "<f4")
    data = hdr.with_suffix(".bsq")
    offset = int(h.get("header offset", "0"))
    need = offset + int(np.prod(shape)) * 4
    size = data.stat().st_size if data.is_file() else -1
    if size < need:
        what = "missing" if size < 0 else f"{size} bytes where the header needs {need}"
        raise _littoral.LittoralError(f"{data}: {what}")
    arr = np.memmap(data, dtype=dtype, mode="r", offset=offset, shape=shape)
    return arr, h


def _cube(folder: Path, name: str, hdr: Path, report: Dict[str, Any]) -> xr.Dataset:
    base, h = _envi_array(hdr)
    nb, ny, nx = base.shape
    wavelength = _numbers(_field(h, "wavelength", hdr))
    fwhm = _numbers(h.get("fwhm", "")) or [float("nan")] * nb
    coords: Dict[str, Any] = {
        "wavelength": ("wavelength", np.asarray(wavelength), {"units": "nm", "long_name": "band centre wavelength", "standard_name": "radiation_wavelength"}),
        "fwhm": ("wavelength", np.asarray(fwhm), {"units": "nm", "long_name": "band full width at half maximum"}),
    }
    x, y, crs = _grid(h, nx, ny, hdr)
    coords["x"], coords["y"] = x, y
    variables: Dict[str, Any] = {}
    for var, (suffix, long_name, standard, units) in CUBES.items():
        path = hdr if suffix == "" else folder / f"{name}{suffix}.hdr"
        if not path.is_file():
            continue
        arr, hv = (base, h) if suffix == "" else _envi_array(path)
        if arr.shape != base.shape:
            raise _littoral.LittoralError(f"{path}: shape {arr.shape} differs from {hdr}'s {base.shape}")
        attrs = {"units": hv.get("data units", units), "long_name": long_name}
        if standard:
            attrs["standard_name"] = standard
        if crs is not None:
            attrs["grid_mapping"] = "spatial_ref"
        if not report:
            # A cube on its own (e.g. from littoral-cube): its one variable.
            attrs["long_name"] = h.get("description", "")
            attrs.pop("standard_name", None)
            variables["data"] = (("wavelength", "y", "x"), arr, attrs)
            break
        variables[var] = (("wavelength", "y", "x"), arr, attrs)
    if crs is not None:
        coords["spatial_ref"] = ((), np.int32(0), {"crs_wkt": crs, "spatial_ref": crs})
    ds = xr.Dataset(variables, coords=coords)
    ds.attrs.update(_attrs(h, report))
    return ds


def _grid(h: Dict[str, str], nx: int, ny: int, hdr: Path):
    """Pixel-centre coordinates from ENVI's ``map info``, and the CRS's WKT."""
    info = [v.strip() for v in h.get("map info", "").split(",")]
    if len(info) < 7:
        x = ("x", np.arange(nx, dtype=float), {"long_name": "pixel column", "units": "1"})
        y = ("y", np.arange(ny, dtype=float), {"long_name": "pixel row", "units": "1"})
        return x, y, None
    try:
        ref_x, ref_y, east, north, dx, dy = (float(v) for v in info[1:7])
    except ValueError as e:
        raise _littoral.LittoralError(f"{hdr}: map info: {e}") from e
    xs = east + (np.arange(nx) + 0.5 - (ref_x - 1.0)) * dx
    ys = north - (np.arange(ny) + 0.5 - (ref_y - 1.0)) * dy
    crs = h.get("coordinate system string") or None
    if crs is not None:
        xa = {"units": "m", "standard_name": "projection_x_coordinate", "long_name": "easting of the pixel centre", "axis": "X"}
        ya = {"units": "m", "standard_name": "projection_y_coordinate", "long_name": "northing of the pixel centre", "axis": "Y"}
    else:
        xa = {"units": "m", "long_name": "x (east) of the pixel centre in the scene frame", "axis": "X"}
        ya = {"units": "m", "long_name": "y (north) of the pixel centre in the scene frame", "axis": "Y"}
    return ("x", xs, xa), ("y", ys, ya), crs


def _attrs(h: Dict[str, str], report: Dict[str, Any]) -> Dict[str, Any]:
    """NetCDF-safe attributes: the run's settings and provenance."""
    attrs: Dict[str, Any] = {
        "Conventions": "CF-1.10",
        "source": f"littoral {_littoral.version()}",
        "title": h.get("description", ""),
    }
    if not report:
        return attrs
    sensor = report.get("sensor") or {}
    for key in ("sun_zenith_deg", "sun_azimuth_deg", "samples_per_pixel"):
        if sensor.get(key) is not None:
            attrs[key] = sensor[key]
    attrs["scene"] = report.get("scene", "")
    attrs["integrator"] = report.get("integrator", "")
    m = report.get("map") or {}
    if m.get("provenance"):
        attrs["map_provenance_sha256"] = m["provenance"]
    attrs["reused_map"] = int(bool(report.get("reused_map")))
    for section, prefix in (("timings_s", "time_"), ("peak_memory", "peak_memory_")):
        for k, v in (report.get(section) or {}).items():
            if isinstance(v, (int, float)) and v is not None:
                attrs[f"{prefix}{k}"] = v
    est = report.get("estimate") or {}
    for k, v in est.items():
        if isinstance(v, (int, float, str)) and not isinstance(v, bool):
            attrs[f"estimate_{k}"] = v
    if report.get("Ed_above_surface") is not None:
        attrs["Ed_above_surface_W_m2_nm"] = np.asarray(report["Ed_above_surface"], dtype=float)
    attrs["warnings"] = "\n".join(report.get("warnings") or [])
    attrs["report_json"] = json.dumps(report, separators=(",", ":"))
    return attrs


def _band_coords(report: Dict[str, Any], cube: xr.Dataset) -> Dict[str, Any]:
    """The bands of the point readings: the report's (the emission's), or
    the cube's when the report has none (the path integrator's)."""
    if "bands_nm" in report and "fwhm_nm" in report:
        centres, fwhm = report["bands_nm"], report["fwhm_nm"]
    else:
        centres, fwhm = cube["wavelength"].values, cube["fwhm"].values
    return {
        "wavelength": ("wavelength", np.asarray(centres, dtype=float), {"units": "nm", "standard_name": "radiation_wavelength"}),
        "fwhm": ("wavelength", np.asarray(fwhm, dtype=float), {"units": "nm"}),
    }


def _radiometers(report: Dict[str, Any], bands: Dict[str, Any]) -> Optional[xr.Dataset]:
    readings = report.get("radiometers") or []
    if not readings:
        return None
    coords = dict(bands)
    coords["depth"] = ("radiometer", np.asarray([r["depth_m"] for r in readings], dtype=float), {"units": "m", "positive": "down", "long_name": "depth of the radiometer (negative: above the water)"})
    coords["view"] = ("radiometer", np.asarray([str(r["view"]) for r in readings]), {"long_name": "direction the radiometer looks"})
    pos = np.asarray([r.get("position_m", [np.nan, np.nan]) for r in readings], dtype=float)
    coords["x"] = ("radiometer", pos[:, 0], {"units": "m"})
    coords["y"] = ("radiometer", pos[:, 1], {"units": "m"})
    units = "W m-2 sr-1 nm-1"
    data = {
        "L": (("radiometer", "wavelength"), np.asarray([r["L"] for r in readings], dtype=float), {"units": units, "long_name": "radiance"}),
        "stderr": (("radiometer", "wavelength"), np.asarray([r["stderr"] for r in readings], dtype=float), {"units": units, "long_name": "standard error of L"}),
    }
    for key, long_name in (("vov", "variance of the variance"), ("largest_share", "largest single path's share of the sum")):
        if all(key in r for r in readings):
            data[key] = (("radiometer", "wavelength"), np.asarray([r[key] for r in readings], dtype=float), {"units": "1", "long_name": long_name})
    return xr.Dataset(data, coords=coords, attrs={"scene": report.get("scene", "")})


PROFILE_UNITS = {"Ed": "W m-2 nm-1", "Eu": "W m-2 nm-1", "Eod": "W m-2 nm-1", "Eou": "W m-2 nm-1", "Lu": "W m-2 sr-1 nm-1", "Ld": "W m-2 sr-1 nm-1", "R": "1"}
PROFILE_NAMES = {
    "Ed": "downwelling plane irradiance",
    "Eu": "upwelling plane irradiance",
    "Eod": "downwelling scalar irradiance",
    "Eou": "upwelling scalar irradiance",
    "Lu": "upwelling radiance within 10 degrees of the nadir",
    "Ld": "downwelling radiance within 10 degrees of the zenith",
    "R": "irradiance reflectance Eu / Ed",
}


def _profiles(report: Dict[str, Any], bands: Dict[str, Any]) -> Optional[xr.Dataset]:
    tally = report.get("tally") or []
    if not tally:
        return None
    coords = dict(bands)
    coords["depth"] = ("depth", np.asarray([t["depth_m"] for t in tally], dtype=float), {"units": "m", "positive": "down"})
    data: Dict[str, Any] = {}
    data["water_fraction"] = ("depth", np.asarray([t.get("water_fraction", 1.0) for t in tally], dtype=float), {"units": "1", "long_name": "share of the domain that is water at the depth"})
    for key, units in PROFILE_UNITS.items():
        if all(key in t for t in tally):
            data[key] = (("depth", "wavelength"), np.asarray([t[key] for t in tally], dtype=float), {"units": units, "long_name": f"{PROFILE_NAMES[key]}, mean over the water present at the depth"})
        if all(f"{key}_stderr" in t for t in tally):
            data[f"{key}_stderr"] = (("depth", "wavelength"), np.asarray([t[f"{key}_stderr"] for t in tally], dtype=float), {"units": units, "long_name": f"standard error of {key}"})
    kd = report.get("kd") or []
    if kd:
        coords["layer_top"] = ("layer", np.asarray([k["from_m"] for k in kd], dtype=float), {"units": "m"})
        coords["layer_bottom"] = ("layer", np.asarray([k["to_m"] for k in kd], dtype=float), {"units": "m"})
        data["Kd"] = (("layer", "wavelength"), np.asarray([k["Kd"] for k in kd], dtype=float), {"units": "m-1", "long_name": "diffuse attenuation coefficient of Ed between the layer's depths"})
    return xr.Dataset(data, coords=coords, attrs={"scene": report.get("scene", ""), "averaging": "each quantity is the emission's tally at its depth, a mean over the water present there (water_fraction of the domain)"})
