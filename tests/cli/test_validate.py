"""``python -m bt_runtime validate``: exit codes, every problem reported, JSON, models, includes."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from bt_runtime.__main__ import main
from tests.paths import REFERENCE, ROOT

DEMO = ROOT / "trees" / "demo.xml"
NAV2 = REFERENCE / "nav2" / "trees"

BAD = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <SubTree ID="First"/>
      <SubTree ID="Second"/>
      <Repeat num_cycles="abc"><AlwaysSuccess/></Repeat>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="First">
    <Sequnce>
      <AlwaysSuccess/>
    </Sequnce>
  </BehaviorTree>
  <BehaviorTree ID="Second">
    <Inverter>
      <AlwaysSuccess/>
      <AlwaysFailure/>
    </Inverter>
  </BehaviorTree>
  <BehaviorTree ID="Third">
    <Script code="x := "/>
  </BehaviorTree>
  <BehaviorTree ID="Fourth">
    <Sleep msec="1" foo="2"/>
  </BehaviorTree>
  <BehaviorTree ID="AlwaysSuccess">
    <AlwaysSuccess/>
  </BehaviorTree>
  <BehaviorTree ID="Fifth"><SubTree ID="Nowhere"/></BehaviorTree>
  <BehaviorTree ID="Sixth"><AlwaysSuccess _skipIf="1 +"/></BehaviorTree>
</root>
"""


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(["validate", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_demo_tree_is_valid(capsys):
    code, out, err = run(capsys, str(DEMO))
    assert code == 0
    assert out == ""
    assert "3 tree(s) checked, OK" in err


def test_demo_tree_runs_to_success():
    from bt_runtime import BehaviorTreeFactory, NodeStatus

    tree = BehaviorTreeFactory().create_tree_from_file(DEMO)
    assert tree.tick_while_running(0.001) is NodeStatus.SUCCESS
    assert tree.root_blackboard.get("visited") == 3
    assert tree.root_blackboard.get("log") == "kitchen;hall;lab;"


def test_every_problem_of_every_tree_is_reported(tmp_path, capsys):
    bad = write(tmp_path, "bad.xml", BAD)
    code, out, _ = run(capsys, str(bad))
    assert code == 1
    lines = [line for line in out.splitlines() if not line.startswith("    ")]
    expected = [
        (6, "<Repeat>", 'can not be converted to int'),
        (10, "<Sequnce>", "Node not recognized: Sequnce (did you mean: Sequence"),
        (15, "<Inverter>", "must have exactly 1 child"),
        (21, "<Script>", 'Error in the script "x := "'),
        (24, "<Sleep>", "a port with name [foo]"),
        (26, "<BehaviorTree>", "must not use the name of a registered Node"),
        (29, "<SubTree>", "Nowhere"),
        (30, "<AlwaysSuccess>", "_skipIf"),
    ]
    assert len(lines) == len(expected), out
    for line, (lineno, element, text) in zip(lines, expected):
        assert line.startswith(f"{bad}:{lineno}: {element}: "), line
        assert text in line


def test_bad_status_literal_reported_although_btcpp_loads_it(tmp_path, capsys):
    bad = write(tmp_path, "status.xml", '<root BTCPP_format="4">\n<BehaviorTree ID="M">\n<Sequence>\n'
                                        '<Precondition if="1" else="DONE"><AlwaysSuccess/></Precondition>\n'
                                        '<LoopInt queue="" if_empty="{ok}" value="{v}"><AlwaysSuccess/></LoopInt>\n'
                                        '</Sequence></BehaviorTree></root>')
    code, out, _ = run(capsys, "--json", str(bad))
    assert code == 1
    assert json.loads(out) == [{"file": str(bad), "line": 4, "element": "Precondition",
                                "message": 'The port with name "else" and value "DONE" can not be converted '
                                           "to BT::NodeStatus"}]


def test_json_output(tmp_path, capsys):
    bad = write(tmp_path, "bad.xml", BAD)
    code, out, _ = run(capsys, "--json", str(bad))
    assert code == 1
    data = json.loads(out)
    assert isinstance(data, list) and len(data) == 8
    assert all(set(item) == {"file", "line", "element", "message"} for item in data)
    assert data[0] == {"file": str(bad), "line": 6, "element": "Repeat",
                       "message": 'The port with name "num_cycles" and value "abc" can not be converted to int'}


def test_json_output_when_valid(capsys):
    code, out, _ = run(capsys, "--json", str(DEMO))
    assert code == 0
    assert json.loads(out) == []


def test_continues_with_next_file(tmp_path, capsys):
    bad = write(tmp_path, "bad.xml", '<root BTCPP_format="4"><BehaviorTree ID="M"><Nope/></BehaviorTree></root>')
    code, out, err = run(capsys, str(bad), str(tmp_path / "missing.xml"), str(DEMO))
    assert code == 1
    assert f"{bad}:1: <Nope>: Node not recognized: Nope" in out
    assert f"{tmp_path / 'missing.xml'}: cannot read the file" in out
    assert f"{DEMO}: 3 tree(s) checked, OK" in err


def test_malformed_xml(tmp_path, capsys):
    bad = write(tmp_path, "broken.xml", '<root BTCPP_format="4">\n<BehaviorTree ID="M">\n<Sequence>\n'
                                        '</BehaviorTree></root>\n')
    code, out, _ = run(capsys, "--json", str(bad))
    assert code == 1
    (problem,) = json.loads(out)
    assert problem["file"] == str(bad)
    assert problem["line"] in (3, 4)
    assert problem["message"].startswith("Error parsing the XML")


def test_single_line_document_with_two_bad_trees(tmp_path, capsys):
    text = ('<root BTCPP_format="4"><BehaviorTree ID="A"><Nope/></BehaviorTree>'
            '<BehaviorTree ID="B"><Inverter/></BehaviorTree></root>')
    code, out, _ = run(capsys, str(write(tmp_path, "one.xml", text)))
    assert code == 1
    assert "Node not recognized: Nope" in out  # the others share its line: reported as far as possible


MODELS = """<root BTCPP_format="4"><TreeNodesModel>
  <Action ID="MoveTo"><input_port name="goal" type="double"/><output_port name="reached"/></Action>
  <Condition ID="IsReady"/>
</TreeNodesModel></root>"""


def test_models_register_placeholders(tmp_path, capsys):
    models = write(tmp_path, "models.xml", MODELS)
    good = write(tmp_path, "good.xml", '<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence><IsReady/>'
                                       '<MoveTo goal="1.5" reached="{r}"/></Sequence></BehaviorTree></root>')
    code, out, _ = run(capsys, str(good))
    assert code == 1 and "Node not recognized: IsReady" in out
    code, out, _ = run(capsys, "--models", str(models), str(good))
    assert code == 0, out
    wrong = write(tmp_path, "wrong.xml", '<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence>'
                                         '<MoveTo goal="far" speed="2"/></Sequence></BehaviorTree></root>')
    code, out, _ = run(capsys, "--models", str(models), str(wrong))
    assert code == 1
    assert "a port with name [speed]" in out


def test_bad_models_file(tmp_path, capsys):
    code, out, _ = run(capsys, "--models", str(tmp_path / "nope.xml"), str(DEMO))
    assert code == 1
    assert "cannot read the models file" in out


def test_problem_in_included_file(tmp_path, capsys):
    (tmp_path / "sub").mkdir()
    write(tmp_path / "sub", "inc.xml", '<root BTCPP_format="4">\n<BehaviorTree ID="Inc">\n'
                                       '<Repeat num_cycles="x"><AlwaysSuccess/></Repeat>\n</BehaviorTree></root>')
    main_file = write(tmp_path, "main.xml", '<root BTCPP_format="4" main_tree_to_execute="M">\n'
                                            '<include path="sub/inc.xml"/>\n<BehaviorTree ID="M">\n'
                                            '<SubTree ID="Inc"/>\n</BehaviorTree></root>')
    code, out, _ = run(capsys, "--json", str(main_file))
    assert code == 1
    problems = json.loads(out)
    assert [(Path(p["file"]).name, p["line"], p["element"]) for p in problems] == [("inc.xml", 3, "Repeat")]


def test_include_outside_folder_refused(tmp_path, capsys):
    (tmp_path / "a").mkdir()
    write(tmp_path, "secret.xml", '<root BTCPP_format="4"><BehaviorTree ID="S"><AlwaysSuccess/></BehaviorTree></root>')
    main_file = write(tmp_path / "a", "main.xml", '<root BTCPP_format="4"><include path="../secret.xml"/>'
                                                  '<BehaviorTree ID="M"><AlwaysSuccess/></BehaviorTree></root>')
    code, out, _ = run(capsys, str(main_file))
    assert code == 1
    assert "<include>: include path '../secret.xml' resolves outside the folder" in out


@pytest.mark.skipif(not NAV2.is_dir(), reason="the shared Nav2 reference trees are not available")
def test_nav2_jazzy_trees_validate(capsys):
    folder = NAV2 / "jazzy"
    files = sorted(str(p) for p in folder.glob("*.xml"))
    code, out, err = run(capsys, "--no-nodes", "--models", str(folder / "nav2_tree_nodes.xml"), *files)
    assert code == 0, out
    assert "warning" not in err


@pytest.mark.skipif(not NAV2.is_dir(), reason="the shared Nav2 reference trees are not available")
def test_nav2_humble_v3_trees_validate_with_warnings(capsys):
    folder = NAV2 / "humble"
    files = sorted(str(p) for p in folder.glob("*.xml") if p.name != "nav2_tree_nodes.xml")
    code, out, err = run(capsys, "--json", "--no-nodes", "--models", str(folder / "nav2_tree_nodes.xml"), *files)
    assert "BTCPP_format" in err and "SequenceStar -> SequenceWithMemory" in err
    problems = json.loads(out)
    # Nav2 Humble's own models file lacks Spin's is_recovery port, which its calibration tree uses.
    assert [(Path(p["file"]).name, p["element"]) for p in problems] == [("odometry_calibration.xml", "Spin")]
    assert "[is_recovery]" in problems[0]["message"]
    assert code == 1


def test_module_entry_point_subprocess(tmp_path):
    result = subprocess.run([sys.executable, "-m", "bt_runtime", "validate", str(DEMO)], cwd=ROOT,
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    bad = write(tmp_path, "bad.xml", BAD)
    result = subprocess.run([sys.executable, "-m", "bt_runtime", "validate", "--json", str(bad)], cwd=ROOT,
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 1
    assert len(json.loads(result.stdout)) == 8


def test_usage_errors(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["validate"])
    assert exc.value.code == 2
    with pytest.raises(SystemExit) as exc:
        main([])
    assert exc.value.code == 2
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    assert "validate" in capsys.readouterr().out


def test_every_problem_inside_one_tree_and_a_missing_main_tree(tmp_path, capsys):
    path = write(tmp_path, "bad.xml", """<root BTCPP_format="4" main_tree_to_execute="Mian">
  <BehaviorTree ID="Main">
    <Sequence>
      <Unknown1/>
      <AlwaysSuccess/>
      <Unknown2><AlwaysSuccess/></Unknown2>
      <Delay delay_msec="abc"><AlwaysSuccess/></Delay>
    </Sequence>
  </BehaviorTree>
</root>
""")
    code, out, _ = run(capsys, str(path))
    assert code == 1
    lines = out.strip().splitlines()
    assert lines[0] == (f'{path}:1: <root>: main_tree_to_execute="Mian" names no tree of this file (trees: Main); '
                        "did you mean 'Main'?")
    assert [line.split(": ", 1)[0] for line in lines[1:]] == [f"{path}:4", f"{path}:6", f"{path}:7"]
    assert "Unknown1" in lines[1] and "Unknown2" in lines[2] and "delay_msec" in lines[3]


def test_a_tree_file_given_to_models_is_explained(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["validate", "--models", str(DEMO)])
    assert exc.value.code == 2
    assert f"to check {DEMO} itself: python -m bt_runtime validate {DEMO}" in capsys.readouterr().err
    tree = write(tmp_path, "tree.xml", '<root BTCPP_format="4"><BehaviorTree ID="T"><AlwaysSuccess/>'
                                       '</BehaviorTree></root>')
    code, out, _ = run(capsys, "--models", str(tree), str(DEMO))
    assert code == 1 and "this is a tree file, not a models file" in out


def test_a_tree_file_with_embedded_models_gives_its_models(capsys):
    """trees/autonomy.xml carries its models (models --embed): as --models it gives those,
    so the tree validates with no node library registered."""
    autonomy = str(ROOT / "trees" / "autonomy.xml")
    code, out, _ = run(capsys, "--no-nodes", "--models", autonomy, autonomy)
    assert code == 0, out
