"""Local refinement of QUAD9 elements near contact (a body near the wall or another body).

Near contact the flow in the gap varies on the gap's length scale, which the density resolves
only if the elements there are about as small. Each element closer to the wall or to another
body than ``1/ratio`` times its radius is split into four children (the quarters of its
parameter square, mapped by its own biquadratic geometry, so the surface is unchanged),
repeatedly up to ``max_levels`` times. The ratio is scaled with the body's own mesh
(``relative_element_size`` against the k = 4 sphere's): a mesh twice as fine is refined twice
as finely near contact, so the gap is resolved as the body is and the error near contact falls
with the mesh instead of stopping at a floor a fixed ratio sets (``benchmarks/convergence.py``,
docs/validation.md "Accuracy near contact"). The refined mesh has hanging nodes, which the collocation
methods do not mind: the density is discontinuous between elements and only the element
integrals, areas and collocation points enter. The seed had no such refinement; its
near-contact motion was "rough" (thesis ch. 3.3).
"""

from __future__ import annotations

import numpy as np
import scipy.spatial

from . import quad9
from .gaps import WALL

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
    # np.linalg.norm's sum of squares without its argument handling (the same sums; twice as fast on small meshes)
    offsets = element_nodes - element_nodes[:, quad9.CENTRE_NODE, None]
    return np.sqrt((offsets * offsets).sum(axis=-1)).max(axis=1)


def relative_element_size(element_nodes: np.ndarray) -> float:
    """Median element radius of a body's mesh over the body's size (largest node distance from
    the mean node): how finely the mesh resolves the body (0.28 for the k = 4 sphere)."""
    cloud = element_nodes.reshape(-1, 3)
    return float(np.median(element_radius(element_nodes)) / np.linalg.norm(cloud - cloud.mean(axis=0), axis=1).max())


# relative_element_size of the k = 4 sphere (96 elements, the seed's mesh): on it the rule is
# the plain ratio, an element split while its radius exceeds gap / ratio
REFERENCE_ELEMENT_SIZE = 0.2755

# refined meshes are reported unresolved where the resolved length (below) is under this
# fraction of the body's own element radius: there the default scheme passes about 1 % error
# (docs/benchmarks.md, stability map: on the k = 4 sphere, 0.0055 radius; the squeeze flow to the wall is 1.2 %
# off at a gap of 0.005 radius, two spheres 0.85 % at 0.02 and more below)
WARN_FRACTION = 0.02


def body_gap_share(density_order: int) -> float:
    """The share of the gap to another body the elements resolve (``resolved_length``): half of it
    for the bilinear and biquadratic densities; the whole gap for the constant density (the
    scenes' and the traction's): half of it took 2.5 times the time of the recruitment scene's
    steps (adherent cells re-refined as a free cell passes) for squeeze errors that are the
    constant density's anyway (docs/benchmarks.md, stability map)."""
    return 0.5 if density_order > 1 else 1.0


def resolved_length(gap: np.ndarray, neighbour: np.ndarray, body_gap_share: float) -> np.ndarray:
    """The length the elements must resolve: the gap to the wall, ``body_gap_share`` of the gap
    to another body (each body meets the other's flow at the mid-plane, a wall at half the gap:
    with the whole gap two bilinear-density spheres at 0.05 radius were 2.0 % off, against 0.45 %
    with half of it and 0.18 % for one sphere at the wall)."""
    return np.where(neighbour == WALL, gap, body_gap_share * gap)


class BoundingSpheres:
    """Each body's node cloud's mean and largest distance from it, and a k-d tree of the means,
    to find the bodies near one without looking at all of them (a loop over every pair took
    minutes for 1000 adherent cells)."""

    def __init__(self, meshes):
        self.clouds = [m.reshape(-1, 3) for m in meshes]
        self.tree = None
        if len(meshes) > 1:  # one body has no neighbour: no spheres, no tree (a fifth of a small solve's geometry)
            self.middles = np.array([c.mean(axis=0) for c in self.clouds])
            self.reaches = np.array([np.linalg.norm(c - m, axis=1).max() for c, m in zip(self.clouds, self.middles)])
            self.tree = scipy.spatial.cKDTree(self.middles)

    def near(self, p: int, margin: float) -> list:
        """The other bodies whose bounding spheres come within ``margin`` of body p's, in order."""
        if self.tree is None:
            return []
        found = self.tree.query_ball_point(self.middles[p], self.reaches[p] + self.reaches.max() + margin)
        distance = np.linalg.norm(self.middles[found] - self.middles[p], axis=1) if found else np.zeros(0)
        return [q for q, d in sorted(zip(found, distance)) if q != p and d <= self.reaches[p] + self.reaches[q] + margin]


def _gaps(meshes, p, wall, reach, spheres: BoundingSpheres):
    """Gap from each element of body p to the wall (if ``wall``; its lowest node) and to every
    other body near enough to matter (its bounding sphere within ``reach``; from the element's
    centre to the body's nearest node), and the nearest neighbour (WALL or a body index)."""
    elements = meshes[p]
    centres = elements[:, quad9.CENTRE_NODE]
    gap = np.full(len(elements), np.inf)
    neighbour = np.full(len(elements), WALL)
    if wall:
        gap = elements[:, :, 2].min(axis=1)
    for q in spheres.near(p, reach):
        # a k-d tree: the brute-force distance matrix's temporaries took most of a step of two
        # refined cells (fresh memory is slow to fault in on this machine)
        d = scipy.spatial.cKDTree(spheres.clouds[q]).query(centres)[0]
        closer = d < gap
        gap[closer] = d[closer]
        neighbour[closer] = q
    return gap, neighbour


def refine_near_contact(element_nodes: list[np.ndarray], wall: bool, ratio: float,
                        max_levels: int = 6, warn_ratio: float = 3.0,
                        wall_exempt=None, body_gap_share: float = 0.5) -> tuple[list[np.ndarray], dict, list[np.ndarray]]:
    """Refine every body's elements (list of (E_p, 9, 3) arrays, one per body); ``ratio`` 0
    refines nothing. ``body_gap_share``: the share of the gap to another body the elements
    resolve (``resolved_length``). ``wall_exempt`` (one flag per body): bodies not refined for, nor warned
    about, their gap to the wall (adherent cells, whose fixed gap to the wall changes the free
    cells' motion little; see scenes/recruitment_dome.toml).

    Returns the refined meshes, the contacts they leave unresolved and, per body, the element
    of the unrefined mesh each refined element came from. The unresolved contacts are {(p, q):
    smallest gap} for body p near body q (q = WALL for the wall) where the length to resolve is
    below WARN_FRACTION of p's own element radius or the rule still fails after ``max_levels``
    levels (6: the k = 4 sphere's elements end at 1/64 of their radius, and the element count,
    growing about as 1 / gap, stays bounded where the warning is given anyway); with ``ratio``
    0, where an element is wider, in radius, than that length over ``warn_ratio``. docs/benchmarks.md,
    stability map.
    """
    meshes = [e.copy() for e in element_nodes]
    parents = [np.arange(len(e)) for e in element_nodes]
    exempt = np.zeros(len(meshes), bool) if wall_exempt is None else np.asarray(wall_exempt, bool)
    # per body: the split rule r_e * ratios[p] > gap, scaled with the body's own mesh when it is
    # finer than the k = 4 sphere (a coarser one keeps the plain ratio: refining it less made a
    # k = 3 sphere in shear drift 3.5 times faster, test_dynamics)
    ratios = [ratio * max(1.0, REFERENCE_ELEMENT_SIZE / relative_element_size(e)) if ratio > 0 else 0.0
              for e in element_nodes]
    for _ in range(max_levels if ratio > 0 else 0):
        changed = False
        spheres = BoundingSpheres(meshes)
        for p, elements in enumerate(meshes):
            radii = element_radius(elements)
            # only bodies whose bounding spheres come within reach of a coarse element
            gap, neighbour = _gaps(meshes, p, wall and not exempt[p], radii.max() * ratios[p] / body_gap_share, spheres)
            coarse = radii * ratios[p] > resolved_length(gap, neighbour, body_gap_share)
            if coarse.any():
                meshes[p] = np.concatenate([elements[~coarse], split(elements[coarse])])
                spheres.clouds[p] = meshes[p].reshape(-1, 3)  # later bodies measure to the refined nodes
                parents[p] = np.concatenate([parents[p][~coarse], np.repeat(parents[p][coarse], 4)])
                changed = True
        if not changed:
            break
    unresolved = {}
    spheres = BoundingSpheres(meshes)
    for p, elements in enumerate(meshes):
        radii = element_radius(elements)
        reach = radii.max() * max(ratios[p], warn_ratio) / body_gap_share
        gap, neighbour = _gaps(meshes, p, wall and not exempt[p], reach, spheres)
        length = resolved_length(gap, neighbour, body_gap_share)
        if ratio > 0:  # refined: closer than the scheme resolves to about 1 %, or max_levels reached
            coarse = ((length < WARN_FRACTION * np.median(element_radius(element_nodes[p])))
                      | (radii * ratios[p] > length))
        else:
            coarse = radii * warn_ratio > length
        for q in np.unique(neighbour[coarse]):
            unresolved[(p, int(q))] = float(gap[coarse & (neighbour == q)].min())
    return meshes, unresolved, parents
