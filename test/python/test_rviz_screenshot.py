"""scripts/rviz_screenshot's --world takes a world as sim.launch's world:= does: a file, or a name
under config/worlds/ (the shot itself needs Xvfb and rviz: run by hand, see the script's help)."""


def test_world_is_a_name_under_config_worlds_or_a_file(root, tmp_path, monkeypatch, load_script):
    world_file = load_script("rviz_screenshot").world_file
    assert world_file("one_obstacle") == root / "config" / "worlds" / "one_obstacle.yaml"
    own = tmp_path / "mine.yaml"
    own.write_text("{}\n")
    monkeypatch.chdir(tmp_path)
    assert world_file("mine.yaml") == own.resolve()          # a file wins, relative to the working folder
    assert not world_file("no_such_world").is_file()         # neither: the caller reports it
