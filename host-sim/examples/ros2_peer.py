#!/usr/bin/env python3
"""A ROS 2 peer of `host-sim ros2`, written with PyPI's cyclonedds alone (no ROS installation).

It speaks IHMC's footstep interface under ROS 2's naming: DDS topics `rt/<ROS name>`, types
`<pkg>::msg::dds_::<Name>_`, classic CDR. The types below are declared from the .msg files in
host-sim/interfaces (not from the gateway's code).

    python3 -m pip install cyclonedds==11.0.1
    cargo run --release -p host-sim -- ros2 &             # the gateway and the node
    python3 host-sim/examples/ros2_peer.py walk           # four steps forward, statuses printed

`check` is the test the project runs (host-sim/tests/ros2.rs): a walk with a change before
lift-off and one after it, malformed lists, another type and a broken layout on the footstep
topic, an abort; it exits 1 on the first expectation that fails. `types` compares the
declarations below with the .msg files. `stick` steers by ROS's `cmd_vel` (a
`geometry_msgs/Twist` at 20 Hz for 5 s, then let go) and walks to a relative goal
(`geometry_msgs/Pose2D` on `input/goal_relative`): the node chooses the footsteps.
"""

import argparse
import math
import os
import re
import sys
import time
from dataclasses import dataclass, field, fields

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl import types as t
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

# --- the message types (host-sim/interfaces/*/msg/*.msg, ROS 2's geometry_msgs and std_msgs) ---


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@dataclass
class Point32(IdlStruct, typename="geometry_msgs::msg::dds_::Point32_"):
    x: t.float32 = 0.0
    y: t.float32 = 0.0
    z: t.float32 = 0.0


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3
    angular: Vector3


@dataclass
class Pose2D(IdlStruct, typename="geometry_msgs::msg::dds_::Pose2D_"):
    x: t.float64
    y: t.float64
    theta: t.float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0
    w: t.float64 = 1.0


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32 = 0
    nanosec: t.uint32 = 0


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class PointStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PointStamped_"):
    header: Header = field(default_factory=Header)
    point: Point = field(default_factory=Point)


@dataclass
class Polygon(IdlStruct, typename="geometry_msgs::msg::dds_::Polygon_"):
    points: t.sequence[Point32] = field(default_factory=list)


@dataclass
class PolygonStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PolygonStamped_"):
    header: Header = field(default_factory=Header)
    polygon: Polygon = field(default_factory=Polygon)


@dataclass
class SE3TrajectoryPointMessage(
    IdlStruct, typename="ihmc_common_msgs::msg::dds_::SE3TrajectoryPointMessage_"
):
    sequence_id: t.uint32 = 0
    time: t.float64 = 0.0
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)
    linear_velocity: Vector3 = field(default_factory=Vector3)
    angular_velocity: Vector3 = field(default_factory=Vector3)


@dataclass
class QueueableMessage(IdlStruct, typename="ihmc_common_msgs::msg::dds_::QueueableMessage_"):
    sequence_id: t.uint32 = 0
    execution_mode: t.uint8 = 0
    message_id: t.int64 = -1
    previous_message_id: t.int64 = 0
    execution_delay_time: t.float64 = 0.0
    stream_integration_duration: t.float64 = 0.0
    timestamp: t.int64 = 0


@dataclass
class StepConstraintsListMessage(
    IdlStruct, typename="controller_msgs::msg::dds_::StepConstraintsListMessage_"
):
    sequence_id: t.uint32 = 0
    region_origin: t.sequence[Point, 20] = field(default_factory=list)
    region_orientation: t.sequence[Quaternion, 20] = field(default_factory=list)
    region_normal: t.sequence[Vector3, 20] = field(default_factory=list)
    concave_hulls_size: t.sequence[t.int32, 100] = field(default_factory=list)
    number_of_holes_in_region: t.sequence[t.int32, 100] = field(default_factory=list)
    hole_polygons_size: t.sequence[t.int32, 100] = field(default_factory=list)
    vertex_buffer: t.sequence[Point, 50000] = field(default_factory=list)


@dataclass
class FootstepDataMessage(IdlStruct, typename="controller_msgs::msg::dds_::FootstepDataMessage_"):
    sequence_id: t.uint32 = 0
    robot_side: t.uint8 = 255
    location: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)
    predicted_contact_points_2d: t.sequence[Point, 10] = field(default_factory=list)
    trajectory_type: t.uint8 = 0
    swing_height: t.float64 = -1.0
    custom_waypoint_proportions: t.sequence[t.float64, 2] = field(default_factory=list)
    custom_position_waypoints: t.sequence[Point, 12] = field(default_factory=list)
    swing_trajectory: t.sequence[SE3TrajectoryPointMessage, 12] = field(default_factory=list)
    swing_trajectory_blend_duration: t.float64 = 0.0
    swing_duration: t.float64 = -1.0
    transfer_duration: t.float64 = -1.0
    execution_delay_time: t.float64 = 0.0
    touchdown_duration: t.float64 = -1.0
    liftoff_duration: t.float64 = -1.0
    step_constraints: StepConstraintsListMessage = field(default_factory=StepConstraintsListMessage)
    should_check_for_reachability: bool = False


@dataclass
class FootstepDataListMessage(
    IdlStruct, typename="controller_msgs::msg::dds_::FootstepDataListMessage_"
):
    sequence_id: t.uint32 = 0
    footstep_data_list: t.sequence[FootstepDataMessage, 50] = field(default_factory=list)
    execution_timing: t.uint8 = 0
    default_swing_duration: t.float64 = -1.0
    default_transfer_duration: t.float64 = -1.0
    final_transfer_duration: t.float64 = -1.0
    trust_height_of_footsteps: bool = True
    are_footsteps_adjustable: bool = False
    offset_footsteps_with_execution_error: bool = False
    offset_footsteps_height_with_execution_error: bool = False
    queueing_properties: QueueableMessage = field(default_factory=QueueableMessage)
    default_step_constraints: StepConstraintsListMessage = field(
        default_factory=StepConstraintsListMessage
    )
    should_check_for_reachability: bool = False


@dataclass
class FootstepStatusMessage(
    IdlStruct, typename="controller_msgs::msg::dds_::FootstepStatusMessage_"
):
    sequence_id: t.uint32 = 0
    footstep_status: t.uint8 = 255
    footstep_index: t.int32 = 0
    robot_side: t.uint8 = 255
    desired_foot_position_in_world: Point = field(default_factory=Point)
    desired_foot_orientation_in_world: Quaternion = field(default_factory=Quaternion)
    actual_foot_position_in_world: Point = field(default_factory=Point)
    actual_foot_orientation_in_world: Quaternion = field(default_factory=Quaternion)
    swing_duration: t.float64 = 0.0


@dataclass
class WalkingStatusMessage(IdlStruct, typename="controller_msgs::msg::dds_::WalkingStatusMessage_"):
    sequence_id: t.uint32 = 0
    walking_status: t.uint8 = 255


@dataclass
class PauseWalkingMessage(IdlStruct, typename="controller_msgs::msg::dds_::PauseWalkingMessage_"):
    sequence_id: t.uint32 = 0
    pause: bool = False
    clear_remaining_footstep_queue: bool = False


@dataclass
class AbortWalkingMessage(IdlStruct, typename="controller_msgs::msg::dds_::AbortWalkingMessage_"):
    sequence_id: t.uint32 = 0


@dataclass
class CommandRefusal(IdlStruct, typename="walking_node_msgs::msg::dds_::CommandRefusal_"):
    footstep_list_sequence_id: t.uint32 = 0
    footstep_sequence_id: t.uint32 = 0
    footstep_index: t.int32 = 0
    command: str = ""
    reason_code: t.uint8 = 0
    reason: str = ""
    detail: str = ""


STARTED, COMPLETED = 0, 1
WALK_STARTED, WALK_COMPLETED, WALK_ABORT_REQUESTED = 0, 1, 2
LEFT, RIGHT = 0, 1
OVERRIDE, QUEUE = 0, 1

# --- the connection -------------------------------------------------------------------------

RELIABLE = Policy.Reliability.Reliable(duration(seconds=1))
CDR = Policy.DataRepresentation(use_cdrv0_representation=True)


def qos(durability, depth):
    return Qos(RELIABLE, durability, Policy.History.KeepLast(depth), CDR)


class Peer:
    """The gateway's topics under `ns` (IHMC's naming: /ihmc/<robot>/humanoid_control)."""

    def __init__(self, ns, domain=None):
        if domain is None:
            domain = int(os.environ.get("ROS_DOMAIN_ID", "0"))
        self.dp = DomainParticipant(domain)
        vol, tl = Policy.Durability.Volatile, Policy.Durability.TransientLocal

        def writer(name, typ):
            return DataWriter(self.dp, Topic(self.dp, f"rt{ns}/input/{name}", typ), qos(vol, 16))

        def reader(name, typ, durability, depth):
            topic = Topic(self.dp, f"rt{ns}/output/{name}", typ)
            return DataReader(self.dp, topic, qos(durability, depth))

        self.ns = ns
        self.lists = writer("footstep_data_list", FootstepDataListMessage)
        self.pause = writer("pause_walking", PauseWalkingMessage)
        self.abort = writer("abort_walking", AbortWalkingMessage)
        self.cmd_vel = writer("cmd_vel", Twist)
        self.goal = writer("goal_relative", Pose2D)
        self.footstep_status = reader("footstep_status", FootstepStatusMessage, tl, 64)
        self.walking_status = reader("walking_status", WalkingStatusMessage, tl, 1)
        self.refusals = reader("command_refusal", CommandRefusal, tl, 64)
        self.cog = reader("reference/cog", PointStamped, vol, 1)
        self.zmp = reader("reference/zmp", PointStamped, vol, 1)
        self.support = reader("reference/support_polygon", PolygonStamped, vol, 1)
        self.statuses, self.walks, self.refused = [], [], []
        self.last_cog = self.last_zmp = self.last_support = None

    def wait_for_gateway(self, timeout=30.0):
        """Until the gateway's footstep subscription is matched."""
        end = time.time() + timeout
        while time.time() < end:
            if self.lists.get_matched_subscriptions() and self.walking_status.get_matched_publications():
                return
            time.sleep(0.05)
        raise SystemExit(f"no gateway on {self.ns} after {timeout} s")

    def spin(self, seconds=0.0):
        """Reads every output for `seconds` (a writer's goodbye, an InvalidSample, is skipped)."""
        end = time.time() + seconds

        def valid(reader, typ):
            return [s for s in reader.take(N=100) if isinstance(s, typ)]

        while True:
            self.statuses += valid(self.footstep_status, FootstepStatusMessage)
            self.walks += valid(self.walking_status, WalkingStatusMessage)
            self.refused += valid(self.refusals, CommandRefusal)
            for s in valid(self.cog, PointStamped):
                self.last_cog = s
            for s in valid(self.zmp, PointStamped):
                self.last_zmp = s
            for s in valid(self.support, PolygonStamped):
                self.last_support = s
            if time.time() >= end:
                return
            time.sleep(0.01)

    def until(self, cond, timeout, what):
        end = time.time() + timeout
        while time.time() < end:
            self.spin(0.02)
            if cond():
                return
        raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def step(seq, side, x, y, yaw=0.0):
    q = Quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    return FootstepDataMessage(sequence_id=seq, robot_side=side, location=Point(x, y, 0.0), orientation=q)


def footsteps(list_id, first_id, n, x0, mode=OVERRIDE, length=0.15):
    """n steps forward from feet at x0, right foot first, the last one closing the stance."""
    steps = []
    for k in range(n):
        side = RIGHT if k % 2 == 0 else LEFT
        x = x0 + length * (k if k + 1 == n else k + 1)
        steps.append(step(first_id + k, side, x, -0.1 if side == RIGHT else 0.1))
    return FootstepDataListMessage(
        sequence_id=list_id, footstep_data_list=steps, queueing_properties=QueueableMessage(execution_mode=mode)
    )


# --- the declarations against the .msg files -------------------------------------------------

PRIMITIVE = {
    "byte": t.uint8, "uint8": t.uint8, "uint32": t.uint32, "int32": t.int32, "int64": t.int64,
    "float64": t.float64, "float32": t.float32, "bool": bool, "string": str,
}


def check_types(interfaces):
    """Every .msg file's fields, in order, against the dataclass of the same name."""
    classes = {c.__name__: c for c in IdlStruct.__subclasses__()}
    checked = 0
    for pkg in sorted(os.listdir(interfaces)):
        d = os.path.join(interfaces, pkg, "msg")
        if not os.path.isdir(d):
            continue
        for f in sorted(os.listdir(d)):
            name = f[:-4]
            cls = classes[name]
            declared = [(x.name, x.type) for x in fields(cls)]
            msg = []
            for line in open(os.path.join(d, f)):
                line = line.split("#")[0].strip()
                if not line or re.match(r"^\S+\s+[A-Z][A-Z0-9_]*\s*=", line):
                    continue  # a constant
                typ, fname = line.split()[:2]
                msg.append((fname, typ))
            assert [n for n, _ in declared] == [n for n, _ in msg], f"{name}: field names differ"
            for (fname, pytype), (_, typ) in zip(declared, msg):
                m = re.fullmatch(r"([\w/]+)(\[(<=)?(\d*)\])?", typ)
                base, seq, bound = m.group(1), m.group(2), m.group(4)
                base = base.split("/")[-1]
                elem = PRIMITIVE.get(base) or classes[base if base != "SE3TrajectoryPointMessage" else base]
                expect = (t.sequence[elem, int(bound)] if bound else t.sequence[elem]) if seq else elem
                assert pytype == expect, f"{name}.{fname}: {pytype} against {typ}"
            checked += 1
    return checked


# --- the walk of the book and the test ------------------------------------------------------


def walk(peer):
    peer.wait_for_gateway()
    peer.spin(0.3)
    x0 = peer.last_cog.point.x if peer.last_cog else 0.0
    peer.lists.write(footsteps(1, 1, 4, round(x0, 3)))
    peer.until(lambda: any(w.walking_status == WALK_COMPLETED for w in peer.walks), 30, "the walk")
    for s in peer.statuses:
        kind = "lifted off" if s.footstep_status == STARTED else "landed at"
        p = s.actual_foot_position_in_world
        print(f"step {s.sequence_id}: {kind} ({p.x:.4f}, {p.y:.4f})")
    for r in peer.refused:
        print(f"refused: {r.command} {r.footstep_sequence_id}: {r.reason} {r.detail}")


def stick(peer):
    """A teleoperation stick on cmd_vel: 0.15 m/s forward at 20 Hz for 5 s, then let go (the
    gateway sends zero after 0.5 s and the robot stands); then a relative goal 0.4 m ahead.
    Checks that the COG went forward at about that speed, stopped, and reached the goal."""
    peer.wait_for_gateway()
    peer.spin(0.3)
    x0 = peer.last_cog.point.x if peer.last_cog else 0.0
    end = time.time() + 5.0
    while time.time() < end:
        peer.cmd_vel.write(Twist(Vector3(0.15, 0.0, 0.0), Vector3(0.0, 0.0, 0.0)))
        peer.spin(0.05)
    peer.spin(6.0)
    x1 = peer.last_cog.point.x
    assert 0.3 < x1 - x0 < 1.2, f"the stick walked {x1 - x0:.3f} m"
    peer.spin(0.5)
    assert abs(peer.last_cog.point.x - x1) < 0.005, "still moving after the stick was let go"
    peer.goal.write(Pose2D(0.4, 0.0, 0.0))
    peer.until(lambda: peer.last_cog.point.x > x1 + 0.3, 20, "the goal walk")
    peer.spin(4.0)
    x2 = peer.last_cog.point.x
    assert abs(x2 - (x1 + 0.4)) < 0.05, f"the goal walk ended at {x2 - x1:.3f} m, not 0.4"
    refused = [r for r in peer.refused if r.command in ("cmd_vel", "goal")]
    assert not refused, f"refused: {[(r.command, r.reason) for r in refused]}"
    print(f"stick: {x1 - x0:.3f} m, goal: {x2 - x1:.3f} m")
    print("ok")


def bench(peer, lists=40):
    """A 16-step walk; while it walks, `lists` OVERRIDE lists 0.1 s apart, each moving the last
    step by 1 mm (each becomes one STEP_MODIFY): the gateway measures each list's way to the bus
    (`host-sim ros2 --out DIR` writes gateway.json and prints the figures at its exit)."""
    peer.wait_for_gateway()
    peer.spin(0.3)
    x0 = round(peer.last_cog.point.x, 3) if peer.last_cog else 0.0
    plan = footsteps(1, 1, 16, x0, length=0.1)
    peer.lists.write(plan)
    peer.until(lambda: any(s.footstep_status == STARTED for s in peer.statuses), 10, "the first lift-off")
    for k in range(lists):
        plan.sequence_id = 2 + k
        plan.footstep_data_list[-1].location.x += 0.001 if k % 2 == 0 else -0.001
        peer.lists.write(plan)
        peer.spin(0.1)
    peer.until(lambda: any(w.walking_status == WALK_COMPLETED for w in peer.walks), 30, "the walk's end")
    print(f"{lists + 1} lists sent; {len(peer.refused)} refused")


def near(a, b, tol=2e-4):
    return abs(a.x - b.x) <= tol and abs(a.y - b.y) <= tol


def check(peer):
    peer.wait_for_gateway()
    peer.spin(0.5)
    assert peer.last_cog is not None and peer.last_cog.header.frame_id == "world", "no reference"
    assert peer.last_support is not None and len(peer.last_support.polygon.points) >= 4
    # 1. A walk; step 104 moved 5 cm before its lift-off, step 101 after its lift-off.
    sent = footsteps(1, 101, 6, 0.0)
    peer.lists.write(sent)
    peer.until(lambda: any(s.sequence_id == 101 and s.footstep_status == STARTED for s in peer.statuses), 10,
               "step 101 lifting off")
    changed = footsteps(2, 101, 6, 0.0)
    changed.footstep_data_list[3].location.x += 0.05
    changed.footstep_data_list[0].location.x += 0.05
    peer.lists.write(changed)
    peer.until(lambda: any(w.walking_status == WALK_COMPLETED for w in peer.walks), 30, "the walk's end")
    done = {s.sequence_id: s for s in peer.statuses if s.footstep_status == COMPLETED}
    assert sorted(done) == [101, 102, 103, 104, 105, 106], f"completed {sorted(done)}"
    started = [s.sequence_id for s in peer.statuses if s.footstep_status == STARTED]
    assert started == [101, 102, 103, 104, 105, 106], f"started {started}"
    for k, sid in enumerate(range(101, 107)):
        want = (sent if sid == 101 else changed).footstep_data_list[k].location
        got = done[sid]
        assert near(got.desired_foot_position_in_world, want), f"step {sid} desired {got}"
        assert near(got.actual_foot_position_in_world, want), f"step {sid} landed {got}, sent {want}"
        assert 0.5 < got.swing_duration < 1.2, f"step {sid} swing {got.swing_duration}"
    late = [r for r in peer.refused if r.footstep_sequence_id == 101]
    assert late and late[0].reason == "lifted_off" and late[0].footstep_list_sequence_id == 2, \
        f"late change: {late}"
    walks = [w.walking_status for w in peer.walks]
    assert walks == [WALK_STARTED, WALK_COMPLETED], f"walking status {walks}"
    print("walk: 6 steps landed where sent, the change before lift-off walked, the late one refused")
    # 2. Malformed lists: each refused with its reason, and nothing walks.
    feet_x = max(s.actual_foot_position_in_world.x for s in done.values())
    bad = {
        "not_finite": footsteps(20, 201, 2, feet_x),
        "unknown_side": footsteps(21, 211, 2, feet_x),
        "not_level": footsteps(22, 221, 2, feet_x),
        "bad_orientation": footsteps(23, 231, 2, feet_x),
        "unknown_mode": footsteps(25, 251, 2, feet_x, mode=9),
        "queue_full": footsteps(26, 261, 20, feet_x, length=0.02),
    }
    bad["not_finite"].footstep_data_list[1].location.y = float("nan")
    bad["unknown_side"].footstep_data_list[0].robot_side = 7
    bad["not_level"].footstep_data_list[0].orientation = Quaternion(math.sin(0.1), 0.0, 0.0, math.cos(0.1))
    bad["bad_orientation"].footstep_data_list[0].orientation = Quaternion(0.0, 0.0, 0.0, 0.0)
    # 51 footsteps: IHMC's type bounds the list at 50, so a writer of the same type name with
    # an unbounded list sends them (the bound is not on the wire).
    @dataclass
    class UnboundedList(IdlStruct, typename="controller_msgs::msg::dds_::FootstepDataListMessage_"):
        sequence_id: t.uint32 = 0
        footstep_data_list: t.sequence[FootstepDataMessage] = field(default_factory=list)
        execution_timing: t.uint8 = 0
        default_swing_duration: t.float64 = -1.0
        default_transfer_duration: t.float64 = -1.0
        final_transfer_duration: t.float64 = -1.0
        trust_height_of_footsteps: bool = True
        are_footsteps_adjustable: bool = False
        offset_footsteps_with_execution_error: bool = False
        offset_footsteps_height_with_execution_error: bool = False
        queueing_properties: QueueableMessage = field(default_factory=QueueableMessage)
        default_step_constraints: StepConstraintsListMessage = field(default_factory=StepConstraintsListMessage)
        should_check_for_reachability: bool = False

    long = footsteps(24, 241, 51, feet_x, length=0.0)
    unbounded = DataWriter(peer.dp, Topic(peer.dp, f"rt{peer.ns}/input/footstep_data_list", UnboundedList),
                           qos(Policy.Durability.Volatile, 16))
    n_status = len(peer.statuses)
    n_walks = len(peer.walks)
    for m in bad.values():
        peer.lists.write(m)
    peer.spin(0.5)
    unbounded.write(UnboundedList(sequence_id=24, footstep_data_list=long.footstep_data_list))
    lists = set(range(20, 27))
    peer.until(lambda: {r.footstep_list_sequence_id for r in peer.refused} >= lists, 5,
               "the refusals of the malformed lists")
    expect = dict(bad, too_many_steps=long)
    for reason, m in expect.items():
        got = [r.reason for r in peer.refused if r.footstep_list_sequence_id == m.sequence_id]
        if reason == "queue_full":
            # The node takes 16 steps: the 17th is refused, the rest of the list is not sent,
            # and the 16 it took are dropped again: nothing of the list walks.
            assert got.count("queue_full") == 1 and "after_refused_step" in got \
                and got.count("list_not_walked") == 16, f"list 26: {got}"
        else:
            assert got == [reason], f"list {m.sequence_id}: {got}, expected {reason}"
    peer.spin(1.5)
    assert len(peer.statuses) == n_status and len(peer.walks) == n_walks, "a refused list moved the robot"
    print("malformed lists and one longer than the node's queue: refused with their reasons, nothing walked")
    # 3. Another type on the footstep topic, and a broken layout under the right type name.
    other = DataWriter(peer.dp, Topic(peer.dp, f"rt{peer.ns}/input/footstep_data_list", Point), qos(
        Policy.Durability.Volatile, 1))
    other.write(Point(1.0, 2.0, 3.0))

    @dataclass
    class Truncated(IdlStruct, typename="controller_msgs::msg::dds_::FootstepDataListMessage_"):
        sequence_id: t.uint32 = 0

    broken = DataWriter(peer.dp, Topic(peer.dp, f"rt{peer.ns}/input/footstep_data_list", Truncated), qos(
        Policy.Durability.Volatile, 1))
    peer.spin(0.5)
    broken.write(Truncated(sequence_id=30))
    peer.until(lambda: {"wrong_type", "malformed"} <= {r.reason for r in peer.refused}, 5,
               "the wrong type and the malformed message reported")
    print("another type and a broken layout: reported, the gateway runs on")
    # 4. A second walk, aborted after two lift-offs: the robot stops after the swing.
    peer.spin(0.5)
    x0 = max(s.actual_foot_position_in_world.x for s in done.values())
    x0 = min(s.actual_foot_position_in_world.x for s in done.values() if s.sequence_id in (105, 106))
    peer.lists.write(footsteps(40, 401, 10, x0))
    peer.until(lambda: sum(1 for s in peer.statuses if s.footstep_status == STARTED and s.sequence_id > 400) == 2,
               10, "two lift-offs of the second walk")
    peer.abort.write(AbortWalkingMessage(sequence_id=41))
    peer.until(lambda: any(w.walking_status == WALK_ABORT_REQUESTED and w.sequence_id == 41 for w in peer.walks), 3,
               "the abort")
    peer.spin(3.0)
    second = [s.sequence_id for s in peer.statuses if s.footstep_status == STARTED and s.sequence_id > 400]
    assert len(second) <= 3, f"steps started after the abort: {second}"
    a = peer.last_cog.point
    peer.spin(0.5)
    b = peer.last_cog.point
    assert near(a, b, 1e-6), f"the COG still moves after the abort: {a} -> {b}"
    print(f"abort: the walk stopped after {len(second)} lift-offs; the COG rests")
    print("ok")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["walk", "check", "types", "vanish", "bench", "stick"])
    ap.add_argument("--namespace", default="/ihmc/hrp2/humanoid_control")
    ap.add_argument("--domain", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", "0")))
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--interfaces", default=os.path.join(here, "..", "interfaces"))
    a = ap.parse_args()
    if a.mode == "types":
        print(f"{check_types(a.interfaces)} message types agree with the .msg files")
        return
    peer = Peer(a.namespace, a.domain)
    if a.mode == "walk":
        walk(peer)
    elif a.mode == "bench":
        bench(peer)
    elif a.mode == "stick":
        try:
            stick(peer)
        except AssertionError as e:
            print(f"FAILED: {e}")
            sys.exit(1)
    elif a.mode == "vanish":
        # Starts a long walk and exits at the first lift-off without a word (the test kills it).
        peer.wait_for_gateway()
        peer.lists.write(footsteps(90, 901, 12, 0.0))
        peer.until(lambda: any(s.footstep_status == STARTED for s in peer.statuses), 10, "a lift-off")
        print("lifted off", flush=True)
        time.sleep(60)
    else:
        try:
            check(peer)
        except AssertionError as e:
            print(f"FAILED: {e}")
            sys.exit(1)


if __name__ == "__main__":
    main()
