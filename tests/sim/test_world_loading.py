"""A world file is parsed once per process, yet every caller gets a world of its own."""

from __future__ import annotations

import os
from pathlib import Path

from sim.world import load_world, resolve_world_path


def _copy_of_apartment(tmp_path: Path) -> Path:
    path = tmp_path / "flat.yaml"
    path.write_text(resolve_world_path("apartment").read_text())
    return path


def test_each_load_is_an_independent_copy(tmp_path: Path) -> None:
    path = _copy_of_apartment(tmp_path)
    first, second = load_world(path), load_world(path)
    assert first == second and first is not second
    first.obstacles.clear()
    assert load_world(path).obstacles == second.obstacles != []


def test_a_changed_file_is_read_again(tmp_path: Path) -> None:
    path = _copy_of_apartment(tmp_path)
    before = load_world(path)
    path.write_text(path.read_text().replace("\nname: apartment", "\nname: flat", 1))
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 10_000_000))
    assert (before.name, load_world(path).name) == ("apartment", "flat")


def test_a_robot_profile_is_parsed_once_and_overrides_stay_with_their_caller(tmp_path: Path) -> None:
    from sim.robot import ROBOTS_DIR, load_profile

    path = tmp_path / "bot.yaml"
    path.write_text((ROBOTS_DIR / "burger.yaml").read_text())
    plain = load_profile(path)
    fast = load_profile(path, max_linear=plain.max_linear / 2)
    assert fast.max_linear == plain.max_linear / 2
    assert load_profile(path) == plain  # the override changed only its own copy
    path.write_text(path.read_text() + "\n# edited\n")
    os.utime(path, ns=(1, 1))
    assert load_profile(path) == plain  # re-read (new size and time), same content
