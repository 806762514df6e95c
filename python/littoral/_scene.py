"""Scenes as objects: TOML text plus the path that names it."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Mapping, Optional, Union

from . import _littoral

PathLike = Union[str, "os.PathLike[str]"]

#: What a scene made from text is called in errors; relative file names in
#: it are read from the current directory.
TEXT_ORIGIN = "<scene>"


class Scene:
    """A littoral scene, validated.

    A scene is its TOML text (the format of ``littoral render SCENE.toml``)
    and the path that names it in error messages and anchors the relative
    file names in it (spectra, meshes, height fields). Every constructor
    validates with littoral's own checks, so a scene that exists is one
    littoral can run; a fault raises :class:`littoral.SceneError` with the
    message the command line prints and its ``key`` (dotted), ``path`` and
    ``line``.

    Scenes are immutable: :meth:`with_` returns a changed copy.

    >>> s = Scene.default().with_({"water.chl": 5.0, "photons.count": 200_000})
    >>> s["water.chl"]
    5.0
    """

    __slots__ = ("_text", "_origin", "_summary")

    def __init__(self, text: str, origin: PathLike = TEXT_ORIGIN) -> None:
        self._text = str(text)
        self._origin = str(origin)
        self._summary = _littoral.scene_check(self._text, self._origin, "{}")

    # -- constructors -------------------------------------------------
    @classmethod
    def default(cls) -> "Scene":
        """The built-in coastal scene (``littoral scene default``)."""
        return cls(_littoral.scene_default_text(), "<built-in coastal scene>")

    @classmethod
    def from_toml(cls, path_or_text: Union[PathLike, str]) -> "Scene":
        """A scene from a TOML file, or from TOML text.

        A :class:`pathlib.Path` (or ``os.PathLike``) is always a file; a
        string is a file when it names one that exists and holds no
        newline, else it is the scene's text (relative file names in it
        are then read from the current directory).
        """
        if isinstance(path_or_text, os.PathLike):
            path = Path(path_or_text)
            return cls(_read(path), path)
        text = str(path_or_text)
        if "\n" not in text and Path(text).is_file():
            return cls(_read(Path(text)), text)
        return cls(text, TEXT_ORIGIN)

    @classmethod
    def from_dict(
        cls, d: Mapping[str, Any], base_dir: Optional[PathLike] = None
    ) -> "Scene":
        """A scene from nested mappings (as :meth:`to_dict` gives).

        ``base_dir`` anchors relative file names (default: the current
        directory).
        """
        text = _littoral.scene_from_json(_to_json("scene", d))
        origin = TEXT_ORIGIN if base_dir is None else Path(base_dir) / TEXT_ORIGIN
        return cls(text, origin)

    # -- reading ------------------------------------------------------
    def to_toml(self) -> str:
        """The scene as TOML text (a file ``littoral render`` reads)."""
        return self._text

    def to_dict(self) -> dict:
        """The scene as nested dicts, lists and numbers."""
        return json.loads(_littoral.scene_to_json(self._text))

    def __getitem__(self, key: str) -> Any:
        """The value at a dotted key (``scene["water.chl"]``); ``KeyError``
        when the scene file does not set it (littoral's default applies)."""
        value = _littoral.scene_get(self._text, key)
        if value is None:
            raise KeyError(key)
        return json.loads(value)

    def get(self, key: str, default: Any = None) -> Any:
        """The value at a dotted key, or ``default`` when not set."""
        try:
            return self[key]
        except KeyError:
            return default

    @property
    def origin(self) -> str:
        """The path naming the scene in errors (``<scene>`` for text)."""
        return self._origin

    @property
    def summary(self) -> str:
        """littoral's one-line summary (``littoral scene check``)."""
        return self._summary

    def bands(self) -> "tuple[list[float], list[float]]":
        """The band centres and FWHMs (nm) the scene renders."""
        return _littoral.scene_bands(self._text, self._origin, "{}")

    # -- changing -----------------------------------------------------
    def with_(self, changes: Optional[Mapping[str, Any]] = None, **kw: Any) -> "Scene":
        """A copy with dotted keys set, validated.

        ``scene.with_({"water.chl": 5, "sensor.pixels": [32, 32]})``; keyword
        arguments name keys with ``__`` for the dot
        (``scene.with_(water__chl=5)``). A value of ``None`` removes the key
        (littoral's default applies). Tables on the way are made as needed.
        The copy's TOML has its tables' keys sorted and no comments. Errors
        raise :class:`littoral.SceneError` naming the key.
        """
        text = self._text
        items = list((changes or {}).items())
        items += [(k.replace("__", "."), v) for k, v in kw.items()]
        for key, value in items:
            if value is None:
                text = _littoral.scene_remove(text, key)
            else:
                text = _littoral.scene_set(text, key, _to_json(key, value))
        origin = self._origin
        if origin not in (TEXT_ORIGIN, "<built-in coastal scene>") and not origin.endswith(
            " (edited)"
        ):
            origin = f"{origin} (edited)"
        return Scene(text, origin)

    def __repr__(self) -> str:
        return f"<littoral.Scene from {self._origin}: {self._summary}>"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Scene) and self.to_dict() == other.to_dict()

    __hash__ = None  # type: ignore[assignment]


def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except OSError as e:
        raise _littoral.SceneError(f"{path}: read: {e.strerror or e}") from e


def _to_json(key: str, value: Any) -> str:
    """``value`` as JSON, numpy scalars and arrays included."""

    def default(o: Any) -> Any:
        if hasattr(o, "tolist"):
            return o.tolist()
        if isinstance(o, os.PathLike):
            return os.fspath(o)
        raise TypeError(f"{type(o).__name__} is not a value a scene can hold")

    try:
        return json.dumps(value, default=default, allow_nan=False)
    except (TypeError, ValueError) as e:
        err = _littoral.SceneError(f"{key}: {e}")
        err.key = key
        raise err from None
