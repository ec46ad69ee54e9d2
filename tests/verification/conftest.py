"""Helpers for the verification tests: solves in units a = mu = 1 (SI values of 1)."""

import numpy as np
import pytest

import warpbem as wb


@pytest.fixture(scope="session")
def sphere_mesh():
    """Meshes of the unit sphere by subdivisions k (k = 4 is the seed's 96 elements)."""
    cache = {}

    def get(k):
        if k not in cache:
            cache[k] = wb.mesh.sphere(1.0, k)
        return cache[k]

    return get


def resistance(mesh, position, motion, wall=True, **options):
    """Holding force and torque of a body moved rigidly with motion = (U, Omega); ``options``:
    fields of ``wb.SolverOptions``."""
    body = wb.Body(mesh, position=position, fixed=True, velocity=motion[:3], angular_velocity=motion[3:])
    sol = wb.solve_mobility([body], viscosity=1.0, wall=wall, options=wb.SolverOptions(**options))
    return sol.force[0], sol.torque[0]


def grand_resistance(mesh, position, orientation=(1, 0, 0, 0), wall=True, **options):
    """6x6 matrix mapping (U, Omega) to the holding (F, T); columns from six solves."""
    columns = []
    for k in range(6):
        motion = np.zeros(6)
        motion[k] = 1.0
        body = wb.Body(mesh, position=position, orientation=orientation, fixed=True,
                       velocity=motion[:3], angular_velocity=motion[3:])
        sol = wb.solve_mobility([body], viscosity=1.0, wall=wall, options=wb.SolverOptions(**options))
        columns.append(np.concatenate([sol.force[0], sol.torque[0]]))
    return np.array(columns).T
