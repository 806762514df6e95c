"""The native module (Rust, PyO3): a thin layer over littoral::job.

Scenes travel as TOML text plus an origin path; overrides as JSON
(``{"photons": 1000, "integrator": "path"}``); reports come back as JSON.
Use the package's public API (``littoral.render`` etc.) instead.
"""

from typing import Callable, List, Optional, Tuple

class LittoralError(Exception):
    path: Optional[str]
    line: Optional[int]
    key: Optional[str]

class SceneError(LittoralError): ...

ProgressCallback = Callable[[str, int, int, bool], object]

def scene_default_text() -> str: ...
def scene_set(text: str, key: str, value: str) -> str: ...
def scene_remove(text: str, key: str) -> str: ...
def scene_get(text: str, key: str) -> Optional[str]: ...
def scene_to_json(text: str) -> str: ...
def scene_from_json(json: str) -> str: ...
def scene_check(text: str, origin: str, overrides: str) -> str: ...
def scene_bands(text: str, origin: str, overrides: str) -> Tuple[List[float], List[float]]: ...
def render(
    text: str,
    origin: str,
    out_dir: str,
    overrides: str,
    mem_budget: str,
    threads: int,
    map: Optional[str] = None,
    progress: Optional[ProgressCallback] = None,
) -> str: ...
def emit(
    text: str,
    origin: str,
    map: str,
    overrides: str,
    mem_budget: str,
    threads: int,
    report: Optional[str] = None,
    progress: Optional[ProgressCallback] = None,
) -> str: ...
def sensor_names() -> List[str]: ...
def sensor_weights(
    name: str, centres: List[float], fwhm: List[float]
) -> Tuple[List[str], List[float], List[float], List[float]]: ...
def version() -> str: ...
