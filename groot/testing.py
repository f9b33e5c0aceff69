"""Helpers for testing Groot2 interoperability: a blocking protocol client, port picking, the
shared checkers' location. Used by ``tests/test_groot*.py`` and ``bench/groot.py``."""

from __future__ import annotations

import json
import os
import socket
from pathlib import Path
from typing import Any

import zmq

from . import protocol as P


def find_shared() -> Path | None:
    """The project's ``shared`` folder: ``$BT_RUNTIME_SHARED``, else a ``shared`` folder beside
    the repository or one of its parents; None when absent."""
    env = os.environ.get("BT_RUNTIME_SHARED")
    if env:
        return Path(env) if Path(env).is_dir() else None
    for parent in Path(__file__).resolve().parents[1:]:
        if (parent / "shared" / "tools" / "groot2").is_dir():
            return parent / "shared"
    return None


def groot2_tools() -> Path | None:
    shared = find_shared()
    tools = shared / "tools" / "groot2" if shared else None
    return tools if tools is not None and (tools / "groot2_probe.py").is_file() else None


def free_port_pair(host: str = "127.0.0.1") -> int:
    """A port p such that p and p+1 are both free right now (TCP)."""
    for _ in range(200):
        with socket.socket() as s:
            s.bind((host, 0))
            port = s.getsockname()[1]
        if port >= 65535:
            continue
        with socket.socket() as s2:
            try:
                s2.bind((host, port + 1))
            except OSError:
                continue
        return port
    raise OSError("no free port pair")


class GrootClient:
    """A lock-step REQ client of the Groot2 protocol (what Groot2 itself does)."""

    def __init__(self, port: int, host: str = "127.0.0.1", timeout: float = 2.0):
        self.ctx = zmq.Context()
        self.sock = self.ctx.socket(zmq.REQ)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.setsockopt(zmq.RCVTIMEO, int(timeout * 1000))
        self.sock.setsockopt(zmq.SNDTIMEO, int(timeout * 1000))
        self.sock.connect(f"tcp://{host}:{port}")
        self.host, self.port = host, port

    def raw(self, frames: list[bytes]) -> list[bytes]:
        self.sock.send_multipart(frames)
        return self.sock.recv_multipart()

    def request(self, rtype: int | str, payload: bytes | str | None = None) -> list[bytes]:
        """Reply frames after checking the header; ``[b"error", msg]`` errors are returned as is."""
        if isinstance(rtype, str):
            rtype = ord(rtype)
        header = P.request_header(rtype)
        frames = [header]
        if payload is not None:
            frames.append(payload.encode() if isinstance(payload, str) else payload)
        reply = self.raw(frames)
        if reply[0] == b"error":
            return reply
        if len(reply[0]) != P.REPLY_HEADER_SIZE or reply[0][:6] != bytes((2,)) + header[1:]:
            raise AssertionError(f"bad reply header {reply[0].hex()} for {header.hex()}")
        return reply

    def uuid(self) -> bytes:
        return self.request(P.STATUS)[0][6:]

    def fulltree(self) -> str:
        return self.request(P.FULLTREE)[1].decode()

    def status(self) -> list[tuple[int, int]]:
        return P.unpack_status(self.request(P.STATUS)[1])

    def status_bytes(self) -> bytes:
        return self.request(P.STATUS)[1]

    def blackboard(self, *names: str) -> bytes:
        return self.request(P.BLACKBOARD, ";".join(names))[1]

    def insert_hook(self, uid: int, *, mode: int = 0, desired: str = "SKIPPED", once: bool = False,
                    position: int = 0, enabled: bool = True) -> list[bytes]:
        hook = {"enabled": enabled, "uid": uid, "mode": mode, "once": once,
                "desired_status": desired, "position": position}
        return self.request(P.HOOK_INSERT, json.dumps(hook))

    def unlock(self, uid: int, desired: str = "SKIPPED", remove: bool = False,
               position: int = 0) -> list[bytes]:
        data = {"uid": uid, "desired_status": desired, "position": position, "remove_when_done": remove}
        return self.request(P.BREAKPOINT_UNLOCK, json.dumps(data))

    def hooks(self) -> list[dict[str, Any]]:
        return json.loads(self.request(P.HOOKS_DUMP)[1])

    def close(self) -> None:
        self.sock.close(linger=0)
        self.ctx.term()

    def __enter__(self) -> GrootClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
