"""Local refinement of QUAD9 elements near contact (a body near the wall or another body).

Near contact the flow in the gap varies on the gap's length scale, which a density constant
per element resolves only if the elements there are about as small. Each element closer to the
wall or to another body than ``1/ratio`` times its radius is split into four children (the
quarters of its parameter square, mapped by its own biquadratic geometry, so the surface is
unchanged), repeatedly up to ``max_levels`` times. The refined mesh has hanging nodes, which
the piecewise-constant collocation method does not mind: only the element integrals, areas and
collocation points enter. The seed had no such refinement; its near-contact motion was
"rough" (thesis ch. 3.3).
"""

from __future__ import annotations

import numpy as np

from . import quad9

# node (s, t) of each child's 9 nodes, for the four quarters of [-1, 1]^2
_CHILD_PARAMS = np.array(
    [
        (s0 + 0.5 * (quad9.REFERENCE_NODES + 1.0)[:, 0], t0 + 0.5 * (quad9.REFERENCE_NODES + 1.0)[:, 1])
        for t0 in (-1.0, 0.0)
        for s0 in (-1.0, 0.0)
    ]
)  # (4, 2, 9)
_CHILD_SHAPES = quad9.shape_functions(_CHILD_PARAMS[:, 0], _CHILD_PARAMS[:, 1])[0]  # (4, 9, 9)


def split(element_nodes: np.ndarray) -> np.ndarray:
    """(E, 9, 3) -> (4 E, 9, 3): each element's four children, parent by parent."""
    return np.einsum("cka,eai->ecki", _CHILD_SHAPES, element_nodes).reshape(-1, 9, 3)


def element_radius(element_nodes: np.ndarray) -> np.ndarray:
    return np.linalg.norm(element_nodes - element_nodes[:, 8:9], axis=-1).max(axis=1)


WALL = -1  # neighbour id of the wall in the contact lists


def _gaps(meshes, p, wall, ratio):
    """Gap from each element centre of body p to the wall (if ``wall``) and to every other body
    near enough to matter, and the nearest neighbour (WALL or a body index)."""
    elements = meshes[p]
    centres = elements[:, 8]
    gap = np.full(len(elements), np.inf)
    neighbour = np.full(len(elements), WALL)
    if wall:
        gap = elements[:, :, 2].min(axis=1)
    clouds = [m.reshape(-1, 3) for m in meshes]
    middle = clouds[p].mean(axis=0)
    reach = np.linalg.norm(clouds[p] - middle, axis=1).max()
    largest = element_radius(elements).max() * ratio
    for q, cloud in enumerate(clouds):
        if q == p:
            continue
        other = cloud.mean(axis=0)
        # only bodies whose bounding spheres come within reach of a coarse element
        if np.linalg.norm(middle - other) > reach + np.linalg.norm(cloud - other, axis=1).max() + largest:
            continue
        d = np.concatenate([np.sqrt(((c[:, None, :] - cloud[None, :, :]) ** 2).sum(axis=-1).min(axis=1))
                            for c in np.array_split(centres, max(1, len(centres) // 256))])  # bounded memory
        closer = d < gap
        gap[closer] = d[closer]
        neighbour[closer] = q
    return gap, neighbour


def refine_near_contact(element_nodes: list[np.ndarray], wall: bool, ratio: float,
                        max_levels: int = 4, warn_ratio: float = 3.0,
                        wall_exempt=None) -> tuple[list[np.ndarray], dict, list[np.ndarray]]:
    """Refine every body's elements (list of (E_p, 9, 3) arrays, one per body); ``ratio`` 0
    refines nothing. ``wall_exempt`` (one flag per body): bodies not refined for, nor warned
    about, their gap to the wall (adherent cells, whose fixed gap to the wall changes the free
    cells' motion little; see scenes/recruitment_dome.toml).

    Returns the refined meshes, the contacts they leave unresolved and, per body, the element
    of the unrefined mesh each refined element came from. The unresolved contacts are {(p, q): smallest gap}
    for body p near body q (q = WALL for the wall) where an element of p is still wider (in
    radius) than its gap over ``warn_ratio``. The stability map (README) shows why: with the
    default k = 4 sphere the refinement bottoms out at gaps near 0.05 radius, where squeeze-flow
    forces are 3 % off and motion in shear 1 %; at 0.01 radius they are 27 % and 5 % off, and
    below about 0.005 radius the results are meaningless or GMRES stalls.
    """
    meshes = [e.copy() for e in element_nodes]
    parents = [np.arange(len(e)) for e in element_nodes]
    exempt = np.zeros(len(meshes), bool) if wall_exempt is None else np.asarray(wall_exempt, bool)
    for _ in range(max_levels if ratio > 0 else 0):
        changed = False
        for p, elements in enumerate(meshes):
            gap, _ = _gaps(meshes, p, wall and not exempt[p], ratio)
            coarse = element_radius(elements) * ratio > gap
            if coarse.any():
                meshes[p] = np.concatenate([elements[~coarse], split(elements[coarse])])
                parents[p] = np.concatenate([parents[p][~coarse], np.repeat(parents[p][coarse], 4)])
                changed = True
        if not changed:
            break
    unresolved = {}
    for p, elements in enumerate(meshes):
        gap, neighbour = _gaps(meshes, p, wall and not exempt[p], max(ratio, warn_ratio))
        coarse = element_radius(elements) * warn_ratio > gap
        for q in np.unique(neighbour[coarse]):
            unresolved[(p, int(q))] = float(gap[coarse & (neighbour == q)].min())
    return meshes, unresolved, parents
