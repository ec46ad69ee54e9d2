"""The store of kept blocks (warpbem/hydro/operators/kept_blocks.py): a dense operator built with
it takes the blocks of unmoved bodies from the last matrix and assembles only the rest, in each
of the three placements, and gives the matrix a fresh assembly gives; an operator whose matrix
another took assembles it again on its own."""

import numpy as np
import pytest

import warpbem as wb
from warpbem.hydro.geometry import SurfaceGeometry
from warpbem.hydro.operators import BoundaryOperator, KeptBlocks, QuadratureOptions, discrete_form

SPHERE = wb.mesh.sphere(1.0, 2)
A = wb.Body(SPHERE, position=(0.0, 0.0, 1.5), fixed=True)
B = wb.Body(SPHERE, position=(3.0, 0.5, 1.4), fixed=True)
NEAR_WALL, FAR = (-5.0, 1.0, 1.05), (-5.0, 1.0, 2.5)  # refined near the wall (contact_refinement 3), not far


def description(bodies, **kwargs):
    geometry = SurfaceGeometry.from_bodies(bodies, 2, 1.0, True, 3.0)
    return BoundaryOperator(geometry, True, **kwargs)


def fresh(bodies) -> np.ndarray:
    return discrete_form(description(bodies), "dense").to_dense()


def moving(position):
    return wb.Body(SPHERE, position=position)


def test_unmoved_bodies_keep_their_blocks_in_place_and_the_matrix_is_the_fresh_one():
    store = KeptBlocks()
    first = discrete_form(description([A, B, moving(FAR)]), "dense", kept=store)
    pointer = first.matrix().ptr
    assert not first.reused_bodies.any()  # nothing was held
    moved = [A, B, moving((-4.5, 1.0, 2.5))]  # the moving cell keeps its element count
    second = discrete_form(description(moved), "dense", kept=store)
    np.testing.assert_array_equal(second.to_dense(), fresh(moved))
    assert second.reused_bodies.tolist() == [True, True, False]
    assert store.placement == "in place" and second.matrix().ptr == pointer
    # the first operator's matrix was taken: asked again, it assembles its own, afresh
    np.testing.assert_array_equal(first.to_dense(), fresh([A, B, moving(FAR)]))
    assert first.matrix().ptr != pointer and second.matrix().ptr == pointer


def test_a_kept_block_moves_within_its_buffer_when_the_moving_cell_shrinks():
    """The moving cell first, refined near the wall, then far from it: its element count falls,
    the kept cells' block shifts towards the start within the same buffer."""
    store = KeptBlocks()
    near = discrete_form(description([moving(NEAR_WALL), A, B]), "dense", kept=store)
    pointer = near.matrix().ptr
    bodies = [moving(FAR), A, B]
    far = discrete_form(description(bodies), "dense", kept=store)
    np.testing.assert_array_equal(far.to_dense(), fresh(bodies))
    assert far.size < near.size and far.reused_bodies.tolist() == [False, True, True]
    assert store.placement == "moved" and far.matrix().ptr == pointer


def test_kept_blocks_are_gathered_into_a_new_matrix_where_they_cannot_move_in_place():
    """Kept bodies on either side of a moving cell whose count changes are not one block: they
    are gathered into a new buffer, and the store then holds that one only."""
    store = KeptBlocks()
    first = discrete_form(description([A, moving(FAR), B]), "dense", kept=store)
    pointer = first.matrix().ptr
    bodies = [A, moving(NEAR_WALL), B]
    second = discrete_form(description(bodies), "dense", kept=store)
    np.testing.assert_array_equal(second.to_dense(), fresh(bodies))
    assert second.size > first.size and second.reused_bodies.tolist() == [True, False, True]
    assert store.placement == "gathered" and second.matrix().ptr != pointer
    assert store.holds(second._lease) and not store.holds(first._lease)


def test_only_an_operator_of_the_same_kind_quadrature_and_precision_takes_kept_blocks():
    store = KeptBlocks()
    bodies = [A, B, moving(FAR)]
    discrete_form(description(bodies), "dense", kept=store).matrix()
    same = description(bodies)
    assert store.reusable_bodies(same.signature("cpu"), same.geometry).all()
    for other in (dict(kind="adjoint_double_layer"), dict(quadrature=QuadratureOptions(order=3)),
                  dict(dtype="float32")):
        changed = description(bodies, **other)
        assert not store.reusable_bodies(changed.signature("cpu"), changed.geometry).any()
    with pytest.raises(ValueError, match="holds no matrix"):
        KeptBlocks().take(description(bodies).signature("cpu"), description(bodies).geometry, np.ones(3, bool),
                          None, None)
