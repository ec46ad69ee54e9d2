"""``warpbem xdmf RUN.h5``: the bodies of a run as moving QUAD9 meshes for ParaView (XDMF 3).

Writes ``RUN.xdmf`` (XML: a temporal collection with one grid per frame) and ``RUN.xdmf.h5``
(the data it points to, group ``/xdmf``: the connectivity of all bodies' elements and each
body's index per element, written once, and the world node coordinates of every frame, in
metres). The run file is only read, without HDF5's file lock, so a run that is still writing
can be looked at: the frames complete in every column so far are taken.

Element node order: XDMF's ``Quadrilateral_9`` is read as VTK_BIQUADRATIC_QUAD (corners
counter-clockwise, then the mid-edge nodes of edges 01, 12, 23, 30, then the centre), which is
the order of ``warpbem.surfaces.quad9.REFERENCE_NODES``, so the connectivity is written unchanged.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np

from ..surfaces.body import Body
from .io import RunFileError, complete_rows, open_result, read_meshes
from .scene import SceneError, parse


DISPLACEMENT = "deformation_node_displacement"  # the frame column of deformable cells' shapes


def read_frames(run_path: Path):
    """(meshes, time (F,), positions (F, n, 3), orientations (F, n, 4), node displacements (F, n,
    N, 3) in the body frames or None for rigid runs) of the frames complete in every column (the
    writer fills the columns one by one), read without a lock."""
    with open_result(run_path, needs=("time", "position", "orientation", "scene", "scene_folder")) as f:
        meshes = read_meshes(f)
        if meshes is None:  # a file of an earlier version: the meshes rebuilt from its scene
            try:
                meshes = [b.mesh for b in parse(json.loads(f.attrs["scene"]), Path(f.attrs["scene_folder"])).bodies]
            except SceneError as err:
                raise RunFileError(f"{run_path}: cannot rebuild the meshes of its scene: {err}") from err
        frames = complete_rows(f)
        if frames == 0:
            raise RunFileError(f"{run_path}: the run has no frame yet")
        time, positions, orientations = (f[k][:frames] for k in ("time", "position", "orientation"))
        displacement = f[DISPLACEMENT][:frames] if DISPLACEMENT in f else None
    if positions.shape[1] != len(meshes):
        raise RunFileError(f"{run_path}: {positions.shape[1]} bodies in the frames but {len(meshes)} in its scene")
    return meshes, time, positions, orientations, displacement


def world_nodes(meshes, positions, orientations, displacement=None) -> np.ndarray:
    """All bodies' nodes in the world frame, concatenated; ``displacement`` (n, N, 3): the
    deformable cells' node displacements in their body frames (warpbem/elastic/deformable.py)."""
    out = []
    for i, (m, p, q) in enumerate(zip(meshes, positions, orientations)):
        nodes = m.nodes if displacement is None else m.nodes + displacement[i, :len(m.nodes)]
        out.append(nodes @ Body(m, orientation=q).rotation().T + p)
    return np.concatenate(out)


def _data_item(parent, dims, number_type, precision, reference):
    item = ET.SubElement(parent, "DataItem", Dimensions=" ".join(map(str, dims)), NumberType=number_type,
                         Precision=str(precision), Format="HDF")
    item.text = reference


def write(run_path) -> Path:
    """Write ``RUN.xdmf`` and ``RUN.xdmf.h5`` beside the run file ``RUN.h5``; returns the .xdmf."""
    run_path = Path(run_path)
    meshes, time, positions, orientations, displacement = read_frames(run_path)
    offsets = np.cumsum([0] + [len(m.nodes) for m in meshes])
    connectivity = np.concatenate([m.elements + o for m, o in zip(meshes, offsets)])
    body = np.concatenate([np.full(m.n_elements, i, dtype=np.int32) for i, m in enumerate(meshes)])
    n_nodes, n_elements = int(offsets[-1]), len(connectivity)

    data_path, xml_path = run_path.with_suffix(".xdmf.h5"), run_path.with_suffix(".xdmf")
    names = [f"frame{i:06d}" for i in range(len(time))]
    with h5py.File(data_path, "w") as f:
        group = f.create_group("xdmf")
        group.attrs["source"] = str(run_path.resolve())
        group.create_dataset("connectivity", data=connectivity.astype(np.int64))
        group.create_dataset("body", data=body)
        nodes = group.create_group("nodes")
        nodes.attrs["unit"] = "m"
        for k, (name, p, q) in enumerate(zip(names, positions, orientations)):
            nodes.create_dataset(name, data=world_nodes(meshes, p, q, None if displacement is None else displacement[k]))

    root = ET.Element("Xdmf", Version="3.0")
    domain = ET.SubElement(root, "Domain")
    series = ET.SubElement(domain, "Grid", Name=run_path.stem, GridType="Collection", CollectionType="Temporal")
    ET.SubElement(series, "Information", Name="units", Value="SI: coordinates in m, time in s")
    ref = f"{data_path.name}:/xdmf"  # relative to the .xdmf file, so the pair can be moved together
    for name, t in zip(names, time):
        grid = ET.SubElement(series, "Grid", Name=name, GridType="Uniform")
        ET.SubElement(grid, "Time", Value=repr(float(t)))  # repr: the exact double back on reading
        topology = ET.SubElement(grid, "Topology", TopologyType="Quadrilateral_9", NumberOfElements=str(n_elements))
        _data_item(topology, (n_elements, 9), "Int", 8, f"{ref}/connectivity")
        geometry = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
        _data_item(geometry, (n_nodes, 3), "Float", 8, f"{ref}/nodes/{name}")
        attribute = ET.SubElement(grid, "Attribute", Name="body", AttributeType="Scalar", Center="Cell")
        _data_item(attribute, (n_elements,), "Int", 4, f"{ref}/body")
    ET.indent(root)
    ET.ElementTree(root).write(xml_path, encoding="utf-8", xml_declaration=True)
    return xml_path
