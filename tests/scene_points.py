"""Each point of a scene file's sweep, loaded as ``warpbem sweep`` runs them (tests only)."""

from pathlib import Path

from warpbem.app import scene
from warpbem.app.sweep import grid

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def sweep_scenes(name: str) -> list:
    """The loaded ``Scene`` of every point of scenes/<name>.toml's sweep (all its axes)."""
    path = SCENES / f"{name}.toml"
    return [scene.load(path, overrides) for _, overrides in grid([], scene.load(path).sweep)]
