"""Deformable cells in time: the quasi-static linear elastic model (thesis ch. 2.2 C, ch. 2.3).

Model. A deformable cell's surface at a state is its rigid placement (position x_c,
orientation R) of its reference mesh displaced in its body frame:

    x = x_c + R (X + u(X)),

u the node displacement of the state (``nodal_displacement`` of the element values). The flow
sees the deformed surface as a rigid body at that instant (its mobility is solved on it). At
each accepted step the displacement of the step's end follows from the start state: the
traction the fluid exerts on every body there (``solve_traction``, closed by each body's total
external load, the start frame's force and torque), turned into the body frame and solved by
the interior elastic problem on the reference mesh (``interior.py``), u_(n+1) = E[R_n^T t_n].

Assumptions and limits. Linear elasticity (small strains: D << 1, i.e. Ca = mu gdot / G << 1).
Quasi-static: the cell is at elastic equilibrium with the traction at every instant, which
holds when the elastic relaxation is fast against the flow (viscous number mu gdot / G small;
the cell's own internal viscosity is not modelled), and the displacement lags the traction by
one step (first order in dt): the shape solved at the start is carried by the step's rigid
rotation, so a cell spinning at Omega in shear shows its inclination Omega dt behind (45
degrees - Omega dt; 42.1 degrees with 1 ms steps at 100 1/s, 44.7 with 0.1 ms). The material
does not circulate: the shape is re-solved in the rotated frame each step, so a steady shape
in shear (45 degrees, D = 5 Ca / 4 as Ca -> 0) is reached at once and tank-treading of the
material points, which needs the cell's interior kinematics, is not represented. The traction
includes the fluid's only (contact tractions are for the adhesion coupling, not wired here).
"""

from __future__ import annotations

import numpy as np

from ..forces.interaction import Interaction
from ..hydro.traction import solve_traction
from ..surfaces.body import rotation_matrix
from ..surfaces.mesh import Mesh
from .interior import InteriorElasticity, check_material
from .shape import nodal_displacement, shear_plane_deformation


class Deformation(Interaction):
    """Quasi-static linear elastic deformation of the ``deformable`` bodies (module docstring):
    per body ``shear_modulus`` (Pa) and ``poisson_ratio``; ``flow`` the model's ``Flow``."""

    name = "deformation"
    shapes_bodies = True

    def __init__(self, meshes, deformable, shear_modulus, poisson_ratio, flow, *, quadrature_order: int = 2,
                 contact_refinement: float = 3.0):
        self.meshes = list(meshes)
        self.deformable = np.asarray(deformable, dtype=bool)
        if len(self.deformable) != len(self.meshes) or not self.deformable.any():
            raise ValueError("deformable must flag each body, at least one of them")
        for i in np.flatnonzero(self.deformable):
            check_material(shear_modulus[i], poisson_ratio[i])
        self.flow = flow
        self.contact_refinement = contact_refinement
        self.quadrature_order = quadrature_order
        self.shear_modulus, self.poisson_ratio = list(shear_modulus), list(poisson_ratio)
        self.max_nodes = max(len(m.nodes) for m in self.meshes)
        self.device = "cpu"
        self.elastic = {}

    def prepare(self, device) -> None:
        self.device = device
        # assembled once per cell, in its body frame (they depend on the reference shape only)
        self.elastic = {i: InteriorElasticity(self.meshes[i], self.shear_modulus[i], self.poisson_ratio[i], device,
                                              quadrature_order=self.quadrature_order)
                        for i in np.flatnonzero(self.deformable)}

    def state_columns(self):
        n = len(self.meshes)
        return {"node_displacement": ("m (body frame; rows past a mesh's nodes are zero)", (n, self.max_nodes, 3)),
                "orientation": ("1 (quaternion w, x, y, z of the shape measured)", (n, 4))}

    def initial_state(self, bodies):
        return {"node_displacement": np.zeros((len(self.meshes), self.max_nodes, 3)),
                "orientation": np.array([b.orientation for b in bodies])}

    def body_meshes(self, part, meshes):
        out = list(meshes)
        for i in np.flatnonzero(self.deformable):
            nodes = self.meshes[i].nodes
            out[i] = Mesh(nodes + part["node_displacement"][i, :len(nodes)], self.meshes[i].elements)
        return out

    def advance_shape(self, part, start_bodies, start_loads, end_orientations):
        if not self.elastic:
            self.prepare(self.device)
        traction = solve_traction(start_bodies, self.flow.shear_rate, self.flow.viscosity, self.flow.wall,
                                  start_loads.force, start_loads.torque, self.device,
                                  quadrature_order=self.quadrature_order, contact_refinement=self.contact_refinement)
        displacement = np.zeros_like(part["node_displacement"])
        for i, elastic in self.elastic.items():
            # each element's traction, in the body frame of the state it was solved at
            local = elastic.solve(traction.on_mesh(i) @ start_bodies[i].rotation())
            displacement[i, :len(self.meshes[i].nodes)] = nodal_displacement(self.meshes[i], local.displacement)
        return {"node_displacement": displacement, "orientation": np.array(end_orientations, dtype=float)}

    def derived_columns(self):
        n = len(self.meshes)
        return {"taylor_deformation": ("1", (n,), "D = (L - B) / (L + B) of each body's best-fit ellipsoid cut by"
                                       " the shear plane (x flow, z gradient)"),
                "inclination_angle": ("rad", (n,), "angle of that section's long axis from the flow direction")}

    def derived_values(self, part):
        d, angle = np.zeros(len(self.meshes)), np.zeros(len(self.meshes))
        for i, mesh in enumerate(self.meshes):
            nodes = (mesh.nodes + part["node_displacement"][i, :len(mesh.nodes)]) @ rotation_matrix(part["orientation"][i]).T
            d[i], angle[i] = shear_plane_deformation(nodes)
        return {"taylor_deformation": d, "inclination_angle": angle}
