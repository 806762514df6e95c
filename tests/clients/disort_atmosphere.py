#!/usr/bin/env python3
"""DISORT's answer for the atmosphere `littoral scene atmosphere --toa` printed.

Reads that JSON (argument 1) and solves each band's column with DISORT
(nanodisort, libRadtran's C DISORT), layer by layer with littoral's own
optical depths, single-scattering albedos and phase functions (depolarised
Rayleigh and Henyey-Greenstein or a named model's Mie table, mixed by their
scattering optical depths),
the sun's beam at its top and a black surface, or the scene's Lambertian
ground (``ground_reflectance`` per band). Prints JSON, per band:

* ``direct``, ``diffuse``: the beam's and the sky's irradiance at the surface;
* ``up_at_top``: the irradiance leaving the top;
* ``sky``: the mean radiance of each of littoral's sky cells at the surface
  (cosine-weighted over 3 x 3 directions within the cell), and ``toa``: the
  same for the light leaving the top;
* ``path_radiance``: with a sensor above the surface (``view``), the
  radiance going up toward it at its level (over a black surface: the path
  radiance), in its exact direction;
* ``at_sensor``: the radiance at that sensor over the scene's Lambertian
  ground (``ground_reflectance``, 0 for none);
* ``t_up``: the total transmittance from a Lambertian ground to that
  sensor along its view. DISORT solves the column again over a ground of
  albedo A = 1: the sensor's radiance grows by A E_d(A) t_up / pi, with
  E_d(A) DISORT's direct plus diffuse irradiance at the ground over that
  albedo (which holds the light the air sends back down), so
  t_up = pi (L(A) - L(0)) / (A E_d(A)).

DISORT's azimuth is measured from the beam's direction of travel (phi =
phi0 is forward scattering for light going down). littoral's sky cells
measure the sky element's azimuth from the sun's, so the light from a cell
at phi travels at phi from the beam: the same number. Its top cells measure
the travel direction from the direction toward the sun: phi + 180 from the
beam.
"""

import json
import math
import sys

import numpy as np
import nanodisort as nd

NSTR = 32
NMOM = 256
NPHASE = 721
SUB = 3


def cell_directions(zenith_bins, azimuth_bins):
    """Per cell, the (mu, phi_deg) sub-directions: mu^2 uniform (cosine
    weight), phi uniform within the cell."""
    dz = math.pi / 2 / zenith_bins
    da = 180.0 / azimuth_bins
    mus, phis = [], []
    for iz in range(zenith_bins):
        a, b = math.cos(iz * dz), math.cos((iz + 1) * dz)
        for k in range(SUB):
            u = (k + 0.5) / SUB
            mus.append(math.sqrt(b * b + u * (a * a - b * b)))
    for ia in range(azimuth_bins):
        for k in range(SUB):
            phis.append((ia + (k + 0.5) / SUB) * da)
    return mus, phis


# A named aerosol's Legendre moments and phase grid, per band's table.
_MOMENTS = {}


def solve(band, sun_zenith_deg, mus, phis, levels=None, albedo=0.0):
    layers = [l for l in band["layers"] if sum(v for k, v in l.items() if not k.endswith("_km")) > 0]
    # littoral lists the layers from the top down, as DISORT numbers them.
    q = band["rayleigh_q"]
    g = band.get("aerosol_g", 0.0)
    ell = np.arange(NMOM + 1)
    table = band.get("aerosol_phase")
    if table and id(table) in _MOMENTS:
        aer, mu_p, p_aer = _MOMENTS[id(table)]
    elif table:
        # A named model's Mie table (mean 1 over the sphere), linear in
        # angle as littoral reads it: moments by quadrature on a fine angle
        # grid, and the phase on a grid fine in the forward peak.
        ang = np.asarray(table["angles_deg"], dtype=float)
        val = np.asarray(table["values"], dtype=float)
        th = np.radians(np.linspace(0.0, 180.0, 360001))
        p_th = np.interp(np.degrees(th), ang, val)
        w = np.sin(th)
        w[0] *= 0.5
        w[-1] *= 0.5
        w *= th[1] - th[0]
        norm = 0.5 * np.sum(p_th * w)
        mu = np.cos(th)
        aer = np.empty(NMOM + 1)
        p_prev, p_cur = np.ones_like(mu), mu.copy()
        aer[0] = 1.0
        for l in range(1, NMOM + 1):
            if l > 1:
                p_prev, p_cur = p_cur, ((2 * l - 1) * mu * p_cur - (l - 1) * p_prev) / l
            aer[l] = 0.5 * np.sum(p_th * p_cur * w) / norm
        th_p = np.radians(np.concatenate([np.linspace(180.0, 10.0, 341, endpoint=False), np.linspace(10.0, 0.0, 401)]))
        mu_p = np.cos(th_p)
        p_aer = np.interp(np.degrees(th_p)[::-1], ang, val)[::-1] / norm
        _MOMENTS[id(table)] = (aer, mu_p, p_aer)
    else:
        aer = g ** ell
        mu_p = np.linspace(-1.0, 1.0, NPHASE)
        p_aer = (1 - g * g) / (1 + g * g - 2 * g * mu_p) ** 1.5
    ds = nd.DisortState()
    ds.nstr = NSTR
    ds.nlyr = len(layers)
    ds.nmom = NMOM
    levels = levels if levels is not None else [0.0, None]
    ds.ntau = len(levels)
    # umu ascending: light going down (negative), then up.
    down = sorted(-m for m in mus) if mus else []
    up = sorted(mus)
    ds.numu = len(down) + len(up) if levels[-1] is None else len(up)
    ds.nphi = len(phis)
    ds.nphase = len(mu_p)
    ds.usrtau = True
    ds.usrang = True
    ds.lamber = True
    ds.quiet = True
    ds.intensity_correction = True
    ds.old_intensity_correction = False
    ds.allocate()
    tau = np.array([sum(v for k, v in l.items() if not k.endswith("_km")) for l in layers])
    sca_r = np.array([l["rayleigh"] for l in layers])
    sca_a = np.array([l["aerosol_scattering"] for l in layers])
    sca = sca_r + sca_a
    ds.dtauc = tau
    # DISORT's conservative case (albedo exactly 1, where no ozone absorbs)
    # can fail; an albedo 1e-9 below changes nothing measurable.
    ds.ssalb = np.minimum(np.where(tau > 0, sca / tau, 0.0), 1.0 - 1e-9)
    share = np.where(sca > 0, sca_r / np.where(sca > 0, sca, 1.0), 1.0)
    # Legendre coefficients g_l (p = sum (2l+1) g_l P_l, p normalised to 1
    # over 4 pi / 4 pi): Rayleigh 1 + 2q/(3+q) P2, HG g^l.
    ell = np.arange(NMOM + 1)
    ray = np.zeros(NMOM + 1)
    ray[0] = 1.0
    ray[2] = 2.0 * q / (5.0 * (3.0 + q))
    ds.pmom = (share[None, :] * ray[:, None] + (1 - share[None, :]) * aer[:, None])
    p_ray = 3.0 / (3.0 + q) * (1.0 + q * mu_p ** 2)
    p_hg = p_aer
    ds.mu_phase = mu_p
    ds.phase = share[:, None] * p_ray[None, :] + (1 - share[:, None]) * p_hg[None, :]
    ds.utau = np.array([tau.sum() if l is None else min(l, tau.sum()) for l in levels])
    ds.umu = np.array(down + up) if levels[-1] is None else np.array(up)
    ds.phi = np.array(phis)
    ds.fbeam = band["band"]["toa_irradiance"]
    ds.umu0 = math.cos(math.radians(sun_zenith_deg))
    ds.phi0 = 0.0
    ds.albedo = albedo
    ds.fisot = 0.0
    ds.solve()
    return ds, down, up


def main():
    d = json.load(open(sys.argv[1]))
    grid = d["sky_grid"]
    nz, na = grid["zenith_bins"], grid["azimuth_bins"]
    mus, phis = cell_directions(nz, na)
    g = (d.get("aerosol") or {}).get("g", 0.0)
    out = []
    for band in d["bands"]:
        band["aerosol_g"] = g
        ground = band.get("ground_reflectance") or 0.0
        ds, down, up = solve(band, d["sun_zenith_deg"], mus, phis, albedo=ground)
        uu = np.asarray(ds.uu)  # (numu, ntau, nphi)
        nd_ = len(down)
        sky, toa = [], []
        for iz in range(nz):
            for ia in range(na):
                s_sky, s_toa = 0.0, 0.0
                for k in range(SUB):
                    mu = mus[iz * SUB + k]
                    i_down = down.index(-mu)
                    i_up = nd_ + up.index(mu)
                    for j in range(SUB):
                        # Sky: travel at phi from the beam.
                        s_sky += uu[i_down, 1, ia * SUB + j]
                        # Top: travel at phi + 180 from the beam; by the
                        # symmetry about the beam's plane, phi' = 180 - phi.
                        s_toa += uu[i_up, 0, (na - 1 - ia) * SUB + (SUB - 1 - j)]
                sky.append(s_sky / SUB ** 2)
                toa.append(s_toa / SUB ** 2)
        view = d.get("view")
        path = None
        if view:
            b = len(out)
            mu = math.cos(math.radians(view["view_zenith_deg"]))
            phi = (view["view_azimuth_from_sun_deg"] + 180.0) % 360.0
            vs, _, _ = solve(band, d["sun_zenith_deg"], [mu], [phi], levels=[view["depth"][b]])
            path = float(np.asarray(vs.uu)[0, 0, 0])
            # Over the scene's own ground: the whole radiance at the sensor.
            gs, _, _ = solve(
                band, d["sun_zenith_deg"], [mu], [phi], levels=[view["depth"][b]], albedo=ground
            )
            at_sensor = float(np.asarray(gs.uu)[0, 0, 0])
            # Over a white ground: the sensor's level, then the ground.
            ws, _, _ = solve(
                band, d["sun_zenith_deg"], [mu], [phi], levels=[view["depth"][b], None], albedo=1.0
            )
            lit = float(np.asarray(ws.uu)[1, 0, 0])
            ed = float(ws.rfldir[1] + ws.rfldn[1])
            t_up = math.pi * (lit - path) / ed
        out.append(
            {
                "path_radiance": path,
                "t_up": t_up if view else None,
                "at_sensor": at_sensor if view else None,
                "nm": band["band"]["nm"],
                "direct": float(ds.rfldir[1]),
                "diffuse": float(ds.rfldn[1]),
                "up_at_top": float(ds.flup[0]),
                "sky": sky,
                "toa": toa,
            }
        )
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
