"""The whole-body COM and ZMP of a walk, by Pinocchio (PyPI `pin`), as an oracle for
host-sim's multi-body model of an imported robot.

Reads JSON on stdin: {"urdf": path, "gravity": g, "dt": s, "ticks": [{"base": [x, y, z, yaw],
"q": {joint: angle}}]}; every joint not named stays at 0. Builds the URDF's model with a free
flyer at its root link, and per tick: the configuration (base upright with that heading), the
velocity and acceleration from central differences on the configuration manifold
(`pinocchio.difference`), the COM and its acceleration, and the rate of the centroidal
angular momentum. With the ground reaction F = m (c'' + g z) and its moment about the origin
M = c x F + dL/dt, the ZMP on the floor is (-M_y / F_z, M_x / F_z). Writes JSON on stdout:
[{"com": [x, y, z], "zmp": [x, y]}] for the ticks 1 .. n-2.
"""

import json
import math
import sys

import numpy as np
import pinocchio as pin


def main():
    job = json.load(sys.stdin)
    model = pin.buildModelFromUrdf(job["urdf"], pin.JointModelFreeFlyer())
    model.gravity.linear = np.array([0.0, 0.0, -job["gravity"]])
    data = model.createData()
    dt = job["dt"]
    qs = []
    for tick in job["ticks"]:
        q = pin.neutral(model)
        x, y, z, yaw = tick["base"]
        q[0:3] = [x, y, z]
        q[3:7] = [0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)]
        for name, angle in tick["q"].items():
            jid = model.getJointId(name)
            if jid >= model.njoints:
                raise SystemExit(f"no joint {name} in {job['urdf']}")
            q[model.joints[jid].idx_q] = angle
        qs.append(q)
    out = []
    mass = sum(i.mass for i in model.inertias)
    g = job["gravity"]
    for k in range(1, len(qs) - 1):
        v = pin.difference(model, qs[k - 1], qs[k + 1]) / (2.0 * dt)
        a = (pin.difference(model, qs[k], qs[k + 1]) - pin.difference(model, qs[k - 1], qs[k])) / (
            dt * dt
        )
        pin.centerOfMass(model, data, qs[k], v, a)
        c = data.com[0].copy()
        acc = data.acom[0].copy()
        dh = pin.computeCentroidalMomentumTimeVariation(model, data, qs[k], v, a)
        force = mass * (acc + np.array([0.0, 0.0, g]))
        moment = np.cross(c, force) + dh.angular
        out.append(
            {
                "com": c.tolist(),
                "zmp": [-moment[1] / force[2], moment[0] / force[2]],
            }
        )
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
