"""Scenes: round trips, edits and errors that name the key."""

from __future__ import annotations

import pytest

import littoral


def test_the_default_scene_round_trips_through_toml_and_dicts():
    s = littoral.Scene.default()
    again = littoral.Scene.from_toml(s.to_toml())
    assert again.to_dict() == s.to_dict()
    from_dict = littoral.Scene.from_dict(s.to_dict())
    assert from_dict.to_dict() == s.to_dict()
    # The edited text is TOML littoral reads back to the same values.
    edited = s.with_({"water.chl": 3.5})
    assert littoral.Scene.from_toml(edited.to_toml()).to_dict() == edited.to_dict()
    assert edited["water.chl"] == 3.5
    assert s.summary.startswith("scene 'coastal' is valid")


def test_from_toml_reads_a_file_and_text(tmp_path, small):
    f = tmp_path / "s.toml"
    f.write_text(small.to_toml())
    assert littoral.Scene.from_toml(f).to_dict() == small.to_dict()
    assert littoral.Scene.from_toml(str(f)).origin == str(f)
    assert littoral.Scene.from_toml(small.to_toml()).origin == "<scene>"


def test_edits_set_remove_and_use_keyword_names(small):
    s = small.with_(water__iop={"a": 0.3, "b": 0.1}, photons__count=500)
    assert s["water.iop"] == {"a": 0.3, "b": 0.1}
    assert s["photons.count"] == 500
    assert s.with_({"sensor.pixels": None}).get("sensor.pixels") is None
    with pytest.raises(littoral.SceneError, match="photons: missing field `count`"):
        s.with_({"photons.count": None})
    with pytest.raises(KeyError):
        s["sensor.nothing_here"]


@pytest.mark.parametrize(
    "change, key, words",
    [
        ({"water.iop.a": -1.0}, "water.iop.a", "must be >= 0"),
        ({"sensor.pixels": [32, 32, 32]}, "sensor.pixels", "expected exactly 2"),
        ({"water.colour": 3}, "water", "unknown field `colour`"),
        ({"sun.zenith_deg": "high"}, "sun.zenith_deg", ""),
    ],
)
def test_bad_values_raise_scene_error_naming_the_key(small, change, key, words):
    with pytest.raises(littoral.SceneError) as e:
        small.with_(change)
    assert e.value.key == key
    assert words in str(e.value)
    assert isinstance(e.value.line, int)
    # The message is the command line's: PATH:LINE: KEY: what.
    assert str(e.value).startswith(f"{small.origin}:{e.value.line}: {key}:")


def test_values_a_scene_cannot_hold_are_refused_naming_the_key(small):
    with pytest.raises(littoral.SceneError) as e:
        small.with_({"water.iop.a": float("nan")})
    assert e.value.key == "water.iop.a"
    with pytest.raises(littoral.SceneError) as e:
        small.with_({"water.iop.a": object()})
    assert e.value.key == "water.iop.a"


def test_a_missing_file_is_a_scene_error(tmp_path):
    with pytest.raises(littoral.SceneError, match="no-such.toml"):
        littoral.Scene.from_toml(tmp_path / "no-such.toml")
