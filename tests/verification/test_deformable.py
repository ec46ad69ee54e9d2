"""Deformable cells in time (``warpbem/elastic/deformable.py``): the quasi-static linear
elastic model stepped with the rigid-body dynamics, its frame columns, scene keys and resume.

A free cell in unbounded simple shear (mu = 1 mPa s, gdot = 100 1/s, G = 10 Pa: Ca = mu gdot /
G = 0.01) carries the traction of the uniform stress 5 mu E, so the model's shape is the
sphere strained by 5 mu E / 2G: D = 5 Ca / 4 with its long axis at 45 degrees to the flow,
which the shape solved at a step's start and carried by the step's rotation (Omega = gdot / 2)
shows Omega dt behind.
"""

import h5py
import numpy as np
import pytest

import warpbem as wb
from warpbem.app import cli, scene, xdmf
from warpbem.dynamics import Flow, Model, Simulator, StepPolicy
from warpbem.elastic.deformable import Deformation

A, CA, DT = 5e-6, 0.01, 1e-4

SCENE = """
[flow]
shear_rate = 100.0
viscosity = 1.0e-3
wall = false
[time]
end = 0.0004
dt_max = 1.0e-4
scheme = "euler"
[[bodies]]
position = [0.0, 0.0, 0.0]
deformable = true
shear_modulus = 10.0
mesh = { shape = "sphere", radius = 5.0e-6, subdivisions = 2 }
"""


def test_a_deformable_cell_in_shear_takes_and_keeps_the_quasi_static_shape():
    """k = 4: D within 2 % of 5 Ca / 4 (1.2 % measured, the elastic solve's discretisation)
    from the first step on, the inclination pi / 4 - Omega dt to 1e-3 rad, the cell spinning
    at gdot / 2 to 1 %; the body's mesh at the state is the displaced one."""
    mesh = wb.mesh.sphere(A, 4)
    flow = Flow(100.0, 1e-3, False)
    model = Model([mesh], [False], flow, interactions=[Deformation([mesh], [True], [10.0], [0.33], flow)],
                  policy=StepPolicy(DT, 1e-6, 1e-9), scheme="euler")
    sim = Simulator(model)
    state = model.initial_state([[0.0, 0.0, 0.0]])
    for _ in range(3):
        state, frame = sim.step(state)
        spin = frame.angular_velocity[0, 1]
        assert frame.derived["taylor_deformation"][0] == pytest.approx(1.25 * CA, rel=2e-2)
        assert frame.derived["inclination_angle"][0] == pytest.approx(np.pi / 4 - spin * DT, abs=1e-3)
    assert spin == pytest.approx(50.0, rel=1e-2)
    shaped = model.bodies(state)[0].mesh
    assert shaped is not mesh and np.abs(shaped.nodes - mesh.nodes).max() > 0.5 * 1.25 * CA * A


def test_a_deformable_run_is_written_resumed_and_played(tmp_path):
    """The run file carries the node displacements and the shape columns; a resumed run repeats
    the uninterrupted one; warpbem xdmf plays the deformed meshes."""
    path = tmp_path / "cell.toml"
    path.write_text(SCENE)
    straight, split = tmp_path / "straight.h5", tmp_path / "split.h5"
    assert cli.main(["run", str(path), "--output", str(straight)]) == 0
    assert cli.main(["run", str(path), "--output", str(split), "--set", "time.end=0.0002"]) == 0
    assert cli.main(["run", "--resume", "--output", str(split), "--set", "time.end=0.0004"]) == 0
    with h5py.File(straight) as a, h5py.File(split) as b:
        for column, scale in (("position", A), ("orientation", 1.0), ("deformation_node_displacement", A),
                              ("taylor_deformation", 1.0)):
            np.testing.assert_allclose(b[column][:], a[column][:], rtol=0, atol=1e-10 * scale)
        assert a["taylor_deformation"][-1, 0] == pytest.approx(1.25 * CA, rel=0.1)  # k = 2
    xdmf.write(straight)
    with h5py.File(straight.with_suffix(".xdmf.h5")) as f:
        first, last = f["xdmf/nodes/frame000000"][:], f["xdmf/nodes/frame000004"][:]
    assert np.abs(np.linalg.norm(last, axis=1) - np.linalg.norm(first, axis=1)).max() > 0.5 * 1.25 * CA * A


@pytest.mark.parametrize("override, message", [
    ("bodies.0.shear_modulus=-1.0", r"bodies.0.shear_modulus: -1 is outside"),
    ("bodies.0.fixed=true", r"bodies.0.deformable: a deformable body must be free"),
    ("bodies.0.poisson_ratio=0.5", r"bodies.0.poisson_ratio: 0.5 is outside the allowed range"),
    ("physics.adhesion=true flow.wall=true", r"deformable cells are not coupled to adhesion yet"),
])
def test_deformable_scene_keys_are_checked_by_name(tmp_path, override, message):
    path = tmp_path / "cell.toml"
    path.write_text(SCENE)
    with pytest.raises(scene.SceneError, match=message):
        scene.load(path, override.split())


def test_a_deformable_body_needs_its_modulus(tmp_path):
    path = tmp_path / "cell.toml"
    path.write_text(SCENE.replace("shear_modulus = 10.0\n", ""))
    with pytest.raises(scene.SceneError, match="give its shear_modulus"):
        scene.load(path)
