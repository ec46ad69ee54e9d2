"""Forces layer: interactions, each one object with the protocol of ``interaction.py``."""

from .adhesion import Adhesion
from .external import STANDARD_GRAVITY, ExternalLoads, Gravity
from .interaction import ImplicitCoordinates, Interaction, Loads
from .repulsion import Repulsion

__all__ = ["STANDARD_GRAVITY", "Adhesion", "ExternalLoads", "Gravity", "ImplicitCoordinates", "Interaction", "Loads", "Repulsion"]
