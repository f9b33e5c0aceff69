"""Live view: the recording's channels served over the Foxglove WebSocket protocol (foxglove-sdk).

The server is one more sink of the recording's ``ChannelSet`` context, so it receives the same
CDR bytes as the bag (``ros2msg`` schemas, ``cdr`` encoding). Latched topics (the map, the
static transforms) are re-sent when a client subscribes, as ROS's transient-local QoS would.
The server binds to 127.0.0.1 unless told otherwise.
"""

from __future__ import annotations

import threading
from typing import Any

from .channels import ChannelSet

DEFAULT_PORT = 8765


class FoxgloveLive:
    def __init__(self, channels: ChannelSet, port: int = DEFAULT_PORT, host: str = "127.0.0.1",
                 name: str = "bt_runtime"):
        import foxglove
        from foxglove.websocket import Capability

        self.channels = channels
        self._latched: dict[str, tuple[Any, int, bytes]] = {}
        self._lock = threading.Lock()
        self._last_time_ns = -(2**62)
        try:
            self.server = foxglove.start_server(name=name, host=host, port=port, context=channels.context,
                                                capabilities=[Capability.Time], server_listener=_listener(self))
        except Exception as exc:  # the SDK's FoxgloveError: a port in use, a bad address
            raise OSError(f"--foxglove: cannot serve on {host}:{port}: {exc}") from None
        self.host = host
        self.port = self.server.port

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def sent(self, messages: list[tuple[str, bytes, int]]) -> None:
        """Called after each batch of logged ``(topic, data, log time)``: keeps the latched
        ones, tells clients the robot time."""
        latched = self.channels.latched
        newest = self._last_time_ns
        for topic, data, t_ns in messages:
            if topic in latched:
                with self._lock:
                    self._latched[topic] = (self.channels.channels[topic], t_ns, data)
            if t_ns > newest:
                newest = t_ns
        if newest > self._last_time_ns + 50_000_000:  # 20 Hz at most
            self._last_time_ns = newest
            self.server.broadcast_time(newest)

    def close(self) -> None:
        self.server.stop()

    def resend_latched(self, topic: str) -> None:
        with self._lock:
            last = self._latched.get(topic)
        if last is not None:
            ch, t_ns, data = last
            ch.log(data, log_time=t_ns)


def _listener(live: FoxgloveLive) -> Any:
    """The server's callbacks (on the SDK's thread): a new subscriber of a latched topic gets
    its last message. The SDK's ServerListener protocol class supplies no-op defaults."""
    from foxglove.websocket import ServerListener

    class Listener(ServerListener):
        def on_subscribe(self, client: Any, channel: Any) -> None:
            live.resend_latched(channel.topic)

    return Listener()
