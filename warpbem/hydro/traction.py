"""Surface traction on rigid bodies: the Completed Adjoint Double Layer (thesis ch. 2.2 B, eq.
2.18-2.25; Phan-Thien & Fan 1995).

The flow outside rigid bodies is the single layer of their surface traction t (the force per
area the fluid exerts), u = u_inf - int G t dS (eq. 2.18), G the wall Green's function when the
wall is on. Its traction on the surface, from outside, gives a second-kind equation for t alone
(eq. 2.21, halved):

    (1/2 + D*) t = t_inf,     (D* t)(xi) = PV int n(xi) . Sigma(xi; x) t(x) dS(x),

Sigma(xi; x) the stress at xi of the (wall) Stokeslet at x (``kernels/assembly.py``, kind
"adjoint_double_layer"), t_inf = sigma_inf . n the ambient traction (u_inf = gdot z e_x:
sigma_inf = mu gdot (e_x e_z + e_z e_x)). Inside a rigid body the flow is a rigid motion,
whose stress vanishes, so no velocity enters: the rigid motions' eigenvalue -1 of D*
(eq. 2.21) leaves six free modes per body, fixed by the body's force and torque (eq.
2.22-2.24): with phi^(p,m) the rigid modes of body p orthonormalised over its surface (as in
the CDL solve),

    (1/2 + D*) t + sum_{p,m} phi^(p,m) <phi^(p,m), t> = t_inf + sum_{p,m} phi^(p,m) c^(p,m),

where c^p = L_p^-1 (F_p, T_p) are the coordinates of the fluid's force and torque on body p in
those modes (F = int t dS, T = int (x - x_p) x t dS). Unlike the double layer, only the -1
eigenvalue needs the deflation (Phan-Thien & Fan 1996). Taking <phi, .> of the equation shows
int t dS = F to the discretisation error of the adjoint identity <phi, (1/2 + D*) t> = 0.

Extra tractions (a Hertz contact, thesis eq. 4.8; lubrication, eq. 3.4-3.8) act on the surface
besides the fluid's: ``extra_traction`` t_c (E, 3) per element. The body's balance then reads
F_fluid = -(F_ext + int t_c dS), and the solution's ``total_traction`` is t + t_c, the load the
elastic solve needs. The thesis adds t_c to the right-hand side of eq. 2.25 and solves for the
total; by linearity that is (1/2 + D*) (t + t_c) = t_inf + (1/2 + D*) t_c (deflated alike),
the same solution, which here costs no extra product.

Contact loads (repulsion, bonds) come as ``point_loads``: a force at a surface point, spread
over the body's elements as a Hertz pressure p ~ sqrt(1 - r^2 / a_c^2) of the contact radius
a_c (thesis eq. 4.8) sampled at the collocation points within it, scaled so that the element
tractions sum to the force exactly; a patch narrower than the elements there (or a_c = 0: a
bond) lands on the nearest element, its moment shifted by at most that element's distance
(the body's balance takes the moment as spread). They join the extra traction.

With ``load_response`` the same operator also solves the loads acting alone, without the
ambient flow (the body loads, the extra traction and the point loads): ``load_traction``, their
surface traction plus the fluid's answer to them, in equilibrium on every body but for the body
loads, which have no surface traction. By linearity the total traction less it is the ambient
flow's on the force-free bodies (what the flow alone does to a deformable cell; the rest is its
own loads' doing: elastic/deformable.py, "Contacts").

Units: the kernels see lengths over the bodies' mean radius L and tractions over a scale
sigma_0 (the largest of mu |gdot|, |F| / L^2, |T| / L^3); the solution is in Pa.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import runtime
from ..surfaces.placement import check_placement
from .deflated import RigidModes, deflated_operator, deflated_solve
from .geometry import SurfaceGeometry
from .mobility import checked_loads, checked_bodies
from .operators import BoundaryOperator, QuadratureOptions, discrete_form
from .options import Flow, SolverOptions


@dataclass(frozen=True)
class TractionSolution:
    """traction: (E, 3) Pa at the collocation points (element centres, ``points``, m) of all
    bodies' elements (after contact refinement), ``areas`` (E,) m^2, ``body_of_element`` (E,);
    force, torque (n, 3): the integrated traction of each body (N, N m, torque about its
    reference point), the fluid's load on it; GMRES iterations and residual.

    Examples
    --------
    A cell held at rest in wall shear: its elements' tractions, and their sum, the fluid's
    load, which is minus the force that holds it (here to 0.3 %, the k = 2 mesh's accuracy):

    >>> import warpbem as wb
    >>> held = wb.Body(wb.mesh.sphere(radius=5e-6, subdivisions=2), position=(0.0, 0.0, 7.5e-6), fixed=True)
    >>> holding = wb.solve_mobility([held], shear_rate=100.0, options=wb.SolverOptions(density_order=1))
    >>> sol = wb.solve_traction([held], shear_rate=100.0, forces=holding.force, torques=holding.torque)
    >>> sol.traction.shape == sol.points.shape == (len(sol.areas), 3)
    True
    >>> print(f"{sol.force[0, 0] / -holding.force[0, 0]:.2f}")
    1.00
    """

    traction: np.ndarray
    total_traction: np.ndarray  # fluid traction plus the extra traction given, Pa
    load_traction: np.ndarray | None  # Pa: the loads alone, no flow, with the fluid's answer (or None)
    points: np.ndarray
    normals: np.ndarray
    areas: np.ndarray
    body_of_element: np.ndarray
    parent_element: np.ndarray  # (E,) the element of its body's own mesh each element refines
    force: np.ndarray
    torque: np.ndarray
    iterations: int
    residual: float
    shear_rate: float
    viscosity: float
    _single_layer: tuple = field(repr=False, compare=False)  # (operator, Gauss points, their loads), scaled

    def of_body(self, p: int) -> np.ndarray:
        """(E_p, 3) traction on body p's elements, Pa."""
        return self.traction[self.body_of_element == p]

    def on_mesh(self, p: int, kind: str = "total") -> np.ndarray:
        """(E_mesh, 3) Pa: the traction of ``kind`` ("total", "fluid" or "loads":
        ``load_traction``) on body p's own mesh elements, the area-weighted mean over the
        elements the contact refinement split each into (the input of the elastic problem, which
        works on the unrefined reference mesh)."""
        kinds = {"total": self.total_traction, "fluid": self.traction, "loads": self.load_traction}
        if kinds.get(kind) is None:
            raise ValueError(f"no {kind!r} traction in this solution (kinds: total, fluid, loads with"
                             " load_response)")
        own = self.body_of_element == p
        values = kinds[kind][own]
        parent = self.parent_element[own]
        count = parent.max() + 1
        area = np.bincount(parent, self.areas[own], minlength=count)
        return np.stack([np.bincount(parent, self.areas[own] * values[:, i], minlength=count) for i in range(3)],
                        axis=1) / area[:, None]

    def velocity(self, points) -> np.ndarray:
        """(m, 3) velocity (m/s) of eq. 2.18, u = u_inf - int G t dS / mu, at ``points`` (m, 3)
        off the surfaces: in the fluid the flow, inside a body its rigid motion (the interior
        flow of a rigid body), by Gauss quadrature of the element tractions (accurate farther
        than about one element from the surface)."""
        operator, poles, loads, length, stress_scale = self._single_layer
        points = np.atleast_2d(np.asarray(points, dtype=float))
        disturbance = operator.point_force_velocity(points / length, poles, loads)
        ambient = np.zeros_like(points)
        ambient[:, 0] = self.shear_rate * points[:, 2]
        return ambient - disturbance * stress_scale * length / self.viscosity

    def surface_velocity(self) -> np.ndarray:
        """(E, 3) velocity (m/s) of eq. 2.18 on the surface, at the collocation points: the
        rigid motion of each body, to the discretisation error (the single layer's weakly
        singular self element by Duffy triangles, ``kernels/assembly.py``)."""
        operator, _, _, length, stress_scale = self._single_layer
        adjoint = operator.description
        single = BoundaryOperator(adjoint.geometry, adjoint.wall, adjoint.quadrature, "single_layer", adjoint.dtype)
        disturbance = discrete_form(single, operator.mode, operator.device).apply(
            self.traction.ravel() / stress_scale).reshape(-1, 3)
        ambient = np.zeros_like(self.points)
        ambient[:, 0] = self.shear_rate * self.points[:, 2]
        return ambient - disturbance * stress_scale * length / self.viscosity


def spread_point_loads(geometry, length: float, point_loads, n_bodies: int) -> np.ndarray:
    """(E, 3) traction (Pa) of ``point_loads`` (``solve_traction``) on ``geometry``'s elements."""
    extra = np.zeros((geometry.n_elements, 3))
    for body, point, force, radius in point_loads:
        if not 0 <= body < n_bodies:
            raise ValueError(f"point load on body {body}: there are {n_bodies} bodies")
        if not (np.all(np.isfinite(force)) and np.isfinite(radius) and radius >= 0):
            raise ValueError(f"point load on body {body}: force {force!r} and contact radius {radius!r} must be"
                             " finite, the radius >= 0")
        a, b = geometry.body_ranges[body]
        areas = geometry.areas[a:b] * length**2
        r2 = np.sum((geometry.collocation[a:b] * length - np.asarray(point, dtype=float)) ** 2, axis=1)
        pressure = np.sqrt(np.clip(1.0 - r2 / radius**2, 0.0, None)) if radius > 0 else np.zeros(b - a)
        if not pressure.any():
            pressure[np.argmin(r2)] = 1.0
        extra[a:b] += np.outer(pressure / np.dot(pressure, areas), force)
    return extra


def solve_traction(bodies, shear_rate: float = 0.0, viscosity: float = Flow.viscosity, wall: bool = True,
                   forces=None, torques=None, device="cpu", *, extra_traction=None, point_loads=(),
                   load_response: bool = False, options: SolverOptions | None = None) -> TractionSolution:
    """Traction on every rigid body (SI units) in the flow u = shear_rate z e_x (Pa s viscosity,
    no-slip wall z = 0 when ``wall``), given each body's external load ``forces``, ``torques``
    ((n, 3) N, N m, as ``MobilitySolution.force/torque``: for a free body the loads applied to
    it, for a fixed one the load that holds it): at rest in Stokes flow the fluid's load on a
    body is minus its external load and of any ``extra_traction`` (Pa, e.g. a contact's; module
    docstring): an (E, 3) array over the elements after contact refinement, or a function of
    the collocation points and their unit normals ((E, 3) each, m) that returns one;
    ``point_loads``: (body, point (m), force (N), contact radius (m)) each, spread as the module
    docstring says (neither in ``forces``); ``load_response``: also solve the loads without the
    flow (``load_traction``). ``options``: the ``SolverOptions`` of the solve (quadrature,
    contact refinement, GMRES, precision, operator mode); the traction is constant per element,
    so its density order is 1 (the contact refinement's default follows it).

    Examples
    --------
    A sphere pulled by 1 pN in unbounded fluid: the fluid's traction on it is uniform, minus
    the pull over the area, F / (4 pi a^2) (Stokes; Pozrikidis 1992, sec. 2.2), here within
    0.6 % on every element of the k = 2 mesh:

    >>> import math
    >>> import warpbem as wb
    >>> cell = wb.Body(wb.mesh.sphere(radius=5e-6, subdivisions=2))
    >>> sol = wb.solve_traction([cell], viscosity=1e-3, wall=False, forces=[[1e-12, 0.0, 0.0]])
    >>> ratio = sol.traction[:, 0] / (-1e-12 / (4 * math.pi * 5e-6**2))
    >>> print(f"{ratio.min():.3f} {ratio.max():.3f} {sol.force[0, 0]:.4g} N")
    0.995 1.004 -1.001e-12 N
    """
    runtime.resolve_device(device)  # a device this machine lacks: DeviceError before any work
    bodies = checked_bodies(bodies)
    flow = Flow(shear_rate, viscosity, wall)
    shear_rate, viscosity = flow.shear_rate, flow.viscosity
    options = options or SolverOptions()
    if options.density_order not in (None, 1):
        raise ValueError(f"the traction is constant per element (density_order 1), got density_order"
                         f" {options.density_order}")
    options = options.without_accuracy().resolved(time_stepping=True)
    fluid_force = -checked_loads("forces", forces, bodies, fixed_allowed=True)
    fluid_torque = -checked_loads("torques", torques, bodies, fixed_allowed=True)
    check_placement(bodies, wall)

    length = float(np.mean([b.mesh.equivalent_radius() for b in bodies]))
    geometry = SurfaceGeometry.from_bodies(bodies, options.quadrature_order, length, wall, options.contact_refinement,
                                           options.refine_fixed_at_wall)
    if callable(extra_traction):
        extra_traction = extra_traction(geometry.collocation * length, geometry.collocation_normals)
    extra = np.zeros((geometry.n_elements, 3)) if extra_traction is None else np.asarray(extra_traction, dtype=float)
    if extra.shape != (geometry.n_elements, 3) or not np.all(np.isfinite(extra)):
        raise ValueError(f"extra_traction must be finite with shape ({geometry.n_elements}, 3), one row per element"
                         f" after contact refinement; got {extra.shape}")
    extra = extra + spread_point_loads(geometry, length, point_loads, len(bodies))
    for p, (a, b) in enumerate(geometry.body_ranges):
        arm = (geometry.collocation[a:b] - geometry.centres[p]) * length
        fluid_force[p] -= (geometry.areas[a:b, None] * length**2 * extra[a:b]).sum(axis=0)
        fluid_torque[p] -= (geometry.areas[a:b, None] * length**2 * np.cross(arm, extra[a:b])).sum(axis=0)
    scale = max(viscosity * abs(shear_rate), np.abs(fluid_force).max() / length**2,
                np.abs(fluid_torque).max() / length**3)
    scale = scale if scale > 0 else 1.0
    quadrature = QuadratureOptions(order=options.quadrature_order, adaptive=options.adaptive_quadrature)
    adjoint = discrete_form(BoundaryOperator(geometry, wall, quadrature, "adjoint_double_layer", options.dtype),
                            options.operator, device)
    # the right side in two parts, scaled: the ambient traction sigma_inf . n, and the rigid
    # modes' loads (the loads acting alone, without the flow: ``load_response``)
    normals = geometry.collocation_normals
    ambient = (viscosity * shear_rate / scale * np.stack([normals[:, 2], np.zeros(len(normals)), normals[:, 0]],
                                                          axis=1)).ravel()
    rigid = RigidModes.of(geometry)
    loads_rhs = np.zeros(3 * geometry.n_elements)
    for p, rows in enumerate(rigid.ranges):
        loads = np.concatenate([fluid_force[p] / (scale * length**2), fluid_torque[p] / (scale * length**3)])
        loads_rhs[rows] = rigid.modes[p] @ rigid.dual_of_loads(p, loads)
    # only the -1 eigenvalue of D* needs the deflation (module docstring): every body shifted
    system = deflated_operator(lambda t, c: adjoint.apply(t), rigid, np.ones(len(bodies), bool),
                               non_rigid_part=False)
    result = deflated_solve(system, ambient + loads_rhs, options)
    alone = None
    if load_response:
        response = deflated_solve(system, loads_rhs, options)
        alone = response.solution.reshape(-1, 3) * scale + extra
    traction = result.solution.reshape(-1, 3) * scale
    areas = geometry.areas * length**2
    points = geometry.collocation * length
    force = np.zeros((len(bodies), 3))
    torque = np.zeros((len(bodies), 3))
    for p, (a, b) in enumerate(geometry.body_ranges):
        force[p] = (areas[a:b, None] * traction[a:b]).sum(axis=0)
        torque[p] = (areas[a:b, None] * np.cross(points[a:b] - bodies[p].position, traction[a:b])).sum(axis=0)
    weights = np.linalg.norm(geometry.qp_area_vectors, axis=-1)  # (E, Q), scaled
    loads = (result.solution.reshape(-1, 1, 3) * weights[..., None]).reshape(-1, 3)
    return TractionSolution(traction, traction + extra, alone, points, normals.copy(), areas, geometry.body_of_element.copy(),
                            geometry.parent_element.copy(), force, torque,
                            result.iterations, result.residual, shear_rate, viscosity,
                            (adjoint, geometry.qp_positions.reshape(-1, 3), loads, length, scale))
