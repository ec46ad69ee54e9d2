"""The state of an adhesive run from its trajectory (Chang, Tees & Hammer 2000, PNAS 97:11262:
the adhesion state diagram), for ``warpbem sweep`` results and ``scenes/state_diagram.py``.

Rule (documented, applied to each adhesive free cell): over the last half of the run, the mean
velocity along the flow V = (x(t_end) - x(t_mid)) / (t_end - t_mid) is compared with the
cell's velocity without bonds V_h (its velocity in the first frame, before any bond forms):

    firm adhesion    V < FIRM * V_h          (under 1 %: 3.5 um/s for a 5 um cell in 100 1/s)
    rolling          FIRM * V_h <= V < FREE * V_h, with bonds in the last half
    no adhesion      V >= FREE * V_h (at least half the free velocity), or no bond in the last half

Chang et al. (2000) separate the same three states by the mean velocity relative to the
hydrodynamic one (and add "transient adhesion" between rolling and no adhesion, which this
rule counts as rolling when bonds slow the cell below half its free velocity).
"""

from __future__ import annotations

import numpy as np

FIRM = 0.01
FREE = 0.5
STATES = ("no adhesion", "rolling", "firm adhesion")


def classify(time, x, bonds, free_velocity) -> tuple[str, float]:
    """(state, V / V_h) of one cell: ``time`` (s) and ``x`` (m) of its frames, its bond count per
    frame and its velocity without bonds (m/s)."""
    time, x, bonds = (np.asarray(a, dtype=float) for a in (time, x, bonds))
    if len(time) < 3 or not free_velocity > 0:
        raise ValueError("classify needs at least 3 frames and a positive free velocity")
    late = time >= 0.5 * (time[0] + time[-1])
    first = int(np.argmax(late))
    ratio = (x[-1] - x[first]) / (time[-1] - time[first]) / free_velocity
    if ratio >= FREE or not np.any(bonds[late] > 0):
        return STATES[0], float(ratio)
    return (STATES[2] if ratio < FIRM else STATES[1]), float(ratio)
