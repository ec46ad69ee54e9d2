"""warpbem: boundary-element Stokes flow of rigid (and, later, elastic) cells above a no-slip
wall, on NVIDIA Warp. Importing the package compiles nothing and touches no device."""

from . import mesh, units
from .body import Body
from .linalg import ConvergenceError
from .mesh import MeshError
from .mobility import ContactResolutionWarning, MobilitySolution, MobilitySolver, solve_mobility
from .placement import PlacementError

__version__ = "0.1.0"
__all__ = ["mesh", "units", "Body", "solve_mobility", "MobilitySolver", "MobilitySolution", "ConvergenceError",
           "MeshError", "PlacementError", "ContactResolutionWarning", "__version__"]
