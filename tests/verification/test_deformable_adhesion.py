"""Adhesion on deformable cells (``warpbem/elastic/deformable.py``, "Adhesion"; thesis ch. 4.2):
the receptors ride on the displaced surface, the bonds' forces act at their tips, and a cell
whose displacement stays within the mobility snapshots' tolerance uses them.

* A linear displacement u = eps X of the surface moves every tip by eps applied to the surface
  point under it, which on a sphere of radius a is the tip pulled back radially by the
  roughness (a / (a + roughness) of it): exact for the mesh's interpolation of a linear field,
  up to the k = 4 mesh's distance from the sphere.
* The bonds' point loads sum to the bond force on the cell and sit at the world tips
  x_c + R (X_tip + u), u the displacement the gaps see (less the cell's own loads' part).
* A stiff cell (G = 4 kPa: its displacement ~0.1 nm, within the 2 nm snapshot lattice) is
  captured exactly as the rigid cell with the same Hertz patch; a soft one (G = 4 Pa) deforms
  by more than the lattice and is solved at every state.
"""

import numpy as np
import pytest

import warpbem as wb
from warpbem.dynamics.model import Flow, Model, SolverOptions, StepPolicy
from warpbem.dynamics.simulator import Simulator
from warpbem.elastic.deformable import Deformation
from warpbem.forces.adhesion import Adhesion
from warpbem.forces.bond_model import BondOptions
from warpbem.forces.external import STANDARD_GRAVITY, Gravity
from warpbem.forces.repulsion import Repulsion
from warpbem.surfaces.body import Body
from warpbem.surfaces.gaps import WALL
from warpbem.surfaces.mesh import Mesh

from .test_adhesion import MESH, REST_GAP, TABLE_4_1, A  # the rolling cell of the adhesion tests


def test_receptors_ride_on_the_displaced_surface():
    mesh = wb.mesh.sphere(5e-6, 4)
    bonds = Adhesion(BondOptions(**TABLE_4_1))
    adhesion = Model([mesh], [False], interactions=[bonds]).bound("bond")  # the host view: tips, no device
    eps = np.array([[0.01, 0.004, 0.0], [0.004, -0.006, 0.002], [0.0, 0.002, -0.004]])
    deformed = Body(Mesh(mesh.nodes + mesh.nodes @ eps.T, mesh.elements), position=(0.0, 0.0, 6e-6))
    moved = adhesion.tips_at([deformed]) - adhesion.tips
    surface = adhesion.tips * 5e-6 / (5e-6 + adhesion.roughness)
    np.testing.assert_allclose(moved, surface @ eps.T, rtol=0, atol=2e-3 * 0.01 * 5e-6)
    assert adhesion.tips_at([Body(mesh)]) is adhesion.tips  # an undeformed cell: the reference tips


def rolling_model(shear_modulus, deformable):
    gravity = Gravity([1050.0], 1000.0, STANDARD_GRAVITY)
    bonds = Adhesion(BondOptions(**TABLE_4_1, seed=3), shear_modulus=[shear_modulus])
    flow = Flow(100.0, 1e-3)
    shape = [Deformation([True], [shear_modulus], [0.33])] if deformable else []
    return Model([MESH], [False], flow, interactions=[gravity, Repulsion(), bonds, *shape],
                 solver=SolverOptions(reuse_tolerance=2e-9), policy=StepPolicy(2e-5, 1e-7, 1e-9), scheme="euler")


def capture(model, steps):
    sim = Simulator(model)
    state = model.initial_state([[0.0, 0.0, A + REST_GAP]])
    frames = []
    for _ in range(steps):
        state, frame = sim.step(state)
        frames.append(frame)
    return sim, state, frames


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
@pytest.mark.filterwarnings("ignore::warpbem.DeformationWarning")
def test_a_stiff_deformable_cell_is_captured_as_the_rigid_one_and_its_bonds_load_it_at_their_tips():
    """40 steps of 20 us: same bonds, velocity within 2e-3 of the rigid cell's free velocity
    after the first step (in which the cell, released undeformed, takes its shape: its surface
    slip moves it at 1.9 % of its velocity then; 1.1e-3 measured after it, a lateral wobble that
    decays by 5 % a step), the displacement below the snapshot lattice (snapshots used); the
    bonds' point loads of the last state sum to the bond force and sit at the tips of the bonded
    receptors."""
    rigid = capture(rolling_model(4e3, False), 40)[2]
    sim, state, frames = capture(rolling_model(4e3, True), 40)
    assert frames[-1].parts["bond"]["count"][0] >= 2
    free = rigid[0].velocity[0, 0]
    for r, d in zip(rigid, frames):
        assert d.parts["bond"]["count"][0] == r.parts["bond"]["count"][0]
    for r, d in zip(rigid[1:], frames[1:]):
        np.testing.assert_allclose(d.velocity[0], r.velocity[0], rtol=0, atol=2e-3 * free)
    assert 0 < np.abs(state.parts["deformation"]["node_displacement"]).max() < 2e-9
    assert sim.hydro.snapshots_solved > 0
    evaluation = sim.evaluate(state)
    dt = evaluation.planned_dt
    _, points = evaluation.step_loads(dt)
    bond_rows = next(where for x, where in evaluation.implicit.owners if x.name == "bond")
    magnitudes = evaluation.implicit_step(dt)[1][bond_rows]
    bonds = evaluation.implicit.coordinates.part(bond_rows)
    expected = bonds.loads(magnitudes).force[0]
    on_tips = bonds.point_loads(magnitudes)
    assert len(on_tips) == np.count_nonzero(magnitudes) and all(b == 0 and o == WALL for b, o, _, _ in on_tips)
    np.testing.assert_allclose(sum(f for _, _, _, f in on_tips), expected, rtol=1e-10)
    assert len(points) > len(on_tips)  # the step's point loads: the bonds' and the repulsion's
    body = sim.model.bodies(state, contact=True)[0]  # the tips ride on the shape the gaps see
    rows = np.flatnonzero(state.parts["bond"]["receptor"] >= 0)
    receptors = state.parts["bond"]["receptor"][rows].astype(int)
    world_tips = body.position + sim.model.bound("bond").tips_at([body])[receptors] @ body.rotation().T
    world_tips[:, 2] += state.parts["bond"]["offset"][rows]  # the Hertz patch's lowering of the tip
    for _, _, point, _ in on_tips:
        assert np.linalg.norm(world_tips - point, axis=1).min() < 1e-15
