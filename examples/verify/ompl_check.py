#!/usr/bin/env python3
"""Independent check of kinsynth's reachability with an OMPL planner (RRTConnect).

For each task of a reach report, plans from home (every joint at 0) with OMPL's RRTConnect in
joint space, with pinocchio for the kinematics and coal (FCL) for collisions, and says whether
an independent planner reaches the tasks that kinsynth reached and, above all, any that kinsynth
missed (an R that misses reachable tasks misleads the optimiser).

- The robot is the exported URDF with its SRDF (`kinsynth urdf` or `optimize` write both); the
  obstacles are the scenario's, loaded as `fcl_check.py` loads them (meshes by their
  `representation`). An imported arm's URDF is read as `fcl_check.py` reads it: `<capsule>`
  collision elements, which pinocchio's URDF parser drops, are read by the script.
- The planner's state is one value per joint: the angle of a revolute joint, the length of a
  prismatic one, and the angle θ of a `continuous` joint, on [−π, π] as kinsynth imports it
  (pinocchio's configuration holds cos θ and sin θ).
- A state is valid when every robot body is farther than the scenario's `clearance` from every
  obstacle and every self pair the SRDF leaves enabled is apart (coal's collision with a
  security margin).
- Goals: configurations whose `tool0` lies within the planner's `goal_tolerance` of the task
  point, found by damped-least-squares inverse kinematics (pinocchio) from home and from random
  starts within the joint limits, and valid. RRTConnect then connects home to any of them.
- A path OMPL returns (its motions checked at OMPL's discrete resolution, `--resolution`) is
  re-checked at 400 samples per edge, as `fcl_check.py` does; a task counts as reached by OMPL
  only when its path passes.
- An oriented task's goal postures also hold its constraint: `tool0`'s z axis within
  `approach_tolerance` of `approach` (an approach cone), or its frame within
  `orientation_tolerance` of `orientation` (a full pose); the inverse kinematics then also
  turns the tool (weighted as kinsynth's default `orientation_weight`, 0.3 m per radian).

Needs `pip install pin coal ompl`; not used by the tests.

usage: ompl_check.py ROBOT.urdf ROBOT.srdf SCENARIO.toml REACH.json
           [--seconds S] [--seed N] [--missed] [--resolution R] [--tip FRAME]
           [--package-dir DIR]...

`--seconds` is the time per task (default 2, inverse kinematics included), `--missed` checks
only the tasks kinsynth did not reach, `--tip` names the tool frame of an imported arm
(default `tool0`, kinsynth's), `--package-dir` where its `package://` meshes lie. Exit status 1 when OMPL reaches, with a path that passes
the dense re-check, a task kinsynth missed; 0 otherwise.
"""
import argparse
import json
import os
import sys
import time
import tomllib

try:
    import numpy as np
    import ompl  # noqa: F401  (used in the planning functions)
    import pinocchio as pin
except ImportError as e:
    sys.exit(f"ompl_check.py: {e}: needs the Python packages pin coal ompl (pip install pin coal ompl)")

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fcl_check import (  # noqa: E402
    configuration,
    enable_self_pairs,
    load_robot,
    obstacle_geometry,
    read_file,
    rotation,
)

DENSE = 400  # samples per edge of the dense re-check


class Problem:
    """The robot, its collision model with the obstacles, and a validity test."""

    def __init__(self, urdf, srdf, scenario_path, tip="tool0", package_dirs=()):
        self.scenario = read_file(scenario_path, tomllib.load, binary=True)
        self.clearance = float(self.scenario.get("clearance", 0.0))
        planner = self.scenario.get("planner", {})
        self.tolerance = float(planner.get("goal_tolerance", 0.02))
        self.model, self.geom, self.notes = load_robot(urdf, package_dirs)
        # The state: one value per joint, in pinocchio's velocity order; where each goes in q.
        self.slots = []
        self.lo = np.zeros(self.model.nv)
        self.hi = np.zeros(self.model.nv)
        for j, name in zip(self.model.joints[1:], self.model.names[1:]):
            if j.nv != 1 or j.nq not in (1, 2):
                raise SystemExit(
                    f"{urdf}: joint {name!r} ({j.shortname()}): only revolute, continuous and "
                    "prismatic joints are supported"
                )
            self.slots.append((j.idx_q, j.nq))
            if j.nq == 2:  # continuous: kinsynth's range
                self.lo[j.idx_v], self.hi[j.idx_v] = -np.pi, np.pi
            else:
                self.lo[j.idx_v] = self.model.lowerPositionLimit[j.idx_q]
                self.hi[j.idx_v] = self.model.upperPositionLimit[j.idx_q]
        self.n = self.model.nv
        robot = len(self.geom.geometryObjects)
        enable_self_pairs(self.model, self.geom, srdf)
        self.self_pairs = len(self.geom.collisionPairs)
        obstacles = []
        for k, o in enumerate(self.scenario.get("obstacle", [])):
            g = obstacle_geometry(o, os.path.dirname(scenario_path))
            placement = pin.SE3(rotation(o), np.array(o["position"], dtype=float))
            obstacles.append(
                self.geom.addGeometryObject(pin.GeometryObject(f"obstacle{k}", 0, placement, g))
            )
        for r in range(robot):
            for ob in obstacles:
                self.geom.addCollisionPair(pin.CollisionPair(r, ob))
        self.data = self.model.createData()
        self.gdata = pin.GeometryData(self.geom)
        for p, cp in enumerate(self.geom.collisionPairs):
            env = cp.second in obstacles or cp.first in obstacles
            self.gdata.collisionRequests[p].security_margin = self.clearance if env else 0.0
        self.tip_frame = self.model.getFrameId(tip)
        if self.tip_frame >= len(self.model.frames):
            raise SystemExit(f"{urdf}: no frame named {tip!r} (--tip)")
        self.checks = 0

    def q(self, x):
        """pinocchio's configuration for the state x (one value per joint)."""
        return configuration(self.model, self.slots, x)

    def valid(self, x):
        """No contact: obstacles beyond the clearance, enabled self pairs apart."""
        self.checks += 1
        return not pin.computeCollisions(
            self.model, self.data, self.geom, self.gdata, self.q(x), True
        )

    def tip(self, x):
        """The pose of `tool0` at the state x."""
        pin.forwardKinematics(self.model, self.data, self.q(x))
        pin.updateFramePlacement(self.model, self.data, self.tip_frame)
        return self.data.oMf[self.tip_frame]

    def errors(self, q, target, goal):
        """Position error vector and, for an oriented goal, the rotation error vector (world
        frame) and the angle the goal's tolerance bounds."""
        m = self.tip(q)
        ep = target - m.translation
        if goal is None:
            return ep, None, 0.0
        kind, want, _ = goal
        if kind == "approach":
            z = m.rotation[:, 2]
            ew = np.cross(z, want)  # turns z toward the approach direction
            angle = np.arccos(np.clip(z @ want, -1.0, 1.0))
            if angle > 0.5 * np.pi:  # beyond a right angle, turn by the full angle
                ew = ew / max(np.linalg.norm(ew), 1e-12) * angle
        else:
            ew = pin.log3(want @ m.rotation.T)
            angle = np.linalg.norm(ew)
        return ep, ew, angle

    def within(self, q, target, goal):
        ep, _, angle = self.errors(q, target, goal)
        return np.linalg.norm(ep) <= self.tolerance and (goal is None or angle <= goal[2])

    def ik(self, target, goal, q0, iterations=150):
        """Damped least squares on the tip position (and orientation for an oriented goal)
        within the limits, in the planner's state (one value per joint) from q0; the final
        state and whether it meets the goal."""
        q = q0.copy()
        w = 0.3  # metres per radian, kinsynth's default orientation_weight
        for _ in range(iterations):
            ep, ew, angle = self.errors(q, target, goal)
            if np.linalg.norm(ep) < 0.25 * self.tolerance and (
                goal is None or angle < 0.25 * goal[2]
            ):
                break
            # Its columns are the joints' velocities: dθ for every joint, continuous ones too.
            J6 = pin.computeFrameJacobian(
                self.model, self.data, self.q(q), self.tip_frame, pin.LOCAL_WORLD_ALIGNED
            )
            if goal is None:
                J, err = J6[:3], ep
            else:
                J, err = np.vstack([J6[:3], w * J6[3:]]), np.concatenate([ep, w * ew])
            step = J.T @ np.linalg.solve(J @ J.T + 1e-4 * np.eye(len(err)), err)
            q = np.clip(q + step, self.lo, self.hi)
        return q, self.within(q, target, goal)

    def edge_clean(self, a, b):
        """Every one of DENSE + 1 samples of the straight edge a → b is valid."""
        return all(self.valid(a + s * (b - a)) for s in np.linspace(0.0, 1.0, DENSE + 1))


def task_goal(task):
    """The orientation part of a scenario task: None for a point task, else
    ("approach", unit direction, tolerance) or ("pose", rotation matrix, tolerance)."""
    if "approach" in task:
        a = np.array(task["approach"], dtype=float)
        return "approach", a / np.linalg.norm(a), float(task["approach_tolerance"])
    if "orientation" in task:
        return "pose", rotation(task["orientation"]), float(task["orientation_tolerance"])
    return None


def plan_task(problem, target, goal, seconds, rng, resolution):
    """OMPL's result for one task: (status, seconds used, goal postures, IK tries)."""
    from ompl import base as ob
    from ompl import geometric as og

    start_time = time.monotonic()
    n = problem.n
    home = np.zeros(n)
    goals = []
    tries = 0
    # Goal postures: from home first, then from random starts, for up to a third of the time.
    while time.monotonic() - start_time < seconds / 3 and len(goals) < 10:
        q0 = home if tries == 0 else rng.uniform(problem.lo, problem.hi)
        tries += 1
        q, ok = problem.ik(target, goal, q0)
        if ok and problem.valid(q):
            goals.append(q)
    if not goals:
        return "no valid posture", time.monotonic() - start_time, 0, tries
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(problem.lo[i]))
        bounds.setHigh(i, float(problem.hi[i]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    ss.setStateValidityChecker(lambda s: problem.valid([s[i] for i in range(n)]))
    si = ss.getSpaceInformation()
    si.setStateValidityCheckingResolution(resolution)
    start = space.allocState()
    for i in range(n):
        start[i] = 0.0
    ss.setStartState(start)
    goal = ob.GoalStates(si)
    for g in goals:
        s = space.allocState()
        for i in range(n):
            s[i] = float(g[i])
        goal.addState(s)
    ss.setGoal(goal)
    ss.setPlanner(og.RRTConnect(si))
    left = seconds - (time.monotonic() - start_time)
    if left <= 0 or not ss.solve(left) or not ss.haveExactSolutionPath():
        return "no path", time.monotonic() - start_time, len(goals), tries
    used = time.monotonic() - start_time
    path = ss.getSolutionPath()
    pts = [np.array([path.getState(k)[i] for i in range(n)]) for k in range(path.getStateCount())]
    clean = all(problem.edge_clean(a, b) for a, b in zip(pts, pts[1:]))
    return ("reached" if clean else "path fails dense check"), used, len(goals), tries


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("urdf")
    ap.add_argument("srdf")
    ap.add_argument("scenario")
    ap.add_argument("reach")
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--missed", action="store_true")
    ap.add_argument("--resolution", type=float, default=0.002)
    ap.add_argument("--tip", default="tool0", help="the tool frame (default tool0)")
    ap.add_argument("--package-dir", action="append", default=[], help="root of package://")
    args = ap.parse_args()

    from ompl import util as ou

    ou.setLogLevel(ou.LogLevel.LOG_WARN)
    ou.RNG.setSeed(args.seed + 1)  # OMPL refuses seed 0
    rng = np.random.default_rng(args.seed)
    problem = Problem(args.urdf, args.srdf, args.scenario, args.tip, args.package_dir)
    report = read_file(args.reach, json.load)
    tasks = problem.scenario.get("task", [])
    for n in problem.notes:
        print(n)
    home_valid = problem.valid(np.zeros(problem.n))
    if not home_valid:
        print("home collides: OMPL can reach no task")
    counts = {"kinsynth": 0, "ompl": 0, "only_ompl": 0, "checked": 0, "skipped": 0}
    for t in report["targets"]:
        i = t["index"]
        goal = task_goal(tasks[i]) if i < len(tasks) else None
        mine = bool(t["reached"])
        counts["kinsynth"] += mine
        if args.missed and mine:
            counts["skipped"] += 1
            continue
        counts["checked"] += 1
        target = np.array(t["point"], dtype=float)
        if home_valid:
            status, used, goals, tries = plan_task(
                problem, target, goal, args.seconds, rng, args.resolution
            )
        else:
            status, used, goals, tries = "home collides", 0.0, 0, 0
        theirs = status == "reached"
        counts["ompl"] += theirs
        counts["only_ompl"] += theirs and not mine
        flag = "  <-- reached by OMPL only" if theirs and not mine else ""
        print(
            f"task {i:3}: kinsynth {'reached' if mine else 'missed '}  OMPL {status} "
            f"({used:.2f} s, {goals} valid goal postures from {tries} IK starts){flag}"
        )
    print(
        f"{counts['checked']} tasks checked ({counts['skipped']} skipped), kinsynth reached "
        f"{counts['kinsynth']} of {len(report['targets'])}, OMPL reached {counts['ompl']} "
        f"of those checked; {counts['only_ompl']} reached by OMPL only; "
        f"{problem.self_pairs} self pairs enabled, {problem.checks} validity checks, "
        f"{args.seconds} s per task"
    )
    sys.stdout.flush()
    # The bindings report reference leaks at interpreter exit; leave without them.
    os._exit(1 if counts["only_ompl"] else 0)


if __name__ == "__main__":
    main()
