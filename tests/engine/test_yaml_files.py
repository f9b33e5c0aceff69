"""The one YAML loader behind worlds, robot profiles and maps: plain data only."""

import pytest
import yaml

from bt_runtime.yaml_files import safe_load


def test_plain_data_loads():
    assert safe_load("a: [1, 2.5, x]\nb: {c: true}\n") == {"a": [1, 2.5, "x"], "b": {"c": True}}


def test_python_object_tags_are_refused():
    with pytest.raises(yaml.YAMLError):
        safe_load("!!python/object/apply:os.system ['echo pwned']")
