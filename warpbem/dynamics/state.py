"""The time-varying part of a scene (DESIGN.md §3, §6.3): everything a step changes and a
resumed run needs, and nothing else (the static part is the ``Model``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class State:
    """time (s); positions (n, 3) m and orientations (n, 4) unit quaternions (w, x, y, z) of the
    bodies' reference points; ``steps``: steps taken since t = 0 (it sets the frame schedule
    and, with a seed, counter-based random streams); ``parts``: the state owned by interactions,
    {interaction name: {column: array}} (``forces/interaction.py`` says how an interaction adds
    its part).

    Examples
    --------
    >>> import warpbem as wb
    >>> state = wb.State(0.0, positions=[[0.0, 0.0, 6e-6]], orientations=[[1.0, 0.0, 0.0, 0.0]])
    >>> state.time, state.positions.shape, state.steps
    (0.0, (1, 3), 0)

    A model places its bodies and starts its interactions' own parts (``Model.initial_state``).
    """

    time: float
    positions: np.ndarray
    orientations: np.ndarray
    steps: int = 0
    parts: dict = field(default_factory=dict)

    def __post_init__(self):
        positions = np.array(self.positions, dtype=float)
        orientations = np.array(self.orientations, dtype=float)
        if positions.ndim != 2 or positions.shape[1] != 3 or orientations.shape != (len(positions), 4):
            raise ValueError(f"a state needs positions (n, 3) and orientations (n, 4), got {positions.shape}"
                             f" and {orientations.shape}")
        if not (np.all(np.isfinite(positions)) and np.all(np.isfinite(orientations)) and np.isfinite(self.time)):
            raise ValueError(f"state at t = {self.time!r} s is not finite")
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "orientations", orientations)
        object.__setattr__(self, "time", float(self.time))
        object.__setattr__(self, "steps", int(self.steps))
