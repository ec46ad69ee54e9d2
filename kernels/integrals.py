"""Launchers of the boundary-integral kernels of ``assembly.py`` (thin: host arrays in, device or
host arrays out), one per kernel, so that the operators of ``warpbem/hydro/operators/`` hold no
launch code (DESIGN.md §2). ``k`` is a namespace of ``build_kernels``, ``device`` a Warp device;
index arrays are taken as NumPy and copied to the device here; rows are split over the CPU
thread pool by ``launch.launch_rows``.

Lists (``lists``): (group of each target, CSR starts of each group's items, the items), the
near lists of ``FarField.near_lists`` or one group holding every element or pole.
"""

from __future__ import annotations

import numpy as np

from .launch import launch_rows


def _wp():
    import warp as wp  # here, not at the top: `import warpbem` must not load Warp

    return wp


def indices(values, device):
    """A device int array of ``values`` (any integer NumPy array or list), read-only: on the CPU
    the host array itself (copy=False), with no copy."""
    wp = _wp()
    return wp.array(np.ascontiguousarray(values, dtype=np.int32), dtype=int, device=device, copy=False)


def device_lists(lists, device) -> tuple:
    """The three arrays of ``lists`` on the device (module docstring)."""
    return tuple(indices(a, device) for a in lists)


def every_item(n_targets: int, n_items: int) -> tuple:
    """Lists that give every one of ``n_items`` items to each of ``n_targets`` targets."""
    return np.zeros(n_targets), [0, n_items], np.arange(n_items)


def points(values, k, device):
    """A device vec3 array of (n, 3) host points (in the kernels' precision)."""
    wp = _wp()
    return wp.array(np.ascontiguousarray(values), dtype=k.green.vec3, device=device)


def assemble_entries(k, device, surface, rows, cols, matrix, compact: bool = False) -> None:
    """Entries of ``matrix`` (a device 2-D array) between collocation points ``rows`` and the
    unknowns of elements ``cols``: at the points' and elements' own indices, or ``compact``ly
    (row i, columns of the j-th listed element), for the treecode's near blocks."""
    r, c = indices(rows, device), indices(cols, device)
    launch_rows(k.assemble_entries, len(rows), lambda start, stop: [start, surface, r, c, int(compact), matrix],
                device, extra_dim=len(cols))


def gather_entries(k, device, source, source_points, target, target_points) -> None:
    """The blocks between ``source_points`` of matrix ``source`` copied to those between
    ``target_points`` of ``target`` (the same bodies at their new places)."""
    src, dst = indices(source_points, device), indices(target_points, device)
    launch_rows(k.gather_entries, len(target_points), lambda start, stop: [start, source, src, src, target, dst, dst],
                device, extra_dim=len(target_points))


def self_blocks(k, device, surface, n_points: int, kernel, sign: float):
    """(n_points,) device 3x3 blocks: ``sign`` times the result of ``kernel`` (``self_blocks``,
    the single layers' Duffy integral, or ``same_body_row_sums``) at every collocation point."""
    wp = _wp()
    blocks = wp.zeros(n_points, dtype=k.green.mat33, device=device)
    launch_rows(kernel, n_points, lambda start, stop: [start, surface, blocks[start:stop]], device)
    return wp.array(blocks.numpy() * sign, dtype=k.green.mat33, device=device)


def identity_self_blocks(k, device, surface, listed_points, matrix) -> None:
    """The self blocks of ``listed_points`` written into ``matrix`` where it is, from the
    rigid-translation identity of its own row sums (CUDA: the matrix never goes through the host)."""
    listed = indices(listed_points, device)
    launch_rows(k.identity_self_blocks, len(listed_points), lambda start, stop: [start, surface, listed, matrix],
                device)


def write_self_blocks(k, device, listed_points, blocks, matrix) -> None:
    """The given device ``blocks`` of ``listed_points`` written into ``matrix`` where it is."""
    listed = indices(listed_points, device)
    launch_rows(k.write_self_blocks, len(listed_points), lambda start, stop: [start, listed, blocks, matrix], device)


def dense_matvec(k, device, entries, size: int, x: np.ndarray):
    """The flat row-major ``entries`` (size x size) times host ``x``, by thread blocks (one per
    row) where the matrix lives; a device array."""
    from .assembly import MATVEC_BLOCK

    wp = _wp()
    vector = wp.array(x, dtype=k.green.dtype, device=device)
    out = wp.zeros(size, dtype=k.green.dtype, device=device)
    wp.launch_tiled(k.dense_matvec, dim=[size], inputs=[entries, size, vector, out], block_dim=MATVEC_BLOCK,
                    device=device)
    return out


def apply_listed(k, device, surface, diagonal, density: np.ndarray, lists) -> np.ndarray:
    """(3 n,) float64: at every collocation point the integrals over its group's listed elements
    of ``density`` ((n, 3) host) plus the ``diagonal`` self block; ``lists`` device arrays."""
    wp = _wp()
    n = len(density)
    vec3 = k.green.vec3
    q = wp.array(density, dtype=vec3, device=device)
    out = wp.zeros(n, dtype=vec3, device=device)
    launch_rows(k.apply_matrix_free, n, lambda start, stop: [start, surface, diagonal, q, *lists, out[start:stop]],
                device)
    return out.numpy().reshape(-1).astype(np.float64)


def field_at_points(k, device, surface, density: np.ndarray, targets: np.ndarray, lists) -> np.ndarray:
    """(T, 3) float64: the layer of ``density`` ((n, 3) host) at ``targets`` off the surfaces,
    over each target's listed elements (nearly singular integrals adaptive); ``lists`` host."""
    wp = _wp()
    n = len(targets)
    vec3 = k.green.vec3
    on_device = device_lists(lists, device)
    t = wp.array(targets, dtype=vec3, device=device)
    q = wp.array(density, dtype=vec3, device=device)
    out = wp.zeros(n, dtype=vec3, device=device)
    launch_rows(k.field_at_points, n, lambda start, stop: [start, surface, q, t, *on_device, out[start:stop]], device)
    return out.numpy().astype(np.float64)


def point_force_velocity(k, device, targets, poles, forces, lists) -> np.ndarray:
    """(T, 3) float64: sum over each target's listed poles of G(target, pole) force (``lists``
    device arrays)."""
    wp = _wp()
    vec3 = k.green.vec3
    t, p, f = (wp.array(np.ascontiguousarray(a), dtype=vec3, device=device) for a in (targets, poles, forces))
    out = wp.zeros(len(targets), dtype=vec3, device=device)
    launch_rows(k.point_force_velocity, len(targets), lambda start, stop: [start, t, p, f, *lists, out[start:stop]],
                device)
    return out.numpy().astype(np.float64)


def point_force_tensors(k, device, targets, poles) -> np.ndarray:
    """(T, P, 3, 3) float64 Green's tensors G(target, pole)."""
    wp = _wp()
    t, p = points(targets, k, device), points(poles, k, device)
    out = wp.empty((len(targets), len(poles)), dtype=k.green.mat33, device=device)
    # a few poles: light work, not worth the thread pool below some thousand targets
    launch_rows(k.point_force_tensors, len(targets), lambda start, stop: [start, t, p, out[start:stop]], device,
                extra_dim=len(poles), threaded=len(targets) * len(poles) > 20000)
    return out.numpy().astype(np.float64)


def proxy_interactions(k, device, targets, sources, strengths: int) -> np.ndarray:
    """(3 P, strengths P) float64 (``strengths`` 12: the kernel's 9 double-layer and 3 force
    components): the velocities at the P ``targets`` per unit strength at the P ``sources``
    (the treecode's boxes' Chebyshev points)."""
    wp = _wp()
    t, s = points(targets, k, device), points(sources, k, device)
    size = len(targets)
    matrix = wp.empty((3 * size, strengths * size), dtype=k.green.dtype, device=device)
    launch_rows(k.proxy_interactions, size, lambda start, stop: [start, t, s, matrix], device, extra_dim=size)
    return matrix.numpy().astype(np.float64, copy=False)
