#!/usr/bin/env python3
"""An example controller for the walking node, written from the DBC alone.

It walks the robot straight ahead: it appends footsteps (right foot first, then alternating,
and a closing step beside the last one), starts the walk, asks for a stop after the queue,
and sends a heartbeat every 100 ms throughout (the node stops a moving robot after 500 ms
without one). Every frame is encoded by cantools from ``host-sim/can/walking.dbc``; the
CRC-8 the commands end with is the one the DBC's comment on CONTROL describes (AUTOSAR:
polynomial 0x2F, initial value and final XOR 0xFF, over the identifier as two little-endian
bytes and the data before the CRC). All CONTROL frames (heartbeats, start, stop) take their
sequence numbers from one counter, so that every heartbeat is new and the start is ahead of
the control commands before it. cantools rounds exact half units to even where the node's
own encoder rounds them away from zero: a coordinate exactly between two 0.5 mm steps may go
out one step apart (0.5 mm), which the node takes as given.

Three ways to run it:

  controller.py live --channel can0 [--interface socketcan]
      the plan sent in real time on a CAN bus through python-can, printing the node's
      answers (needs a CAN interface: not available on the test machine, so not tested here);
  controller.py plan --out ctl.log
      the plan written as a candump -l log (times from host-sim's epoch), for
      ``host-sim replay ctl.log`` (host-sim/tests/controller.rs does this);
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

import can
import cantools

HERE = os.path.dirname(os.path.abspath(__file__))
DBC = os.path.join(HERE, "..", "can", "walking.dbc")
# host-sim's log epoch: 2026-01-01T00:00:00Z.
EPOCH_S = 1767225600
HEARTBEAT_S = 0.1


def crc8(frame_id, data):
    """CRC-8/AUTOSAR over the identifier (2 bytes, little-endian) and `data`."""
    crc = 0xFF
    for byte in bytes([frame_id & 0xFF, frame_id >> 8]) + bytes(data):
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x2F) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def encode(db, name, signals):
    """The frame `name` with `signals`, its CRC (if it has one) computed and set."""
    msg = db.get_message_by_name(name)
    if any(s.name == "crc" for s in msg.signals):
        data = msg.encode(dict(signals, crc=0))
        signals = dict(signals, crc=crc8(msg.frame_id, data[:-1]))
    return can.Message(
        arbitration_id=msg.frame_id, data=msg.encode(signals), is_extended_id=False
    )


def plan(db, steps, length, width, seconds):
    """The controller's frames as (time [s], message), in time order."""
    half = width / 2.0
    out = []
    seq = 0

    def control(t, op):
        nonlocal seq
        seq = (seq + 1) % 256
        out.append((t, encode(db, "CONTROL", {"seq": seq, "op": op})))

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
                "step_id": i, "left": int(left), "reserved": 0, "x": x, "y": y, "yaw": 0.0,
            }))
        )
    # 100 ms: start, then stop once the queue is walked.
    control(0.1, "start")
    control(0.1, "stop")
    k = 0
    while k * HEARTBEAT_S <= seconds:
        control(k * HEARTBEAT_S, "heartbeat")
        k += 1
    out.sort(key=lambda e: e[0])
    return out, poses


def write_log(path, frames):
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


def live(db, frames, channel, interface):
    bus = can.Bus(channel=channel, interface=interface)
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
    p.add_argument("mode", choices=["plan", "check", "live"])
    p.add_argument("log", nargs="?", help="check: the bus log to check")
    p.add_argument("--out", help="plan: the log to write")
    p.add_argument("--channel", default="can0")
    p.add_argument("--interface", default="socketcan")
    p.add_argument("--steps", type=int, default=6)
    p.add_argument("--length", type=float, default=0.2)
    p.add_argument("--width", type=float, default=0.2)
    p.add_argument("--seconds", type=float, default=9.0)
    a = p.parse_args()
    if a.steps < 1:
        p.error("--steps must be at least 1")
    db = cantools.database.load_file(DBC, strict=True)
    frames, poses = plan(db, a.steps, a.length, a.width, a.seconds)
    if a.mode == "plan":
        if not a.out:
            p.error("plan needs --out")
        write_log(a.out, frames)
        print(f"{len(frames)} frames ({len(poses)} footsteps) written to {a.out}")
    elif a.mode == "check":
        if not a.log:
            p.error("check needs the log")
        problems = check(db, a.log, poses)
        for line in problems:
            print(line)
        if problems:
            sys.exit(1)
        print(f"{a.log}: every command accepted, standing with the feet on the last steps")
    else:
        live(db, frames, a.channel, a.interface)


if __name__ == "__main__":
    main()
