"""A recording has one command topic per gate input that drove: teleop and any configured input."""

from __future__ import annotations

import asyncio

from bt_runtime.runtime.config import GateConfig, RuntimeConfig
from bt_runtime.runtime.messages import Twist
from bt_runtime.runtime.recording.recorder import Recorder


class Captured:
    """The part of RecordPipeline the recorder writes to, keeping what it was given."""

    tick_guard = None

    def __init__(self):
        self.messages: list[tuple[str, str, float, object]] = []

    def put(self, kind, topic, stamp, msg):
        self.messages.append((kind, topic, stamp, msg))


async def test_each_input_that_drives_gets_its_own_command_topic(make_runtime):
    inputs = {"teleop": {"topic": "cmd_vel_teleop", "priority": 100, "timeout": 0.5},
              "joystick": {"topic": "joy_vel", "priority": 120, "timeout": 0.5}}
    rt = make_runtime(config=RuntimeConfig(gate=GateConfig(inputs=inputs)))
    pipeline = Captured()
    recorder = Recorder(rt, pipeline)
    recorder.attach()
    await rt.start()
    for name, command in (("teleop", (0.05, 0.1)), ("joystick", (-0.04, 0.0))):
        for _ in range(10):
            rt.driver.publish_command_input(name, *command)
            await asyncio.sleep(0.05)
        await asyncio.sleep(0.6)  # stale again
    await rt.stop()
    recorder.detach()
    per_topic = {topic: msg for kind, topic, _t, msg in pipeline.messages if kind == "command"}
    assert per_topic["/cmd_vel/teleop"] == Twist(0.05, 0.1)
    assert per_topic["/cmd_vel/joystick"] == Twist(-0.04, 0.0)
