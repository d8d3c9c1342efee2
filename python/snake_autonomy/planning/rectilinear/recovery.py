"""Recovery behaviours of the layered planner: one state machine, and a progress checker.

When no candidate arc is valid (or the progress checker finds the robot has not moved), the planner
asks the next behaviour of `sequence` (config/nav.yaml `recovery:`), as Nav2's recovery
subtree runs its behaviours in turn (round robin): back_off (tail first along the body's own track,
for one replan; possible when the body sweep of the way back is clear), turn (in place, towards the
route's side, with a reshape the body sweep finds clear), wait (hold one replan: the views may clear a
misjudged cell). With `known_only` backing off and turning keep the body on cells the local map knows
(seen as floor or lain on): the camera never saw what lies beside or behind the body.
With `back_off_steer` a back-off steers against the turning side when the body sweep finds that
clear (backing, the body turns the other way round: a car's multi-point turn; holding the curvature,
each back-off undid the turn in place before it), else straight, else along the track. A behaviour
that is not possible now is skipped; none possible: wait.
Dead ends: after `escape_after` recoveries within `dead_end_radius_m` of one place the robot escapes:
it backs off, replan after replan, until base_link is `escape_m` from that place (Nav2's BackUp with
its distance), and the route (grid_route.py) makes that place dearer for the rest of the run, so that
the same arcs do not lead it straight back in. A valid arc ends the recovery (the next one
starts from the sequence's beginning).
Progress checker (Nav2's SimpleProgressChecker): the robot must move `progress_m` within
`progress_window_s` while it follows; if it does not, the planner recovers as if no arc were valid.
"""
import math
from collections import deque
from dataclasses import dataclass
from typing import Dict, List, Optional, Tuple

BACK_OFF, TURN, WAIT = "back_off", "turn", "wait"
BEHAVIOURS = (BACK_OFF, TURN, WAIT)


@dataclass(frozen=True)
class RecoveryParams:
    """config/nav.yaml `recovery:`; the defaults are its values."""
    sequence: Tuple[str, ...] = (BACK_OFF, BACK_OFF, TURN, TURN)
    back_off_m: float = 0.1           # the tail's way back must be clear this far (a replan's back-off)
    turn_crawl_m: float = 0.05        # a turn in place crawls on this far in a replan (4-5 mm/s on COBRA)
    progress_m: float = 0.05
    progress_window_s: float = 120.0
    known_only: bool = True           # back off / turn only over cells seen or lain on
    back_off_steer: bool = False      # back off steering against the turn's side when its sweep is clear
    escape_after: int = 0             # recoveries within dead_end_radius_m of one place before escaping (0: never)
    escape_m: float = 0.4             # an escape backs off until base_link is this far from that place
    dead_end_radius_m: float = 0.3

    def validate(self) -> List[str]:
        p = []
        if not isinstance(self.sequence, (list, tuple)) or not self.sequence or \
                any(b not in BEHAVIOURS for b in self.sequence):
            p.append(f"sequence: expected a non-empty list of {', '.join(BEHAVIOURS)}, got {self.sequence!r}")
        p += [f"{k}: must be > 0, got {getattr(self, k)}" for k in
              ("back_off_m", "turn_crawl_m", "progress_m", "progress_window_s", "escape_m", "dead_end_radius_m")
              if not getattr(self, k) > 0]
        if isinstance(self.escape_after, bool) or not isinstance(self.escape_after, int) or self.escape_after < 0:
            p.append(f"escape_after: must be an integer >= 0, got {self.escape_after!r}")
        p += [f"{k}: must be true or false, got {getattr(self, k)!r}" for k in ("known_only", "back_off_steer")
              if not isinstance(getattr(self, k), bool)]
        return p


class Recovery:
    def __init__(self, params: RecoveryParams = RecoveryParams()):
        self.params = params
        self._i = 0
        self.active = False
        self.side: Optional[float] = None    # the turning side, kept through one recovery
        self.count: Dict[str, int] = {b: 0 for b in BEHAVIOURS}

    def reset(self) -> None:
        self._i, self.active, self.side = 0, False, None

    def next(self, possible: Dict[str, bool]) -> str:
        """The next behaviour of the sequence that is possible now (wait if none is)."""
        seq = self.params.sequence
        self.active = True
        for k in range(len(seq)):
            b = seq[(self._i + k) % len(seq)]
            if possible.get(b, b == WAIT):
                self._i = (self._i + k + 1) % len(seq)
                self.count[b] += 1
                return b
        self._i = 0
        self.count[WAIT] += 1
        return WAIT


class ProgressChecker:
    """Whether the robot moved progress_m within the last progress_window_s of following."""

    def __init__(self, progress_m: float, window_s: float):
        self.progress_m, self.window_s = progress_m, window_s
        self._samples = deque()

    def reset(self) -> None:
        self._samples.clear()

    def stuck(self, t_s: float, xy) -> bool:
        self._samples.append((t_s, float(xy[0]), float(xy[1])))
        while self._samples and self._samples[0][0] < t_s - self.window_s:
            self._samples.popleft()
        t0, x0, y0 = self._samples[0]
        if t_s - t0 < 0.9 * self.window_s:
            return False
        return max(math.hypot(x - x0, y - y0) for _, x, y in self._samples) < self.progress_m
