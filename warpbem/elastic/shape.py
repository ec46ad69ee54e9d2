"""A cell's deformed surface from its displacement, and its shape measures.

The elastic solve (``interior.py``) gives the displacement at the element centres (the
collocation points); each QUAD9 node takes the value at the node of the linear function fitted
by least squares to the centres of the elements around it (those sharing a node with an element
that holds it: 9 or more, not all in one plane on a curved surface), which reproduces a linear
displacement field exactly and a smooth one to second order in the element size. The plain
mean of the elements that share a node is only first order (at the cube-sphere's corners three
elements meet asymmetrically: 6.7 % of a linear field at k = 4).

Shape in the shear plane (x the flow, z the gradient; thesis figs. 2.9-2.14): the ellipsoid
fitted to the nodes by least squares, (x - c)^T A (x - c) = 1, cut by the plane y = c_y; its
semi-axes L >= B give the Taylor deformation D = (L - B) / (L + B) and the inclination angle of
the long axis from the flow direction (rad, in (-pi/2, pi/2]). For an ellipsoid the fit is
exact; for other shapes it is the best-fit ellipsoid's.
"""

from __future__ import annotations

import numpy as np

from ..surfaces.mesh import Mesh
from ..surfaces.quad9 import CENTRE_NODE


def nodal_weights(mesh: Mesh):
    """The (n_nodes, n_elements) sparse matrix taking element values to each node's value of
    the linear fit to the element centres around it (module docstring): the first row of the
    fit's pseudo-inverse, per node. It depends on the reference mesh only, so a deforming cell
    builds it once."""
    from scipy.sparse import csr_matrix

    centres = mesh.element_nodes()[:, CENTRE_NODE]
    scale = mesh.size()
    holders = [[] for _ in mesh.nodes]
    for e, element in enumerate(mesh.elements):
        for node in element:
            holders[node].append(e)
    rows, columns, values = [], [], []
    for node, own in enumerate(holders):
        ring = np.unique(np.concatenate([[e for n in mesh.elements[o] for e in holders[n]] for o in own]))
        offset = (centres[ring] - mesh.nodes[node]) / scale
        design = np.column_stack([np.ones(len(ring)), offset])
        rows.append(np.full(len(ring), node))
        columns.append(ring)
        values.append(np.linalg.pinv(design)[0])
    return csr_matrix((np.concatenate(values), (np.concatenate(rows), np.concatenate(columns))),
                      shape=(len(mesh.nodes), mesh.n_elements))


def nodal_displacement(mesh: Mesh, element_displacement, weights=None) -> np.ndarray:
    """(n_nodes, 3), m: each node's value of the linear fit to the element centres around it
    (module docstring); ``weights`` the mesh's ``nodal_weights``, built here if not given."""
    u = np.asarray(element_displacement, dtype=float)
    if u.shape != (mesh.n_elements, 3):
        raise ValueError(f"element_displacement must have shape ({mesh.n_elements}, 3), got {u.shape}")
    return (nodal_weights(mesh) if weights is None else weights) @ u


def deformed(mesh: Mesh, element_displacement) -> Mesh:
    """The mesh with its nodes displaced (body frame)."""
    return Mesh(mesh.nodes + nodal_displacement(mesh, element_displacement), mesh.elements)


def shear_plane_deformation(nodes, centre=(0.0, 0.0, 0.0)) -> tuple[float, float]:
    """(Taylor deformation D, inclination angle in rad) of the surface through ``nodes`` (n, 3)
    about ``centre``, from the fitted ellipsoid's section in the x-z plane."""
    x = np.asarray(nodes, dtype=float) - np.asarray(centre, dtype=float)
    # unknowns: A_xx, A_yy, A_zz, A_xy, A_xz, A_yz of x^T A x = 1
    design = np.stack([x[:, 0] ** 2, x[:, 1] ** 2, x[:, 2] ** 2,
                       2 * x[:, 0] * x[:, 1], 2 * x[:, 0] * x[:, 2], 2 * x[:, 1] * x[:, 2]], axis=1)
    a = np.linalg.lstsq(design, np.ones(len(x)), rcond=None)[0]
    section = np.array([[a[0], a[4]], [a[4], a[2]]])
    values, vectors = np.linalg.eigh(section)  # ascending: the long axis first
    if values[0] <= 0:
        raise ValueError("the fitted surface is not an ellipsoid in the shear plane")
    long_axis, short_axis = 1.0 / np.sqrt(values)
    direction = vectors[:, 0]
    angle = float(np.arctan2(direction[1], direction[0]))
    if angle <= -np.pi / 2:
        angle += np.pi
    elif angle > np.pi / 2:
        angle -= np.pi
    return float((long_axis - short_axis) / (long_axis + short_axis)), angle
