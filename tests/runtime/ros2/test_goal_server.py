"""Goals from any ROS 2 client, over real DDS: ``sim-robot`` in its own process, the runtime with
``Ros2Driver`` and trees/autonomy.xml in this one (it serves ``autonomy/navigate_to_pose`` and
``autonomy/goal_pose``), and a NavigateToPose client written here against the action's DDS
topics (rmw_cyclonedds's request/reply wire, rcl_action's topic names), not the runtime's client.

One robot process for the whole story (it keeps the test short): a goal with feedback ends
SUCCEEDED; a cancelled goal ends CANCELED and the robot stops; a goal preempted by a second one
ends ABORTED while the second succeeds; a PoseStamped on the goal topic starts a goal.
"""

import asyncio
import itertools
import os

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.app import AutonomyRuntime  # noqa: E402
from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, dds, idl  # noqa: E402
from tests.helpers import SimRobotProcess, dds_domain, wait_until  # noqa: E402
from tests.paths import ROOT  # noqa: E402

S = idl.GoalStatus
NAV = idl.NavigateToPose
ACTION = "rq/autonomy/navigate_to_pose/_action/"


@pytest.fixture(autouse=True)
def loopback(monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())


class RawNavigateClient:
    """NavigateToPose spoken on the wire: the three services' rq/rr topics (16-byte request
    header: our request writer's handle, a sequence number) and the feedback/status topics."""

    def __init__(self, node: dds.DdsNode, base: str = "autonomy/navigate_to_pose"):
        self.node = node
        self.replies: dict[tuple[str, int], asyncio.Future] = {}
        self.feedback: dict[bytes, list] = {}
        self.statuses: dict[bytes, int] = {}
        self.seq = itertools.count(1)
        self.services = {}
        for service, req, rep in (("send_goal", NAV.SendGoal_Request, NAV.SendGoal_Response),
                                  ("get_result", NAV.GetResult_Request, NAV.GetResult_Response),
                                  ("cancel_goal", idl.CancelGoal_Request, idl.CancelGoal_Response)):
            topic = f"/{base}/_action/{service}"
            user = f"clientid={node.unique_id()};"
            writer = node.writer(f"rq{topic}Request", idl.service_wire(req), dds.SERVICES, user_data=user)
            reader = node.reader(f"rr{topic}Reply", idl.service_wire(rep), dds.SERVICES,
                                 lambda s, _n, name=service: self._on_reply(name, s), user_data=user)
            guid = writer.get_instance_handle() & 0xFFFF_FFFF_FFFF_FFFF
            self.services[service] = (writer, reader, guid)
        node.reader(f"rt/{base}/_action/feedback", NAV.FeedbackMessage, dds.DEFAULT, self._on_feedback)
        node.reader(f"rt/{base}/_action/status", idl.GoalStatusArray, dds.ACTION_STATUS, self._on_status)

    def _on_reply(self, service: str, samples: list) -> None:
        guid = self.services[service][2]
        for sample in samples:
            fut = self.replies.pop((service, sample.seq), None)
            if sample.guid == guid and fut is not None and not fut.done():
                fut.set_result(sample)

    def _on_feedback(self, samples: list, _now: float) -> None:
        for sample in samples:
            self.feedback.setdefault(bytes(sample.goal_id.uuid), []).append(sample.feedback)

    def _on_status(self, samples: list, _now: float) -> None:
        for sample in samples:
            for st in sample.status_list:
                self.statuses[bytes(st.goal_info.goal_id.uuid)] = st.status

    def ready(self) -> bool:
        return all(w.get_matched_subscriptions() and r.matched_writers() for w, r, _ in self.services.values())

    async def call(self, service: str, body, timeout: float):
        writer, _, guid = self.services[service]
        seq = next(self.seq)
        fut = self.node.loop.create_future()
        self.replies[(service, seq)] = fut
        writer.write(idl.wrap(guid, seq, body))
        return await asyncio.wait_for(fut, timeout)

    async def send_goal(self, x: float, y: float) -> bytes:
        goal_id = os.urandom(16)
        goal = NAV.Goal(pose=idl.PoseStamped(header=idl.Header(frame_id="map"),
                                             pose=idl.Pose(position=idl.Point(x, y, 0.0))))
        reply = await self.call("send_goal", NAV.SendGoal_Request(goal_id=idl.UUID(uuid=goal_id), goal=goal), 5)
        assert reply.accepted
        return goal_id

    def result(self, goal_id: bytes) -> asyncio.Task:
        return asyncio.ensure_future(self.call("get_result", NAV.GetResult_Request(goal_id=idl.UUID(uuid=goal_id)),
                                               60))

    async def cancel(self, goal_id: bytes):
        info = idl.GoalInfo(goal_id=idl.UUID(uuid=goal_id))
        return await self.call("cancel_goal", idl.CancelGoal_Request(goal_info=info), 5)


def speed(driver) -> float:
    odom = driver.latest.get("odom")
    return abs(odom.twist.linear) if odom is not None else 0.0


async def test_navigate_to_pose_from_a_plain_dds_client():
    import nodes

    domain = dds_domain()
    robot = SimRobotProcess(domain, "--robot", "burger", duration=90)
    client_node = None
    try:
        await robot.ready()
        driver = Ros2Driver(Ros2Config(domain_id=domain))
        runtime = AutonomyRuntime(driver, realtime=True, register=[nodes.register_all])
        runtime.load_tree(ROOT / "trees" / "autonomy.xml")
        await runtime.start()
        try:
            client_node = dds.DdsNode(domain)
            client = RawNavigateClient(client_node)
            names = [c.name for c in driver.components()]
            await wait_until(lambda: runtime.supervisor.all_healthy(names) and client.ready(), 25,
                             "components healthy and the action server matched")

            # 1. a goal 1 m ahead: feedback on the way, SUCCEEDED
            first = await client.send_goal(-1.0, -2.0)
            done = await client.result(first)
            fb = client.feedback.get(first, [])
            assert done.status == S.STATUS_SUCCEEDED, (done.status, done.result)
            assert done.result.error_code == 0
            assert len(fb) >= 3
            assert fb[0].distance_remaining > fb[-1].distance_remaining + 0.4
            assert fb[-1].current_pose.pose.position.x > -1.6 and fb[-1].current_pose.header.frame_id == "map"
            assert fb[-1].navigation_time.to_sec() > fb[0].navigation_time.to_sec()
            assert fb[-1].number_of_recoveries == 0
            assert client.statuses[first] == S.STATUS_SUCCEEDED

            # 2. cancel a long goal while driving: CANCELED, the robot stops
            second = await client.send_goal(3.5, -2.5)
            pending = client.result(second)
            await wait_until(lambda: speed(driver) > 0.1, 15, "the robot to drive")
            reply = await client.cancel(second)
            assert reply.return_code == idl.CancelGoal_Response.ERROR_NONE
            assert [bytes(g.goal_id.uuid) for g in reply.goals_canceling] == [second]
            done = await asyncio.wait_for(pending, 10)
            assert done.status == S.STATUS_CANCELED
            await wait_until(lambda: speed(driver) < 0.02, 3, "the robot to stop")

            # 3. preemption: a long goal, then a short one; the first ends, the second succeeds
            third = await client.send_goal(3.5, -2.5)
            pending3 = client.result(third)
            await wait_until(lambda: speed(driver) > 0.1, 15, "the robot to drive")
            fourth = await client.send_goal(-1.5, -2.0)
            pending4 = client.result(fourth)
            done3 = await asyncio.wait_for(pending3, 10)
            assert done3.status == S.STATUS_ABORTED and "preempted" in done3.result.error_msg
            done4 = await asyncio.wait_for(pending4, 40)
            assert done4.status == S.STATUS_SUCCEEDED, done4.result

            # 4. RViz's 2D Goal Pose: a PoseStamped on autonomy/goal_pose starts a goal
            poses = client_node.publisher("autonomy/goal_pose", idl.PoseStamped)
            await wait_until(lambda: driver.goal_server.topic_reader.matched_writers() > 0, 5, "topic matched")
            poses.write(idl.PoseStamped(header=idl.Header(frame_id="map"),
                                        pose=idl.Pose(position=idl.Point(-1.0, -2.0, 0.0))))
            await wait_until(lambda: driver.goal_server.topic_goals, 5, "the topic goal")
            topic_goal = driver.goal_server.topic_goals[-1]
            assert (topic_goal.pose.x, topic_goal.pose.y) == (-1.0, -2.0)
            topic_result = await asyncio.wait_for(topic_goal, 40)
            assert topic_result.succeeded, topic_result
            pose = driver.latest["pose"].pose
            assert abs(pose.x + 1.0) < 0.35 and abs(pose.y + 2.0) < 0.35
        finally:
            await runtime.stop()
    finally:
        if client_node is not None:
            client_node.close()
        robot.stop()
