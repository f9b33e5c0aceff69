"""A lifecycle node whose first get_state reply is lost does not fail the bring-up.

A ROS 2 service drops its reply when it has not yet matched the client's reply reader
(rmw_cyclonedds's rmw_send_response waits 100 ms for it, then gives up), which the client
cannot see from its side: its own endpoints are matched, the request arrives, no reply comes.
The lifecycle polls recover (a new request every period); the bring-up's first contact must
too, by asking again, not by waiting out ``service_timeout`` and failing. A node that is found
but never answers, and one that is not there at all, fail with reasons that tell them apart.
"""

import asyncio
import os

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.bringup import BringupPlan, bring_up  # noqa: E402
from bt_runtime.runtime.ros2 import Ros2Config, Ros2Driver, dds, idl  # noqa: E402
from tests.helpers import dds_domain  # noqa: E402

NS = f"lost_reply_{os.getpid()}"  # names no other test run answers for
ST = idl.State


@pytest.fixture(autouse=True)
def loopback(monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", dds.loopback_config())


class LossyLifecycleNode:
    """get_state/change_state of one managed node; the first ``drop`` get_state requests get no
    reply (as a reply to a client whose reader the server had not matched yet)."""

    def __init__(self, node: dds.DdsNode, name: str, *, drop: int, state: int = ST.PRIMARY_STATE_UNCONFIGURED):
        self.state, self.drop, self.asked = state, drop, 0
        dds.ServiceServer(node, f"{name}/get_state", idl.GetState_Request, idl.GetState_Response, self.get_state)
        dds.ServiceServer(node, f"{name}/change_state", idl.ChangeState_Request, idl.ChangeState_Response,
                          self.change_state)

    def get_state(self, _request):
        self.asked += 1
        if self.asked <= self.drop:
            return None  # no reply
        return idl.GetState_Response(current_state=ST(self.state, ""))

    def change_state(self, request):
        goal = {idl.Transition.TRANSITION_CONFIGURE: (ST.PRIMARY_STATE_UNCONFIGURED, ST.PRIMARY_STATE_INACTIVE),
                idl.Transition.TRANSITION_ACTIVATE: (ST.PRIMARY_STATE_INACTIVE, ST.PRIMARY_STATE_ACTIVE)}
        start, end = goal.get(int(request.transition.id), (None, None))
        ok = self.state == start
        if ok:
            self.state = end
        return idl.ChangeState_Response(success=ok)


def driver_for(domain: int, nodes: list[str], service_timeout: float) -> Ros2Driver:
    return Ros2Driver(Ros2Config(domain_id=domain, namespace=NS, components={},
                                 lifecycle={"bringup": {"node_names": nodes, "service_timeout": service_timeout},
                                            "transition_timeout": 5.0}))


async def test_a_lost_get_state_reply_is_asked_again_and_the_bring_up_goes_on():
    domain = dds_domain()
    loop = asyncio.get_running_loop()
    robot = dds.DdsNode(domain, loop=loop, namespace=NS)
    lossy = LossyLifecycleNode(robot, "controller_server", drop=1)
    driver = driver_for(domain, ["controller_server"], service_timeout=4.0)
    await driver.start()
    try:
        client = driver._node_clients("controller_server")[0]
        assert await client.wait_ready(20), "discovery"
        started = loop.time()
        report = await bring_up(driver, driver.bringup_plan(), loop.time)
        assert report.status == "active", report.reason
        assert report.nodes[0].steps == ["configure", "activate"]
        assert lossy.state == ST.PRIMARY_STATE_ACTIVE
        assert client.resent >= 1 and lossy.asked >= 3  # the lost one, its repeat, the checks after
        assert loop.time() - started < 3.0  # asked again after 0.5 s, not after the 4 s budget
    finally:
        await driver.stop()
        robot.close()


async def test_a_found_node_that_never_answers_and_a_missing_one_fail_with_different_reasons():
    domain = dds_domain()
    loop = asyncio.get_running_loop()
    robot = dds.DdsNode(domain, loop=loop, namespace=NS)
    LossyLifecycleNode(robot, "planner_server", drop=10**6)  # hung: never answers
    driver = driver_for(domain, ["planner_server"], service_timeout=1.5)
    await driver.start()
    try:
        assert await driver._node_clients("planner_server")[0].wait_ready(20), "discovery"
        report = await bring_up(driver, driver.bringup_plan(), loop.time)
        assert report.failed and "planner_server/get_state was found but did not answer within 1.5 s" in report.reason
        missing = await bring_up(driver, BringupPlan(("ghost_server",), {}, 1.0, 1.0), loop.time)
        assert missing.failed and "(ghost_server/get_state) were not found within 1 s" in missing.reason
    finally:
        await driver.stop()
        robot.close()
