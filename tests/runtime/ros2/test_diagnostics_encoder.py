"""A DiagnosticArray packed by ros2/diagnostics_encoder.py is byte-equal to what Cyclone's
writer serialises from the IDL objects (stamp by ``idl.Time.from_sec``, padded as
``DataWriter.write`` pads), for empty and full arrays, every level, non-ASCII and empty text."""

import random

import pytest

pytest.importorskip("cyclonedds")

from bt_runtime.runtime.ros2 import idl  # noqa: E402
from bt_runtime.runtime.ros2.diagnostics_encoder import encode_diagnostic_array  # noqa: E402

WORDS = ["", "a", "ok", "lidar", "silent for 2.50 s", "Übergang", "bt_runtime: scan", "x" * 31, "日本"]


def cyclone(t: float, frame_id: str, statuses) -> bytes:
    msg = idl.DiagnosticArray(header=idl.Header(stamp=idl.Time.from_sec(t), frame_id=frame_id), status=[
        idl.DiagnosticStatus(level=level, name=name, message=message, hardware_id=hw,
                             values=[idl.KeyValue(key=k, value=v) for k, v in values])
        for level, name, message, hw, values in statuses])
    data = msg.serialize(use_version_2=None)
    return data.ljust((len(data) + 3) & ~3, b"\0")


@pytest.mark.parametrize("seed", range(5))
def test_packed_bytes_equal_cyclones(seed):
    rng = random.Random(seed)
    for _ in range(60):
        statuses = [(rng.choice([0, 1, 2, 3]), rng.choice(WORDS), rng.choice(WORDS), rng.choice(WORDS),
                     [(rng.choice(WORDS), rng.choice(WORDS)) for _ in range(rng.randrange(0, 5))])
                    for _ in range(rng.randrange(0, 12))]
        t = rng.uniform(0, 2e9)
        frame_id = rng.choice(["", "base_link", "Ü"])
        assert encode_diagnostic_array(t, frame_id, statuses) == cyclone(t, frame_id, statuses)
