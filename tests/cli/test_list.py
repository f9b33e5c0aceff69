"""``python -m bt_runtime list``: the shipped worlds, a world's goals, robots and trees."""

from bt_runtime.__main__ import main


def test_list_worlds_goals_robots_trees(capsys):
    assert main(["list", "worlds"]) == 0
    assert capsys.readouterr().out.splitlines()[0].startswith("apartment        16 x 12 m")
    assert main(["list", "goals"]) == 0
    assert "yard_east        x=+3.50 y=-2.50 yaw=+0.00 rad" in capsys.readouterr().out
    assert main(["list", "goals", "--world", "round_obstacles"]) == 0
    assert "yard_east" not in capsys.readouterr().out
    assert main(["list", "robots"]) == 0
    assert [line.split()[0] for line in capsys.readouterr().out.splitlines()] == ["burger", "waffle", "rosbot2"]
    assert main(["list", "trees"]) == 0
    assert "trees/autonomy.xml" in capsys.readouterr().out.split()
