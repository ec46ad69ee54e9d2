"""The interior elastic problem (thesis ch. 2.2 C, eq. 2.26-2.31): the displacement u of a
linearly elastic cell (shear modulus G, Poisson ratio nu) from the traction t on its surface,
by Somigliana's identity on the boundary (Betti's reciprocal theorem; Brebbia & Dominguez
1992), with the free-space Kelvinlet: the cell does not reach the wall (DESIGN.md §4), and
the wall's effect enters through the traction (``warpbem/hydro/traction.py``).

For xi on the surface, with r = x - xi and n the outward normal at x,

    (1/2) u(xi) + PV int p*(xi, x) u(x) dS(x) = int u*(xi, x) t(x) dS(x),

    u*(xi, x) = [(3 - 4 nu) I / r + r r^T / r^3] / (16 pi G (1 - nu))   (the Kelvinlet),
    p*(xi, x) = -[(1 - 2 nu) Q + 3 P] / (8 pi (1 - nu)),
    Q = [I (r.n) - (r n^T - n r^T)] / r^3,  P = r r^T (r.n) / r^5      (its traction).

The four kernels have no material constants (``kernels/assembly.py``: "inverse_distance",
"single_layer" for the Stokeslet (I / r + r r^T / r^3) / 8 pi, "elastic_rotation",
"elastic_dyadic"), so one compiled set serves every cell; G and nu only weight them. The
unknown is constant per element, collocated at the centres; the singular self element of the
double layer follows from the rigid-translation identity (1/2 + PV int p* dS = 0, as for the
Stokes double layer, thesis ch. 3.3), that of the weakly singular Kelvinlet from Duffy
triangles. The rigid motions are the eigenvalue -1 eigenfunctions (eq. 2.27-2.29): the
displacement is defined up to them, and Wielandt's deflation fixes it with <phi, u> = 0 for
the six orthonormal rigid modes (eq. 2.30-2.31), i.e. u is the deformation with no mean
translation or rotation. The traction must balance (the cell in equilibrium: zero resultant
force and moment); any imbalance has no elastic solution and is reported.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..hydro.deflated import RigidModes, deflated_operator, deflated_solve
from ..hydro.geometry import SurfaceGeometry
from ..hydro.operators import BoundaryOperator, QuadratureOptions, discrete_form
from ..hydro.options import SolverOptions
from ..surfaces.body import Body
from ..surfaces.mesh import Mesh


class ElasticInputError(ValueError):
    """A material constant out of range or a traction that does not fit the body."""


def check_material(shear_modulus: float, poisson_ratio: float):
    """G > 0 (Pa) and -1 < nu < 1/2: the range where linear isotropic elasticity is stable
    (positive shear and bulk moduli)."""
    if not (np.isfinite(shear_modulus) and shear_modulus > 0):
        raise ElasticInputError(f"shear_modulus must be a positive finite number (Pa), got {shear_modulus!r}")
    if not (np.isfinite(poisson_ratio) and -1.0 < poisson_ratio < 0.5):
        raise ElasticInputError(f"poisson_ratio must lie in (-1, 0.5), got {poisson_ratio!r}")


@dataclass(frozen=True)
class Displacement:
    """displacement (E, 3) m at the collocation points ``points`` (E, 3) m of the body's
    elements, with no mean rigid motion; GMRES iterations and residual; ``imbalance``: the
    traction's resultant force over the largest |t| dS sum (0 for a cell in equilibrium)."""

    displacement: np.ndarray
    points: np.ndarray
    iterations: int
    residual: float
    imbalance: float


class InteriorElasticity:
    """The elastic operators of a cell's reference mesh (its body frame), assembled once (they
    depend on the shape only: DESIGN.md §3, model no more than a scene needs) and reused for
    every traction and every placement of the cell: ``solve`` takes the traction in the body
    frame, ``solve_placed`` a world traction on a placed ``Body`` of this mesh. ``options``: the
    quadrature, precision and GMRES settings (``SolverOptions``); the operators are one cell's,
    assembled dense whatever the operator mode (a cell's matrix is small and used at every
    solve), on its own mesh (no contact refinement: the cell is alone in free space)."""

    def __init__(self, mesh: Mesh, shear_modulus: float, poisson_ratio: float, device="cpu", *,
                 options: SolverOptions | None = None):
        check_material(shear_modulus, poisson_ratio)
        self.shear_modulus, self.poisson_ratio = float(shear_modulus), float(poisson_ratio)
        self.mesh = mesh
        self.length = float(mesh.equivalent_radius())
        self.options = (options or SolverOptions()).without_accuracy().resolved(time_stepping=True)
        order = self.options.quadrature_order
        self.geometry = SurfaceGeometry.from_bodies([Body(mesh)], order, self.length, False, 0.0)
        quadrature = QuadratureOptions(order=order, adaptive=self.options.adaptive_quadrature)

        def matrix(kind):
            description = BoundaryOperator(self.geometry, False, quadrature, kind, self.options.dtype)
            return discrete_form(description, "dense", device).to_dense()

        nu = self.poisson_ratio
        # scaled: lengths over L, tractions over G, so displacements come out over L
        self.double_layer = -((1 - 2 * nu) * matrix("elastic_rotation") + 3 * matrix("elastic_dyadic")) / (
            8 * np.pi * (1 - nu))
        self.single_layer = ((2 - 4 * nu) * matrix("inverse_distance") + 8 * np.pi * matrix("single_layer")) / (
            16 * np.pi * (1 - nu))
        # the displacement is defined up to rigid motions: deflated, <phi, u> = 0 (eq. 2.30-2.31)
        self.system = deflated_operator(lambda u, c: self.double_layer @ u, RigidModes.of(self.geometry), [True],
                                        non_rigid_part=False)

    def solve_placed(self, body: Body, traction) -> Displacement:
        """Displacement (world frame, at the placed collocation points) of ``body`` (this mesh,
        placed anywhere) under the world traction (E, 3) Pa on its elements: solved in the
        body frame, t_body = R^T t, and turned back, u = R u_body."""
        if body.mesh is not self.mesh:
            raise ElasticInputError("the body must carry the mesh these operators were assembled for")
        rotation = body.rotation()
        local = self.solve(np.asarray(traction, dtype=float) @ rotation)
        return replace(local, displacement=local.displacement @ rotation.T,
                       points=local.points @ rotation.T + body.position)

    def solve(self, traction) -> Displacement:
        """Displacement (body frame) for the body-frame traction (Pa): an (E, 3) array over the
        mesh's elements, or a function of their collocation points and unit normals ((E, 3)
        each, m, body frame)."""
        g = self.geometry
        if callable(traction):
            traction = traction(g.collocation * self.length, g.collocation_normals)
        t = np.asarray(traction, dtype=float)
        if t.shape != (g.n_elements, 3) or not np.all(np.isfinite(t)):
            raise ElasticInputError(f"traction must be finite with shape ({g.n_elements}, 3), one row per element;"
                                    f" got {t.shape}")
        weighted = g.areas[:, None] * t
        imbalance = float(np.abs(weighted.sum(axis=0)).max() / max(np.abs(weighted).sum(), 1e-300))
        rhs = self.single_layer @ (t / self.shear_modulus).ravel()
        result = deflated_solve(self.system, rhs, self.options)
        return Displacement(result.solution.reshape(-1, 3) * self.length, g.collocation * self.length,
                            result.iterations, result.residual, imbalance)
