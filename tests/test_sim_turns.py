"""The turns at the grid's edge (`swarmgen.sim.turns`): the kept draws are the streams' own, and
the plain-Python turn gives the numpy turn's bits (headings, leg lengths, draws taken)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmgen.sim import world as world_module
from swarmgen.sim.grid import GAMMAS, Geometry, mix64
from swarmgen.sim.turns import GOLDEN, KEPT, Draws, longest, longest_one
from swarmgen.sim.world import World

W, H = 37, 23


def directions(key: int, drawn: int, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The cosine and sine of draws drawn+1 .. drawn+count of a stream, as the world computed
    them before draws were kept: mix the stream's state, take its top 53 bits."""
    state = np.uint64((key + drawn * int(GOLDEN)) % 2**64)
    z = mix64(state + GAMMAS[1 : count + 1])
    angle = (2.0 * math.pi) * ((z >> np.uint64(11)).astype(np.float64) * (1.0 / 2.0**53))
    return np.cos(angle), np.sin(angle)


def test_kept_draws_are_the_streams_draws() -> None:
    keys = np.array([1, 2**63 + 5, 2**64 - 1, 987654321], dtype=np.uint64)
    draws = Draws(keys)
    g = np.arange(4, dtype=np.int64)
    # forward past several fills, then back (a restored snapshot), then one at a time
    for drawn in ([0, 3, 7, 56], [57, 60, 100, 500], [2, 0, 99, 501], [KEPT * 3] * 4):
        taken = np.array(drawn, dtype=np.int64)
        cos, sin = draws.candidates(g, taken)
        for i, key in enumerate(keys.tolist()):
            want_cos, want_sin = directions(key, drawn[i], 8)
            assert cos[i].tolist() == want_cos.tolist()
            assert sin[i].tolist() == want_sin.tolist()
            one_cos, one_sin = draws.one(i, drawn[i] + 1)
            assert one_cos == directions(key, drawn[i] + 1, 8)[0].tolist()
            assert one_sin == directions(key, drawn[i] + 1, 8)[1].tolist()


def test_one_body_s_leg_is_the_numpy_leg() -> None:
    rng = np.random.default_rng(4)
    starts = [(0.0, 0.0), (W, 0.0), (0.0, H), (W, H), (W - 1e-12, 5.5), (3.25, H - 1e-9)]
    starts += [(float(x), float(y)) for x, y in rng.random((300, 2)) * (W, H)]
    heads = [0.0, math.pi / 2, math.pi, -math.pi / 2, math.pi / 4, 1e-17]
    heads += (rng.random(300) * 2 * math.pi).tolist()
    ox, oy = np.array([s[0] for s in starts] * 2), np.array([s[1] for s in starts] * 2)
    angle = np.array(heads * 2)[: len(ox)]
    dx, dy = np.cos(angle), np.sin(angle)
    dx[:6], dy[6:12] = 0.0, -0.0  # axis-parallel legs, both signed zeros
    steps = longest(ox, oy, dx, dy, W, H)
    for i in range(len(ox)):
        one = longest_one(float(ox[i]), float(oy[i]), float(dx[i]), float(dy[i]), W, H)
        assert one == int(steps[i]), i


def world(runs: int) -> World:
    """Three members per run, fanned out from the south side of a small grid."""
    keys = np.arange(runs, dtype=np.uint64) * np.uint64(7919) + np.uint64(3)
    xs, heads = np.array([5.0, 18.0, 30.0]), np.array([2.5, 1.6, 0.4])
    targets = np.zeros((runs, 0, 2), dtype=np.int64)
    return World(Geometry(W, H, 1), keys, xs, np.zeros(3), heads, targets)


@pytest.mark.parametrize("rounds", [[5, 90, 91, 400, 2000], [3000]])
def test_few_members_turn_as_numpy_turns_them(
    monkeypatch: pytest.MonkeyPatch, rounds: list[int]
) -> None:
    ran = []
    for few in (0, 10**6):  # every turn in numpy, then every turn in plain Python
        monkeypatch.setattr(world_module, "FEW", few)
        w = world(6)
        for g in range(len(w.moving)):
            w.start_covering(g, 0, reports=False)
        now = np.zeros(6, dtype=np.int64)
        for h in rounds:
            horizon = np.full(6, h, dtype=np.int64)
            horizon[::2] += 17  # runs' rounds end apart
            now, _ = w.advance(now, horizon)
        ran.append(
            (
                w.body.tolist(),
                w.s0.tolist(),
                w.seg_end.tolist(),
                w.draws.drawn.tolist(),
                [w.seen_times(r).tolist() for r in range(6)],
            )
        )
    assert ran[0] == ran[1]
    assert max(ran[0][3]) > KEPT  # the kept draws were filled again on the way
