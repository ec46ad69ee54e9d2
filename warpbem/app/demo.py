"""The default scene: a free cell passing a firmly adherent one in wall-bounded shear.

A free spherical cell (radius 5 um) at height 7.75 um and lateral offset (glance) 10.5 um is
placed at a row of streamwise positions x past a fixed spherical cell whose centre sits
5.25 um above the wall (thesis ch. 5.3). At each x the mobility problem is solved: the free
cell's velocity and spin, and the force and torque that hold the adherent cell. Shear rate
100 1/s, plasma viscosity 1.2 mPa s. (Time stepping the same scene is the trajectory; here we
tabulate the instantaneous velocities along the pass.)
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from .. import units
from ..hydro.mobility import MobilitySolver
from ..surfaces import mesh
from ..surfaces.body import Body
from .io import TableWriter


@dataclass(frozen=True)
class DemoScene:
    radius: float = 5 * units.um
    subdivisions: int = 4
    adherent_height: float = 5.25 * units.um
    free_height: float = 7.75 * units.um
    glance: float = 10.5 * units.um
    x_start: float = -30 * units.um
    x_stop: float = 30 * units.um
    positions: int = 25
    shear_rate: float = 100.0
    viscosity: float = 1.2 * units.cP


def run(output, device="cpu", scene: DemoScene = DemoScene(), progress=print):
    cell = mesh.sphere(scene.radius, scene.subdivisions)
    adherent = Body(cell, position=(0.0, 0.0, scene.adherent_height), fixed=True)
    xs = np.linspace(scene.x_start, scene.x_stop, scene.positions)
    columns = {
        "x": ("m", ()),
        "free_velocity": ("m/s", (3,)),
        "free_angular_velocity": ("rad/s", (3,)),
        "adherent_force": ("N", (3,)),
        "adherent_torque": ("N m", (3,)),
        "gmres_iterations": ("1", ()),
        "gmres_residual": ("1", ()),
        "wall_time": ("s", ()),
    }
    # the adherent cell never moves: its operator blocks are kept between positions
    solver = MobilitySolver(shear_rate=scene.shear_rate, viscosity=scene.viscosity, device=device)
    start = time.perf_counter()
    with TableWriter(output, columns, asdict(scene), device, title="warpbem demo: free cell passing an adherent cell") as out:
        progress(f"{'x [um]':>8} {'U [um/s]':>10} {'V [um/s]':>10} {'W [um/s]':>10} "
                 f"{'Omega_y [1/s]':>14} {'F_x adh. [pN]':>14} {'iters':>6} {'time [s]':>9}")
        for i, x in enumerate(xs):
            t0 = time.perf_counter()
            free = Body(cell, position=(x, scene.glance, scene.free_height))
            sol = solver.solve([free, adherent])
            elapsed = time.perf_counter() - t0
            out.append(x=x, free_velocity=sol.velocity[0], free_angular_velocity=sol.angular_velocity[0],
                       adherent_force=sol.force[1], adherent_torque=sol.torque[1],
                       gmres_iterations=sol.iterations, gmres_residual=sol.residual, wall_time=elapsed)
            u = sol.velocity[0] / units.um
            eta = (time.perf_counter() - start) / (i + 1) * (len(xs) - i - 1)
            progress(f"{x / units.um:8.2f} {u[0]:10.2f} {u[1]:10.3f} {u[2]:10.3f} "
                     f"{sol.angular_velocity[0, 1]:14.3f} {sol.force[1, 0] / units.pN:14.2f} "
                     f"{sol.iterations:6d} {elapsed:9.2f}   [{i + 1}/{len(xs)}, ETA {eta:.0f} s]")
    return output
