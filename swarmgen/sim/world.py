"""The abstract world of the paper's "Performance Evaluation", in numpy, for a batch of runs.

A bounded grid of `width` x `height` patches without obstacles; patch (i, j) is the unit square
centred on the point (i, j), so a body at (x, y) stands on patch (floor(x + 0.5), floor(y + 0.5)).
Members move one patch length per tick. A member sees the patches within `view` of its own in
both axes (view 1: its patch and the 8 around it, the Moore neighbourhood). Member types may
see differently (`Scenario.views`): the members of one view radius form a *sight* class, and
what they stood on, and which patches have a target in their view, is kept per class; the
grid's padding is the largest view, and which patches are seen is shared by all.

The batch holds `runs` independent repetitions with the same composition; member `g` of the
batch is member `g % per_run` of run `g // per_run`. Everything is an array over all members or
all runs, so one numpy call advances every member of every repetition.

Coverage is the random-direction algorithm: a covering member flies straight until its next
step would leave the grid, then turns to a uniformly random direction that keeps it inside
(drawn again until it does). Movement is computed a straight segment at a time: at tick k a
body is at `origin + (k - s0) * heading`, with the same floating-point expression everywhere, so
results do not depend on how ticks are grouped into rounds. Internally positions are kept in
patch-corner coordinates (u = x + 0.5), where the patch is simply floor(u). Random draws come
from a counter-based generator keyed by (run, member, draw number): the same seed gives the same
numbers however runs are batched or spread over processes.

Coverage is recorded as times: `first[c]` is the first tick a covering member stood on patch c;
when each patch was first *seen* is the minimum of `first` over the view around it
(`seen_times`), so coverage times to any percentage are order statistics. During the run only
the count of patches seen is kept up to date (`covered`), for the stop condition. Stretches of a
leg whose view holds no unseen patch and no target are skipped without computing their positions
(`swarmgen.sim.blocks`): they cannot change a number.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmgen.sim.blocks import Blocks, entering_parts
from swarmgen.sim.grid import (
    BLOCK,
    F64,
    I64,
    INF,
    MEMBER_KEY,
    SHIFT,
    STRETCH,
    U64,
    Bool,
    Geometry,
    Points,
    distinct,
    mix64,
)
from swarmgen.sim.targets import CLAIMED, FOUND, RESCUED, UNFOUND, Targets
from swarmgen.sim.turns import TRIES, Draws, inside, longest, longest_one, turn_one

__all__ = ["CLAIMED", "FOUND", "RESCUED", "UNFOUND", "World"]

Pieces = tuple[tuple[I64, I64, I64, I64], F64]  # (member, start, steps, s0), body rows
FEW = 12  # members left turning in a round that turn in plain Python (`swarmgen.sim.turns`)


class World(Targets):
    """Bodies, coverage and targets of `runs` repetitions; see the module docstring."""

    def __init__(
        self,
        geometry: Geometry,
        run_keys: U64,
        start_x: F64,
        start_y: F64,
        headings: F64,
        targets: I64,
        views: I64 | None = None,
    ) -> None:
        """`start_x`, `start_y`, `headings`: per member of one run; `run_keys`: one random key
        per run; `targets`: (runs, count, 2) patch coordinates; `views`: per member of one run,
        its view radius, at most `geometry.view` (default: that view for every member)."""
        self.geometry = geo = geometry
        self.W, self.H, self.v = geo.width, geo.height, geo.view
        self.WH = geo.cells
        self.PW, self.PH = geo.width + 2 * geo.view, geo.height + 2 * geo.view
        self.PWH = self.PW * self.PH
        self.runs = runs = len(run_keys)
        self.per_run = per_run = len(start_x)
        self.run_of: I64 = np.repeat(np.arange(runs, dtype=np.int64), per_run)
        own = np.full(per_run, geo.view, dtype=np.int64) if views is None else np.asarray(views)
        # the sight classes: their view radii, and each member's class
        self.views: list[int] = sorted({int(v) for v in own}) or [geo.view]
        self.sight: I64 = np.tile(np.searchsorted(self.views, own), runs).astype(np.int64)
        self._init_bodies(run_keys, start_x, start_y, headings)
        self.blocks = Blocks(runs, geo)  # before the targets: their views mark blocks
        self._init_coverage()
        self._init_targets(targets)

    def _init_bodies(self, run_keys: U64, start_x: F64, start_y: F64, headings: F64) -> None:
        """Random streams, positions, headings and activity flags of every member."""
        runs, per_run = self.runs, self.per_run
        count = runs * per_run
        member = np.tile(np.arange(per_run, dtype=np.uint64), runs)
        run_keys = np.asarray(run_keys, dtype=np.uint64)
        # each member's random stream: splitmix64, state = key + draws * golden gamma
        self.draws = Draws(mix64(run_keys[self.run_of] + member * MEMBER_KEY))
        # the body, in patch-corner coordinates: position (the segment's origin while
        # covering), heading, the segment's first and last tick
        self.body: NDArray[np.float64] = np.empty((count, 4), dtype=np.float64)
        self.ox: F64 = self.body[:, 0]  # views: the columns of `body`
        self.oy: F64 = self.body[:, 1]
        self.dx: F64 = self.body[:, 2]
        self.dy: F64 = self.body[:, 3]
        self.ox[:] = np.tile(np.asarray(start_x, dtype=np.float64), runs) + 0.5
        self.oy[:] = np.tile(np.asarray(start_y, dtype=np.float64), runs) + 0.5
        self.dx[:] = np.tile(np.cos(headings), runs)
        self.dy[:] = np.tile(np.sin(headings), runs)
        self.s0: I64 = np.zeros(count, dtype=np.int64)
        self.seg_end: I64 = np.zeros(count, dtype=np.int64)
        self.start_cell: I64 = np.floor(self.oy).astype(np.int64) * self.W + np.floor(
            self.ox
        ).astype(np.int64)
        self.moving: Bool = np.zeros(count, dtype=np.bool_)  # running Coverage
        self.detecting: Bool = np.zeros(count, dtype=np.bool_)  # running TargetMonitoring
        self.reports: Bool = np.zeros(count, dtype=np.bool_)  # its Coverage ends on a find

    def _init_coverage(self) -> None:
        """Coverage: per sight class the first tick on each patch and which patches were stood
        on; which patches were seen (the flags are padded by the largest view so a view never
        needs bounds checks); patches seen per run."""
        runs, classes = self.runs, len(self.views)
        # every per-patch array is indexed in the padded grid (run included, `cell`), as the
        # round's positions are; its padding is never stood on, seen from the start
        self.first: NDArray[np.int32] = np.full((classes, runs * self.PWH), INF, dtype=np.int32)
        # patches stood on, and past them `dummy`: the index `Points` gives past a row's end,
        # always stood on (never new) and never near a target
        self.dummy = runs * self.PWH
        # the dtype of positions
        self.index: np.dtype[Any] = np.dtype(np.int32 if self.dummy < 2**31 else np.int64)
        self.stood: NDArray[np.uint8] = np.zeros((classes, self.dummy + 1), dtype=np.uint8)
        self.stood[:, self.dummy] = 1
        seen = np.ones((runs, self.PH, self.PW), dtype=np.uint8)  # the padding counts as seen
        seen[:, self.v : self.v + self.H, self.v : self.v + self.W] = 0
        self.seen_flag: NDArray[np.uint8] = seen.reshape(-1)
        self._covered: I64 = np.zeros(runs, dtype=np.int64)
        # members that began covering (member, tick, padded patch) whose patch is not recorded
        # yet: recorded together when coverage is next read or moved (`_flush`)
        self._starts: list[tuple[int, int, int]] = []
        self._stamp_seen: NDArray[np.int32] = np.zeros(runs * self.PWH, dtype=np.int32)
        self._view_offsets = []  # per sight class: its view around a patch, in the padded grid
        for v in self.views:
            oy_, ox_ = np.divmod(np.arange((2 * v + 1) ** 2, dtype=np.int64), 2 * v + 1)
            offsets = ((oy_ - v) * self.PW + (ox_ - v)).astype(self.index)
            self._view_offsets.append(offsets)

    # --- geometry

    def cell(self, run: I64 | int, ix: int, iy: int) -> I64:
        """The flat index of patch (ix, iy) of runs in the padded grids."""
        cell: I64 = (np.asarray(run, dtype=np.int64) * self.PH + iy + self.v) * self.PW
        cell += ix + self.v
        return cell

    def patch(self, cell: int) -> tuple[int, int, int]:
        """The run and patch (ix, iy) of a flat index in the padded grids."""
        run, rest = divmod(cell, self.PWH)
        iy, ix = divmod(rest, self.PW)
        return run, ix - self.v, iy - self.v

    def where(self, member: int, tick: int | None = None) -> tuple[float, float]:
        """Where a member is (at `tick` if it is covering)."""
        steps = float(tick - self.s0[member]) if tick is not None and self.moving[member] else 0.0
        u = self.ox[member] + steps * self.dx[member]
        w = self.oy[member] + steps * self.dy[member]
        return float(u) - 0.5, float(w) - 0.5

    def place(self, member: int, x: float, y: float) -> None:
        """Put a standing member at (x, y) (a drive ends, or is stopped on the way)."""
        self.ox[member], self.oy[member] = x + 0.5, y + 0.5

    # --- covering

    def start_covering(self, member: int, tick: int, reports: bool) -> list[int]:
        """Coverage starts: the member goes on from where it stands, in its current direction.
        Its view now counts as seen; returns the unfound targets in view (if it detects)."""
        self.stop_covering(member, tick)  # a second Coverage goes on from where it is
        self.moving[member] = True
        self.reports[member] = reports
        self.s0[member] = tick
        ox, oy, dx, dy = self.body[member].tolist()  # one body: plain floats, the same bits
        self.seg_end[member] = tick + longest_one(ox, oy, dx, dy, self.W, self.H)
        ix, iy = int(self.ox[member]), int(self.oy[member])
        self._starts.append((member, tick, int(self.cell(int(self.run_of[member]), ix, iy))))
        if self.detects(member):
            return self.targets_in_view(member, ix, iy)
        return []

    def stop_covering(self, member: int, tick: int) -> None:
        """Coverage ends (finished or preempted): the body stands where it is at `tick`."""
        if not self.moving[member]:
            return
        steps = np.float64(tick - self.s0[member])
        self.ox[member] = self.ox[member] + steps * self.dx[member]
        self.oy[member] = self.oy[member] + steps * self.dy[member]
        self.moving[member] = False
        self.reports[member] = False

    def detects(self, member: int) -> bool:
        """Whether the member reports targets in view (monitoring, or a reporting Coverage)."""
        return bool(self.detecting[member] or self.reports[member])

    def _turn(self, g: I64, body: F64, s0: I64, seg_end: I64) -> tuple[F64, I64]:
        """Members whose next step would leave the grid (their body rows, segment origin and
        end ticks): new origin where they stand, a new random direction that keeps them
        inside, a new straight segment. Stores and returns the new body rows and end ticks."""
        steps = (seg_end - s0).astype(np.float64)
        ox = body[:, 0] + steps * body[:, 2]
        oy = body[:, 1] + steps * body[:, 3]
        body[:, 0], body[:, 1] = ox, oy
        drawn = self.draws.drawn[g]
        todo = np.arange(len(g))
        gt, oxt, oyt, dt = g, ox, oy, drawn  # those still to turn (all of them at first)
        for block in range(TRIES):  # candidates in blocks; the first that keeps it inside wins
            cx, cy = self.draws.candidates(gt, dt)
            ok = inside(cx + oxt[:, None], cy + oyt[:, None], self.W, self.H)
            pick = np.argmax(ok, axis=1)
            at = np.arange(len(todo))
            found = ok[at, pick]
            if found.all():  # the usual case: no row to select
                rows = slice(None) if block == 0 else todo
                body[rows, 2], body[rows, 3] = cx[at, pick], cy[at, pick]
                drawn[rows] = dt + pick + 1  # the draws up to the chosen one are taken
                break
            hit = np.flatnonzero(found)
            done, chosen = todo[hit], pick[hit]
            body[done, 2], body[done, 3] = cx[hit, chosen], cy[hit, chosen]
            drawn[done] = dt[hit] + chosen + 1
            miss = ~found
            todo, dt = todo[miss], dt[miss] + BLOCK
            gt, oxt, oyt = g[todo], ox[todo], oy[todo]
        else:  # vanishingly unlikely: head for the centre
            drawn[todo] = dt
            cx = self.W / 2 - ox[todo]
            cy = self.H / 2 - oy[todo]
            norm = np.hypot(cx, cy)
            body[todo, 2], body[todo, 3] = cx / norm, cy / norm
        self.draws.drawn[g] = drawn
        end = seg_end + longest(ox, oy, body[:, 2], body[:, 3], self.W, self.H)
        self.body[g] = body
        self.s0[g] = seg_end
        self.seg_end[g] = end
        return body, end

    def _turn_few(self, g: I64, body: F64, s0: I64, seg_end: I64, horizon: I64) -> Pieces:
        """`_turn` for a few members, in plain Python with the same operations (the same bits),
        until each one's segment reaches its horizon; returns their pieces as `_pieces` keeps
        them (member, start tick, steps, segment origin tick; body rows)."""
        pieces: list[tuple[int, int, int, int]] = []
        rows: list[list[float]] = []
        for i, (ox, oy, dx, dy) in enumerate(body.tolist()):
            member, start, end, until = int(g[i]), int(s0[i]), int(seg_end[i]), int(horizon[i])
            while end < until:
                steps = float(end - start)
                ox, oy = ox + steps * dx, oy + steps * dy
                dx, dy = turn_one(self.draws, member, ox, oy, self.W, self.H)
                start, end = end, end + longest_one(ox, oy, dx, dy, self.W, self.H)
                pieces.append((member, start, min(end, until) - start, start))
                rows.append([ox, oy, dx, dy])
            self.body[member] = ox, oy, dx, dy
            self.s0[member], self.seg_end[member] = start, end
        columns = np.array(pieces, dtype=np.int64).reshape(-1, 4).T
        return (columns[0], columns[1], columns[2], columns[3]), np.array(rows).reshape(-1, 4)

    def _pieces(self, g: I64, cur: I64, horizon: I64, expand: bool = True) -> Points:
        """Move members `g` from tick `cur` to `horizon` (turning at the boundary as often as
        needed); returns every patch passed, ticks cur+1..horizon."""
        ints: list[tuple[I64, I64, I64, I64]] = []  # member, start tick, steps, segment s0
        floats: list[NDArray[np.float64]] = []  # segment origin and heading (body rows)
        # the rows of the members still moving, carried from one turn to the next
        body, s0, seg_end = self.body[g], self.s0[g], self.seg_end[g]
        while g.size:
            n = np.minimum(seg_end, horizon) - cur
            if expand:
                ints.append((g, cur, n, s0))
                floats.append(body)
            turning = seg_end < horizon
            if not turning.any():
                break
            g, horizon, cur = g[turning], horizon[turning], seg_end[turning]
            if len(g) <= FEW:  # numpy's cost per call would outweigh the few members' turns
                few, rows = self._turn_few(g, body[turning], s0[turning], cur, horizon)
                if expand:
                    ints.append(few)
                    floats.append(rows)
                break
            body, seg_end = self._turn(g, body[turning], s0[turning], cur)
            s0 = cur
        if not ints:
            return Points.empty()
        gm, start, n, s0 = (np.concatenate([p[i] for p in ints]) for i in range(4))
        return self._expand(gm, start - s0 + 1, n, s0, np.concatenate(floats))

    def _expand(self, gm: I64, a: I64, n: I64, s0: I64, body: F64) -> Points:
        """The patches of pieces (member, first step `a` from the segment origin, `n` steps,
        origin tick, body row), cut into stretches of `STRETCH` steps; a stretch whose view
        meets no dirty block (`Blocks`) is left out, as nothing it passes can change."""
        m = -(-n // STRETCH)
        piece = np.repeat(np.arange(len(n)), m)
        j = np.arange(len(piece), dtype=np.int64) - np.repeat(np.cumsum(m) - m, m)
        sa = a[piece] + j * STRETCH
        cnt = np.minimum(STRETCH, n[piece] - j * STRETCH)
        ends = []
        for steps in (sa, sa + cnt - 1):  # the stretch's first and last position
            st = steps.astype(np.float64)
            ends.append(
                (
                    (st * body[piece, 2] + body[piece, 0]).astype(np.int64),
                    (st * body[piece, 3] + body[piece, 1]).astype(np.int64),
                )
            )
        (xa, ya), (xb, yb) = ends
        keep = self.blocks.touches(
            self.run_of[gm[piece]],
            np.minimum(xa, xb),
            np.maximum(xa, xb),
            np.minimum(ya, yb),
            np.maximum(ya, yb),
        )
        piece, sa, cnt = (np.compress(keep, a) for a in (piece, sa, cnt))
        if not piece.size:
            return Points.empty()
        # a row whose leg's previous stretch is the row before it (kept, so full and adjacent)
        linked = np.zeros(len(piece), dtype=np.bool_)
        linked[1:] = (piece[1:] == piece[:-1]) & (sa[1:] == sa[:-1] + STRETCH)
        gm, s0, body = gm[piece], s0[piece], body[piece]
        # one row per stretch: steps sa .. sa + STRETCH - 1 from the segment origin (the same
        # expression, step * heading + origin, as everywhere), `dummy` past the stretch's end
        column = np.arange(STRETCH, dtype=np.float64)
        steps = sa.astype(np.float64)[:, None] + column[None, :]
        u = steps * body[:, 2, None]
        u += body[:, 0, None]
        w = steps * body[:, 3, None]
        w += body[:, 1, None]
        flat: NDArray[np.signedinteger] = w.astype(self.index)  # in the grid: floor
        flat *= self.PW
        flat += u.astype(self.index)
        flat += self.cell(self.run_of[gm], 0, 0).astype(self.index)[:, None]
        np.putmask(flat, column[None, :] >= cnt[:, None], self.dummy)
        return Points(gm, s0 + sa, flat.reshape(-1), linked)

    def _snapshot(self, g: I64) -> list[NDArray[np.generic]]:
        return [a[g].copy() for a in self._state()]

    def _restore(self, g: I64, saved: list[NDArray[np.generic]], mask: Bool) -> None:
        for array, values in zip(self._state(), saved, strict=True):
            array[g[mask]] = values[mask]

    def _state(self) -> list[NDArray[np.generic]]:
        return [self.body, self.s0, self.seg_end, self.draws.drawn]

    # --- one round

    def advance(self, now: I64, horizon: I64) -> tuple[I64, list[tuple[int, int, int, int]]]:
        """Move every covering member of run r from tick now[r] to horizon[r], or only to the
        first tick at which one of them (detecting) has an unfound target in view. Returns that
        end tick per run and the finds there: (run, member, x patch, y patch), member order."""
        self._flush()
        end = horizon.copy()
        movers = np.flatnonzero(self.moving)
        runs = self.run_of[movers]
        live = horizon[runs] > now[runs]
        movers, runs = movers[live], runs[live]
        if not movers.size:
            return end, []
        watch = (self.detecting | self.reports) & (self.unfound[self.run_of] > 0)
        watching = bool(watch[movers].any())
        saved = self._snapshot(movers) if watching else []
        points = self._pieces(movers, now[runs], horizon[runs])
        finds: list[tuple[int, int, int, int]] = []
        if len(points) and watching:
            hit = np.flatnonzero(self._near_points(points) > 0)
            hit = hit[watch[points.members(hit)]]
            if hit.size:
                hit_runs = points.flat[hit] // self.PWH
                hit_ticks = points.ticks(hit)
                np.minimum.at(end, hit_runs, hit_ticks)
                at = hit[hit_ticks == end[hit_runs]]
                for i in at[np.argsort(points.members(at), kind="stable")]:
                    run, ix, iy = self.patch(int(points.flat[i]))
                    finds.append((run, int(points.members(np.array([i]))[0]), ix, iy))
                cut = end[runs] < horizon[runs]
                if cut.any():  # replay those runs' members up to the find (same draws)
                    self._restore(movers, saved, cut)
                    self._pieces(movers[cut], now[runs[cut]], end[runs[cut]], False)
                    points = points.until(end, self.PWH, self.dummy)
        self._commit(points)
        return end, finds

    def _near_points(self, points: Points) -> NDArray[np.int16]:
        """`near` at each point, for the sight class of the member passing it."""
        near: NDArray[np.int16]
        if len(self.views) == 1:
            near = self.near[0][points.flat]
            return near
        sight = np.repeat(self.sight[points.gm], STRETCH)
        near = self.near[sight, points.flat]
        return near

    # --- coverage and targets

    @property
    def covered(self) -> I64:
        """Patches seen so far, per run (the starts not yet recorded included)."""
        self._flush()
        return self._covered

    def _flush(self) -> None:
        """Record the patches members began covering on, all at once: a start's whole view is
        seen at its tick whether it is recorded alone or with others (`first` keeps the
        minimum, the seen set is a set), and nothing reads coverage before this."""
        if not self._starts:
            return
        members, ticks, cells = zip(*self._starts, strict=True)
        self._starts.clear()
        self._commit(Points.starts(members, ticks, cells, self.dummy))

    def _commit(self, points: Points) -> None:
        """Record the patches members stood on, per sight class (`_commit_sight`)."""
        if len(self.views) == 1:
            self._commit_sight(0, points)
            return
        sight = self.sight[points.gm]
        for k in range(len(self.views)):
            self._commit_sight(k, points.select(sight == k))

    def _commit_sight(self, k: int, points: Points) -> None:
        """Record the patches members of sight class k stood on. Rounds go forward in time per
        run, so only patches never stood on before by the class can change; the patches they
        bring into view are counted (`covered`); *when* each patch was first seen is derived at
        the end (`seen_times`)."""
        if not len(points):
            return
        stood = self.stood[k]
        new = np.flatnonzero(np.take(stood, points.flat) == 0)
        if not new.size:
            return
        flat = points.flat[new]
        np.minimum.at(self.first[k], flat, points.ticks(new).astype(np.int32))
        # a patch passed twice brings the same view: `distinct` below drops the repeats
        stood[flat.astype(np.intp, copy=False)] = 1
        # each point's predecessor stands with its whole view seen (now or before): only what
        # the step adds can be new; a row's first point brings its view, unless the row before
        # it is its leg's previous stretch (the predecessor is then that row's last point)
        start = (new & (STRETCH - 1)) == 0
        firsts = np.flatnonzero(start)
        start[firsts] = ~points.linked[new[firsts] >> SHIFT]
        parts = entering_parts(
            flat,
            points.flat[new - 1],  # at a start: another row's, unused
            start,
            self.geometry,
            self._view_offsets[k],
            self.views[k],
        )
        # the unseen candidates, part by part (the same array as filtering `entering` whole,
        # without concatenating the seen two thirds first). `np.compress` and `np.take`:
        # boolean indexing by a scattered mask is several times slower (same values, order)
        seen = self.seen_flag
        around = np.concatenate([np.compress(np.take(seen, p) == 0, p) for p in parts])
        fresh = distinct(around, self._stamp_seen)
        self.seen_flag[fresh.astype(np.intp, copy=False)] = 1
        self._covered += self.blocks.seen(fresh)  # per run: its patches' blocks are its own

    def seen_times(self, run: int) -> NDArray[np.int32]:
        """When each patch of a run was first seen (INF: never), as a (height, width) grid: the
        minimum, over the sight classes, of their `first` over their view around each patch."""
        self._flush()
        seen = np.full((self.H, self.W), INF, dtype=np.int32)
        for k, v in enumerate(self.views):
            first = self.first[k].reshape(self.runs, self.PH, self.PW)[run]  # padding: INF
            for oy in range(self.v - v, self.v + v + 1):
                for ox in range(self.v - v, self.v + v + 1):
                    np.minimum(seen, first[oy : oy + self.H, ox : ox + self.W], out=seen)
        return seen
