"""The dynamics layer (DESIGN.md §3): Model and State validation, the step as a pipeline (gaps
searched once per state, one solve per stage, the implicit repulsion by linearity), frames that
describe their own state, runs that land on their end and frame times, and state owned by an
interaction carried through steps, frames and files."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.app.io import TableWriter
from warpbem.app.run import read_state
from warpbem.dynamics import Flow, Model, Simulator, SolverOptions, State, StepPolicy, frame_columns
from warpbem.forces import STANDARD_GRAVITY, BoundInteraction, ExternalLoads, Gravity, Interaction, Loads, Repulsion

A = 5e-6
SPHERE = wb.mesh.sphere(A, 2)


def test_model_and_state_refuse_what_cannot_run():
    with pytest.raises(ValueError, match="one flag per mesh"):
        Model([SPHERE], [False, True])
    with pytest.raises(ValueError, match="scheme must be one of"):
        Model([SPHERE], [False], scheme="rk4")
    with pytest.raises(ValueError, match="names must be unique"):
        Model([SPHERE], [False], interactions=[Repulsion(), Repulsion()])

    with pytest.raises(ValueError, match="viscosity"):
        Flow(1.0, -1.0)
    # an interaction is checked against the bodies when the model is made
    with pytest.raises(ValueError, match="densities must be"):
        Model([SPHERE], [False], interactions=[Gravity([-1.0])])
    with pytest.raises(ValueError, match="densities must be 2 positive numbers"):
        Model([SPHERE, SPHERE], [False, True], interactions=[Gravity([1050.0])])
    with pytest.raises(ValueError, match="body 1 is fixed"):
        Model([SPHERE, SPHERE], [False, True],
              interactions=[ExternalLoads([[0, 0, 0], [1e-12, 0, 0]], np.zeros((2, 3)))])
    with pytest.raises(ValueError, match=r"positions \(n, 3\) and orientations \(n, 4\)"):
        State(0.0, np.zeros((2, 3)), np.zeros((1, 4)))
    with pytest.raises(ValueError, match="not finite"):
        State(float("nan"), np.zeros((1, 3)), [[1, 0, 0, 0]])
    model = Model([SPHERE], [False])
    with pytest.raises(ValueError, match="the state has 2 bodies, the model 1"):
        model.bodies(State(0.0, np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 1))))


def passing_cells(scheme="heun", repulsion=None, dt_max=2e-3):
    """A free cell of 1.05 g/cc passing a held one in wall shear (thesis ch. 5 in small)."""
    gravity = Gravity([1050.0, 1050.0], 1000.0, STANDARD_GRAVITY)
    interactions = [gravity] + ([repulsion] if repulsion else [])
    model = Model([SPHERE, SPHERE], [False, True], Flow(100.0, 1.2e-3), interactions=interactions,
                  solver=SolverOptions(contact_refinement=0.0), policy=StepPolicy(dt_max, 1e-5, 0.5e-6),
                  scheme=scheme)
    state = model.initial_state([[-12e-6, 4e-6, 8e-6], [0.0, 0.0, 5.5e-6]])
    return model, state


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
@pytest.mark.parametrize("scheme, solves_per_step", [("euler", 1), ("heun", 2)])
def test_a_frame_is_solved_at_its_own_positions_at_no_extra_cost(scheme, solves_per_step):
    """Every frame's velocities and holding loads are those of ``solve_mobility`` at the frame's
    positions with the frame's loads (to the GMRES tolerance), not those of the stage before it;
    and writing the frame costs no solve: the end state's solve is the next step's first stage
    (Euler: one solve per step, Heun: two, plus one for the first frame)."""
    model, state = passing_cells(scheme)
    sim = Simulator(model)
    calls = []
    solve, solve_loads = sim.mobility.solve, sim.mobility.solve_loads
    sim.mobility.solve = lambda *args, **kwargs: calls.append(1) or solve(*args, **kwargs)
    # a batch of k loads counts k solves (its columns share one GMRES)
    sim.mobility.solve_loads = lambda bodies, forces, *args, **kwargs: (
        calls.extend([1] * len(forces)) or solve_loads(bodies, forces, *args, **kwargs))
    frames = [sim.frame(state)]
    for _ in range(3):
        state, frame = sim.step(state)
        frames.append(frame)
    assert len(calls) == 1 + 3 * solves_per_step
    weight = model.bound("gravity").force
    for previous, frame in zip(frames, frames[1:]):
        bodies = model.bodies(State(frame.time, frame.positions, frame.orientations))
        exact = wb.solve_mobility(bodies, 100.0, 1.2e-3, forces=weight, options=wb.SolverOptions(contact_refinement=0.0, density_order=model.solver.density_order))
        np.testing.assert_allclose(frame.force[1], exact.force[1], rtol=1e-6)
        np.testing.assert_allclose(frame.velocity[0], exact.velocity[0], rtol=1e-6)
        # the test can fail: the previous frame's holding load differs far beyond that
        assert np.abs(previous.force[1] - exact.force[1]).max() > 1e-3 * np.abs(exact.force[1]).max()
        assert frame.dt == pytest.approx(frame.time - previous.time, rel=1e-12)
    np.testing.assert_array_equal(frames[-1].positions, state.positions)


class CountingFinder:
    """Wraps a GapFinder, counting the searches of each pair in each configuration."""

    def __init__(self, finder):
        self.finder, self.counts = finder, {}

    def between(self, bodies, i, j):
        self._count(bodies, i, j)
        return self.finder.between(bodies, i, j)

    def to_wall(self, bodies, indices):
        for i in indices:
            self._count(bodies, i, "wall")
        return self.finder.to_wall(bodies, indices)

    def _count(self, bodies, i, j):
        key = (tuple(b.position.tobytes() for b in bodies), i, j)
        self.counts[key] = self.counts.get(key, 0) + 1


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_gaps_are_searched_once_per_state_and_retries_cost_no_solve():
    """A cell settling onto the wall with repulsion: the step-size rule, the repulsion and the
    frame's closest_gap share one gap search per pair and state; a contact adds one solve (its
    unit force's motion) to each evaluation, and the implicit force for any step length follows
    from those solves without another."""
    m = wb.mesh.sphere(A, 2)
    gravity = Gravity([1050.0], 1000.0, STANDARD_GRAVITY)
    model = Model([m], [False], Flow(0.0, 1.2e-3), interactions=[gravity, Repulsion()],
                  solver=SolverOptions(contact_refinement=0.0), policy=StepPolicy(0.05, 1e-6, 1e-9))
    sim = Simulator(model)
    sim.gaps = CountingFinder(sim.gaps)
    state = model.initial_state([[0.0, 0.0, 0.25e-6 - m.nodes[:, 2].min()]])
    calls = []
    solve, solve_loads = sim.mobility.solve, sim.mobility.solve_loads
    sim.mobility.solve = lambda *args, **kwargs: calls.append(1) or solve(*args, **kwargs)
    # a batch of k loads counts k solves (its columns share one GMRES)
    sim.mobility.solve_loads = lambda bodies, forces, *args, **kwargs: (
        calls.extend([1] * len(forces)) or solve_loads(bodies, forces, *args, **kwargs))
    for _ in range(3):
        state, frame = sim.step(state)
    assert sim.gaps.counts and max(sim.gaps.counts.values()) == 1
    assert len(calls) == 2 * (1 + 3 * 2)  # background + one contact, per evaluation (Heun)
    start = sim.evaluate(state)
    before = len(calls)
    short, long = start.motion(1e-4)[0][0, 2], start.motion(1e-1)[0][0, 2]
    assert len(calls) == before and short != long  # backward Euler over different steps
    assert frame.loads["repulsion"].force[0, 2] > 0 and frame.closest_gap < 0.25e-6


def test_runs_land_on_their_end_and_frame_times(tmp_path):
    """Steps never jump over a frame time: with frames every 0.25 s the stepping lands on 0.25 and
    0.5 s and ends on time.end = 0.6 s exactly, in equal steps no longer than dt_max."""
    from warpbem.app import run

    from .test_scene import BASE, write

    table = {**BASE, "time": {"end": 0.6, "dt_max": 0.2, "dt_min": 0.05, "contact_gap": 1e-6,
                              "frame_interval": 0.25}}
    out = tmp_path / "frames.h5"
    final = run.run(write(tmp_path, table), out, progress=lambda line: None)
    import h5py

    with h5py.File(out) as f:
        assert f["time"][:].tolist() == [0.0, 0.25, 0.5, 0.6]
        assert f["steps"][:].tolist() == [0, 2, 4, 5] and np.all(f["dt"][1:] <= 0.2)
        assert f["time"].attrs["unit"] == "s" and "this frame's positions" in f["velocity"].attrs["description"]
    assert final.time == 0.6
    assert StepPolicy.landing(0.2, 0.6) == pytest.approx(0.2) and StepPolicy.landing(0.25, 0.6) == pytest.approx(0.2)
    assert StepPolicy.landing(0.2, 0.1) == 0.1 and StepPolicy.landing(0.2, np.inf) == 0.2


class Odometer(Interaction):
    """An interaction that owns state: the distance each reference point has travelled (m)."""

    name = "odometer"

    def bound(self, model, device=None):
        return TravelledDistance(self, model, device)


class TravelledDistance(BoundInteraction):
    """The odometer on a model's bodies: one distance per body."""

    def state_columns(self):
        return {"distance": ("m", (self.model.n_bodies,))}

    def initial_state(self, bodies):
        return {"distance": np.zeros(len(bodies))}

    def advance_state(self, part, start_bodies, end_bodies, end_contacts, dt, end_time):
        travelled = [np.linalg.norm(b.position - a.position) for a, b in zip(start_bodies, end_bodies)]
        return {"distance": part["distance"] + travelled}


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_an_interaction_s_own_state_is_stepped_framed_and_read_back(tmp_path):
    """The documented way for an interaction to own state (forces/interaction.py): its part of the
    State starts from initial_state, advances after each accepted step, is written in every
    frame as <name>_<column> and is read back from the file exactly (what a resumed run needs)."""
    model, state = passing_cells("euler")
    model = Model(model.meshes, model.fixed, model.flow, model.interactions + (Odometer(),), model.solver,
                  model.policy, model.scheme)
    state = model.initial_state(state.positions)
    assert list(state.parts) == ["odometer"] and state.parts["odometer"]["distance"].tolist() == [0.0, 0.0]
    sim = Simulator(model)
    columns = frame_columns(model)
    assert columns["odometer_distance"].shape == (2,) and columns["odometer_distance"].unit == "m"
    path, total = tmp_path / "own_state.h5", np.zeros(2)
    with TableWriter(path, columns, {}, "cpu") as writer:
        writer.append(**sim.frame(state).columns())
        for _ in range(3):
            new, frame = sim.step(state)
            total += np.linalg.norm(new.positions - state.positions, axis=1)
            state = new
            writer.append(**frame.columns())
    np.testing.assert_allclose(state.parts["odometer"]["distance"], total, rtol=1e-14)
    assert total[0] > 0 and total[1] == 0  # the held cell does not move
    import h5py

    with h5py.File(path) as f:
        back = read_state(f, model, 3)
    assert back.time == state.time and back.steps == state.steps == 3
    np.testing.assert_array_equal(back.positions, state.positions)
    np.testing.assert_array_equal(back.parts["odometer"]["distance"], state.parts["odometer"]["distance"])


@pytest.mark.filterwarnings("ignore::warpbem.ContactResolutionWarning")
def test_rigid_scenes_build_no_traction_or_elastic_operator(monkeypatch):
    """Model no more than a scene needs (issue 10 item 9): a rigid cell settling in shear with
    repulsion and an adherent neighbour assembles double layers only, never the adjoint
    (traction), single-layer or elastic operators."""
    from warpbem.hydro.operators import DiscreteOperator

    kinds = []
    original = DiscreteOperator.__init__

    def recording(self, description, *args, **kwargs):
        kinds.append(description.kind)
        original(self, description, *args, **kwargs)

    monkeypatch.setattr(DiscreteOperator, "__init__", recording)
    m = wb.mesh.sphere(A, 2)
    gravity = Gravity([1050.0, 1000.0], 1000.0, STANDARD_GRAVITY)
    model = Model([m, m], [False, True], Flow(100.0, 1.2e-3), interactions=[gravity, Repulsion()],
                  policy=StepPolicy(0.01, 1e-6, 1e-9))
    sim = Simulator(model)
    state = model.initial_state([[0.0, 0.0, 1.5 * A], [3 * A, 0.0, 1.2 * A]])
    for _ in range(2):
        state, _ = sim.step(state)
    assert kinds and set(kinds) == {"double_layer"}


def test_the_simulator_binds_device_state_to_its_own_copies():
    """Per-device state (compiled kernels, assembled elastic operators) lives in the simulator's
    bindings of the interactions (Interaction.bound), which read the model's meshes: the
    configurations are frozen, the model's own host view holds no device data and refuses to
    step, so one model serves several simulators."""
    import dataclasses

    from warpbem.elastic.deformable import Deformation

    cell = wb.mesh.sphere(5e-6, 2)
    flow = Flow(100.0, 1.2e-3, wall=False)
    model = Model([cell], [False], flow, interactions=[Deformation([True], [4e3], [0.33])])
    first, second = Simulator(model), Simulator(model)
    host = model.bound("deformation")
    assert host.elastic == {} and host.meshes is model.meshes  # nothing assembled for the model's view
    assert all(0 in sim.interactions[0].elastic and sim.interactions[0].model is model for sim in (first, second))
    assert first.interactions[0] is not host and first.interactions[0] is not second.interactions[0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.interaction("deformation").shear_modulus = (1e3,)
    state = model.initial_state([[0.0, 0.0, 0.0]])
    with pytest.raises(RuntimeError, match="bound without a device"):
        host.advance_shape(state.parts["deformation"], model.bodies(state), Loads.zero(1),
                           state.orientations, 1e-4, [])
    assert np.array_equal(first.step(state)[0].positions, second.step(state)[0].positions)
