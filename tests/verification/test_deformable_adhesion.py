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
  by more than the lattice and is solved at every state. Its displacement is Hooke's for the
  load it carries: the mean strain of any elastic body is its mean stress through the
  compliance, and the mean stress is the first moment of the surface traction (below).
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
from warpbem.surfaces import quad9
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


def capture(model, steps, solves=None):
    """``steps`` steps of ``model`` from the rolling cell's start; ``solves``, a list, records
    the body-frame traction (E, 3) of every elastic solve of the deformable cell, in order."""
    sim = Simulator(model)
    if solves is not None:
        elastic = next(x for x in sim.interactions if x.name == "deformation").elastic[0]
        solve = elastic.solve
        elastic.solve = lambda traction: solves.append(np.array(traction)) or solve(traction)
    state = model.initial_state([[0.0, 0.0, A + REST_GAP]])
    frames = []
    for _ in range(steps):
        state, frame = sim.step(state)
        frames.append(frame)
    return sim, state, frames


def hookes_mean_strain(mesh, traction, shear_modulus, poisson_ratio):
    """The mean strain of an elastic body of ``mesh`` under the balanced element traction
    (E, 3) Pa: the mean stress is the traction's first moment over the volume, sigma = (1/V)
    int sym(t x) dS (the average-stress theorem, from div sigma = 0 inside and sigma n = t on
    the surface by the divergence theorem; Nemat-Nasser & Hori 1993, Micromechanics), and the
    strain Hooke's, eps = (sigma - nu / (1 + nu) tr(sigma) I) / 2G: exact for any load."""
    positions, vector_weights = quad9.surface_quadrature(mesh.element_nodes(), 4)
    moments = np.einsum("eqi,eq->ei", positions, np.linalg.norm(vector_weights, axis=-1))  # int_e x dS
    first = traction.T @ moments / mesh.volume()
    stress = 0.5 * (first + first.T)
    return (stress - poisson_ratio / (1 + poisson_ratio) * np.trace(stress) * np.eye(3)) / (2 * shear_modulus)


def mean_strain(mesh, node_displacement):
    """(1/V) int sym(n u) dS = (1/V) int eps dV (divergence theorem) of the node displacement
    (n_nodes, 3) m, interpolated over the QUAD9 elements."""
    positions, vector_weights = quad9.surface_quadrature(mesh.element_nodes(), 4)
    moved, _ = quad9.surface_quadrature((mesh.nodes + node_displacement)[mesh.elements], 4)
    gradient = np.einsum("eqi,eqj->ij", vector_weights, moved - positions) / mesh.volume()
    return 0.5 * (gradient + gradient.T)


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
@pytest.mark.filterwarnings("ignore::warpbem.DeformationWarning")
def test_a_stiff_deformable_cell_is_captured_as_the_rigid_one_and_its_bonds_load_it_at_their_tips():
    """40 steps of 20 us: same bonds, velocity within 2e-3 of the rigid cell's free velocity
    after the first step (in which the cell, released undeformed, takes its shape: its surface
    slip moves it at 1.9 % of its velocity then; 1.1e-3 measured after it, a lateral wobble that
    decays by 5 % a step), the displacement below the snapshot lattice (snapshots used); the
    bonds' point loads of the last state sum to the bond force and sit at the tips of the bonded
    receptors.

    The displacement is tied to G = 4 kPa by Hooke's law for the mean strain
    (``hookes_mean_strain``: the average-stress theorem, exact for any traction): the node
    displacement of the last state (its step's target: tau = 3 mu / 2G = 0.4 us << dt) and its
    contact part each have the mean strain of the traction their elastic solve took (the step's
    total traction; the cell's own loads with the fluid's answer), to 15 % of its norm (6.6 % and
    5.9 % measured: the elastic solve's discretisation on the 24 elements of k = 2, 7.0 % for a
    uniform shear traction there and 2.5 % at k = 4). The norms are 8.2e-5 and 1.6e-5; the flow's
    part has eps_xz = 4.7e-5, 1.5 times the unbounded sphere's 5 mu gdot / 4G (Roscoe 1967) near
    the wall. A G off by 10 in the elastic solve is off by 90 % or 900 % here."""
    rigid = capture(rolling_model(4e3, False), 40)[2]
    solves = []
    sim, state, frames = capture(rolling_model(4e3, True), 40, solves)
    total, own = solves[-2:]  # the last step's: its target, then the contact part (the bonds load the cell)
    part = state.parts["deformation"]
    for traction, displacement in ((total, part["node_displacement"][0]), (own, part["contact_displacement"][0])):
        expected = hookes_mean_strain(MESH, traction, 4e3, 0.33)
        measured = mean_strain(MESH, displacement[:len(MESH.nodes)])
        assert np.linalg.norm(measured - expected) < 0.15 * np.linalg.norm(expected)
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
