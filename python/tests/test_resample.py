"""Sensor bands: the Dataset resampled as littoral-cube resamples the cube."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

import littoral


def test_resample_matches_the_cube_tool(tmp_path, cli):
    scene = littoral.Scene.from_toml(
        "[spectral]\nstart_nm = 400.0\nend_nm = 900.0\nbands = 50\n"
        "[sun]\nzenith_deg = 30.0\nirradiance = 1.0\n[domain]\nsize_m = [10.0, 10.0]\n"
        "[water]\niop = { a = 0.1, b = 0.2 }\n[photons]\ncount = 2000\n[sensor]\npixels = [8, 6]\n"
    )
    out = tmp_path / "out"
    r = littoral.render(scene, out=out, progress=False)
    s2 = littoral.resample(r.cube, "sentinel2a-msi")
    subprocess.run(
        [str(cli / "littoral-cube"), "resample", str(out / "scene.rrs.hdr"), "--sensor", "sentinel2a-msi", "--out", str(tmp_path / "s2.hdr")],
        check=True,
        capture_output=True,
    )
    from test_render import read_bsq

    expect = read_bsq(tmp_path / "s2.hdr")
    got = s2.R_rs.values
    assert got.shape == expect.shape
    assert np.allclose(got, expect, rtol=2e-6, atol=0)
    assert "stderr" not in s2
    assert s2.band.values[0] == littoral.read_envi_header(tmp_path / "s2.hdr")["band names"].split(",")[0].strip()
    assert np.all(np.diff(s2.wavelength.values) > 0)
    assert "sentinel2a-msi" in littoral.sensors()


def test_an_unknown_sensor_is_an_error_naming_the_shipped_ones(small):
    r = littoral.render(small, progress=False)
    with pytest.raises(littoral.SceneError, match="sentinel2a-msi"):
        littoral.resample(r.cube, "hubble")
