# host-sim's MuJoCo bridge: steps the engine and nothing else (host-sim/src/physics/bridge.rs).
#
# Protocol on stdin/stdout, every number little-endian:
#   host -> bridge  u32 n, then n bytes of MJCF (UTF-8)
#   bridge -> host  one line: "OK <mujoco version> <nq> <nu> <nsensordata>" or "ERR <message>"
#   then frames, each starting with one opcode byte:
#     b'I' + nq f64          set qpos (qvel = 0), mj_forward; answer an observation
#     b'S' + u32 k + nu f64 + 6 f64
#                            ctrl := the nu values, xfrc_applied of the body "trunk" := the six
#                            values (force, torque, world frame), k calls of mj_step; answer an
#                            observation
#     b'V' + 2 f64           the floating base's linear velocity x, y (world frame) := the two
#                            values, mj_forward; answer an observation
#     b'Q'                   exit
#   observation: f64 time, nsensordata f64 sensordata, then the ground truth for the
#   evaluation (never for the controller): base position (3), base quaternion w x y z (4),
#   floor-contact CoP x y, total floor normal force, 1.0 if a geom other than the two soles
#   touches the floor else 0.0, the floor's normal force on the left sole, on the right sole.
import struct
import sys


def main():
    out = sys.stdout.buffer
    inp = sys.stdin.buffer

    def read(n):
        b = inp.read(n)
        if len(b) != n:
            sys.exit(0)
        return b

    (n,) = struct.unpack("<I", read(4))
    xml = read(n).decode("utf-8")
    try:
        import mujoco
        import numpy as np
    except Exception as e:  # noqa: BLE001
        out.write(("ERR cannot import mujoco (pip install mujoco): %s\n" % e).encode())
        out.flush()
        return
    try:
        m = mujoco.MjModel.from_xml_string(xml)
    except Exception as e:  # noqa: BLE001
        out.write(("ERR MJCF rejected: %s\n" % str(e).replace("\n", " ")).encode())
        out.flush()
        return
    d = mujoco.MjData(m)
    floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    left = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "l_sole")
    right = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "r_sole")
    soles = {left, right}
    base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "waist")
    trunk = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "trunk")
    # The base's free joint: its first three velocities are the linear velocity, world frame.
    base_joint = m.body_jntadr[base] if base >= 0 else -1
    free_dof = -1
    if base_joint >= 0 and m.jnt_type[base_joint] == mujoco.mjtJoint.mjJNT_FREE:
        free_dof = m.jnt_dofadr[base_joint]
    out.write(("OK %s %d %d %d\n" % (mujoco.__version__, m.nq, m.nu, m.nsensordata)).encode())
    out.flush()
    f6 = np.zeros(6)

    def observe():
        fz_sum = 0.0
        px = 0.0
        py = 0.0
        other = 0.0
        f_left = 0.0
        f_right = 0.0
        for i in range(d.ncon):
            c = d.contact[i]
            if c.geom1 != floor and c.geom2 != floor:
                continue
            g = c.geom2 if c.geom1 == floor else c.geom1
            if g not in soles:
                other = 1.0
            mujoco.mj_contactForce(m, d, i, f6)
            # Normal force along the contact frame's first axis (the floor normal, +z).
            fz = f6[0] * abs(c.frame[2])
            fz_sum += fz
            if g == left:
                f_left += fz
            elif g == right:
                f_right += fz
            px += fz * c.pos[0]
            py += fz * c.pos[1]
        if fz_sum > 1e-9:
            px /= fz_sum
            py /= fz_sum
        else:
            px = float("nan")
            py = float("nan")
        head = np.array([d.time])
        truth = np.concatenate(
            [d.xpos[base], d.xquat[base], [px, py, fz_sum, other, f_left, f_right]]
        )
        out.write(head.astype("<f8").tobytes())
        out.write(np.asarray(d.sensordata, dtype="<f8").tobytes())
        out.write(truth.astype("<f8").tobytes())
        out.flush()

    while True:
        op = read(1)
        if op == b"I":
            q = np.frombuffer(read(8 * m.nq), dtype="<f8")
            mujoco.mj_resetData(m, d)
            d.qpos[:] = q
            mujoco.mj_forward(m, d)
            observe()
        elif op == b"S":
            (k,) = struct.unpack("<I", read(4))
            d.ctrl[:] = np.frombuffer(read(8 * m.nu), dtype="<f8")
            d.xfrc_applied[trunk, :] = np.frombuffer(read(48), dtype="<f8")
            for _ in range(k):
                mujoco.mj_step(m, d)
            observe()
        elif op == b"V":
            v = np.frombuffer(read(16), dtype="<f8")
            if free_dof < 0:
                sys.exit(1)
            d.qvel[free_dof : free_dof + 2] = v
            mujoco.mj_forward(m, d)
            observe()
        else:
            return


if __name__ == "__main__":
    main()
