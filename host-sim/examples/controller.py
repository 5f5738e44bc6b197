#!/usr/bin/env python3
"""An example controller for the walking node, written from the DBC alone.

It walks the robot straight ahead: it opens the node's session (a ``reset`` carrying the
session the node publishes in SESSION: after it the session is one more), appends footsteps
(right foot first, then alternating, and a closing step beside the last one; numbered from
the node's next step number, DIAG's next_step), starts the walk, asks for a stop after the
queue, and sends a heartbeat every 100 ms throughout (the node stops a moving robot after
500 ms without one). Every frame is encoded by cantools from ``host-sim/can/walking.dbc``; the
CRC-8 the commands end with is the one the DBC's comments describe (AUTOSAR: polynomial
0x2F, initial value and final XOR 0xFF, over the identifier as two little-endian bytes, for
the footstep frames the Gray code of the step number's high byte, and the data before the
CRC). All CONTROL frames (the reset, heartbeats, start, stop) take their sequence numbers
from one counter, above the node's SESSION last_seq, so that every one is new. cantools rounds exact half units to even where the node's
own encoder rounds them away from zero: a coordinate exactly between two 0.5 mm steps may go
out one step apart (0.5 mm), which the node takes as given.

Five ways to run it:

  controller.py live --channel can0 [--interface socketcan]
      waits for the node's SESSION and DIAG, then sends the plan in real time on a CAN bus
      through python-can, printing the node's answers (needs a CAN interface that is up: see
      the book's real-bus chapter; without one it says what is missing in one line, exit 2);
  controller.py plan --out out/ctl.log [--session E --first-step N --last-seq S]
      the plan written as a candump -l log (times from host-sim's epoch), for
      ``host-sim replay out/ctl.log`` (host-sim/tests/controller.rs does this); the defaults are
      host-sim's node (session 0, steps from 0, no control command before);
  controller.py stick --out out/stick.log [--session E --last-seq S]
      a scripted stick instead of footsteps: the node chooses the steps from a VELOCITY
      stream every 50 ms (0.15 m/s forward, at 5 s 0.04 m/s sideways, at 9 s a turn of
      0.15 rad/s, at 12 s its reversal, at 15 s zero), as a log for ``host-sim replay``;
      ``controller.py check LOG --stick`` checks every velocity accepted and the robot
      standing at the end (host-sim/tests/controller.rs);
  controller.py frame OP --session E --seq S
      prints one CONTROL frame for ``cansend`` (OP: reset, heartbeat, start, stop, stop_now, start_adjusting);
  controller.py check can.log
      checks a log of the bus (host-sim's output; give the same options as to ``plan``):
      every command answered and accepted, the robot standing at the end with its feet where
      the last two steps put them.

Options: --steps N (footsteps before the closing one, default 6), --length L (m, default
0.2), --width W (m, the distance of the feet, default 0.2: HRP-2's stance), --seconds S
(how long the heartbeat runs, default 9).
"""

import argparse
import os
import sys
import time

try:
    import can
    import cantools
except ImportError as missing:  # said as a usage error in main(), without a traceback
    MISSING = missing.name or str(missing)
else:
    MISSING = None

HERE = os.path.dirname(os.path.abspath(__file__))
DBC = os.path.join(HERE, "..", "can", "walking.dbc")
# host-sim's log epoch: 2026-01-01T00:00:00Z.
EPOCH_S = 1767225600
HEARTBEAT_S = 0.1


def crc8(frame_id, data, key=None):
    """CRC-8/AUTOSAR over the identifier (2 bytes, little-endian), `key` (a footstep frame's
    byte: see `step_key`; VELOCITY's two bytes: see `velocity`) if given, and `data`."""
    crc = 0xFF
    if isinstance(key, int):
        key = bytes([key])
    head = bytes([frame_id & 0xFF, frame_id >> 8]) + (key or b"")
    for byte in head + bytes(data):
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x2F) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def step_key(number):
    """The CRC key of step number `number`: the Gray code of its high byte."""
    high = (number >> 8) & 0xFF
    return high ^ (high >> 1)


def encode(db, name, signals, number=None):
    """The frame `name` with `signals`, its CRC (if it has one) computed and set; a footstep
    frame's `number` gives its step_id (the low byte) and its CRC key."""
    msg = db.get_message_by_name(name)
    key = None
    if number is not None:
        signals = dict(signals, step_id=number & 0xFF)
        key = step_key(number)
    if any(s.name == "crc" for s in msg.signals):
        data = msg.encode(dict(signals, crc=0))
        signals = dict(signals, crc=crc8(msg.frame_id, data[:-1], key))
    return can.Message(
        arbitration_id=msg.frame_id, data=msg.encode(signals), is_extended_id=False
    )


def plan(db, steps, length, width, seconds, session=0, first_step=0, last_seq=0):
    """The controller's frames as (time [s], message), in time order: the handshake in the
    node's session `session`, then the walk in the next one."""
    half = width / 2.0
    out = []
    controls = []  # (time, op): numbered in time order below, so that each is new

    def control(t, op):
        controls.append((t, op))

    control(0.0, "reset")

    # t = 0: the footsteps, right first, x growing by `length`; then the closing step.
    poses = []
    for i in range(steps):
        left = i % 2 == 1
        poses.append((left, (i + 1) * length, half if left else -half))
    last_left = poses[-1][0]
    poses.append((not last_left, poses[-1][1], -half if last_left else half))
    for i, (left, x, y) in enumerate(poses):
        out.append(
            (0.0, encode(db, "STEP_APPEND", {
                "left": int(left), "reserved": 0, "x": x, "y": y, "yaw": 0.0,
            }, number=first_step + i))
        )
    # 100 ms: start, then stop once the queue is walked.
    control(0.1, "start")
    control(0.1, "stop")
    k = 0
    while k * HEARTBEAT_S <= seconds:
        control(k * HEARTBEAT_S, "heartbeat")
        k += 1
    # In time order (the sort is stable: the reset first, the start before the stop): each
    # with the next sequence number; after the reset, in the next session.
    controls.sort(key=lambda e: e[0])
    for i, (t, op) in enumerate(controls):
        epoch = session if op == "reset" else session + 1
        signals = {"session": epoch & 0xFFFF, "seq": last_seq + 1 + i, "op": op}
        out.append((t, encode(db, "CONTROL", signals)))
    # The reset before the footsteps of t = 0.
    out.sort(key=lambda e: (e[0], e[1].arbitration_id != 0x020 or e[1].data[6] != 4))
    return out, poses


# The scripted stick: (from time [s], vx [m/s], vy [m/s], wz [rad/s]): forward, a step
# change to sideways, a turn and its reversal, then zero (the robot stops and stands).
STICK = [(0.0, 0.15, 0.0, 0.0), (5.0, 0.0, 0.04, 0.0), (9.0, 0.05, 0.0, 0.15),
         (12.0, 0.05, 0.0, -0.15), (15.0, 0.0, 0.0, 0.0)]
STICK_END_S = 19.0
STICK_PERIOD_S = 0.05


def velocity(db, epoch, seq, vx, vy, wz):
    """A VELOCITY frame: the sequence number's low 24 bits (bits 16-23 XOR the session's
    second byte), the CRC keyed with the session's low byte and the Gray code of the sequence
    number's high byte (the DBC's comment)."""
    msg = db.get_message_by_name("VELOCITY")
    signals = {"seq_low": seq & 0xFFFF, "seq_mid": ((seq >> 16) ^ (epoch >> 8)) & 0xFF,
               "vx": vx, "vy": vy, "wz": wz}
    data = msg.encode(dict(signals, crc=0))
    high = (seq >> 24) & 0xFF
    key = bytes([epoch & 0xFF, high ^ (high >> 1)])
    signals["crc"] = crc8(msg.frame_id, data[:-1], key)
    return can.Message(arbitration_id=msg.frame_id, data=msg.encode(signals),
                       is_extended_id=False)


def stick(db, session=0, last_seq=0):
    """The scripted stick's frames as (time [s], message): the handshake in the node's session
    `session`, then a VELOCITY every 50 ms in the next one (each proves the controller alive:
    no heartbeat, which the bus would deliver before a VELOCITY of the same instant)."""
    seq = last_seq + 1
    out = [(0.0, encode(db, "CONTROL", {"session": session & 0xFFFF, "seq": seq,
                                        "op": "reset"}))]
    k = 2
    while k * STICK_PERIOD_S <= STICK_END_S:
        t = k * STICK_PERIOD_S
        _, vx, vy, wz = [s for s in STICK if s[0] <= t][-1]
        seq += 1
        out.append((t, velocity(db, session + 1, seq, vx, vy, wz)))
        k += 1
    return out


def check_stick(db, path, sent):
    """Problems found in the bus log of the stick's walk: every command answered and accepted,
    the robot standing at the end."""
    problems = []
    acks, state = [], None
    for m in read_log(path):
        if m.arbitration_id == 0x080:
            acks.append(db.decode_message(m.arbitration_id, m.data))
        elif m.arbitration_id == 0x300:
            state = str(db.decode_message(m.arbitration_id, m.data)["state"])
    velocities = [a for a in acks if str(a["command"]) == "velocity"]
    if len(velocities) != sent:
        problems.append(f"{len(velocities)} VELOCITY answers for {sent} sent")
    for a in acks:
        if str(a["reason"]) != "accepted":
            problems.append(f"refused: {a['command']} {a['seq']}: {a['reason']}")
    if state != "standing":
        problems.append(f"the last STATUS says {state}, not standing")
    return problems


def write_log(path, frames):
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "w") as f:
        for t, m in frames:
            us = EPOCH_S * 1_000_000 + round(t * 1e6)
            data = m.data.hex().upper()
            f.write(f"({us // 1_000_000}.{us % 1_000_000:06d}) can0 {m.arbitration_id:03X}#{data}\n")


def read_log(path):
    """The frames of a candump -l log, through python-can's reader."""
    with can.LogReader(path) as reader:
        return list(reader)


def check(db, path, poses):
    """Problems found in the bus log at `path` (empty: the walk went as planned)."""
    problems = []
    ack = db.get_message_by_name("ACK")
    acks, feet, state = [], {}, None
    for m in read_log(path):
        if m.arbitration_id == ack.frame_id:
            if crc8(m.arbitration_id, m.data[:-1]) != m.data[-1]:
                problems.append(f"ACK with a bad CRC: {m.data.hex()}")
                continue
            acks.append(db.decode_message(m.arbitration_id, m.data))
        elif m.arbitration_id in (0x210, 0x211, 0x300):
            d = db.decode_message(m.arbitration_id, m.data)
            if m.arbitration_id == 0x300:
                state = str(d["state"])
            else:
                feet[m.arbitration_id] = d
    appends = [a for a in acks if str(a["command"]) == "append"]
    if len(appends) != len(poses):
        problems.append(f"{len(appends)} footstep answers for {len(poses)} footsteps")
    for a in acks:
        if str(a["reason"]) != "accepted":
            problems.append(f"refused: {a['command']} {a['seq']}: {a['reason']}")
    if state != "standing":
        problems.append(f"the last STATUS says {state}, not standing")
    for frame_id, left in ((0x210, True), (0x211, False)):
        want = next(p for p in reversed(poses) if p[0] == left)
        got = feet.get(frame_id)
        if got is None or abs(got["x"] - want[1]) > 1e-3 or abs(got["y"] - want[2]) > 1e-3:
            problems.append(f"{'left' if left else 'right'} foot at {got}, not {want[1:]}")
    return problems


def session_of(db, bus, timeout=2.0):
    """The node's session, next step number and last sequence number, from its SESSION and
    DIAG frames (sent every 100 ms)."""
    session = diag = None
    end = time.monotonic() + timeout
    while (session is None or diag is None) and time.monotonic() < end:
        r = bus.recv(timeout=0.1)
        if r is None:
            continue
        if r.arbitration_id == 0x303:
            session = db.decode_message(r.arbitration_id, r.data)
        elif r.arbitration_id == 0x301:
            diag = db.decode_message(r.arbitration_id, r.data)
    if session is None or diag is None:
        raise SystemExit("no SESSION and DIAG from the node: is it on the bus?")
    return int(session["epoch"]), int(diag["next_step"]), int(session["last_seq"])


def bus_or_exit(args):
    """The CAN bus on args.channel, or a one-line error that says what is missing (exit 2)."""
    try:
        return can.Bus(channel=args.channel, interface=args.interface)
    except (OSError, can.CanError, ValueError, ImportError) as e:
        code = getattr(e, "errno", None)
        if code == 97:  # EAFNOSUPPORT: the kernel has no SocketCAN
            hint = ("this kernel has no SocketCAN: load it (sudo modprobe can can_raw; "
                    "vcan for a virtual bus) or use a kernel with CAN")
        elif code == 19:  # ENODEV: no such interface
            hint = (f"there is no interface {args.channel}: bring one up (sudo ip link set "
                    f"{args.channel} type can bitrate 1000000 && sudo ip link set "
                    f"{args.channel} up), or a virtual one (see the book's real-bus chapter)")
        else:
            hint = "see the book's real-bus chapter, \"Setting up a CAN interface\""
        print(f"controller.py: CAN interface {args.channel} ({args.interface}): {e}; {hint}",
              file=sys.stderr)
        sys.exit(2)


def live(db, args):
    bus = bus_or_exit(args)
    epoch, first, last = session_of(db, bus)
    print(f"session {epoch}, next step {first}, last sequence number {last}")
    frames, _ = plan(db, args.steps, args.length, args.width, args.seconds, epoch, first, last)
    start = time.monotonic()
    ack = db.get_message_by_name("ACK")
    for t, m in frames:
        while time.monotonic() - start < t:
            r = bus.recv(timeout=0.001)
            if r is not None and r.arbitration_id == ack.frame_id:
                print(db.decode_message(r.arbitration_id, r.data))
        bus.send(m)
    bus.shutdown()


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("mode", choices=["plan", "check", "live", "frame", "stick"])
    p.add_argument("log", nargs="?", help="check: the bus log to check; frame: the operation")
    p.add_argument("--out", help="plan: the log to write")
    p.add_argument("--channel", default="can0")
    p.add_argument("--interface", default="socketcan")
    p.add_argument("--steps", type=int, default=6)
    p.add_argument("--length", type=float, default=0.2)
    p.add_argument("--width", type=float, default=0.2)
    p.add_argument("--seconds", type=float, default=9.0)
    p.add_argument("--session", type=lambda v: int(v, 0), default=0,
                   help="plan, frame: the node's session epoch (SESSION)")
    p.add_argument("--first-step", type=int, default=0,
                   help="plan: the node's next step number (DIAG next_step)")
    p.add_argument("--last-seq", type=int, default=0,
                   help="plan: the node's last sequence number (SESSION last_seq)")
    p.add_argument("--seq", type=int, default=1, help="frame: its sequence number")
    p.add_argument("--stick", action="store_true",
                   help="check: the log of the scripted stick's walk (mode stick)")
    a = p.parse_args()
    if a.steps < 1:
        p.error("--steps must be at least 1")
    if a.mode == "check":
        if not a.log:
            p.error("check needs the log")
        if not os.path.isfile(a.log):
            p.error(f"{a.log}: no such file (`host-sim replay LOG --out DIR` writes DIR/can.log)")
    if MISSING:
        p.error(f"the python module {MISSING} is missing: pip install python-can cantools")
    db = cantools.database.load_file(DBC, strict=True)
    if a.mode == "frame":
        ops = ["heartbeat", "start", "stop", "stop_now", "reset", "start_adjusting"]
        if a.log not in ops:
            p.error(f"frame needs an operation: one of {', '.join(ops)}")
        m = encode(db, "CONTROL", {"session": a.session & 0xFFFF, "seq": a.seq, "op": a.log})
        print(f"{m.arbitration_id:03X}#{m.data.hex().upper()}")
        return
    if a.mode == "live":
        live(db, a)
        return
    if a.mode == "stick":
        if not a.out:
            p.error("stick needs --out")
        frames = stick(db, a.session, a.last_seq)
        write_log(a.out, frames)
        print(f"{len(frames)} frames ({len(frames) - 1} VELOCITY) written to {a.out}")
        return
    if a.mode == "check" and a.stick:
        problems = check_stick(db, a.log, len(stick(db, a.session, a.last_seq)) - 1)
        for line in problems:
            print(line)
        if problems:
            sys.exit(1)
        print(f"{a.log}: every velocity accepted, standing at the end")
        return
    frames, poses = plan(db, a.steps, a.length, a.width, a.seconds, a.session, a.first_step,
                         a.last_seq)
    if a.mode == "plan":
        if not a.out:
            p.error("plan needs --out")
        write_log(a.out, frames)
        print(f"{len(frames)} frames ({len(poses)} footsteps) written to {a.out}")
    elif a.mode == "check":
        problems = check(db, a.log, poses)
        for line in problems:
            print(line)
        if problems:
            sys.exit(1)
        print(f"{a.log}: every command accepted, standing with the feet on the last steps")


if __name__ == "__main__":
    main()
