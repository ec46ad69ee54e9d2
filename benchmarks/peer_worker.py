"""Runs INSIDE the peer's own Python (its venv), driven by ``peer_side_by_side.py``: times one
rigid multiblob sphere above a wall with RigidMultiblobsWall's own functions (GPL; this file
only calls them, none of its code is copied here).

    <peer venv>/bin/python peer_worker.py /path/to/RigidMultiblobsWall

Reads one JSON request per line on stdin, ``{"case": "free" | "parallel" | "normal", "h": 1.5,
"blobs": 162, "repeats": 3}``, and answers one JSON line: the raw results (free: U_x and
Omega_y of a force- and torque-free sphere in the shear u = (z, 0, 0); parallel / normal: the
force F_x / F_z on a sphere translating with unit velocity along x / z, not rotating), the times
of the solves after one warm-up, and the blob model used. Radius a = 1 (the hydrodynamic radius
of the peer's ``shell_N_*_Rg_*_Rh_1`` models, whose header gives the blob spacing: the blob
radius is half of it, which is what makes the unbounded drag 6 pi, checked), viscosity 1, wall
z = 0.

One solve, timed whole: read the blob model (the mesh's equivalent), build the body, the
Rotne-Prager-Blake blob mobility M (``mobility.single_wall_fluid_mobility``), its Cholesky factor
(SciPy) and the solves with it; free: (U, Omega) = N K^T M^-1 u_inf with N = (K^T M^-1 K)^-1;
held: F = K^T M^-1 K V. (The peer's own ``Body.calc_mobility_body`` inverts M whole: 4 times
slower at 2562 blobs, 16 s against about 4; the factor is the fair, faster route.)
"""

import glob
import json
import os
import sys
import time
import warnings

import numpy as np
import scipy.linalg

warnings.simplefilter("ignore")  # the peer imports the deprecated `imp`
PEER = os.path.abspath(sys.argv[1])
sys.path.insert(0, PEER)
from body import body  # noqa: E402
from mobility import mobility as mb  # noqa: E402
from quaternion_integrator.quaternion import Quaternion  # noqa: E402
from read_input import read_vertex_file  # noqa: E402

ETA = 1.0


def model_file(blobs: int) -> str:
    """The peer's sphere of ``blobs`` blobs with hydrodynamic radius 1."""
    pattern = os.path.join(PEER, "multi_bodies", "Structures", f"shell_N_{blobs}_Rg_*_Rh_1.vertex")
    found = sorted(glob.glob(pattern))
    if not found:
        raise SystemExit(f"no sphere model of {blobs} blobs with Rh = 1 in {PEER}/multi_bodies/Structures")
    return found[0]


def solve(case: str, h: float, path: str) -> dict:
    with open(path) as f:
        blob_radius = float(f.readline().split()[1]) / 2  # header: N, blob spacing (radius: half of it)
    reference = read_vertex_file.read_vertex_file(path)
    sphere = body.Body(np.array([0.0, 0.0, h]), Quaternion([1.0, 0.0, 0.0, 0.0]), reference, blob_radius)
    sphere.mobility_blobs = mb.single_wall_fluid_mobility
    factor = scipy.linalg.cho_factor(sphere.calc_mobility_blobs(ETA, blob_radius))  # M is SPD
    K = sphere.calc_K_matrix()
    if case == "free":
        r = sphere.get_r_vectors()
        u_inf = np.zeros_like(r)
        u_inf[:, 0] = r[:, 2]
        solved = scipy.linalg.cho_solve(factor, np.column_stack([K, u_inf.ravel()]))  # M^-1 [K, u_inf]
        motion = np.linalg.solve(K.T @ solved[:, :6], K.T @ solved[:, 6])  # N K^T M^-1 u_inf
        return dict(U=float(motion[0]), Omega=float(motion[4]), blob_radius=blob_radius)
    velocity = np.zeros(6)
    velocity[0 if case == "parallel" else 2] = 1.0
    load = K.T @ scipy.linalg.cho_solve(factor, K @ velocity)  # K^T M^-1 K V
    return dict(F=float(load[0 if case == "parallel" else 2]), blob_radius=blob_radius)


def main():
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        path = model_file(int(request["blobs"]))
        solve(request["case"], request["h"], path)  # warm-up
        times = []
        for _ in range(int(request.get("repeats", 3))):
            t = time.perf_counter()
            result = solve(request["case"], request["h"], path)
            times.append(time.perf_counter() - t)
        result.update(times=times, model=os.path.basename(path), blobs=int(request["blobs"]))
        print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
