"""metadata.yaml is rendered with each topic's and segment's entry kept from its first
rendering (``Rosbag2Bag.metadata_yaml``): the text is exactly PyYAML's dump of the whole
information, as counts, segments and topics grow, and rosbags reads it."""

from __future__ import annotations

import pytest
import yaml

pytest.importorskip("foxglove")

from bt_runtime.runtime.messages import Twist  # noqa: E402
from bt_runtime.runtime.recording.bag import Rosbag2Bag  # noqa: E402
from bt_runtime.runtime.recording.channels import ChannelSet, dump_yaml  # noqa: E402
from bt_runtime.runtime.recording.convert import ConvertState, command, tf_static  # noqa: E402


def _log(bag: Rosbag2Bag, outputs, t_ns: int) -> None:
    if bag.idle:
        bag.open_segment()
    for name, typename, data in outputs:
        if name not in bag.channels.loggers:
            bag.channels.add(name, typename, latched=name == "/tf_static")
        bag.channels.loggers[name](data, t_ns, None)
        bag.count(name, t_ns)


def test_the_text_is_the_dump_of_the_whole_information(tmp_path):
    bag = Rosbag2Bag(tmp_path / "bag", ChannelSet(), custom_data={"scenario": "yard: east", "seed": "7"})
    state = ConvertState()
    assert bag.metadata_yaml() == dump_yaml(bag.metadata())  # no topic, no segment
    texts = []
    for segment in range(3):
        for k in range(5 + segment):
            t = segment * 10.0 + k * 0.1
            _log(bag, command(state, "/cmd_vel", t, Twist(0.1 * k, -0.2)), int(t * 1e9))
            if segment == 1:  # a topic that appears in a later segment
                _log(bag, tf_static(state, "/tf_static", t, (0.1, 0.0, 0.0)), int(t * 1e9))
        assert bag.close_segment()
        text = bag.metadata_yaml()
        assert text == dump_yaml(bag.metadata())
        texts.append(text)
    info = yaml.safe_load(texts[-1])["rosbag2_bagfile_information"]
    assert [t["message_count"] for t in info["topics_with_message_count"]] == [18, 6]
    assert info["relative_file_paths"] == ["bag_0.mcap", "bag_1.mcap", "bag_2.mcap"]
    assert [f["message_count"] for f in info["files"]] == [5, 12, 7]
    bag.close()
    assert (tmp_path / "bag" / "metadata.yaml").read_text() == texts[-1]
