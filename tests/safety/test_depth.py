"""Deep SubTree chains are refused at load time with file:line, never a RecursionError (run,
validate); a tree at the limit loads, ticks and halts."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from bt_runtime.errors import XMLLoadError
from bt_runtime.factory import BehaviorTreeFactory
from bt_runtime.xml.depth import MAX_TREE_DEPTH
from tests.paths import ROOT


def chain_xml(n: int) -> str:
    """T0 -> SubTree T1 -> ... -> T{n} (AlwaysSuccess): n + 1 levels expanded."""
    parts = ['<root BTCPP_format="4" main_tree_to_execute="T0">']
    parts += [f'<BehaviorTree ID="T{i}">\n  <SubTree ID="T{i + 1}"/>\n</BehaviorTree>' for i in range(n)]
    parts.append(f'<BehaviorTree ID="T{n}">\n  <AlwaysSuccess/>\n</BehaviorTree></root>')
    return "\n".join(parts)


def test_chain_at_the_limit_loads_ticks_and_halts():
    tree = BehaviorTreeFactory().create_tree_from_text(chain_xml(MAX_TREE_DEPTH - 1))
    assert tree.tick_once().name == "SUCCESS"
    tree.halt_tree()


def test_chain_over_the_limit_is_refused_with_file_and_line(tmp_path):
    path = tmp_path / "deep.xml"
    path.write_text(chain_xml(2000), encoding="utf-8")
    with pytest.raises(XMLLoadError) as caught:
        BehaviorTreeFactory().create_tree_from_file(path)
    err = caught.value
    assert err.file and str(path) in str(err.file) and err.line and err.element == "SubTree"
    assert "2001 levels deep" in err.message and f"limit {MAX_TREE_DEPTH}" in err.message


@pytest.mark.parametrize("command", [["validate"], ["run", "--duration", "1"]])
def test_cli_reports_deep_chains_without_a_traceback(tmp_path, command):
    path = tmp_path / "deep.xml"
    path.write_text(chain_xml(2000), encoding="utf-8")
    result = subprocess.run([sys.executable, "-m", "bt_runtime", command[0], str(path), *command[1:]],
                            cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), capture_output=True,
                            text=True, timeout=120)
    output = result.stdout + result.stderr
    assert result.returncode != 0
    assert "Traceback" not in output and "RecursionError" not in output
    assert f"{path.name}:" in output and "levels deep" in output
