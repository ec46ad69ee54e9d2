"""Time integration of rigid-body positions and orientations (thesis ch. 2.3: explicit Euler
in the seed; Heun's second-order predictor-corrector added here).

Orientations are unit quaternions (w, x, y, z). Over a step the angular velocity is taken as
constant, so the rotation is exact for it: q <- exp(Omega dt / 2) q, renormalised.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .state import State

SCHEMES = ("euler", "heun")
DEFAULT_SCHEME = "heun"  # second order: the thesis's trajectories need it near contact (docs/dynamics.md)


def quaternion_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of quaternions (w, x, y, z), row by row."""
    aw, av = a[..., :1], a[..., 1:]
    bw, bv = b[..., :1], b[..., 1:]
    return np.concatenate([aw * bw - np.sum(av * bv, axis=-1, keepdims=True),
                           aw * bv + bw * av + np.cross(av, bv)], axis=-1)


def rotate(orientations: np.ndarray, angular_velocity: np.ndarray, dt: float) -> np.ndarray:
    """Turn each orientation by the rotation of angular velocity Omega (rad/s) over dt."""
    angle = np.linalg.norm(angular_velocity, axis=-1, keepdims=True) * dt
    axis = np.divide(angular_velocity * dt, angle, out=np.zeros_like(angular_velocity), where=angle > 0)
    turn = np.concatenate([np.cos(0.5 * angle), np.sin(0.5 * angle) * axis], axis=-1)
    q = quaternion_multiply(turn, orientations)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def advance(state: State, velocity: np.ndarray, angular_velocity: np.ndarray, dt: float) -> State:
    """Move every body rigidly with the given velocities for dt (fixed bodies carry zeros)."""
    return replace(state, time=state.time + dt, positions=state.positions + velocity * dt,
                   orientations=rotate(state.orientations, angular_velocity, dt))


def step(state: State, velocities, dt: float, scheme: str = "heun") -> tuple[State, tuple]:
    """One step of ``scheme``; ``velocities(state) -> (U, Omega)`` evaluates the mobility.

    Returns the new state and the (U, Omega) used (Heun: the mean of its two stages).
    """
    if scheme not in SCHEMES:
        raise ValueError(f"scheme must be one of {SCHEMES}, got {scheme!r}")
    u1, w1 = velocities(state)
    if scheme == "euler":
        return advance(state, u1, w1, dt), (u1, w1)
    u2, w2 = velocities(advance(state, u1, w1, dt))
    u, w = 0.5 * (u1 + u2), 0.5 * (w1 + w2)
    return advance(state, u, w, dt), (u, w)
