"""Forces layer: interactions, each one object with the protocol of ``interaction.py``."""

from .adhesion import Adhesion, BondOptions
from .external import STANDARD_GRAVITY, ExternalLoads, Gravity
from .interaction import ImplicitCoordinates, Interaction, Loads
from .repulsion import Repulsion

__all__ = ["STANDARD_GRAVITY", "Adhesion", "BondOptions", "ExternalLoads", "Gravity", "ImplicitCoordinates", "Interaction", "Loads", "Repulsion"]
