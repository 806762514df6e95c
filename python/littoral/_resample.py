"""A cube over a real sensor's bands, as ``littoral-cube resample`` makes it."""

from __future__ import annotations

from typing import List, Union

import numpy as np
import xarray as xr

from . import _littoral


def sensors() -> List[str]:
    """The shipped sensors' names (``csv:FILE`` reads a table of your own)."""
    return list(_littoral.sensor_names())


def resample(ds: Union[xr.Dataset, xr.DataArray], sensor: str) -> Union[xr.Dataset, xr.DataArray]:
    """``ds`` integrated over ``sensor``'s bands.

    ``ds`` has a ``wavelength`` dimension with ``wavelength`` and ``fwhm``
    coordinates (nm), as :func:`littoral.render` gives. Each sensor band
    reads the cube's bands weighted by the share of the band's response
    that falls in each (littoral's ``Resampler``, the weights
    ``littoral-cube resample`` uses); bands whose response the cube's
    range does not cover are left out. Every variable with a ``wavelength``
    dimension is resampled except ``stderr``-like ones (their bands are
    not independent after weighting), which are dropped; the result has a
    ``band`` dimension with the sensor's band names, ``wavelength`` and
    ``fwhm`` as coordinates.
    """
    if "wavelength" not in ds.dims:
        raise ValueError("resample: the data have no 'wavelength' dimension")
    centres = np.asarray(ds["wavelength"].values, dtype=np.float32)
    if "fwhm" in ds.coords:
        fwhm = np.asarray(ds["fwhm"].values, dtype=np.float32)
    else:
        raise ValueError("resample: the data have no 'fwhm' coordinate along 'wavelength'")
    names, c, w, flat = _littoral.sensor_weights(sensor, centres.tolist(), fwhm.tolist())
    matrix = xr.DataArray(
        np.asarray(flat).reshape(len(names), len(centres)),
        dims=("band", "wavelength"),
    )

    def one(da: xr.DataArray) -> xr.DataArray:
        out = xr.dot(matrix, da.drop_vars([v for v in ("wavelength", "fwhm") if v in da.coords]), dim="wavelength")
        out = out.transpose("band", *[d for d in da.dims if d != "wavelength"])
        out.attrs = dict(da.attrs)
        return out.astype(da.dtype, copy=False)

    coords = {
        "band": ("band", list(names)),
        "wavelength": ("band", np.asarray(c), {"units": "nm", "long_name": "response-weighted band centre"}),
        "fwhm": ("band", np.asarray(w), {"units": "nm"}),
    }
    if isinstance(ds, xr.DataArray):
        return one(ds).assign_coords(coords)
    keep = {k: v for k, v in ds.data_vars.items() if "wavelength" in v.dims and "stderr" not in k}
    rest = {k: v for k, v in ds.data_vars.items() if "wavelength" not in v.dims}
    out = xr.Dataset({**{k: one(v) for k, v in keep.items()}, **rest}, attrs=dict(ds.attrs))
    out.attrs["sensor"] = sensor
    return out.assign_coords(coords)
