#!/usr/bin/env python3
"""Independent re-check of kinsynth's paths with pinocchio and coal (FCL).

Loads an exported robot (URDF + SRDF) and the scenario's obstacles into pinocchio's geometry
model, then samples every edge of every path in a reach report densely and reports any contact:
robot body against obstacle within the scenario's clearance, and every self pair the SRDF leaves
enabled. Needs `pip install pin coal`; not used by the tests.

usage: fcl_check.py ROBOT.urdf ROBOT.srdf SCENARIO.toml REACH.json [SAMPLES_PER_EDGE]
"""
import json
import sys
import tomllib

import coal
import numpy as np
import pinocchio as pin


def rotation(o):
    if "quaternion" in o:
        x, y, z, w = o["quaternion"]
        return pin.Quaternion(w, x, y, z).normalized().matrix()
    r, p, y = o.get("rpy", [0.0, 0.0, 0.0])
    return pin.rpy.rpyToMatrix(r, p, y)


def obstacle_geometry(o):
    shape = o["shape"]
    if shape == "sphere":
        return coal.Sphere(o["radius"])
    if shape == "capsule":
        return coal.Capsule(o["radius"], o["length"])
    if shape == "cylinder":
        return coal.Cylinder(o["radius"], o["length"])
    if shape == "cuboid":
        return coal.Box(*o["size"])
    return None  # meshes: not handled by this script


def main():
    urdf, srdf, scenario_path, reach_path = sys.argv[1:5]
    samples = int(sys.argv[5]) if len(sys.argv) > 5 else 400
    with open(scenario_path, "rb") as f:
        scenario = tomllib.load(f)
    clearance = scenario.get("clearance", 0.0)
    model = pin.buildModelFromUrdf(urdf)
    geom = pin.buildGeomFromUrdf(model, urdf, pin.GeometryType.COLLISION)
    robot_geoms = list(range(len(geom.geometryObjects)))
    geom.addAllCollisionPairs()
    pin.removeCollisionPairs(model, geom, srdf)
    self_pairs = len(geom.collisionPairs)
    obstacles = []
    skipped = 0
    for k, o in enumerate(scenario.get("obstacle", [])):
        g = obstacle_geometry(o)
        if g is None:
            skipped += 1
            continue
        placement = pin.SE3(rotation(o), np.array(o["position"], dtype=float))
        gid = geom.addGeometryObject(pin.GeometryObject(f"obstacle{k}", 0, placement, g))
        obstacles.append(gid)
    env_pairs = []
    for r in robot_geoms:
        for ob in obstacles:
            geom.addCollisionPair(pin.CollisionPair(r, ob))
            env_pairs.append(len(geom.collisionPairs) - 1)
    data = model.createData()
    gdata = pin.GeometryData(geom)
    with open(reach_path) as f:
        report = json.load(f)
    checked = 0
    hits = []
    worst = np.inf
    env_set = set(env_pairs)
    for t in report["targets"]:
        path = t.get("path")
        if not path:
            continue
        idx = [model.joints[model.getJointId(n)].idx_q for n in path["joint_names"]]
        pts = [np.array(p) for p in path["points"]]
        for a, b in zip(pts, pts[1:]):
            for s in np.linspace(0.0, 1.0, samples + 1):
                q = pin.neutral(model)
                q[idx] = a + s * (b - a)
                pin.updateGeometryPlacements(model, data, geom, gdata, q)
                pin.computeDistances(geom, gdata)
                checked += 1
                for p, res in enumerate(gdata.distanceResults):
                    d = res.min_distance
                    limit = clearance if p in env_set else 0.0
                    if p in env_set:
                        worst = min(worst, d)
                    if d <= limit:
                        cp = geom.collisionPairs[p]
                        hits.append(
                            (t["index"], geom.geometryObjects[cp.first].name,
                             geom.geometryObjects[cp.second].name, d)
                        )
    print(
        f"{checked} configurations, {self_pairs} self pairs enabled by the SRDF, "
        f"{len(obstacles)} obstacles ({skipped} mesh obstacles skipped), "
        f"smallest body-obstacle distance {worst:.4f} m, clearance {clearance} m"
    )
    for h in hits[:20]:
        print(f"  task {h[0]}: {h[1]} - {h[2]} at {h[3]:.4f} m")
    print(f"{len(hits)} contacts")
    sys.exit(1 if hits else 0)


if __name__ == "__main__":
    main()
