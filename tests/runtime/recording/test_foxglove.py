"""``run --foxglove``: a client of the Foxglove WebSocket protocol connects on loopback,
subscribes, and receives /cmd_vel and /behavior_tree_log as ROS 2 CDR."""

from __future__ import annotations

import asyncio
import json
import re
import signal
import struct
import subprocess
import sys
import time

import pytest

from tests.paths import ROOT

pytest.importorskip("foxglove")
websockets = pytest.importorskip("websockets.asyncio.client")

WANTED = {"/cmd_vel": "geometry_msgs/msg/Twist", "/behavior_tree_log": "nav2_msgs/msg/BehaviorTreeLog"}


def _wait_for_url(proc: subprocess.Popen, timeout: float = 120.0) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        found = re.search(r"foxglove: (ws://\S+)", line)
        if found:
            return found.group(1)
    raise AssertionError("no 'foxglove: ws://...' line on stderr")


async def _receive(url: str) -> dict[str, list[bytes]]:
    got: dict[str, list[bytes]] = {}
    subs: dict[int, str] = {}
    channels: dict[str, int] = {}

    async def subscribe(ws, topics) -> None:
        batch = []
        for topic in topics:
            sub_id = len(subs) + 1
            subs[sub_id] = topic
            batch.append({"id": sub_id, "channelId": channels[topic]})
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": batch}))

    # foxglove-sdk speaks the Foxglove WebSocket protocol under its current name, foxglove.sdk.v1
    async with websockets.connect(url, subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"]) as ws:
        assert ws.subprotocol in ("foxglove.sdk.v1", "foxglove.websocket.v1")
        while not all(got.get(t) for t in WANTED):
            frame = await asyncio.wait_for(ws.recv(), 30)
            if isinstance(frame, str):
                msg = json.loads(frame)
                if msg["op"] == "advertise":
                    new = []
                    for ch in msg["channels"]:
                        if ch["topic"] in WANTED:
                            assert ch["encoding"] == "cdr" and ch["schemaEncoding"] == "ros2msg"
                            assert ch["schemaName"] == WANTED[ch["topic"]]
                            channels[ch["topic"]] = ch["id"]
                            new.append(ch["topic"])
                    if new:
                        await subscribe(ws, new)
                elif msg["op"] == "status" and "Unknown channel" in msg.get("message", ""):
                    # the server answers a subscription that arrives right after the
                    # advertisement before it registered the channel: ask again
                    await asyncio.sleep(0.1)
                    await subscribe(ws, [t for t in channels if not got.get(t)])
            elif frame[0] == 0x01:  # message data: opcode, subscription id, log time, payload
                sub_id, _t = struct.unpack_from("<IQ", frame, 1)
                got.setdefault(subs[sub_id], []).append(frame[13:])
    return got


def test_client_receives_cmd_vel_and_tree_log(tmp_path):
    from bt_runtime.runtime.recording.types import typestore

    config = tmp_path / "rec.yaml"
    config.write_text("tree_log: all\n")  # every tick's log, so one arrives soon after subscribing
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_runtime", "run", "trees/autonomy.xml", "--goal", "yard_east", "--realtime",
         "--duration", "60", "--foxglove", "0", "--record-config", str(config), "--no-progress"],
        cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        url = _wait_for_url(proc)
        assert url.startswith("ws://127.0.0.1:")
        got = asyncio.run(asyncio.wait_for(_receive(url), 90))
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
    store = typestore()
    twist = store.deserialize_cdr(got["/cmd_vel"][0], WANTED["/cmd_vel"])
    assert hasattr(twist.linear, "x") and hasattr(twist.angular, "z")
    log = store.deserialize_cdr(got["/behavior_tree_log"][0], WANTED["/behavior_tree_log"])
    assert log.event_log and log.event_log[0].current_status in ("IDLE", "RUNNING", "SUCCESS", "FAILURE")


@pytest.mark.parametrize("virtual", [False, True], ids=["realtime", "virtual"])
def test_every_topic_is_advertised_before_its_first_message(virtual):
    """A live client sees every topic at once (and may subscribe before the first message of each),
    on a real-time loop (writer thread) and on virtual time (writer work on the loop)."""
    from websockets.sync.client import connect

    from bt_runtime.runtime.app import AutonomyRuntime
    from bt_runtime.runtime.clock import run as run_loop
    from bt_runtime.runtime.recording.cli import Recording
    from sim.driver import SimDriver
    from sim.recording import recording_hooks

    async def main() -> tuple[dict, dict]:
        driver = SimDriver("apartment", "burger", seed=1)
        runtime = AutonomyRuntime(driver)
        runtime.load_tree('<root BTCPP_format="4"><BehaviorTree ID="Main"><AlwaysSuccess/></BehaviorTree></root>')
        recording = Recording(foxglove_port=0).start(runtime, recording_hooks(driver))
        expected = recording.recorder.topics()
        advertised: dict[str, str] = {}
        try:  # the runtime is not started: nothing is published, only advertised
            with connect(recording.live.url, subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"]) as ws:
                deadline = time.monotonic() + 30
                while not set(expected) <= set(advertised) and time.monotonic() < deadline:
                    frame = ws.recv(timeout=30)
                    msg = json.loads(frame) if isinstance(frame, str) else {}
                    if msg.get("op") == "advertise":
                        advertised.update({ch["topic"]: ch["schemaName"] for ch in msg["channels"]})
        finally:
            recording.stop()
        return expected, advertised

    expected, advertised = run_loop(main(), virtual=True) if virtual else asyncio.run(main())
    assert {"/scan", "/odom", "/tf", "/cmd_vel", "/cmd_vel/teleop", "/behavior_tree_log", "/sim/ground_truth",
            "/map"} <= set(expected)
    assert advertised == expected


@pytest.mark.parametrize("with_bag", [True, False])
def test_live_view_sends_high_rate_streams_at_the_viewing_rate_and_the_bag_keeps_all(tmp_path, with_bag):
    """50 Hz odometry and commands for 2 robot seconds: the bag gets all 100 (and their /tf), a
    subscribed live client gets 10 Hz (live_rate_hz) and then, once the period has passed with
    nothing newer, the latest message of each (a stream that stops shows its last value);
    nothing is sent to a topic nobody subscribed to."""
    import threading

    from websockets.sync.client import connect

    from bt_runtime.runtime.messages import Imu, Odometry, Pose2D, Twist
    from bt_runtime.runtime.recording.bag import Rosbag2Bag
    from bt_runtime.runtime.recording.channels import ChannelSet
    from bt_runtime.runtime.recording.live import FoxgloveLive
    from bt_runtime.runtime.recording.pipeline import RecordPipeline

    bag = Rosbag2Bag(tmp_path / "bag", ChannelSet()) if with_bag else None  # without: held items converted late
    live = FoxgloveLive(ChannelSet(), port=0)
    pipeline = RecordPipeline(bag=bag, live=live, live_rate_hz=10.0)
    for topic, typename in {"/odom": "nav_msgs/msg/Odometry", "/tf": "tf2_msgs/msg/TFMessage",
                            "/cmd_vel": "geometry_msgs/msg/Twist", "/imu": "sensor_msgs/msg/Imu"}.items():
        pipeline._write_one("advertise", topic, 0.0, typename)
    got: dict[str, int] = {}
    last_ns: dict[str, int] = {}
    done = threading.Event()
    try:
        with connect(live.url, subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"]) as ws:
            subs: dict[int, str] = {}
            deadline = time.monotonic() + 30
            while not {"/odom", "/cmd_vel"} <= set(subs.values()) and time.monotonic() < deadline:
                msg = json.loads(ws.recv(timeout=30))
                if msg.get("op") == "advertise":
                    batch = []
                    for ch in msg["channels"]:
                        if ch["topic"] in ("/odom", "/cmd_vel"):
                            subs[len(subs) + 1] = ch["topic"]
                            batch.append({"id": len(subs), "channelId": ch["id"]})
                    ws.send(json.dumps({"op": "subscribe", "subscriptions": batch}))
            channels = live.channels.channels
            while not (channels["/odom"].has_sinks() and channels["/cmd_vel"].has_sinks()):
                assert time.monotonic() < deadline, "the server never saw the subscriptions"
                time.sleep(0.05)

            def receive() -> None:
                while not done.is_set():
                    try:
                        frame = ws.recv(timeout=0.5)
                    except TimeoutError:
                        continue
                    if isinstance(frame, bytes) and frame[0] == 0x01:
                        sub_id, log_ns = struct.unpack_from("<IQ", frame, 1)
                        topic = subs[sub_id]
                        got[topic] = got.get(topic, 0) + 1
                        last_ns[topic] = log_ns

            reader = threading.Thread(target=receive)
            reader.start()
            for k in range(100):
                t = 0.02 * k
                pipeline.put("odom", "/odom", t, Odometry(t, Pose2D(0.01 * k, 0.0, 0.0), Twist(0.5, 0.0)))
                pipeline.put("command", "/cmd_vel", t, Twist(0.5, 0.0))
            pipeline.drain()
            deadline = time.monotonic() + 20
            while (got.get("/odom", 0) < 20 or got.get("/cmd_vel", 0) < 20) and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(0.3)  # anything more would have arrived by now
            sent = dict(got)
            pipeline.drain()  # the period since the last send has not passed: nothing more yet
            pipeline.put("imu", "/imu", 2.1, Imu(2.1, 0.0, 0.0, 0.0))  # robot time moves on
            pipeline.drain()
            while (got.get("/odom", 0) < 21 or got.get("/cmd_vel", 0) < 21) and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(0.3)
            done.set()
            reader.join()
    finally:
        pipeline.stop()
    assert pipeline.errors == 0
    if with_bag:
        assert bag.message_counts() == {"/odom": 100, "/tf": 100, "/cmd_vel": 100, "/imu": 1}
    assert sent == {"/odom": 20, "/cmd_vel": 20}  # /tf, /imu: nobody subscribed
    assert got == {"/odom": 21, "/cmd_vel": 21}
    assert last_ns == {"/odom": 1_980_000_000, "/cmd_vel": 1_980_000_000}  # the streams' last messages
