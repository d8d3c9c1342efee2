"""scripts/rviz_screenshot's --world takes a world as sim.launch's world:= does: a file, or a name
under config/worlds/ (the shot itself needs Xvfb and rviz: run by hand, see the script's help)."""
import importlib.machinery
import importlib.util


def _script(root):
    loader = importlib.machinery.SourceFileLoader("rviz_screenshot", str(root / "scripts" / "rviz_screenshot"))
    spec = importlib.util.spec_from_loader("rviz_screenshot", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def test_world_is_a_name_under_config_worlds_or_a_file(root, tmp_path, monkeypatch):
    world_file = _script(root).world_file
    assert world_file("one_obstacle") == root / "config" / "worlds" / "one_obstacle.yaml"
    own = tmp_path / "mine.yaml"
    own.write_text("{}\n")
    monkeypatch.chdir(tmp_path)
    assert world_file("mine.yaml") == own.resolve()          # a file wins, relative to the working folder
    assert not world_file("no_such_world").is_file()         # neither: the caller reports it
