"""Member types that see differently (`World(views=...)`): a world of two covering members with
views 0 and 2 sees exactly what the two members see alone, in worlds of one member each with the
same random streams (movement does not depend on what is seen), and finds a target when the
member whose view holds it passes."""

from __future__ import annotations

import numpy as np

from swarmgen.sim.grid import INF, MEMBER_KEY, Geometry
from swarmgen.sim.world import World

SIDE = 23
KEYS = np.array([11, 12345], dtype=np.uint64)  # two runs


def world(views: list[int], members: list[int], targets: list[tuple[int, int]]) -> World:
    """Members `members` (of a two-member swarm) on the south side, heading north-west and
    north-east, in a world padded by the largest view; a member keeps its stream whatever the
    world it is in (the run key shifted by its index)."""
    geometry = Geometry(SIDE, SIDE, max(views))
    keys = KEYS + np.uint64(members[0]) * MEMBER_KEY if len(members) == 1 else KEYS
    xs = np.array([8.0, 14.0])[members]
    heads = np.array([2.2, 0.9])[members]
    placed = np.array([targets] * len(KEYS), dtype=np.int64).reshape(len(KEYS), len(targets), 2)
    return World(geometry, keys, xs, np.zeros(len(members)), heads, placed, np.array(views))


def cover(w: World, horizons: list[int]) -> None:
    """Every member covers from tick 0, in rounds up to each horizon."""
    for g in range(len(w.moving)):
        w.start_covering(g, 0, reports=False)
    now = np.zeros(len(KEYS), dtype=np.int64)
    for h in horizons:
        end, _ = w.advance(now, np.full(len(KEYS), h, dtype=np.int64))
        now = end


def test_two_sight_classes_see_what_each_member_sees() -> None:
    horizons = [7, 40, 41, 120, 200]
    both = world([0, 2], [0, 1], [])
    cover(both, horizons)
    assert both.views == [0, 2]
    narrow, wide = world([0], [0], []), world([2], [1], [])
    cover(narrow, horizons)
    cover(wide, horizons)
    for run in range(len(KEYS)):
        expect = np.minimum(narrow.seen_times(run), wide.seen_times(run))
        got = both.seen_times(run)
        assert np.array_equal(got, expect)
        assert both.covered[run] == np.count_nonzero(expect != INF)
        assert 0 < both.covered[run] < SIDE * SIDE  # neither nothing nor everything
    # the narrow member alone sees less than with a view of 2: the classes differ
    alone = world([2], [0], [])
    cover(alone, horizons)
    assert np.count_nonzero(alone.seen_times(0) != INF) > narrow.covered[0]


def test_a_target_is_found_by_the_view_that_holds_it() -> None:
    # two patches east of where member 0 (heading north-west) stands at tick 6: in a view of 2
    # on its way, never on a patch it stands on; member 1 heads north-east, far from it
    path = world([0, 2], [0, 1], [])
    path.start_covering(0, 0, reports=False)
    x, y = path.where(0, 6)
    target = (int(x + 0.5) + 2, int(y + 0.5))
    for views, finds_it in (([0, 2], False), ([2, 0], True)):
        w = world(views, [0, 1], [target])
        w.detecting[:] = True
        for g in range(len(w.moving)):  # both members of both runs
            assert w.start_covering(g, 0, reports=False) == []  # nothing in view at the start
        end, finds = w.advance(np.zeros(2, dtype=np.int64), np.full(2, 12, dtype=np.int64))
        if finds_it:
            assert [(run, g) for run, g, _, _ in finds] == [(0, 0), (1, 2)]
            assert all(2 <= tick < 12 for tick in end), end
            assert w.targets_in_view(0, finds[0][2], finds[0][3]) == [0]
        else:
            assert finds == [] and list(end) == [12, 12]


def test_starts_recorded_together_or_one_by_one_see_the_same() -> None:
    """Members that begin covering are recorded when coverage is next read or moved (a batch's
    starts of one tick at once): the same seen times and counts as recording each at once."""
    together, apart = world([0, 2], [0, 1], []), world([0, 2], [0, 1], [])
    for g in range(len(together.moving)):
        together.start_covering(g, 3 * g, reports=False)
        apart.start_covering(g, 3 * g, reports=False)
        assert apart.covered.sum() > 0  # read: recorded now
    for w in (together, apart):
        w.advance(np.full(len(KEYS), 9, dtype=np.int64), np.full(len(KEYS), 60, dtype=np.int64))
    for run in range(len(KEYS)):
        assert np.array_equal(together.seen_times(run), apart.seen_times(run))
        assert together.covered[run] == apart.covered[run] > 0
