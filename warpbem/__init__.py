"""warpbem: boundary-element Stokes flow of rigid and linearly elastic cells above a no-slip
wall, on NVIDIA Warp. Importing the package compiles nothing and touches no device.

Layers (each imports only those before it): ``surfaces`` (meshes, bodies, gaps) ->
``hydro`` (operators, GMRES, mobility) and ``forces`` (interactions) -> ``elastic`` (interior
elasticity, deformable cells) -> ``dynamics`` (Model, State, the step) -> ``app`` (scene files,
runs, sweeps, output, command line)."""

from . import units
from .app.run import run
from .app.scene import RunSettings, Scene, SceneError
from .app.scene import load as load_scene
from .dynamics.frame import Frame
from .dynamics.model import Model, StepPolicy
from .dynamics.simulator import Simulator
from .dynamics.state import State
from .elastic.deformable import Deformation, DeformationOptions
from .forces.adhesion import Adhesion
from .forces.bond_model import BondOptions
from .forces.external import ExternalLoads, Gravity
from .forces.repulsion import Repulsion
from .elastic.deformable import DeformationError, DeformationWarning
from .hydro.accuracy import AccuracyWarning, ChosenSettings
from .hydro.frozen import FrozenArraySolver
from .hydro.linalg import ConvergenceError
from .hydro.mobility import ContactResolutionWarning, MobilitySolution, MobilitySolver, solve_mobility
from .hydro.traction import TractionSolution, solve_traction
from .hydro.options import Flow, SolverOptions
from .hydro.treecode import TreecodeOptions
from .surfaces import mesh
from .surfaces.body import Body
from .surfaces.mesh import MeshError
from .surfaces.placement import PlacementError
from .runtime import DeviceError

__version__ = "0.1.0"
__all__ = ["mesh", "units", "Model", "State", "Simulator", "StepPolicy", "Frame", "Scene", "RunSettings", "load_scene",
           "run", "SceneError", "Gravity", "ExternalLoads", "Repulsion", "Adhesion", "BondOptions", "Deformation",
           "DeformationOptions", "Body", "Flow", "SolverOptions", "solve_mobility", "MobilitySolver", "FrozenArraySolver",
           "MobilitySolution", "solve_traction", "TractionSolution", "TreecodeOptions", "ConvergenceError", "DeformationError", "DeformationWarning",
           "MeshError", "PlacementError", "DeviceError", "ContactResolutionWarning", "AccuracyWarning", "ChosenSettings", "__version__"]
