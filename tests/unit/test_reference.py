"""The scene-file reference is generated from the options' declarations and checked in: it
must be the one the declarations give now, list every declared key, and its defaults must be
what a scene that leaves the key out gets."""

from pathlib import Path

import pytest

from warpbem.app import scene
from warpbem.app.reference import TABLES, scene_reference
from warpbem.options import declared

ROOT = Path(__file__).resolve().parents[2]
MINIMAL = {"flow": {"shear_rate": 0.0}, "time": {"end": 1e-4}, "physics": {"repulsion": True},
           "bodies": [{"position": [0, 0, 10e-6], "mesh": {"shape": "sphere", "radius": 5e-6, "subdivisions": 1}}]}


def test_checked_in_reference_is_current():
    assert (ROOT / "docs" / "scene-reference.md").read_text() == scene_reference(), (
        "docs/scene-reference.md is stale: python -m warpbem.app.reference > docs/scene-reference.md")


def test_every_declared_key_is_listed():
    text = scene_reference()
    for section, classes, _ in TABLES:
        for cls in classes:
            for name, _, spec in declared(cls):
                assert f"| `{section}.{name}` | {spec.unit} |" in text


def test_a_scene_that_leaves_a_key_out_gets_its_listed_default():
    s = scene.parse(MINIMAL)
    built = {"flow": [s.model.flow], "solver": [s.model.solver], "repulsion": [s.model.interaction("repulsion")],
             "time": [s.model.policy, s], "bodies": [s.bodies[0]]}
    checked = 0
    for section, classes, _ in TABLES:
        for cls in classes:
            for name, default, _ in declared(cls):
                objects = [o for o in built.get(section, []) if hasattr(o, name)]
                if default is None or not objects:
                    continue  # resolved from the context (the reference says how), or not built here
                assert getattr(objects[0], name) == default, f"{section}.{name}"
                checked += 1
    assert checked >= 25  # the test reaches most keys


@pytest.mark.parametrize("section", ["flow", "physics", "time", "solver", "repulsion", "adhesion", "deformation"])
def test_unknown_keys_are_refused_with_the_allowed_ones(section):
    table = {**MINIMAL, section: {**MINIMAL.get(section, {}), "no_such_key": 1}}
    with pytest.raises(scene.SceneError, match=rf"{section}: unknown key 'no_such_key'; allowed keys: "):
        scene.parse(table)
