"""A hostile Groot2 client, run as its own process by test_groot_hostile.py:
``python -m tests.safety.groot_attacker PORT``. Prints how many flood replies it got."""

from __future__ import annotations

import os
import sys
import time

import zmq

from groot import protocol as P
from groot.server import MAX_BLACKBOARD_NAMES


def attack(port: int) -> dict:
    stats: dict = {}
    ctx = zmq.Context()
    try:
        def dealer():
            sock = ctx.socket(zmq.DEALER)
            sock.setsockopt(zmq.LINGER, 0)
            sock.setsockopt(zmq.SNDTIMEO, 2000)
            sock.connect(f"tcp://127.0.0.1:{port}")
            return sock

        header = P.request_header(P.BLACKBOARD)
        sock = dealer()
        sock.send_multipart([b"", header, b";" * (16 * 1024 * 1024)], copy=False)
        sock.close()
        sock = dealer()
        sock.send_multipart([b"", P.request_header(P.STATUS), memoryview(bytearray(200 * 1024 * 1024))], copy=False)
        sock.close()
        sock = dealer()
        sock.send_multipart([b"", header, *([b"x"] * 50)])  # too many parts
        for _ in range(2000):  # a flood of the most expensive legal request
            sock.send_multipart([b"", header, b"Main;" * MAX_BLACKBOARD_NAMES], flags=zmq.NOBLOCK) \
                if sock.poll(0, zmq.POLLOUT) else None
        time.sleep(0.2)
        stats["flood_replies"] = 0
        while sock.poll(10):
            sock.recv_multipart()
            stats["flood_replies"] += 1
        sock.close()
    finally:
        ctx.term()
    return stats




if __name__ == "__main__":
    os.nice(10)  # the attack's own CPU work must not starve the process under test
    print(attack(int(sys.argv[1])))
