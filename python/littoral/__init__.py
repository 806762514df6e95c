"""littoral from Python: spectral light transport in coastal water.

- :class:`Scene`: a scene, validated by littoral (``Scene.default()``,
  ``Scene.from_toml``, ``Scene.from_dict``, ``scene.with_({...})``).
- :func:`render`: a render as a :class:`Result` of xarray Datasets.
- :func:`emit`: a photon map for later renders.
- :func:`open`: a render's outputs on disk, memory-mapped.
- :func:`resample`: a cube over a real sensor's bands.

The work is done by littoral's Rust library (``littoral::job``); this
package only carries scenes in and results out.
"""

from ._littoral import LittoralError, SceneError
from ._littoral import version as _version
from ._io import Result, open, read_envi_header
from ._resample import resample, sensors
from ._run import emit, render
from ._scene import Scene

__version__ = _version()

# Errors raised before littoral sees the scene carry the same fields, unset.
LittoralError.path = None
LittoralError.line = None
LittoralError.key = None

__all__ = [
    "LittoralError",
    "Result",
    "Scene",
    "SceneError",
    "emit",
    "open",
    "read_envi_header",
    "render",
    "resample",
    "sensors",
]
