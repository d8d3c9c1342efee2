"""The 12-link robot (config/robots/chang_rectilinear.yaml) with its own rectilinear gaits
(config/gaits.yaml rectilinear_chang, rectilinear_chang_reverse) through the C++ driver on the
simulated robot with nav runs' flat belly (runs/gait_map.py simulate_point with driver_gait: the
PlantGaitDriver nav runs use), against its gait map (config/gait_maps/chang_rectilinear.yaml), and
the per-robot nav config that makes `nav run --robot chang_rectilinear` use them."""
import math

import pytest
import yaml

ROBOT = "chang_rectilinear"


def _xi(root, gait, kappa_per_m):
    from snake_autonomy.runs.gait_map import gait_map_points, simulate_point
    nav = yaml.safe_load((root / "config" / "nav.yaml").read_text())
    point, = gait_map_points(ROBOT, "rectilinear", [0.02], [kappa_per_m], driver_gait=gait,
                             flat_belly_fraction=nav["plant"]["flat_belly_fraction"], wavelength_m=0.5)
    row = simulate_point(point)
    assert not row["rolled_over"] and row["max_tilt_deg"] < 30.0
    print(f"{gait} kappa {kappa_per_m:g}/m: xi_x {1000 * row['xi_x_m_s']:.2f} mm/s, xi_y "
          f"{1000 * row['xi_y_m_s']:.2f} mm/s, w {math.degrees(row['xi_w_rad_s']):.3f} deg/s, "
          f"tilt {row['max_tilt_deg']:.1f} deg")
    return row["xi_x_m_s"], row["xi_y_m_s"], row["xi_w_rad_s"]


def _gait_map(root):
    return yaml.safe_load((root / "config" / "gait_maps" / "chang_rectilinear.yaml").read_text())


def test_the_12_link_gait_moves_head_first_at_the_gait_maps_speed(root):
    fit, = _gait_map(root)["fits"]
    vx, vy, w = _xi(root, "rectilinear_chang", 0.0)
    assert vx > 0.005                                       # head first, > 5 mm/s
    assert vx == pytest.approx(fit["speed_straight_m_s"], rel=0.1)
    assert abs(w) < 0.1 * fit["omega_per_steer"]            # straight


def test_kappa_positive_turns_the_12_link_robot_left(root):
    fit, = _gait_map(root)["fits"]
    vx, vy, w = _xi(root, "rectilinear_chang", 1.0)
    assert w > 0.5 * fit["omega_per_steer"] > 0.0           # CCW
    assert vx > 0.005                                       # still head first
    vx_r, vy_r, w_r = _xi(root, "rectilinear_chang", -1.0)
    assert w_r < -0.5 * fit["omega_per_steer"]              # and kappa < 0 right


def test_the_reverse_gait_moves_the_12_link_robot_tail_first(root):
    fit, = _gait_map(root)["fits"]
    vx, vy, w = _xi(root, "rectilinear_chang_reverse", 0.0)
    assert vx < -0.5 * fit["speed_straight_m_s"]            # tail first, at least half the speed


def test_nav_runs_of_the_12_link_robot_read_its_own_nav_config(root):
    from snake_autonomy.planning.rectilinear.config import NavConfig, nav_config_path
    own = nav_config_path(ROBOT)
    assert own == root / "config" / f"nav_{ROBOT}.yaml"
    assert nav_config_path(str(root / "config" / "robots" / f"{ROBOT}.yaml")) == own   # a YAML path too
    assert nav_config_path("cobra") == root / "config" / "nav.yaml"
    cfg, base = NavConfig.from_yaml(own), NavConfig.from_yaml()
    assert (cfg.gaits.forward, cfg.gaits.reverse) == ("rectilinear_chang", "rectilinear_chang_reverse")
    assert (base.gaits.forward, base.gaits.reverse) == ("rectilinear", "rectilinear_reverse")
    fit = _gait_map(root)["follower"]
    assert cfg.follower.omega_per_kappa == fit["omega_per_kappa"] != base.follower.omega_per_kappa
    assert cfg.sampler.body_clearance_m < base.sampler.body_clearance_m
    assert cfg.gait.wavelength_m == 0.5
    # what the robot's file does not name is nav.yaml's, key by key within a section
    assert cfg.intrinsics == base.intrinsics and cfg.plant == base.plant
    assert cfg.sampler.horizon_m == base.sampler.horizon_m and cfg.follower.lookahead_m == base.follower.lookahead_m


def test_a_nav_config_base_is_merged_and_its_problems_named(tmp_path, root):
    from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError
    (tmp_path / "base.yaml").write_text("sampler: {horizon_m: 0.9, num_arcs: 7}\ngaits: {forward: a}\n")
    (tmp_path / "own.yaml").write_text("base: base.yaml\nsampler: {horizon_m: 0.5}\ngaits: {reverse: b}\n")
    cfg = NavConfig.from_yaml(tmp_path / "own.yaml")
    assert (cfg.sampler.horizon_m, cfg.sampler.num_arcs) == (0.5, 7)
    assert (cfg.gaits.forward, cfg.gaits.reverse) == ("a", "b")
    (tmp_path / "bad.yaml").write_text("base: nope.yaml\n")
    with pytest.raises(NavConfigError, match="base: no such file 'nope.yaml'"):
        NavConfig.from_yaml(tmp_path / "bad.yaml")
    with pytest.raises(NavConfigError, match=r"gaits.forward: expected a gait name .*got 3"):
        NavConfig.from_dict({"gaits": {"forward": 3}})


def test_a_gait_map_refuses_a_driver_gait_without_curvature_steering():
    from snake_autonomy.runs.gait_map import gait_map_points
    with pytest.raises(ValueError, match="'sidewind' is not a gait of .* with steering: curvature"):
        gait_map_points(ROBOT, "rectilinear", [0.02], [0.0], driver_gait="sidewind")


def test_nav_run_drives_the_12_link_robot_with_its_gait_without_naming_it(root):
    from snake_autonomy.runs.nav_batch import NavRun, NavRunSpec
    from snake_autonomy.sim.world_file import load_world
    world = load_world(root / "config" / "worlds" / "one_obstacle.yaml")
    run = NavRun(NavRunSpec(world, robot=ROBOT, time_limit_s=4.0, keep_frames=False))
    assert (run.gaits.forward, run.gaits.reverse) == ("rectilinear_chang", "rectilinear_chang_reverse")
    assert run.loop.planner.follower.params.back_off is True             # nav_chang_rectilinear.yaml
    m = run.run().metrics
    assert (m["gait"], m["nav_config"]) == ("rectilinear_chang", f"nav_{ROBOT}.yaml")
    assert m["path_length_m"] > 0.005                                    # it moved (the first command at 0.5 s)
    cobra = NavRun(NavRunSpec(world, robot="cobra", time_limit_s=1.0, keep_frames=False))
    cobra.camera.close()
    assert (cobra.gaits.forward, cobra.gaits.reverse) == ("rectilinear", "rectilinear_reverse")
