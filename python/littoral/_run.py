"""Runs: render and emit, on a worker thread, with progress and Ctrl-C."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any, Callable, Dict, Optional, Union

from . import _io, _littoral
from ._scene import Scene

PathLike = Union[str, "os.PathLike[str]"]
#: ``progress`` may be a callable(stage, done, total, finished).
ProgressCallback = Callable[[str, int, int, bool], Any]


def render(
    scene: Optional[Scene] = None,
    *,
    photons: Optional[int] = None,
    bands: Optional[int] = None,
    seed: Optional[int] = None,
    spp: Optional[int] = None,
    integrator: Optional[str] = None,
    inelastic: Optional[bool] = None,
    no_atmosphere: bool = False,
    mem_budget: str = "512MiB",
    threads: int = 0,
    map: Optional[PathLike] = None,  # noqa: A002 - as on the command line
    out: Optional[PathLike] = None,
    progress: Union[bool, ProgressCallback] = True,
) -> "_io.Result":
    """Render ``scene`` (default: the built-in one), as ``littoral render``.

    - ``photons``, ``bands``, ``seed``, ``spp`` (samples per pixel),
      ``integrator`` (``"photon-map"`` or ``"path"``) and ``inelastic``
      (``True``: water Raman scattering and, in water given by its
      constituents, chlorophyll and CDOM fluorescence; ``False``: none)
      override the scene's values, as the command line's flags do;
      ``None`` keeps them.
    - ``no_atmosphere``: see the sea from just above the surface, as
      ``--no-atmosphere``: the scene's ``sensor.altitude_m`` is dropped
      while its atmosphere still lights the sea.
    - ``mem_budget`` bounds the run's memory (``"512MiB"``, ``"2GiB"``);
      ``threads`` = 0 uses every core. The result is the same for any
      number of threads.
    - ``map``: keep the photon map in this file, and reuse it when it was
      traced from the same emission inputs.
    - ``out``: write the outputs (ENVI cubes, EXR, PNG, JSON, HTML) into
      this directory and return them memory-mapped from there; ``None``
      renders into a temporary directory and returns the data in memory.
    - ``progress``: a progress bar (tqdm; in Jupyter its widget) when
      true, nothing when false, or a callable ``(stage, done, total,
      finished)`` called about ten times a second.

    The GIL is released while littoral works. Ctrl-C (``KeyboardInterrupt``)
    stops the run and removes what it had started to write; an exception
    raised by a progress callable stops it the same way. Errors raise
    :class:`littoral.LittoralError` (:class:`littoral.SceneError` for the
    scene) with the message the command line prints.

    Returns a :class:`littoral.Result`: ``.cube`` (an ``xarray.Dataset``
    of ``L_t``, ``L_w``, ``L_surface``, ``R_rs`` and ``stderr`` over
    ``wavelength``, ``y`` and ``x``), ``.radiometers``, ``.profiles`` and
    ``.report``.
    """
    scene = scene if scene is not None else Scene.default()
    overrides = _overrides(
        photons=photons,
        bands=bands,
        seed=seed,
        samples_per_pixel=spp,
        integrator=integrator,
        inelastic=inelastic,
        no_atmosphere=no_atmosphere or None,
    )
    temp = None
    if out is None:
        temp = tempfile.mkdtemp(prefix="littoral-render-")
        out_dir = Path(temp)
    else:
        out_dir = Path(out)
    try:
        with _Progress(progress) as callback:
            _littoral.render(
                scene.to_toml(),
                scene.origin,
                os.fspath(out_dir),
                overrides,
                mem_budget,
                threads,
                None if map is None else os.fspath(map),
                callback,
            )
        result = _io.open(out_dir)
        if temp is not None:
            result.load()
            result.path = None
        return result
    finally:
        if temp is not None:
            shutil.rmtree(temp, ignore_errors=True)


def emit(
    scene: Scene,
    map: PathLike,  # noqa: A002 - as on the command line
    *,
    photons: Optional[int] = None,
    seed: Optional[int] = None,
    inelastic: Optional[bool] = None,
    report: Optional[PathLike] = None,
    mem_budget: str = "512MiB",
    threads: int = 0,
    progress: Union[bool, ProgressCallback] = True,
) -> Dict[str, Any]:
    """Trace ``scene``'s photons into the map file ``map`` (``littoral emit``).

    ``photons``, ``seed`` and ``inelastic`` override the scene as in
    :func:`render`. Returns the emission report as a dict (also written to
    ``report`` when given). A later :func:`render` with the same ``map`` reuses it. Ctrl-C,
    errors and ``progress`` behave as in :func:`render`.
    """
    overrides = _overrides(photons=photons, seed=seed, inelastic=inelastic)
    with _Progress(progress) as callback:
        text = _littoral.emit(
            scene.to_toml(),
            scene.origin,
            os.fspath(map),
            overrides,
            mem_budget,
            threads,
            None if report is None else os.fspath(report),
            callback,
        )
    return json.loads(text)


def _overrides(**kw: Any) -> str:
    return json.dumps({k: v for k, v in kw.items() if v is not None})


class _Progress:
    """The callback handed to the native run: a tqdm bar per stage, the
    user's callable, or nothing."""

    def __init__(self, progress: Union[bool, ProgressCallback]) -> None:
        self.user = progress if callable(progress) else None
        self.bars = bool(progress) and self.user is None
        self.bar = None
        self.stage = None

    def __enter__(self) -> Optional[ProgressCallback]:
        if self.user is not None:
            return self.user
        return self.update if self.bars else None

    def update(self, stage: str, done: int, total: int, finished: bool) -> None:
        if not stage:
            return
        if stage != self.stage:
            self.close()
            from tqdm.auto import tqdm

            self.bar = tqdm(total=total or None, desc=stage, unit_scale=True, leave=False)
            self.stage = stage
        if self.bar is not None:
            self.bar.n = done
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def __exit__(self, *exc: Any) -> None:
        self.close()
