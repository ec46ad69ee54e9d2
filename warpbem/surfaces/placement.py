"""Checks that a set of bodies is a valid scene before any solve: each reference point inside
its own body, no body touching or crossing the wall, no two bodies overlapping."""

from __future__ import annotations

import re

import numpy as np
import scipy.spatial

from . import quad9


class PlacementError(ValueError):
    """Bodies placed where the problem has no solution (overlap, wall crossing)."""


def body_label(name: str | None, i: int) -> str:
    """Body ``i`` named ``name`` as messages call it: the name quoted ("body 'dome'"); with no name
    its index, with a default one ("body3", ``Model``, scenes) the index in it ("body 3", also in
    a snapshot's list of its own)."""
    if name is None:
        return str(i)
    return name[4:] if re.fullmatch(r"body\d+", name) else repr(name)


def winding_number(points: np.ndarray, element_nodes: np.ndarray, order: int = 4) -> np.ndarray:
    """Solid angle of a closed surface seen from each point over 4 pi: 1 inside, 0 outside
    (Gauss's law, (1/4 pi) int (x - p) . n / |x - p|^3 dS)."""
    positions, area_vectors = quad9.surface_quadrature(element_nodes, order)
    x = positions.reshape(-1, 3)
    a = area_vectors.reshape(-1, 3)
    out = np.empty(len(points))
    for start in range(0, len(points), 256):
        d = x[None, :, :] - points[start : start + 256, None, :]
        r3 = np.linalg.norm(d, axis=-1) ** 3
        out[start : start + 256] = (np.einsum("pqi,qi->pq", d, a) / r3).sum(axis=1)
    return out / (4.0 * np.pi)


def signed_distance(points: np.ndarray, element_nodes: np.ndarray, order: int = 8) -> np.ndarray:
    """Distance from each point to the QUAD9 surface, negative inside.

    The nearest of order^2 samples per element starts a Gauss-Newton projection onto that
    element's parameter square, so the result is exact to round-off for points much closer to
    the surface than the element size (near contact, where sampling alone would misjudge).
    """
    grid, _ = quad9.gauss_legendre_square(order)
    grid = np.concatenate([grid, quad9.REFERENCE_NODES])
    n_val, _, _ = quad9.shape_functions(grid[:, 0], grid[:, 1])
    samples = np.einsum("qa,eai->eqi", n_val, element_nodes).reshape(-1, 3)
    nearest = np.empty(len(points), dtype=int)
    for start in range(0, len(points), 256):
        d2 = ((samples[None, :, :] - points[start : start + 256, None, :]) ** 2).sum(axis=-1)
        nearest[start : start + 256] = d2.argmin(axis=1)
    element = nearest // len(grid)
    st = grid[nearest % len(grid)].copy()
    nodes = element_nodes[element]
    for _ in range(8):
        n, ns, nt = quad9.shape_functions(st[:, 0], st[:, 1])
        x = np.einsum("pa,pai->pi", n, nodes)
        jac = np.stack([np.einsum("pa,pai->pi", ns, nodes), np.einsum("pa,pai->pi", nt, nodes)], axis=-1)
        normal_matrix = np.einsum("pik,pil->pkl", jac, jac)
        step = np.linalg.solve(normal_matrix, np.einsum("pik,pi->pk", jac, points - x)[..., None])[..., 0]
        st = np.clip(st + step, -1.0, 1.0)
    n, ns, nt = quad9.shape_functions(st[:, 0], st[:, 1])
    x = np.einsum("pa,pai->pi", n, nodes)
    normal = np.cross(np.einsum("pa,pai->pi", ns, nodes), np.einsum("pa,pai->pi", nt, nodes))
    side = np.sign(np.einsum("pi,pi->p", points - x, normal))
    return side * np.linalg.norm(points - x, axis=1)


def surface_samples(element_nodes: np.ndarray) -> np.ndarray:
    """Points on the surface that the placement checks test: the nodes and 4 x 4 Gauss points
    of every element."""
    positions, _ = quad9.surface_quadrature(element_nodes, 4)
    return np.concatenate([element_nodes.reshape(-1, 3), positions.reshape(-1, 3)])


def check_placement(bodies, wall: bool) -> None:
    # each mesh's samples in its own coordinates: the lowest point of a body needs only their
    # heights (the rotation's last row), the bounding radius none of the motion (256 cells' samples
    # moved whole took 18 ms of a step); the samples moved whole only for pairs that may overlap
    radius_of = {}
    for i, body in enumerate(bodies):
        if not body.mesh.encloses_origin():
            raise PlacementError(
                f"body {body_label(bodies[i].name, i)}: its reference point (position) lies outside its mesh;"
                " the mesh coordinates must be given about a point inside the body"
            )
        samples = body.mesh.surface_samples()
        lowest = (samples @ body.rotation()[2]).min() + body.position[2]
        if wall and lowest <= 0.0:
            raise PlacementError(
                f"body {body_label(bodies[i].name, i)} touches or crosses the wall z = 0: its lowest point is at"
                f" z = {lowest:.4g} m (centre at z = {body.position[2]:.4g} m)"
            )
        if id(body.mesh) not in radius_of:
            radius_of[id(body.mesh)] = np.linalg.norm(samples, axis=1).max()
    if len(bodies) == 1:  # no pair: no bounding spheres, no tree (a third of this check for one body)
        return
    radii = np.array([radius_of[id(b.mesh)] for b in bodies])
    centres = np.array([b.position for b in bodies])
    # pairs whose bounding spheres meet, by a k-d tree: all pairs took seconds for 1000 cells
    candidates = scipy.spatial.cKDTree(centres).query_pairs(2.0 * radii.max(), output_type="ndarray")
    for i, j in sorted(map(tuple, candidates)):
        if np.linalg.norm(centres[i] - centres[j]) <= radii[i] + radii[j]:
            nodes_i, nodes_j = (b.world_nodes()[b.mesh.elements] for b in (bodies[i], bodies[j]))
            samples_i, samples_j = (b.mesh.surface_samples() @ b.rotation().T + b.position
                                    for b in (bodies[i], bodies[j]))
            depth = min(signed_distance(samples_j, nodes_i).min(), signed_distance(samples_i, nodes_j).min())
            if depth <= 0.0:
                raise PlacementError(
                    f"bodies {body_label(bodies[i].name, i)} and {body_label(bodies[j].name, j)} overlap (centres"
                    f" {bodies[i].position.tolist()} and {bodies[j].position.tolist()} m)"
                )
