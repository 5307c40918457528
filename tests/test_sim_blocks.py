"""`swarmgen.sim.blocks.entering`: what a step brings into view, against the plain set difference
of the two views (the view around the new patch less the view around the one before)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from swarmgen.sim.blocks import entering, padded_index
from swarmgen.sim.grid import Geometry

RUNS = 2


def _view_offsets(geometry: Geometry) -> np.ndarray:
    """The view's offsets in the padded grid, as `World` builds them."""
    v, pw = geometry.view, geometry.width + 2 * geometry.view
    oy, ox = np.divmod(np.arange((2 * v + 1) ** 2), 2 * v + 1)
    offsets: np.ndarray = (oy - v) * pw + (ox - v)
    return offsets


def _view(geometry: Geometry, padded: int) -> set[int]:
    """The padded patches in view of a padded patch, one by one."""
    v, pw = geometry.view, geometry.width + 2 * geometry.view
    return {padded + dy * pw + dx for dy in range(-v, v + 1) for dx in range(-v, v + 1)}


def _entering(geometry: Geometry, now: list[int], before: list[int], full: list[bool]) -> list[int]:
    index = padded_index(RUNS, geometry)
    result = entering(
        index[np.array(now)],
        index[np.array(before)],
        np.array(full, dtype=np.bool_),
        geometry,
        _view_offsets(geometry).astype(index.dtype),
    )
    return [int(p) for p in result]


def _flat(geometry: Geometry, run: int, x: int, y: int) -> int:
    return run * geometry.cells + y * geometry.width + x


STEPS = list(itertools.product((-1, 0, 1), repeat=2))  # all 9, standing still included


@pytest.mark.parametrize("view", [1, 2, 3])
@pytest.mark.parametrize("step", STEPS)
def test_a_step_to_a_neighbour_brings_the_difference_of_the_views(
    view: int, step: tuple[int, int]
) -> None:
    geometry = Geometry(width=13, height=11, view=view)
    index = padded_index(RUNS, geometry)
    dx, dy = step
    for run, (x, y) in itertools.product(range(RUNS), [(6, 5), (1, 1), (11, 9), (0, 10)]):
        before = _flat(geometry, run, x, y)
        if not (0 <= x + dx < geometry.width and 0 <= y + dy < geometry.height):
            continue
        now = _flat(geometry, run, x + dx, y + dy)
        got = _entering(geometry, [now], [before], [False])
        expected = _view(geometry, int(index[now])) - _view(geometry, int(index[before]))
        assert set(got) == expected
        # one column and/or one row, each patch once (a diagonal's corner too)
        assert len(got) == len(set(got))


@pytest.mark.parametrize("view", [1, 2])
@pytest.mark.parametrize("jump", [(2, 0), (0, -2), (2, 2), (-2, 1)])
def test_a_jump_brings_the_whole_view(view: int, jump: tuple[int, int]) -> None:
    """Not a step to a neighbour: the whole view (a superset of the difference), as before."""
    geometry = Geometry(width=13, height=11, view=view)
    index = padded_index(RUNS, geometry)
    before = _flat(geometry, 1, 6, 5)
    now = _flat(geometry, 1, 6 + jump[0], 5 + jump[1])
    got = _entering(geometry, [now], [before], [False])
    whole = _view(geometry, int(index[now]))
    assert sorted(got) == sorted(whole)
    assert whole > whole - _view(geometry, int(index[before]))


@pytest.mark.parametrize("view", [1, 2])
def test_a_piece_s_first_point_brings_the_whole_view(view: int) -> None:
    """`full` (a piece's first point): the whole view whatever the point before it is."""
    geometry = Geometry(width=13, height=11, view=view)
    index = padded_index(RUNS, geometry)
    now = _flat(geometry, 0, 4, 4)
    for before in (now, now + 1, _flat(geometry, 1, 9, 9)):
        got = _entering(geometry, [now], [before], [True])
        assert sorted(got) == sorted(_view(geometry, int(index[now])))


def test_a_mixed_batch_is_the_union_point_by_point() -> None:
    """Many points at once (steps, a jump, first points, both runs): every point's own share."""
    geometry = Geometry(width=13, height=11, view=1)
    index = padded_index(RUNS, geometry)
    rng = np.random.default_rng(7)
    now, before, full, expected = [], [], [], set()
    for _ in range(200):
        run, x, y = int(rng.integers(RUNS)), int(rng.integers(2, 11)), int(rng.integers(2, 9))
        dx, dy = (int(d) for d in rng.integers(-2, 3, size=2))
        first = bool(rng.random() < 0.2)
        a, b = _flat(geometry, run, x, y), _flat(geometry, run, x - dx, y - dy)
        now.append(a)
        before.append(b)
        full.append(first)
        view = _view(geometry, int(index[a]))
        neighbour = abs(dx) <= 1 and abs(dy) <= 1
        expected |= view if first or not neighbour else view - _view(geometry, int(index[b]))
    assert set(_entering(geometry, now, before, full)) == expected


def test_view_zero_is_the_patch_itself() -> None:
    geometry = Geometry(width=5, height=5, view=0)
    index = padded_index(RUNS, geometry)
    now = [_flat(geometry, 0, 2, 2), _flat(geometry, 1, 3, 2)]
    got = _entering(geometry, now, [_flat(geometry, 0, 1, 2), now[1]], [False, True])
    assert got == [int(index[p]) for p in now]
