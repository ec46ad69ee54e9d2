"""Receptor-ligand bonds on the device (thesis ch. 4; Bell 1978; Hammer & Apte 1992): bond
geometry, forces and torques reduced per cell, Monte Carlo rupture and formation, insertion
into a per-cell bond table. Arrays in, arrays out; no Model or State objects.

Layout. Receptors are microvillus tips fixed on the cells (``tips``: body-frame offsets from the
reference point, ``receptor_body``); the receptors of adhesive body c are
``receptor_start[c] .. receptor_start[c + 1]``, and its bond slots rows
``c * capacity .. (c + 1) * capacity`` of the table (``bond_receptor``: -1 for a free slot,
``bond_anchor``: the ligand's point, ``bond_partner``: -1 for the wall, else the fixed body
whose surface carries the ligand, ``bond_birth``: time of formation). One thread
per cell sums its own rows in row order, so the reductions are deterministic on CPU and CUDA
alike (no float atomics). Every kernel takes the index of its first thread (``first``), so
its launcher (below the kernels, one per kernel: arrays in, output arrays filled) can split a
long launch over CPU threads (``launch.launch_rows``); no two threads write the same entry.

Hertz patch (thesis ch. 4.2, eq. 4.9). The cells are rigid in the mobility problem; their
compliance enters through the contact patch: a tip at lateral distance rho from the patch
centre (the foot of the cell's closest point to the wall) is lowered by the Hertz surface
displacement of an elastic sphere of radius R pressed to contact radius a_s (Johnson 1985,
Contact Mechanics, eq. 3.42), relative to a rigid approach delta = a_s^2 / R:

    rho <= a_s : -rho^2 / (2 R)                       (flattened onto the patch plane)
    rho >  a_s : u(rho) - delta,  u = [(2 a_s^2 - rho^2) asin(a_s / rho) + a_s sqrt(rho^2 - a_s^2)] / (pi R)

continuous at rho = a_s and zero for a_s = 0. So the receptors inside the contact area lie on
the flat interface and can bind, as the thesis's contact-area rule has it. A bond keeps the
lowering of its tip at formation (``bond_offset``, m along z) for its life: its tip then moves
rigidly with the cell, and a growing or shrinking patch never moves a bond without the cell
moving (the implicit step sees every change of a bond's vector).

Random numbers: a counter-based stream per event, ``rand_init(rand_init(seed, draw), index)``
(PCG hashes): the same seed and counter give the same events on the same device.
"""

import functools
import math
from types import SimpleNamespace

import warp as wp

from .launch import launch_rows

SPLIT_THREADS = 4096  # launches at least this long are split over the CPU threads
MAX_SITES = 32  # ligand sites per lattice square at most (mean 1: P(n > 32) ~ 1e-37)
# exp of an exponent below this is exactly 0 in float64 and float32 (the least subnormal double is
# exp(-744.4)): a receptor this far from its rest length has no formation rate. Most of a rolling
# patch's receptors are (its tips microns above the wall): skipping their draw and exponentials
# took the formation launch from 15.9 to 7.9 ms per step on the 8 x 8 patch (400 000 receptors;
# cProfile over its first 10 ms, the same bonds bit for bit)
NO_RATE_EXPONENT = -800.0


@functools.lru_cache(maxsize=None)
def build_bond_kernels(dtype) -> SimpleNamespace:
    vec3 = wp.types.vector(3, dtype)
    mat33 = wp.types.matrix((3, 3), dtype)
    zero, half, one = dtype(0.0), dtype(0.5), dtype(1.0)
    pi = dtype(math.pi)

    @wp.func
    def hertz_lowering(rho: dtype, contact_radius: dtype, curvature: dtype):
        if contact_radius <= zero:
            return zero
        if rho <= contact_radius:
            return -rho * rho / (dtype(2.0) * curvature)
        a2 = contact_radius * contact_radius
        u = ((dtype(2.0) * a2 - rho * rho) * wp.asin(contact_radius / rho)
             + contact_radius * wp.sqrt(rho * rho - a2)) / (pi * curvature)
        return u - a2 / curvature

    @wp.func
    def rigid_tip(r: int, tips: wp.array(dtype=vec3), receptor_body: wp.array(dtype=int),
                  positions: wp.array(dtype=vec3), rotations: wp.array(dtype=mat33)):
        b = receptor_body[r]
        return positions[b] + rotations[b] * tips[r]

    @wp.func
    def uniform(seed: int, draw: int, index: int):
        state = wp.rand_init(wp.int32(wp.rand_init(seed, draw)), index)
        return dtype(wp.randf(state))

    @wp.func
    def formation_exponent(d: dtype, spring_per_kt: dtype, compliance: dtype):
        """The exponent of eq. 4.2 at the deviation d from the rest length: sigma d (r0 - d / 2) / kT."""
        return spring_per_kt * d * (compliance - half * d)

    @wp.func
    def formation_rate(d: dtype, on_rate: dtype, spring_per_kt: dtype, compliance: dtype):
        """k_f of eq. 4.2 at the deviation d from the rest length: k_f0 exp(sigma d (r0 - d / 2) / kT)."""
        return on_rate * wp.exp(formation_exponent(d, spring_per_kt, compliance))

    @wp.func
    def site_uniform(seed: int, ix: int, iy: int, k: int):
        """The k-th uniform number of ligand lattice square (ix, iy): a hash of the four."""
        return dtype(wp.randf(wp.rand_init(wp.int32(wp.rand_init(wp.int32(wp.rand_init(seed, ix)), iy)), k)))

    @wp.func
    def site_count(seed: int, ix: int, iy: int, mean: dtype):
        """Poisson number of ligand sites in lattice square (ix, iy), by inversion of its CDF."""
        u = site_uniform(seed, ix, iy, 0)
        p = wp.exp(-mean)
        cumulative = p
        n = int(0)
        while u > cumulative and n < MAX_SITES:
            n += 1
            p = p * mean / dtype(n)
            cumulative += p
        return n

    @wp.func
    def site_taken(row: int, capacity: int, bond_receptor: wp.array(dtype=int), bond_anchor: wp.array(dtype=vec3),
                   bond_partner: wp.array(dtype=int), site: vec3):
        """1 if one of the ``capacity`` table rows from ``row`` holds a wall bond on ``site``."""
        taken = int(0)
        for i in range(row, row + capacity):
            if bond_receptor[i] >= 0 and bond_partner[i] < 0:
                a = bond_anchor[i]
                if a[0] == site[0] and a[1] == site[1] and a[2] == site[2]:
                    taken = 1
        return taken

    @wp.kernel(enable_backward=False)
    def bond_geometry(first: int, bond_receptor: wp.array(dtype=int), bond_anchor: wp.array(dtype=vec3),
                      bond_offset: wp.array(dtype=dtype), tips: wp.array(dtype=vec3),
                      receptor_body: wp.array(dtype=int), positions: wp.array(dtype=vec3),
                      rotations: wp.array(dtype=mat33),
                      vector: wp.array(dtype=vec3), moment: wp.array(dtype=mat33)):
        """Per row: the bond vector x_m - x_o from anchor to tip (m; eq. 4.3 has its opposite,
        the direction of the tension) and the moment arm x_m - x_c as the matrix [arm]_x with
        [arm]_x e = arm x e (eq. 4.4 about the reference point x_c)."""
        row = first + wp.tid()
        r = bond_receptor[row]
        if r < 0:
            vector[row] = vec3()
            moment[row] = mat33()
            return
        tip = rigid_tip(r, tips, receptor_body, positions, rotations) + vec3(zero, zero, bond_offset[row])
        vector[row] = tip - bond_anchor[row]
        arm = tip - positions[receptor_body[r]]
        moment[row] = wp.skew(arm)

    @wp.kernel(enable_backward=False)
    def reduce_per_cell(first: int, bond_receptor: wp.array(dtype=int), moment: wp.array(dtype=mat33),
                        bond_force: wp.array(dtype=vec3), capacity: int,
                        force: wp.array(dtype=vec3), torque: wp.array(dtype=vec3), count: wp.array(dtype=int)):
        """Force (N), torque (N m) and number of the bonds of each adhesive cell from each row's
        force on its tip (one thread per cell, rows in order)."""
        c = first + wp.tid()
        f = vec3()
        t = vec3()
        n = int(0)
        for row in range(c * capacity, (c + 1) * capacity):
            if bond_receptor[row] >= 0:
                f = f + bond_force[row]
                t = t + moment[row] * bond_force[row]
                n += 1
        force[c] = f
        torque[c] = t
        count[c] = n

    @wp.kernel(enable_backward=False)
    def rupture(first: int, bond_receptor: wp.array(dtype=int), vector: wp.array(dtype=vec3), spring: dtype,
                rest: dtype,
                compression: int, off_rate: dtype, compliance_per_kt: dtype, dt: dtype, seed: int, draw: int,
                broken: wp.array(dtype=int)):
        """Bell rupture (eq. 4.1): k_r = k_r0 exp(r0 |F| / kT), F = sigma (L - lambda) (a slack bond
        carries no force when bonds resist tension only); broken with 1 - exp(-k_r dt)."""
        row = first + wp.tid()
        broken[row] = 0
        if bond_receptor[row] < 0:
            return
        f = spring * (wp.length(vector[row]) - rest)
        if compression == 0:
            f = wp.max(f, zero)
        rate = off_rate * wp.exp(compliance_per_kt * wp.abs(f))
        if uniform(seed, draw, row) < one - wp.exp(-rate * dt):
            broken[row] = 1
            bond_receptor[row] = -1

    @wp.kernel(enable_backward=False)
    def formation(first: int, bound: wp.array(dtype=int), tips: wp.array(dtype=vec3),
                  receptor_body: wp.array(dtype=int),
                  positions: wp.array(dtype=vec3), rotations: wp.array(dtype=mat33),
                  patch_centre: wp.array(dtype=vec3), patch_radius: wp.array(dtype=dtype),
                  curvature: wp.array(dtype=dtype), rest: dtype, ligand_low: dtype, ligand_high: dtype,
                  spring_per_kt: dtype,
                  compliance: dtype, on_rate: dtype, dt: dtype, seed: int, draw: int,
                  cell_anchor: wp.array(dtype=vec3), cell_deviation: wp.array(dtype=dtype),
                  cell_partner: wp.array(dtype=int),
                  sites: int, site_density: dtype, site_spacing: dtype, site_seed: int, site_deviation: dtype,
                  receptor_cell: wp.array(dtype=int), capacity: int, bond_receptor: wp.array(dtype=int),
                  bond_anchor: wp.array(dtype=vec3), bond_partner: wp.array(dtype=int),
                  candidate: wp.array(dtype=int), anchor: wp.array(dtype=vec3), offset: wp.array(dtype=dtype),
                  partner: wp.array(dtype=int)):
        """Formation (eq. 4.2): k_f = k_f0 exp(sigma |d| (r0 - |d| / 2) / kT), d the deviation from
        the rest length of the best ligand within reach. The wall's ligands, in excess, fill the
        heights ``ligand_low`` <= z <= ``ligand_high`` (a layer, or a plane where the two are
        equal: forces/bond_model.py), so a tip at height z finds one straight below at z - lambda,
        clamped to them; or, if closer to its rest length, the best ligand on a
        ligand-bearing fixed cell (``cell_anchor``, ``cell_deviation``, ``cell_partner``: the
        body, -1 for none; found by ``closest_to_points``); formed with 1 - exp(-k_f dt).
        With ``sites`` the wall's ligands are the points of a Poisson process of density
        ``site_density`` on the plane z = ``ligand_low``, ``site_count`` per square of a lattice
        of ``site_spacing``, each holding one bond: the tip's rate is the sum of eq. 4.2 over the
        free sites (and the cell's ligand) within ``site_deviation`` of its rest length, the one
        it binds drawn in proportion to its rate (one pass: a weighted reservoir)."""
        r = first + wp.tid()
        candidate[r] = 0
        if bound[r] != 0:
            return
        b = receptor_body[r]
        tip = rigid_tip(r, tips, receptor_body, positions, rotations)
        c = patch_centre[b]
        rho = wp.sqrt((tip[0] - c[0]) * (tip[0] - c[0]) + (tip[1] - c[1]) * (tip[1] - c[1]))
        lowering = hertz_lowering(rho, patch_radius[b], curvature[b])
        tip = tip + vec3(zero, zero, lowering)
        if sites != 0:
            # counter 2 n + r: past the formation's (r) and the cap's (n + r, ``insert``)
            pick = wp.rand_init(wp.int32(wp.rand_init(seed, draw)), 2 * bound.shape[0] + r)
            total = zero
            on_site = int(0)
            site = vec3(zero, zero, ligand_low)
            if cell_partner[r] >= 0:
                d = wp.abs(cell_deviation[r])
                total = formation_rate(d, on_rate, spring_per_kt, compliance)
            dz = tip[2] - ligand_low
            window = rest + site_deviation
            if wp.abs(dz) < window:
                row = receptor_cell[r] * capacity
                for ix in range(int(wp.floor((tip[0] - window) / site_spacing)),
                                int(wp.floor((tip[0] + window) / site_spacing)) + 1):
                    for iy in range(int(wp.floor((tip[1] - window) / site_spacing)),
                                    int(wp.floor((tip[1] + window) / site_spacing)) + 1):
                        for k in range(site_count(site_seed, ix, iy, site_density * site_spacing * site_spacing)):
                            point = vec3((dtype(ix) + site_uniform(site_seed, ix, iy, 2 * k + 1)) * site_spacing,
                                         (dtype(iy) + site_uniform(site_seed, ix, iy, 2 * k + 2)) * site_spacing,
                                         ligand_low)
                            d = wp.abs(wp.length(tip - point) - rest)
                            if d < site_deviation:
                                if site_taken(row, capacity, bond_receptor, bond_anchor, bond_partner, point) == 0:
                                    w = formation_rate(d, on_rate, spring_per_kt, compliance)
                                    total += w
                                    if dtype(wp.randf(pick)) * total < w:
                                        on_site = 1
                                        site = point
            if uniform(seed, draw, r) < one - wp.exp(-total * dt):
                candidate[r] = 1
                if on_site == 0:
                    anchor[r] = cell_anchor[r]
                    offset[r] = zero
                    partner[r] = cell_partner[r]
                else:
                    anchor[r] = site
                    offset[r] = lowering
                    partner[r] = -1
            return
        height = wp.clamp(tip[2] - rest, ligand_low, ligand_high)
        d = wp.abs(tip[2] - height - rest)
        on_cell = cell_partner[r] >= 0 and wp.abs(cell_deviation[r]) < d
        if on_cell:
            d = wp.abs(cell_deviation[r])
        if formation_exponent(d, spring_per_kt, compliance) < dtype(NO_RATE_EXPONENT):
            return  # k_f is exactly 0 and no bond forms: its draw is skipped, which changes no other draw
        rate = formation_rate(d, on_rate, spring_per_kt, compliance)
        if uniform(seed, draw, r) < one - wp.exp(-rate * dt):
            candidate[r] = 1
            if on_cell:
                anchor[r] = cell_anchor[r]
                offset[r] = zero
                partner[r] = cell_partner[r]
            else:
                anchor[r] = vec3(tip[0], tip[1], height)
                offset[r] = lowering
                partner[r] = -1

    @wp.kernel(enable_backward=False)
    def insert(first: int, candidate: wp.array(dtype=int), anchor: wp.array(dtype=vec3), offset: wp.array(dtype=dtype),
               partner: wp.array(dtype=int), receptor_start: wp.array(dtype=int), capacity: int, time: dtype,
               replace: int, seed: int, draw: int, n_receptors: int, sites: int,
               bond_receptor: wp.array(dtype=int), bond_anchor: wp.array(dtype=vec3),
               bond_offset: wp.array(dtype=dtype), bond_partner: wp.array(dtype=int),
               bond_birth: wp.array(dtype=dtype), bound: wp.array(dtype=int)):
        """New bonds into each cell's free rows, receptors in index order, up to ``capacity``
        bonds per cell (the cap of thesis figs. 4.12-4.14); past it a new bond is refused, or with
        ``replace`` takes a row drawn uniformly from the cell's (counter n_receptors + r of the
        formation's draw, so the formation's own draws are untouched), whose bond breaks. With
        ``sites`` a wall site another receptor of the cell took in this step is refused."""
        c = first + wp.tid()
        row = c * capacity
        end = (c + 1) * capacity
        for r in range(receptor_start[c], receptor_start[c + 1]):
            taken = int(0)
            if candidate[r] != 0 and sites != 0 and partner[r] < 0:
                taken = site_taken(c * capacity, capacity, bond_receptor, bond_anchor, bond_partner, anchor[r])
            if candidate[r] != 0 and taken == 0:
                while row < end and bond_receptor[row] >= 0:
                    row += 1
                slot = row
                if row >= end and replace != 0:
                    slot = c * capacity + wp.min(int(uniform(seed, draw, n_receptors + r) * dtype(capacity)),
                                                 capacity - 1)
                    bound[bond_receptor[slot]] = 0
                if slot < end:
                    bond_receptor[slot] = r
                    bond_anchor[slot] = anchor[r]
                    bond_offset[slot] = offset[r]
                    bond_partner[slot] = partner[r]
                    bond_birth[slot] = time
                    bound[r] = 1

    @wp.kernel(enable_backward=False)
    def mark_bound(first: int, bond_receptor: wp.array(dtype=int), bound: wp.array(dtype=int)):
        row = first + wp.tid()
        r = bond_receptor[row]
        if r >= 0:
            bound[r] = 1

    return SimpleNamespace(vec3=vec3, mat33=mat33, hertz_lowering=hertz_lowering, bond_geometry=bond_geometry,
                           reduce_per_cell=reduce_per_cell,
                           rupture=rupture, formation=formation, insert=insert, mark_bound=mark_bound)


def _launch(kernel, device, n: int, arguments):
    """Launch over n threads (the kernels' ``first`` offset prepended); on the CPU a long
    launch is split over the thread pool, a short one is not worth the threads."""
    if device.is_cpu and n >= SPLIT_THREADS:
        launch_rows(kernel, n, lambda start, stop: [start, *arguments], device)
    elif n:
        wp.launch(kernel, dim=n, inputs=[0, *arguments], device=device)


def bond_geometry(kernels, device, n: int, bond_receptor, bond_anchor, bond_offset, tips, receptor_body, positions,
                  rotations, vector, moment):
    """``vector`` and ``moment`` of the n table rows."""
    _launch(kernels.bond_geometry, device, n, [bond_receptor, bond_anchor, bond_offset, tips, receptor_body, positions,
                                               rotations, vector, moment])


def reduce_per_cell(kernels, device, n: int, bond_receptor, moment, bond_force, capacity: int, force, torque, count):
    """``force``, ``torque`` and ``count`` of the n adhesive cells."""
    _launch(kernels.reduce_per_cell, device, n, [bond_receptor, moment, bond_force, capacity, force, torque, count])


def rupture(kernels, device, n: int, bond_receptor, vector, spring, rest, compression: int, off_rate,
            compliance_per_kt, dt, seed: int, draw: int, broken):
    """``broken`` of the n table rows, and their ``bond_receptor`` freed."""
    _launch(kernels.rupture, device, n, [bond_receptor, vector, spring, rest, compression, off_rate,
                                         compliance_per_kt, dt, seed, draw, broken])


def mark_bound(kernels, device, n: int, bond_receptor, bound):
    """``bound`` set for the receptor of each of the n table rows."""
    _launch(kernels.mark_bound, device, n, [bond_receptor, bound])


def formation(kernels, device, n: int, bound, tips, receptor_body, positions, rotations, patch_centre, patch_radius,
              curvature, rest, ligand_low, ligand_high, spring_per_kt, compliance, on_rate, dt, seed: int,
              draw: int, cell_anchor, cell_deviation, cell_partner, sites, receptor_cell, capacity: int,
              bond_receptor, bond_anchor, bond_partner, candidate, anchor, offset, partner):
    """``candidate``, ``anchor``, ``offset`` and ``partner`` of the n receptors; ``sites``: None, or
    (density 1/m^2, lattice spacing m, seed, deviation m) of the wall's ligand sites."""
    site = (0, 0.0, 1.0, 0, 0.0) if sites is None else (1, *sites)
    _launch(kernels.formation, device, n, [bound, tips, receptor_body, positions, rotations, patch_centre,
                                           patch_radius, curvature, rest, ligand_low, ligand_high, spring_per_kt,
                                           compliance, on_rate, dt, seed, draw, cell_anchor, cell_deviation,
                                           cell_partner, *site, receptor_cell, capacity, bond_receptor,
                                           bond_anchor, bond_partner, candidate, anchor, offset, partner])


def insert(kernels, device, n: int, candidate, anchor, offset, partner, receptor_start, capacity: int, time,
           replace: bool, seed: int, draw: int, sites: bool, bond_receptor, bond_anchor, bond_offset, bond_partner,
           bond_birth, bound):
    """The new bonds of the n adhesive cells into their table rows (past the cap refused, or with
    ``replace`` in the place of a bond drawn from the formation's ``draw``), and ``bound`` set."""
    _launch(kernels.insert, device, n, [candidate, anchor, offset, partner, receptor_start, capacity, time,
                                        int(replace), seed, draw, candidate.shape[0], int(sites), bond_receptor,
                                        bond_anchor, bond_offset, bond_partner, bond_birth, bound])
