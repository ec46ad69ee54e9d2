"""Forces layer: interactions, each a configuration bound to a model with the protocol of
``interaction.py``."""

from .adhesion import Adhesion
from .bond_model import BondOptions
from .external import STANDARD_GRAVITY, ExternalLoads, Gravity
from .interaction import BoundInteraction, ImplicitCoordinates, Interaction, Loads
from .repulsion import Repulsion

__all__ = ["STANDARD_GRAVITY", "Adhesion", "BondOptions", "BoundInteraction", "ExternalLoads", "Gravity", "ImplicitCoordinates", "Interaction", "Loads", "Repulsion"]
