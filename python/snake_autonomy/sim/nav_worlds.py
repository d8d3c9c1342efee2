"""Generated world families of the navigation experiment (runs/nav_experiment.py), each world a pure
function of its index and parameters:

* random_corridor(k): 1-3 cylinders between the start and a goal 1.4 m ahead (the first family);
* barn_world(k): a dense cluttered field in the manner of the BARN benchmark (Perille et al. 2020,
  "Benchmarking Metric Ground Navigation"): an occupancy grid randomly filled, smoothed by a cellular
  automaton, written as boxes, with a path for the robot's footprint checked before it is returned.

Convention of the experiments: tuning on worlds 0-19, reports on held-out worlds from 100 up.
"""
import math
from dataclasses import dataclass
from typing import List, Tuple

import numpy as np
import shapely
from scipy import ndimage
from shapely.geometry import LineString, Point

from .world_file import FLOOR_TEXTURES, World


def random_corridor(index: int, body_width_m: float = 0.09, gap_factor: float = 2.0,
                    length_m: float = 1.4, half_width_m: float = 0.35, base_seed: int = 1300) -> World:
    """World `index` (a pure function of it): start at the origin heading +x, the goal length_m
    ahead, 1-3 cylinders (radius 5-9 cm) in the corridor x in [0.45, length - 0.35], |y| <=
    half_width; the first within 5 cm of the straight line (the robot must go round it); every
    pair's free gap >= gap_factor x body width (rejection sampling), so a way round exists on the
    open floor beside the corridor too. No walls: the rectilinear gait bends the whole 1.5 m body
    with kappa (the tail swings sideways, it does not follow the head's path), so walls along
    the corridor would be hit by the tail, not by what the planner steers."""
    rng = np.random.default_rng(base_seed + index)
    gap = gap_factor * body_width_m
    n = int(rng.integers(1, 4))
    cyl = []
    for k in range(n):
        for _ in range(200):
            r = float(rng.uniform(0.05, 0.09))
            x = float(rng.uniform(0.45, length_m - 0.35))
            y = float(rng.uniform(-0.05, 0.05)) if k == 0 else float(rng.uniform(-half_width_m, half_width_m))
            if all(math.hypot(x - c[0], y - c[1]) - r - c[2] >= gap for c in cyl):
                cyl.append((x, y, r))
                break
    obstacles = [{"type": "cylinder", "x": x, "y": y, "radius_m": r, "height_m": 0.3} for x, y, r in cyl]
    data = {"name": f"corridor_{index:03d}", "start": [0.0, 0.0, 0.0], "goal": [length_m, 0.0],
            "goal_radius_m": 0.2, "floor_texture": FLOOR_TEXTURES[index % 5], "obstacles": obstacles}
    return World.from_dict(data, f"random_corridor({index})")


def min_gap_m(world: World) -> float:
    """The smallest free gap between two cylinders (inf with one)."""
    c = [(o.x_m, o.y_m, o.radius_m) for o in world.obstacles if o.kind == "cylinder"]
    gaps = [math.hypot(a[0] - b[0], a[1] - b[1]) - a[2] - b[2] for i, a in enumerate(c) for b in c[i + 1:]]
    return min(gaps) if gaps else math.inf


# ---------------------------------------------------------------------------------------------
# BARN-like fields

#: The fill fraction of a field (occupied cells / all cells, after smoothing and the start's and
#: the goal's clearings) is drawn per world from this range, as BARN's initial fill is.
BARN_FILL_RANGE = (0.15, 0.30)
SUBCELLS = 5            # the path check's grid: SUBCELLS x SUBCELLS sub-cells a cell


@dataclass(frozen=True)
class BarnLayout:
    """A generated field: the world and the grid it came from, with its figures."""
    world: World
    occupied: np.ndarray          # bool (rows along y, columns along x); row 0 at origin_m's y
    cell_m: float
    origin_m: Tuple[float, float]   # the field's lower left corner (x, y)
    fill: float                   # occupied cells / cells
    initial_fill: float           # the random fill before smoothing that gave `fill`
    passage_m: float              # 2 x the clearance of the widest start-goal path (its bottleneck)
    robot_clearance_m: float
    body_length_m: float
    tries: int                    # rejection-sampling tries it took

    @property
    def size_m(self) -> Tuple[float, float]:
        return (self.occupied.shape[1] * self.cell_m, self.occupied.shape[0] * self.cell_m)


def barn_world(index: int, robot_clearance_m: float = 0.25, **kw) -> World:
    """barn_layout(index, robot_clearance_m, ...).world: see there."""
    return barn_layout(index, robot_clearance_m, **kw).world


def barn_layout(index: int, robot_clearance_m: float = 0.25, body_length_m: float = 1.5,
                cell_m: float = None, field_m: Tuple[float, float] = (5.0, 4.0),
                fill_range: Tuple[float, float] = BARN_FILL_RANGE, smoothing_iterations: int = 3,
                min_goal_distance_m: float = 3.0, heading_jitter_deg: float = 30.0,
                goal_radius_m: float = 0.25, height_m: float = 0.3, base_seed: int = 2700,
                max_tries: int = 100) -> BarnLayout:
    """World `index` of the BARN-like family (a pure function of the index and the parameters).

    robot_clearance_m is the footprint's half-width (the planner's sampler.body_clearance_m: COBRA
    0.25 m, the 12-link robot 0.15 m). The field (field_m, x along its first edge, y centred on 0)
    is a grid of cells of cell_m, by default robot_clearance_m: a passage of two free cells is
    the footprint's width, so with 0.25 m cells COBRA's 0.5 m footprint passes where three cells
    are free side by side (the check below wants a margin), and the 12-link robot's smaller
    footprint gets a finer, denser field of 0.15 m cells. 5 x 4 m holds a start and a goal 3 m
    apart with room for detours (about 320 cells for COBRA, 900 for the 12-link robot).

    Per try (rng seeded by base_seed + index): a start and a goal >= min_goal_distance_m apart in
    the field; the start heading at the goal +- heading_jitter_deg; a fill fraction drawn from
    fill_range; uniform noise per cell, thresholded at an initial fill and smoothed by the 4-5
    cellular automaton (a cell is occupied after an iteration when >= 5 of its 8 neighbours are,
    or it is and >= 4 are; outside the field counts free). That rule wipes out a 15-30 % random
    fill (it keeps about 1 % of a 30 % fill), so the initial fill is found by bisection such that
    the fill after smoothing and clearing is the drawn one (the rule is monotone: more occupied
    cells in, never fewer out). Cleared: the cells within robot_clearance_m + cell_m / 2 of the
    body lying straight behind the start (body_length_m behind base_link, 2 robot_clearance_m ahead
    of it), and of the goal. The try is kept when its fill lies in fill_range and a path exists
    from the start to the goal for a disc of radius robot_clearance_m, checked on a sub-cell grid
    with the clearance's lower bound (scipy distance transform, 4-connected components); else the
    next try, at most max_tries, then a ValueError. Obstacles: boxes of height_m, a run of occupied
    cells in a row one box, equal runs in consecutive rows one box (MuJoCo and the camera render
    every one). Not checked: the turning radius (0.3-0.45 m) and the tail's swing in a turn.
    """
    hw = float(robot_clearance_m)
    c = hw if cell_m is None else float(cell_m)
    if not (hw > 0 and c > 0 and body_length_m >= 0 and max_tries >= 1):
        raise ValueError(f"barn_world: robot_clearance_m, cell_m > 0, body_length_m >= 0, max_tries >= 1; "
                         f"got {robot_clearance_m}, {cell_m}, {body_length_m}, {max_tries}")
    lo, hi = fill_range
    if not 0 <= lo <= hi < 1:
        raise ValueError(f"barn_world: fill_range must be 0 <= low <= high < 1, got {fill_range}")
    nx, ny = max(1, round(field_m[0] / c)), max(1, round(field_m[1] / c))
    origin = (0.0, -0.5 * ny * c)
    margin = hw + c
    span = (nx * c - 2 * margin, ny * c - 2 * margin)
    if span[0] <= 0 or span[1] <= 0 or math.hypot(*span) < min_goal_distance_m:
        raise ValueError(f"barn_world: a field of {nx * c:g} x {ny * c:g} m holds no start and goal "
                         f"{min_goal_distance_m:g} m apart {margin:g} m from its edges")
    rng = np.random.default_rng(base_seed + index)
    for attempt in range(1, max_tries + 1):
        start, goal = _start_and_goal(rng, origin, span, margin, min_goal_distance_m)
        heading = math.atan2(goal[1] - start[1], goal[0] - start[0]) + math.radians(
            rng.uniform(-heading_jitter_deg, heading_jitter_deg))
        heading = math.atan2(math.sin(heading), math.cos(heading))
        target = float(rng.uniform(lo, hi))
        noise = rng.random((ny, nx))
        keep = ~_cleared(start, heading, goal, hw, body_length_m, c, origin, (ny, nx))
        initial, occupied = _fill_to(noise, keep, target, smoothing_iterations)
        fill = float(occupied.mean())
        if not lo <= fill <= hi:
            continue
        clearance, cells = _clearance(occupied, c, origin)
        passage = _passage_m(clearance, cells(start), cells(goal))
        if passage < 2 * hw:
            continue
        data = {"name": f"barn_{index:03d}",
                "start": [round(start[0], 4), round(start[1], 4), round(math.degrees(heading), 2)],
                "goal": [round(goal[0], 4), round(goal[1], 4)], "goal_radius_m": goal_radius_m,
                "floor_texture": FLOOR_TEXTURES[index % 5],
                "obstacles": _boxes(occupied, c, origin, height_m)}
        world = World.from_dict(data, f"barn_world({index})")
        return BarnLayout(world, occupied, c, origin, fill, initial, passage, hw, body_length_m, attempt)
    raise ValueError(f"barn_world({index}): no field with a path for a footprint half-width of {hw:g} m in "
                     f"{max_tries} tries ({nx * c:g} x {ny * c:g} m, cells {c:g} m, fill {lo:g}-{hi:g}): "
                     f"a larger field or cells, or a lower fill")


def _start_and_goal(rng, origin, span, margin, min_distance):
    """A start and a goal uniform in the field (margin from its edges), >= min_distance apart."""
    for _ in range(1000):
        a, b = (tuple(float(v) for v in (origin[0] + margin + rng.uniform(0, span[0]),
                                          origin[1] + margin + rng.uniform(0, span[1]))) for _ in range(2))
        if math.hypot(b[0] - a[0], b[1] - a[1]) >= min_distance:
            return a, b
    raise ValueError(f"barn_world: no start and goal {min_distance:g} m apart found")


def _cell_boxes(shape, c, origin):
    rows, cols = np.indices(shape)
    x0, y0 = origin[0] + cols * c, origin[1] + rows * c
    return shapely.box(x0, y0, x0 + c, y0 + c)


def _cleared(start, heading, goal, hw, body_length, c, origin, shape) -> np.ndarray:
    """The cells within hw + c / 2 of the body lying straight behind the start (2 hw ahead of it)
    or of the goal."""
    u = (math.cos(heading), math.sin(heading))
    body = LineString([(start[0] - body_length * u[0], start[1] - body_length * u[1]),
                       (start[0] + 2 * hw * u[0], start[1] + 2 * hw * u[1])])
    boxes = _cell_boxes(shape, c, origin)
    r = hw + 0.5 * c
    return (shapely.distance(boxes, body) < r) | (shapely.distance(boxes, Point(goal)) < r)


def _smooth(occupied: np.ndarray, iterations: int) -> np.ndarray:
    """The 4-5 rule: occupied when >= 5 of the 8 neighbours are, or when it is and >= 4 are."""
    kernel = np.ones((3, 3), dtype=int)
    kernel[1, 1] = 0
    for _ in range(iterations):
        n = ndimage.convolve(occupied.astype(int), kernel, mode="constant", cval=0)
        occupied = (n >= 5) | (occupied & (n >= 4))
    return occupied


def _fill_to(noise, keep, target, iterations, steps: int = 30):
    """(initial fill, grid): the smallest threshold of the noise whose smoothed, cleared grid is
    filled >= target (bisection; smoothing and clearing are monotone in the threshold)."""
    def grid(p):
        return _smooth(noise < p, iterations) & keep
    a, b = 0.0, 1.0
    for _ in range(steps):
        m = 0.5 * (a + b)
        if grid(m).mean() >= target:
            b = m
        else:
            a = m
    return b, grid(b)


def _clearance(occupied, c, origin):
    """(clearance_m on the sub-cell grid, point -> sub-cell index): a lower bound of the clearance of
    every point of a 4-connected move through a sub-cell's centre (the distance to the nearest
    occupied sub-cell's centre, less its half diagonal and half a sub-cell)."""
    h = c / SUBCELLS
    fine = np.kron(occupied, np.ones((SUBCELLS, SUBCELLS), dtype=bool))
    if fine.any():
        clearance = (ndimage.distance_transform_edt(~fine) - math.sqrt(0.5) - 0.5) * h
    else:
        clearance = np.full(fine.shape, np.inf)
    clearance[fine] = -np.inf

    def cell(p):
        i = int(np.clip((p[1] - origin[1]) // h, 0, fine.shape[0] - 1))
        j = int(np.clip((p[0] - origin[0]) // h, 0, fine.shape[1] - 1))
        return i, j
    return clearance, cell


def _passage_m(clearance, a, b, steps: int = 24) -> float:
    """2 x the largest clearance d for which sub-cells a and b are 4-connected through sub-cells of
    clearance >= d (the bottleneck of the widest path); 0 when not connected at all."""
    def connected(d):
        labels, _ = ndimage.label(clearance >= d)
        return labels[a] != 0 and labels[a] == labels[b]
    top = float(min(clearance[a], clearance[b]))
    if not math.isfinite(top):
        return math.inf
    if top < 0 or not connected(0.0):
        return 0.0
    if connected(top):
        return 2 * top
    lo, hi = 0.0, top
    for _ in range(steps):
        m = 0.5 * (lo + hi)
        lo, hi = (m, hi) if connected(m) else (lo, m)
    return 2 * lo


def _boxes(occupied, c, origin, height_m) -> List[dict]:
    """Runs of occupied cells in a row, equal runs of consecutive rows merged: one box each."""
    open_runs = {}            # (j0, j1) -> first row
    rects = []
    for i in range(occupied.shape[0] + 1):
        row = occupied[i] if i < occupied.shape[0] else np.zeros(occupied.shape[1], dtype=bool)
        edges = np.flatnonzero(np.diff(np.concatenate(([0], row.astype(np.int8), [0]))))
        runs = set(zip(edges[::2].tolist(), (edges[1::2] - 1).tolist()))
        for run in list(open_runs):
            if run not in runs:
                rects.append((open_runs.pop(run), i - 1, *run))
        for run in runs - set(open_runs):
            open_runs[run] = i
    return [{"type": "box", "x": round(origin[0] + 0.5 * (j0 + j1 + 1) * c, 6),
             "y": round(origin[1] + 0.5 * (i0 + i1 + 1) * c, 6),
             "size_m": [round((j1 - j0 + 1) * c, 6), round((i1 - i0 + 1) * c, 6), height_m], "yaw_deg": 0.0}
            for i0, i1, j0, j1 in sorted(rects)]
