"""Renders: the Dataset against the command line's cube, coordinates,
NetCDF, threads, Ctrl-C, progress and maps."""

from __future__ import annotations

import _thread
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import littoral


def read_bsq(hdr: Path) -> np.ndarray:
    """An ENVI float32 BSQ cube read with Spectral Python, (bands, lines, samples)."""
    import spectral.io.envi as envi

    img = envi.open(str(hdr), str(hdr.with_suffix(".bsq")))
    return np.transpose(np.asarray(img.load(), dtype=np.float32), (2, 0, 1))


def test_the_dataset_equals_the_command_lines_cube_bit_for_bit(tmp_path, small, cli):
    scene = tmp_path / "small.toml"
    scene.write_text(small.to_toml())
    subprocess.run(
        [str(cli / "littoral"), "render", str(scene), "--out", str(tmp_path / "cli"), "--quiet", "--threads", "2"],
        check=True,
    )
    r = littoral.render(littoral.Scene.from_toml(scene), progress=False)
    assert r.path is None  # rendered in a temporary directory, held in memory
    name = "scene"
    for var, suffix in (("L_t", ""), ("L_w", ".lw"), ("L_surface", ".surface"), ("R_rs", ".rrs"), ("stderr", ".stderr")):
        expect = read_bsq(tmp_path / "cli" / f"{name}{suffix}.hdr")
        got = r.cube[var].values
        assert got.dtype == np.float32 and got.shape == expect.shape == (4, 12, 16)
        assert got.tobytes() == expect.tobytes(), var
    assert list(r.cube.wavelength.values) == [400.0, 500.0, 600.0, 700.0]
    assert r.cube.wavelength.attrs["units"] == "nm"
    assert r.cube.L_w.attrs["units"] == "W m-2 sr-1 nm-1"
    assert r.cube.R_rs.attrs["units"] == "sr-1"
    assert r.report["integrator"] == "photon-map"


def test_coordinates_and_crs_follow_the_georeferencing(small):
    s = small.with_({"georef.origin_m": [500000.0, 4100000.0], "georef.epsg": 32617})
    r = littoral.render(s, progress=False)
    gt = r.report["sensor"]["geotransform"]
    x0, dx, _, y0, _, dy = gt
    assert np.allclose(r.cube.x.values, x0 + (np.arange(16) + 0.5) * dx)
    assert np.allclose(r.cube.y.values, y0 + (np.arange(12) + 0.5) * dy)
    assert r.cube.x.values[0] > 500000.0 and r.cube.y.values[0] > 4100000.0
    assert r.cube.R_rs.attrs["grid_mapping"] == "spatial_ref"
    import rioxarray  # noqa: F401 - registers .rio

    assert r.cube.rio.crs.to_epsg() == 32617
    assert np.allclose(tuple(r.cube.rio.transform())[:6], (dx, 0.0, x0, 0.0, dy, y0))


def test_netcdf_round_trips_through_both_engines(tmp_path, small):
    r = littoral.render(small, progress=False)
    for engine in ("netcdf4", "h5netcdf"):
        path = tmp_path / f"cube-{engine}.nc"
        r.cube.to_netcdf(path, engine=engine)
        with xr.open_dataset(path, engine=engine) as back:
            xr.testing.assert_identical(back.load(), r.cube)


def test_outputs_kept_in_a_directory_open_memory_mapped(tmp_path, small):
    out = tmp_path / "out"
    r = littoral.render(small, out=out, progress=False)
    assert r.path == out and (out / "scene.hdr").is_file()
    base = r.cube.L_t.variable._data
    while not isinstance(base, np.ndarray) and hasattr(base, "array"):
        base = base.array
    assert isinstance(np.asarray(base).base, np.memmap) or isinstance(base, np.memmap)
    again = littoral.open(out / "scene.rrs.hdr")  # a product's header opens its run
    xr.testing.assert_identical(again.cube, r.cube)
    with pytest.raises(littoral.LittoralError, match="no such cube header"):
        littoral.open(out / "nothing.hdr")


def test_a_truncated_cube_is_an_error_naming_the_file(tmp_path, small):
    out = tmp_path / "out"
    littoral.render(small, out=out, progress=False)
    data = out / "scene.lw.bsq"
    data.write_bytes(data.read_bytes()[:100])
    with pytest.raises(littoral.LittoralError, match="scene.lw.bsq: 100 bytes"):
        littoral.open(out)


def test_two_renders_in_threads_give_identical_results(small):
    s = small.with_({"photons.count": 20000})
    results = [None, None]

    def run(i):
        results[i] = littoral.render(s, threads=1 + i, progress=False)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    xr.testing.assert_identical(results[0].cube.drop_attrs(), results[1].cube.drop_attrs())


def test_the_gil_is_released_while_littoral_works(small):
    s = small.with_({"photons.count": 400000})
    ticks = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks[0] += 1

    t = threading.Thread(target=count)
    t.start()
    start = time.monotonic()
    try:
        littoral.render(s, progress=False)
    finally:
        stop.set()
        t.join()
    elapsed = time.monotonic() - start
    # Held the whole time, the GIL would let the counter run only in the
    # interpreter's switch intervals of the render's own Python code.
    assert elapsed > 0.2
    assert ticks[0] > 10000


def test_ctrl_c_stops_a_render_and_leaves_its_directory_clean(tmp_path, small):
    s = small.with_({"photons.count": 50_000_000})
    out = tmp_path / "out"
    out.mkdir()
    timer = threading.Timer(1.0, _thread.interrupt_main)
    timer.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        littoral.render(s, out=out, progress=False)
    assert time.monotonic() - start < 20.0
    assert sorted(p.name for p in out.iterdir()) == []


def test_an_exception_from_the_progress_callable_stops_the_run(tmp_path, small):
    s = small.with_({"photons.count": 50_000_000})
    seen = []

    def progress(stage, done, total, finished):
        seen.append((stage, done, total))
        if len(seen) > 3:
            raise RuntimeError("enough")

    out = tmp_path / "out"
    with pytest.raises(RuntimeError, match="enough"):
        littoral.render(s, out=out, progress=progress)
    assert any(stage == "trace photons" and total == 50_000_000 for stage, _, total in seen)
    assert [p.name for p in out.iterdir()] == [] if out.exists() else True


def test_a_kept_map_is_reused(tmp_path, small):
    m = tmp_path / "scene.map"
    report = littoral.emit(small, m, progress=False)
    assert m.is_file() and report["map"]["photons"] > 0
    r = littoral.render(small, map=m, progress=False)
    assert r.report["reused_map"] is True
    assert r.cube.attrs["map_provenance_sha256"] == report["map"]["provenance"]


def test_run_errors_are_exceptions_with_the_command_lines_message(tmp_path, small):
    with pytest.raises(littoral.SceneError, match="mem_budget"):
        littoral.render(small, mem_budget="lots", progress=False)
    with pytest.raises(littoral.SceneError, match="integrator"):
        littoral.render(small, integrator="magic", progress=False)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(littoral.LittoralError, match=str(blocker)):
        littoral.render(small, out=blocker / "out", progress=False)


def test_profiles_and_radiometers_are_datasets(small):
    s = small.with_({"tally.depths_m": [0.0, 1.0, 2.0]}).with_(
        {"radiometer": [{"depth_m": 1.0, "view": "nadir", "position_m": [5.0, 5.0]}]}
    )
    r = littoral.render(s, progress=False)
    p = r.profiles
    assert p.Ed.dims == ("depth", "wavelength") and list(p.depth.values) == [0.0, 1.0, 2.0]
    assert np.array_equal(p.Ed.values[1], np.asarray(r.report["tally"][1]["Ed"]))
    assert p.Kd.dims == ("layer", "wavelength")
    # No floor: every depth is all water, and the means are over it.
    assert list(p.water_fraction.values) == [1.0, 1.0, 1.0]
    rad = r.radiometers
    assert rad.L.dims == ("radiometer", "wavelength")
    assert np.array_equal(rad.L.values[0], np.asarray(r.report["radiometers"][0]["L"]))
    assert str(rad.view.values[0]) == "nadir"


def test_the_path_integrator_gives_radiometers_on_the_cubes_bands(small):
    s = small.with_({"radiometer": [{"depth_m": 0.5, "view": "nadir", "position_m": [5.0, 5.0]}]})
    r = littoral.render(s, integrator="path", spp=4, progress=False)
    assert r.report["integrator"] == "path"
    assert r.profiles is None
    assert list(r.radiometers.wavelength.values) == list(r.cube.wavelength.values)
    assert np.all(r.cube.stderr.values > 0)
    assert np.all(r.radiometers.L.values > 0)


def test_a_cube_on_its_own_opens_as_one_variable(tmp_path, small, cli):
    out = tmp_path / "out"
    littoral.render(small, out=out, progress=False)
    subprocess.run(
        [str(cli / "littoral-cube"), "resample", str(out / "scene.hdr"), "--sensor", "csv:" + str(_gaussians(tmp_path)), "--out", str(tmp_path / "g.hdr")],
        check=True,
        capture_output=True,
    )
    r = littoral.open(tmp_path / "g.hdr")
    assert list(r.cube.data_vars) == ["data"] and r.report == {}
    assert r.cube.data.shape == (2, 12, 16)
    assert r.radiometers is None and r.profiles is None


def _gaussians(d: Path) -> Path:
    p = d / "g.csv"
    p.write_text("band,center_nm,fwhm_nm\nblue,480,20\ngreen,551.5,10\n")
    return p


def test_the_progress_bar_draws_each_stage(small, capsys):
    littoral.render(small.with_({"photons.count": 20000}), progress=True)
    err = capsys.readouterr().err
    assert "trace photons" in err and "render tiles" in err


def test_inelastic_light_switches_on_and_off(tmp_path, small):
    # Water Raman scattering shifts power between bands in emission only
    # when it is on; `inelastic` overrides the scene's `water.raman`.
    scene = small.with_({"water.raman": True, "photons.count": 100_000})
    shifted = {}
    for on in (True, False):
        report = littoral.emit(scene, tmp_path / f"{on}.map", inelastic=on, progress=False)
        shifted[on] = sum(report["energy"]["inelastic_out"])
    assert shifted[True] > 0.0
    assert shifted[False] == 0.0


def test_a_sensor_above_the_atmosphere_adds_rho_t_and_the_path_radiance(small):
    scene = small.with_(
        {
            "sun.irradiance": None,
            "sun.spectrum": "extraterrestrial",
            "atmosphere.sky_photons": 2000,
            "sensor.altitude_m": 700000.0,
        }
    )
    r = littoral.render(scene, progress=False)
    a = r.report["atmosphere"]
    e0 = np.asarray(a["toa_irradiance"])[:, None, None]
    mu0 = np.cos(np.radians(30.0))
    rho = np.pi * r.cube.L_t.values.astype(np.float64) / (e0 * mu0)
    assert np.allclose(r.cube.rho_t.values, rho, rtol=1e-6)
    assert r.cube.rho_t.attrs["units"] == "1"
    want = np.asarray(a["L_path"], dtype=np.float32)[:, None, None]
    assert np.all(r.cube.L_path.values == want) and np.all(want > 0)
    for name in ("t_down", "t_up"):
        want = np.asarray(a[name], dtype=np.float32)[:, None, None]
        assert np.all(r.cube[name].values == want), name
        assert np.all((want > 0) & (want < 1)), name
        assert r.cube[name].attrs["units"] == "1"
    assert "rho_t" not in littoral.render(small, progress=False).cube
    # From just above the surface: the same water, no air between.
    near = littoral.render(scene, no_atmosphere=True, progress=False)
    assert "rho_t" not in near.cube and "L_path" not in near.cube and "t_up" not in near.cube
    assert near.cube.L_w.values.tobytes() == r.cube.L_w.values.tobytes()
    assert near.cube.L_surface.values.tobytes() == r.cube.L_surface.values.tobytes()
    assert not np.array_equal(near.cube.L_t.values, r.cube.L_t.values)
