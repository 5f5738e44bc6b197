"""The feet's lowest geometry by Pinocchio and Coal: the oracle of the imported soles.

Reads a JSON job on stdin: {"urdf": PATH, "package_dir": DIR, "ankles": [JOINT, JOINT]}.
For each ankle joint (the sixth joint of a leg), at the neutral configuration: the collision
geometry attached to that joint (its visual geometry if it has none), as points in the world
frame (a box's corners, a sphere's lowest point, a cylinder's end circles, a mesh's vertices
as Coal loaded them); the lowest height; the bounds of the points within 5 mm of it; the
joint's position. Writes one JSON object per ankle, a list, on stdout. A foot with a COLLADA
mesh is reported as {"skipped": REASON} (Coal's loader does not turn a COLLADA up axis).
"""

import json
import sys

import numpy as np
import pinocchio as pin

BAND = 0.005


def points(go, placement):
    g = go.geometry
    kind = type(g).__name__
    if kind == "Box":
        h = np.asarray(g.halfSide)
        local = np.array(
            [[sx * h[0], sy * h[1], sz * h[2]] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
        )
    elif kind == "Sphere":
        c = placement.translation
        return np.array([[c[0], c[1], c[2] - g.radius]])
    elif kind == "Cylinder":
        a = np.linspace(0, 2 * np.pi, 32, endpoint=False)
        local = np.concatenate(
            [
                np.stack([g.radius * np.cos(a), g.radius * np.sin(a), np.full(32, z)], 1)
                for z in (-g.halfLength, g.halfLength)
            ]
        )
    else:
        local = np.asarray(g.vertices())
    return (placement.rotation @ local.T).T + placement.translation


def main():
    job = json.load(sys.stdin)
    model = pin.buildModelFromUrdf(job["urdf"])
    data = model.createData()
    q = pin.neutral(model)
    pin.forwardKinematics(model, data, q)
    out = []
    built = {}

    def placed(kind):
        if kind not in built:
            geom = pin.buildGeomFromUrdf(model, job["urdf"], kind, package_dirs=[job["package_dir"]])
            gdata = geom.createData()
            pin.updateGeometryPlacements(model, data, geom, gdata)
            built[kind] = (geom, gdata)
        return built[kind]

    for ankle in job["ankles"]:
        jid = model.getJointId(ankle)
        found = None
        for kind in (pin.GeometryType.COLLISION, pin.GeometryType.VISUAL):
            geom, gdata = placed(kind)
            objs = [(i, go) for i, go in enumerate(geom.geometryObjects) if go.parentJoint == jid]
            if objs:
                found = (objs, gdata)
                break
        if found is None:
            out.append({"skipped": "no geometry"})
            continue
        objs, gdata = found
        if any(go.meshPath.lower().endswith(".dae") for _, go in objs):
            out.append({"skipped": "a COLLADA mesh"})
            continue
        pts = np.concatenate([points(go, gdata.oMg[i]) for i, go in objs])
        zs = pts[:, 2].min()
        c = pts[pts[:, 2] <= zs + BAND]
        out.append(
            {
                "ankle": data.oMi[jid].translation.tolist(),
                "lowest": float(zs),
                "x": [float(c[:, 0].min()), float(c[:, 0].max())],
                "y": [float(c[:, 1].min()), float(c[:, 1].max())],
            }
        )
    json.dump(out, sys.stdout)


main()
