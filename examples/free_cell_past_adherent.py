"""A free cell carried past an adherent one in wall shear flow (thesis ch. 5): its velocity and
spin at a row of positions along the flow, and far from the adherent cell, where it moves as a
lone sphere in wall shear (Goldman, Cox & Brenner 1967).

    python examples/free_cell_past_adherent.py            # k = 4 cells, 9 positions

Prints a table (x in um, U in um/s, Omega in rad/s) and returns the rows.
"""

import numpy as np

import warpbem as wb

RADIUS = 5e-6          # m
HEIGHT = 7.75e-6       # m: the free cell's centre above the wall (h/a = 1.55)
GLANCE = 10.5e-6       # m: its lateral offset from the adherent cell (thesis fig. 5.14)
SHEAR_RATE = 100.0     # 1/s
VISCOSITY = 1.2e-3     # Pa s


def free_cell_velocities(positions_x, subdivisions=4, device="cpu"):
    """(x, U (m/s), Omega_y (rad/s)) of the free cell at each x (m), beside an adherent sphere held
    fixed at the origin, 250 nm above the wall."""
    sphere = wb.mesh.sphere(RADIUS, subdivisions)
    adherent = wb.Body(sphere, position=(0.0, 0.0, RADIUS + 0.25e-6), fixed=True)
    solver = wb.MobilitySolver(shear_rate=SHEAR_RATE, viscosity=VISCOSITY, device=device)
    rows = []
    for x in positions_x:
        sol = solver.solve([wb.Body(sphere, position=(x, GLANCE, HEIGHT)), adherent])
        rows.append((x, sol.velocity[0, 0], sol.angular_velocity[0, 1]))
    return rows


def main(subdivisions=4, positions_x=tuple(np.linspace(-40e-6, 40e-6, 9)) + (-2e-3,)):
    rows = free_cell_velocities(positions_x, subdivisions)
    print(" x [um] | U [um/s] | Omega_y [rad/s]")
    for x, u, omega in rows:
        print(f"{x * 1e6:7.1f} | {u * 1e6:8.2f} | {omega:7.3f}")
    return rows


if __name__ == "__main__":
    main()
