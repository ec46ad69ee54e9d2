"""Dynamics layer: the static Model, the time-varying State, the step pipeline (Simulator)
and the integrators (DESIGN.md §3)."""

from .frame import Column, Frame, frame_columns
from .model import Flow, Model, SolverOptions, StepPolicy
from .simulator import Simulator
from .state import State

__all__ = ["Column", "Flow", "Frame", "Model", "Simulator", "SolverOptions", "State", "StepPolicy", "frame_columns"]
