"""R_rs over sand at three chlorophyll concentrations and three depths.

Run from the repository: ``python python/examples/sweep.py`` (about a
minute on two cores); it writes ``sweep.png`` beside itself.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import xarray as xr

import littoral

base = littoral.Scene.default().with_(
    {"water.gradient": None, "bottom.slope": None, "bottom.patch": None, "target": None,
     "radiometer": None, "tally": None, "bottom.depth_m": 5.0, "photons.count": 400_000, "domain.size_m": [20.0, 20.0],
     "sensor.pixels": [16, 16], "sensor.gsd_m": 1.0, "spectral.bands": 64}
)
rrs = xr.concat(
    [xr.concat([littoral.render(base.with_({"water.chl": chl, "bottom.depth_m": depth}), progress=False)
                .cube.R_rs.mean(("x", "y")) for depth in (2.0, 5.0, 15.0)], dim="depth")
     for chl in (0.3, 2.0, 10.0)], dim="chl"
).assign_coords(chl=[0.3, 2.0, 10.0], depth=[2.0, 5.0, 15.0])

fig, axes = plt.subplots(1, 3, figsize=(11, 3.4), sharey=True, constrained_layout=True)
for ax, chl in zip(axes, rrs.chl.values):
    for depth in rrs.depth.values:
        rrs.sel(chl=chl, depth=depth).plot(ax=ax, label=f"sand at {depth:g} m")
    ax.set_title(f"Chl {chl:g} mg m$^{{-3}}$")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("")
    ax.grid(alpha=0.3)
axes[0].set_ylabel("R$_{rs}$ (sr$^{-1}$)")
axes[0].legend(frameon=False)
fig.savefig(Path(__file__).with_name("sweep.png"), dpi=110)
