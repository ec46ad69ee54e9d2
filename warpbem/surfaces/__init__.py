"""Surfaces layer: QUAD9 meshes and element maps, bodies, placement checks, exact gaps,
contact refinement and the adherent cell shapes."""
