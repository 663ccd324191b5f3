"""The scene's ``velocity_safety`` setting: read, defaulted and range-checked."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import DEFAULT_VELOCITY_SAFETY, default_scene_path, load_scene


def _write(tmp_path: Path, **changes: Any) -> Path:
    data: dict[str, Any] = yaml.safe_load(default_scene_path().read_text())
    data["robot"] = str(default_scene_path().parent / data["robot"])
    for key, value in changes.items():
        if value is None:
            data.pop(key, None)
        else:
            data[key] = value
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


def test_shipped_scene_uses_the_full_limits() -> None:
    assert load_scene().velocity_safety == 1.0 == DEFAULT_VELOCITY_SAFETY


def test_setting_is_read(tmp_path: Path) -> None:
    assert load_scene(_write(tmp_path, velocity_safety=0.9)).velocity_safety == 0.9


def test_missing_setting_defaults(tmp_path: Path) -> None:
    assert load_scene(_write(tmp_path, velocity_safety=None)).velocity_safety == 1.0


@pytest.mark.parametrize("value", [0.0, -0.5, 1.01, 2])
def test_out_of_range_names_the_setting_and_range(tmp_path: Path, value: float) -> None:
    with pytest.raises(SceneError) as info:
        load_scene(_write(tmp_path, velocity_safety=value))
    msg = str(info.value)
    assert "velocity_safety: expected a number in (0, 1]" in msg
    assert "scene.yaml:" in msg  # file:line:col


def test_not_a_number(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match="velocity_safety: expected a finite number"):
        load_scene(_write(tmp_path, velocity_safety="fast"))
