#!/usr/bin/env python3
"""Independent re-check of kinsynth's paths with pinocchio and coal (FCL).

Loads an exported robot (URDF + SRDF) and the scenario's obstacles into pinocchio's geometry
model, then samples every edge of every path in a reach report densely and reports any contact:
robot body against obstacle within the scenario's clearance, and every self pair the SRDF leaves
enabled. Needs `pip install pin coal`; not used by the tests.

Obstacles are placed by `position` and `rpy` (fixed axes x, y, z, as URDF) or `quaternion`
([x, y, z, w]). Primitives become coal shapes. A mesh (`shape = "mesh"`: an STL or OBJ `file`
relative to the scenario file, `scale` one factor or [sx, sy, sz] in the mesh's frame) is read
by coal's MeshLoader and stands in as its `representation`:
- `hull` (the default): the convex hull of its vertices (qhull), as kinsynth checks it;
- `trimesh`: the triangle mesh as a bounding-volume hierarchy, as kinsynth checks it;
- `decomposition`: also the triangle mesh (kinsynth checks V-HACD parts, which should contain
  the surface, so a contact with the surface is a real finding).
A triangle mesh is a surface: a body entirely inside a closed mesh is not a contact. Every path
starts at home, outside, so such a body must have crossed the surface between two samples; the
output says when this applies.

usage: fcl_check.py ROBOT.urdf ROBOT.srdf SCENARIO.toml REACH.json [SAMPLES_PER_EDGE]
           [--package-dir DIR]...

`--package-dir DIR` (repeatable) is where `package://NAME/…` mesh paths of an imported arm are
looked up (as `DIR/NAME/…`, pinocchio's rule); relative mesh paths are taken from the URDF's
folder.
"""
import functools
import json
import os
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


@functools.cache
def mesh_geometry(path, scale, representation):
    """A mesh file, scaled, as its convex hull or its triangles (a BVH); read once per key."""
    bvh = coal.MeshLoader().load(path, np.array(scale))
    if representation == "hull":
        bvh.buildConvexHull(True, "Qt")
        return bvh.convex
    if representation in ("trimesh", "decomposition"):
        return bvh
    raise ValueError(f"{path}: unknown mesh representation {representation!r}")


def obstacle_geometry(o, scenario_dir):
    shape = o["shape"]
    if shape == "sphere":
        return coal.Sphere(o["radius"])
    if shape == "capsule":
        return coal.Capsule(o["radius"], o["length"])
    if shape == "cylinder":
        return coal.Cylinder(o["radius"], o["length"])
    if shape == "cuboid":
        return coal.Box(*o["size"])
    if shape == "mesh":
        scale = tuple(float(v) for v in np.broadcast_to(o.get("scale", 1.0), 3))
        path = os.path.join(scenario_dir, o["file"])
        return mesh_geometry(path, scale, o.get("representation", "hull"))
    raise ValueError(f"unknown obstacle shape {shape!r}")


def package_dirs_of(argv):
    """The arguments without the `--package-dir DIR` pairs, and those directories."""
    rest, dirs = [], []
    it = iter(argv)
    for a in it:
        if a == "--package-dir":
            d = next(it, None)
            if d is None:
                sys.exit("fcl_check.py: --package-dir needs a directory")
            dirs.append(d)
        else:
            rest.append(a)
    return rest, dirs


def main():
    args, package_dirs = package_dirs_of(sys.argv[1:])
    if len(args) not in (4, 5):
        usage = __doc__[__doc__.index("usage:") :].split("\n\n")[0]
        sys.exit(f"fcl_check.py: expected 4 or 5 arguments, got {len(args)}\n{usage}")
    urdf, srdf, scenario_path, reach_path = args[:4]
    samples = int(args[4]) if len(args) > 4 else 400
    with open(scenario_path, "rb") as f:
        scenario = tomllib.load(f)
    clearance = scenario.get("clearance", 0.0)
    model = pin.buildModelFromUrdf(urdf)
    geom = pin.buildGeomFromUrdf(
        model,
        urdf,
        pin.GeometryType.COLLISION,
        # Relative mesh paths are taken from the URDF's folder.
        package_dirs=package_dirs + [os.path.dirname(os.path.abspath(urdf))],
    )
    robot_geoms = list(range(len(geom.geometryObjects)))
    geom.addAllCollisionPairs()
    pin.removeCollisionPairs(model, geom, srdf)
    self_pairs = len(geom.collisionPairs)
    obstacles = []
    meshes = 0
    surfaces = 0  # meshes checked as triangles
    for k, o in enumerate(scenario.get("obstacle", [])):
        g = obstacle_geometry(o, os.path.dirname(scenario_path))
        if o["shape"] == "mesh":
            meshes += 1
            surfaces += o.get("representation", "hull") != "hull"
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
        f"{len(obstacles)} obstacles ({meshes} mesh obstacles checked), "
        f"smallest body-obstacle distance {worst:.4f} m, clearance {clearance} m"
    )
    if surfaces:
        print(
            f"  note: {surfaces} mesh obstacles checked as triangle surfaces: a body entirely "
            "inside a closed mesh is not a contact (it must have crossed the surface between "
            "two samples to get there)"
        )
    for h in hits[:20]:
        print(f"  task {h[0]}: {h[1]} - {h[2]} at {h[3]:.4f} m")
    print(f"{len(hits)} contacts")
    sys.exit(1 if hits else 0)


if __name__ == "__main__":
    main()
