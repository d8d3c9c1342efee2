"""Run-time tuning of gains with dynamic_reconfigure: the waypoint tracker's (mission_node, Server ~tracker,
cfg/Tracker.cfg) and the rectilinear follower's (planner_node, Server ~follower, cfg/Follower.cfg).

Start values are the node's configuration (config/tracker.yaml with its overrides; the nav config's
follower: section), written to the parameter server before the Server reads it, so every start begins
from the files again: a tuned value lasts until the node stops (copy it into the YAML to keep it).
The cfg's min/max bound each value (the Server clamps to them). A change holding a value that is not
finite, or one the controller's own validation refuses, is refused whole: the Server keeps and
republishes the gains in use, and the refusal is logged, counted and shown on /diagnostics.
Accepted gains reach the controller between control cycles: the tracker's under mission_node's lock
(its tick holds it), the follower's at the start of planner_node's next tick.
"""
import dataclasses
import math
import threading
from typing import Callable, Dict, List

import rospy
from diagnostic_msgs.msg import DiagnosticStatus
from dynamic_reconfigure.server import Server

from snake_autonomy.cfg import FollowerConfig, TrackerConfig   # generated at build time from cfg/*.cfg
from snake_autonomy.control.waypoint_tracker import TrackerParams
from snake_autonomy.missions.mission import TRACKER_KEYS

#: Tracker.cfg's keys -> (TrackerParams field, factor from the cfg's unit to radians or 1)
TRACKER_GAINS = {key: TRACKER_KEYS[key] for key in ("kp", "delta0_deg", "delta_lim_deg")}
#: Follower.cfg's keys: FollowerParams fields of the same name and unit
FOLLOWER_GAINS = ("k_heading", "lookahead_m", "kappa_rate_per_m_s")


def _text(gains: Dict[str, float]) -> str:
    return ", ".join(f"{k} {v:.6g}" for k, v in gains.items())


class GainServer:
    """One controller's gains behind a dynamic_reconfigure Server (namespace `namespace`, e.g. "~tracker").

    start: the gains in use at start (cfg keys and units). check(changed) lists the problems of the changes
    (cfg keys and units; empty: acceptable); apply(changed) hands accepted ones to the controller.
    in_use() reads the gains the controller runs with now, for /diagnostics."""

    def __init__(self, what: str, config_type, namespace: str, start: Dict[str, float],
                 check: Callable[[Dict[str, float]], List[str]], apply: Callable[[Dict[str, float]], None],
                 in_use: Callable[[], Dict[str, float]]):
        self.what, self.check, self.apply, self.in_use = what, check, apply, in_use
        self.accepted = dict(start)
        self.changes, self.refused, self.last_refusal = 0, 0, ""
        for key, value in start.items():
            lo, hi = config_type.min[key], config_type.max[key]
            if not lo <= value <= hi:
                rospy.logwarn(f"{what} {key} {value:g} is outside the tuning range {lo:g}..{hi:g} of its cfg: "
                              "the tool shows the nearest bound, the controller keeps the configured value")
            rospy.set_param(f"{namespace}/{key}", float(value))
        self.server = Server(config_type, self._on_reconfigure, namespace=namespace)

    def _on_reconfigure(self, config, level):
        """The Server's callback (its service thread): the config it returns is what it publishes."""
        proposed = {k: float(config[k]) for k in self.accepted}
        # level ~0: the Server's first call, with the start values it read back from the parameter server
        changed = {} if level == ~0 else {k: v for k, v in proposed.items() if v != self.accepted[k]}  # NaN too
        problems = [f"{k}: must be a finite number, got {v!r}" for k, v in changed.items() if not math.isfinite(v)]
        if not problems and changed:
            problems = self.check(changed)
        if problems:
            self.refused += 1
            self.last_refusal = "; ".join(problems)[:300]
            rospy.logwarn(f"{self.what} gains refused ({self.last_refusal}); keeping {_text(self.accepted)}")
        elif changed:
            self.apply(changed)
            self.accepted.update(changed)
            self.changes += 1
            rospy.loginfo(f"{self.what} gains set: {_text(changed)}")
        for k, v in self.accepted.items():
            config[k] = v
        return config

    def diagnose(self, stat):
        """The "<what> gains" diagnostics task: the gains in use, changes and refusals."""
        gains = self.in_use()
        stat.summary(DiagnosticStatus.OK, f"{self.what} gains: {_text(gains)}")   # a refusal changed nothing
        for k, v in gains.items():
            stat.add(k, f"{v:.6g}")
        stat.add("changes", str(self.changes))
        stat.add("refused", str(self.refused))
        stat.add("last_refusal", self.last_refusal or "none")
        return stat


class TrackerGains:
    """mission_node's tracker gains: a change goes to the running mission's tracker under the node's lock
    (between ticks) and to every mission started after it, over the mission file's own value; the run log
    gets a `tracker_gains` event."""

    def __init__(self, node):
        self.node = node
        self.tuned: Dict[str, float] = {}              # TrackerParams field -> value (rad), once changed here
        base = node.defaults["tracker"]
        start = {key: base[name] / factor for key, (name, factor) in TRACKER_GAINS.items()}
        self.gains = GainServer("tracker", TrackerConfig, "~tracker", start, self.check, self.apply, self.in_use)
        node.updater.add("tracker gains", self.gains.diagnose)

    @staticmethod
    def _fields(changed: Dict[str, float]) -> Dict[str, float]:
        return {TRACKER_GAINS[k][0]: v * TRACKER_GAINS[k][1] for k, v in changed.items()}

    def check(self, changed):
        with self.node.lock:
            runner = self.node.runner
            params = runner.tracker.params if runner is not None else TrackerParams(**self.node.defaults["tracker"])
        return dataclasses.replace(params, **self._fields(changed)).problems()

    def apply(self, changed):
        fields = self._fields(changed)
        with self.node.lock:
            self.tuned.update(fields)
            if self.node.runner is not None:
                tracker = self.node.runner.tracker
                tracker.params = dataclasses.replace(tracker.params, **fields)
            if self.node.log is not None:
                self.node.log.event({"event": "tracker_gains", **changed}, rospy.get_time())

    def tuned_runner(self, runner):
        """runner with the gains tuned so far applied to its tracker (a new mission's)."""
        if self.tuned:
            runner.tracker.params = dataclasses.replace(runner.tracker.params, **self.tuned)
        return runner

    def in_use(self) -> Dict[str, float]:
        with self.node.lock:
            runner = self.node.runner
            p = vars(runner.tracker.params) if runner is not None else {**self.node.defaults["tracker"], **self.tuned}
        return {key: p[name] / factor for key, (name, factor) in TRACKER_GAINS.items()}


class FollowerGains:
    """planner_node's follower gains: a change goes into the node's nav config (a loop built later has it)
    and, at the start of the next tick, into the running loop's follower."""

    def __init__(self, node):
        self.node = node
        self._lock = threading.Lock()
        self._pending: Dict[str, float] = {}
        start = {key: float(getattr(node.cfg.follower, key)) for key in FOLLOWER_GAINS}
        self.gains = GainServer("follower", FollowerConfig, "~follower", start, self.check, self.apply, self.in_use)
        node.updater.add("follower gains", self.gains.diagnose)

    def check(self, changed):
        return dataclasses.replace(self.node.cfg.follower, **changed).validate()

    def apply(self, changed):
        with self._lock:
            self._pending.update(changed)
            self.node.cfg = dataclasses.replace(self.node.cfg,
                                                follower=dataclasses.replace(self.node.cfg.follower, **changed))

    def before_tick(self, loop) -> None:
        """In the tick's thread, before the loop runs: the accepted changes into its follower."""
        with self._lock:
            pending, self._pending = self._pending, {}
        if pending and loop is not None:
            follower = loop.planner.follower
            follower.params = dataclasses.replace(follower.params, **pending)

    def in_use(self) -> Dict[str, float]:
        loop = self.node.loop
        params = loop.planner.follower.params if loop is not None else self.node.cfg.follower
        return {key: float(getattr(params, key)) for key in FOLLOWER_GAINS}
