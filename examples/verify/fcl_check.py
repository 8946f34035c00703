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

An imported arm's URDF may hold what pinocchio's URDF parser (urdfdom) does not read:
- `<capsule radius length>` collision elements (kinsynth reads them: the axis along the
  element's z, `length` between the two hemisphere centres). urdfdom drops every `<collision>`
  of a link that has one; this script then reads that link's elements from the URDF itself
  (a capsule as coal's `Capsule(radius, length)`, the same solid) and says so. A collision
  element it cannot read either is an error, not a body left unchecked.
- `continuous` joints: pinocchio stores cos θ and sin θ; kinsynth's path holds the angle θ
  (on [−π, π], as kinsynth imports such a joint), and each configuration is built from it.
"""
import functools
import json
import math
import os
import sys
import tomllib
import xml.etree.ElementTree as ET

try:
    import coal
    import numpy as np
    import pinocchio as pin
except ImportError as e:
    sys.exit(f"fcl_check.py: {e}: needs the Python packages pin coal (pip install pin coal)")


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


def resource_path(filename, package_dirs):
    """Where pinocchio finds a mesh (its retrieveResourcePath): `package://` (or `model://`)
    paths in the first package directory that has them, `file://` as given, relative paths in
    the first package directory that has them, absolute paths as given; None when not found."""
    scheme, sep, rest = filename.partition("://")
    if sep:
        if scheme == "file":
            return rest
        if scheme not in ("package", "model"):
            return None
    else:
        if os.path.isabs(filename):
            return filename
        rest = filename
    for d in package_dirs:
        if os.path.exists(os.path.join(d, rest)):
            return os.path.join(d, rest)
    return None


def numbers(element, attribute, count, default=None):
    """`count` numbers of an XML attribute; ValueError naming it when missing or malformed."""
    text = element.get(attribute, default)
    if text is None:
        raise ValueError(f"<{element.tag}> has no {attribute}")
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ValueError(
            f"<{element.tag} {attribute}=\"{text}\">: expected {count} finite number(s)"
        )
    return values


def urdf_collision(element, package_dirs):
    """A URDF `<collision>` element as (its origin in the link frame, coal geometry, shape
    name), read as pinocchio reads the shapes it knows and `<capsule>` as kinsynth reads it."""
    origin = element.find("origin")
    if origin is None:
        placement = pin.SE3.Identity()
    else:
        xyz = numbers(origin, "xyz", 3, "0 0 0")
        rpy = numbers(origin, "rpy", 3, "0 0 0")
        placement = pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz))
    geometry = element.find("geometry")
    shape = None if geometry is None else next(iter(geometry), None)
    if shape is None:
        raise ValueError("no <geometry> shape")
    tag = shape.tag
    if tag in ("capsule", "cylinder"):
        # Both along z. A capsule (URDF, and kinsynth): `length` between the hemisphere
        # centres; coal's Capsule takes the same length (its halfLength is length / 2).
        radius, = numbers(shape, "radius", 1)
        length, = numbers(shape, "length", 1)
        solid = coal.Capsule if tag == "capsule" else coal.Cylinder
        return placement, solid(radius, length), tag
    if tag == "sphere":
        return placement, coal.Sphere(*numbers(shape, "radius", 1)), tag
    if tag == "box":
        return placement, coal.Box(*numbers(shape, "size", 3)), tag
    if tag == "mesh":
        filename = shape.get("filename", "")
        path = resource_path(filename, package_dirs)
        if path is None or not os.path.exists(path):
            raise ValueError(f"mesh {filename!r} not found")
        scale = numbers(shape, "scale", 3, "1 1 1")
        # As pinocchio loads a collision mesh: its triangles, as a bounding-volume hierarchy.
        return placement, coal.MeshLoader().load(path, np.array(scale)), tag
    raise ValueError(f"unknown shape <{tag}>")


def load_robot(urdf, package_dirs=()):
    """pinocchio's model of the URDF and its collision model, completed where pinocchio's URDF
    parser dropped `<collision>` elements (it drops all of a link's when it cannot read one,
    such as a `<capsule>`): those links' elements are read from the URDF here, attached to the
    link's frame as pinocchio attaches its own. Returns (model, geometry model, notes); exits
    with a message for a URDF it cannot read completely."""
    dirs = list(package_dirs) + [os.path.dirname(os.path.abspath(urdf))]
    try:
        root = ET.parse(urdf).getroot()
        model = pin.buildModelFromUrdf(urdf)
        # Relative mesh paths are taken from the URDF's folder.
        geom = pin.buildGeomFromUrdf(model, urdf, pin.GeometryType.COLLISION, package_dirs=dirs)
    except (OSError, ET.ParseError, ValueError, RuntimeError) as e:
        raise SystemExit(f"{urdf}: {e}")
    notes = []
    for link in root.findall("link"):
        elements = link.findall("collision")
        name = link.get("name", "")
        if not elements:
            continue
        frame_id = model.getFrameId(name, pin.FrameType.BODY)
        if frame_id >= model.nframes:
            raise SystemExit(f"{urdf}: link '{name}' has <collision> elements but no frame")
        # urdfdom drops all of a link's elements or none; a mesh may give pinocchio more than
        # one object.
        read = sum(o.parentFrame == frame_id for o in geom.geometryObjects)
        if read >= len(elements):
            continue
        if read:
            raise SystemExit(
                f"{urdf}: link '{name}': pinocchio read {read} of its {len(elements)} "
                "<collision> elements"
            )
        frame = model.frames[frame_id]
        shapes = []
        for k, element in enumerate(elements):
            try:
                placement, g, tag = urdf_collision(element, dirs)
            except ValueError as e:
                raise SystemExit(
                    f"{urdf}: link '{name}', <collision> {k + 1} of {len(elements)}: {e} "
                    "(pinocchio's URDF parser dropped this link's collision elements; unread, "
                    "they would go unchecked)"
                )
            geom.addGeometryObject(
                pin.GeometryObject(
                    f"{name}_{k}", frame.parentJoint, frame_id, frame.placement * placement, g
                )
            )
            shapes.append(tag)
        notes.append(
            f"note: pinocchio's URDF parser dropped the <collision> elements of link '{name}'; "
            f"read from the URDF here: {', '.join(shapes)}"
        )
    return model, geom, notes


def enable_self_pairs(model, geom, srdf):
    """Every pair of robot bodies on different joints, less the SRDF's disabled link pairs
    (pinocchio matches a body to a link by its frame, the added bodies included)."""
    geom.addAllCollisionPairs()
    try:
        pin.removeCollisionPairs(model, geom, srdf)
    except (ValueError, RuntimeError) as e:
        raise SystemExit(str(e) if srdf in str(e) else f"{srdf}: {e}")


def read_file(path, parse, binary=False):
    """`parse` of a file's contents; exits with a message when it cannot be read."""
    try:
        with open(path, "rb" if binary else "r") as f:
            return parse(f)
    except (OSError, ValueError) as e:  # TOML and JSON errors are ValueErrors
        raise SystemExit(f"{path}: {e}")


def joint_slots(model, names, source):
    """Where each named joint's value goes in pinocchio's configuration: (idx_q, nq), nq = 2
    for a continuous joint (cos θ, sin θ), 1 for a revolute or prismatic joint."""
    slots = []
    for n in names:
        if not model.existJointName(n):
            raise SystemExit(f"{source}: joint {n!r} is not in the URDF")
        j = model.joints[model.getJointId(n)]
        if j.nv != 1 or j.nq not in (1, 2):
            raise SystemExit(
                f"{source}: joint {n!r} ({j.shortname()}): only revolute, continuous and "
                "prismatic joints are supported"
            )
        slots.append((j.idx_q, j.nq))
    return slots


def configuration(model, slots, values):
    """pinocchio's configuration with the joints of `slots` at `values` (angles in rad, lengths
    in m) and every other joint at its neutral value (0)."""
    q = pin.neutral(model)
    for (i, nq), v in zip(slots, values):
        if nq == 2:
            q[i], q[i + 1] = math.cos(v), math.sin(v)
        else:
            q[i] = v
    return q


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
    if any(a in ("-h", "--help") for a in sys.argv[1:]):
        print(__doc__.strip())
        return
    args, package_dirs = package_dirs_of(sys.argv[1:])
    if len(args) not in (4, 5):
        usage = __doc__[__doc__.index("usage:") :].split("\n\n")[0]
        sys.exit(f"fcl_check.py: expected 4 or 5 arguments, got {len(args)}\n{usage}")
    urdf, srdf, scenario_path, reach_path = args[:4]
    try:
        samples = int(args[4]) if len(args) > 4 else 400
    except ValueError:
        samples = 0
    if samples < 1:
        sys.exit(f"fcl_check.py: SAMPLES_PER_EDGE must be a positive integer, not {args[4]!r}")
    scenario = read_file(scenario_path, tomllib.load, binary=True)
    clearance = scenario.get("clearance", 0.0)
    model, geom, notes = load_robot(urdf, package_dirs)
    for n in notes:
        print(n)
    robot_geoms = list(range(len(geom.geometryObjects)))
    enable_self_pairs(model, geom, srdf)
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
    report = read_file(reach_path, json.load)
    checked = 0
    hits = []
    worst = np.inf
    worst_self = np.inf  # smallest distance of an enabled self pair
    env_set = set(env_pairs)
    for t in report["targets"]:
        path = t.get("path")
        if not path:
            continue
        slots = joint_slots(model, path["joint_names"], reach_path)
        pts = [np.array(p, dtype=float) for p in path["points"]]
        if any(len(p) != len(slots) for p in pts):
            sys.exit(
                f"fcl_check.py: {reach_path}: task {t['index']}: a path point has not one "
                f"value per joint ({len(slots)})"
            )
        for a, b in zip(pts, pts[1:]):
            for s in np.linspace(0.0, 1.0, samples + 1):
                q = configuration(model, slots, a + s * (b - a))
                pin.updateGeometryPlacements(model, data, geom, gdata, q)
                pin.computeDistances(geom, gdata)
                checked += 1
                for p, res in enumerate(gdata.distanceResults):
                    d = res.min_distance
                    limit = clearance if p in env_set else 0.0
                    if p in env_set:
                        worst = min(worst, d)
                    else:
                        worst_self = min(worst_self, d)
                    if d <= limit:
                        cp = geom.collisionPairs[p]
                        hits.append(
                            (t["index"], geom.geometryObjects[cp.first].name,
                             geom.geometryObjects[cp.second].name, d)
                        )
    print(
        f"{checked} configurations, {self_pairs} self pairs enabled by the SRDF, "
        f"{len(obstacles)} obstacles ({meshes} mesh obstacles checked), "
        f"smallest body-obstacle distance {worst:.4f} m, clearance {clearance} m, "
        f"smallest self-pair distance {worst_self:.4f} m"
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
