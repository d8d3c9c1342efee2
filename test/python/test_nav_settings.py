"""The nav configs' keys are validated (each bad value refused, named with its key and value) and the
shipped configs (config/nav*.yaml) carry the settings the experiments measured: what is on, what was
measured and left off, and that the planned arcs are ones the follower can drive."""
import pytest

from snake_autonomy.planning.rectilinear.config import NavConfig, NavConfigError, nav_config_path
from snake_autonomy.planning.rectilinear.obstacle_map import MapParams


@pytest.mark.parametrize("name", ["nav.yaml", "nav_chang_rectilinear.yaml"])
def test_the_planned_arcs_are_ones_the_follower_can_drive(root, name):
    cfg = NavConfig.from_yaml(root / "config" / name)
    tightest = 1.0 / cfg.follower.min_radius_m          # omega(kappa_max) / speed, path curvature
    # the sampler's tightest arc within 5 % of the follower's: tighter ones are orbits, much wider
    # ones throw away the turns the gait can make
    assert 0.95 * tightest <= cfg.sampler.max_curvature_per_m <= 1.05 * tightest, (name, tightest)
    # tightest circles of COBRA 0.82 m and the 12-link robot 0.41 m orbited goals
    assert cfg.follower.min_radius_m < 0.4


def test_boolean_keys_take_true_or_false_only(tmp_path):
    f = tmp_path / "nav.yaml"
    f.write_text("follower: {back_off: 1}\nsampler: {goal_disc: yes}\n")
    with pytest.raises(NavConfigError) as e:
        NavConfig.from_yaml(str(f))
    assert "follower.back_off: must be true or false, got 1" in str(e.value)
    f.write_text("follower: {back_off: true}\nsampler: {goal_disc: false}\n")
    cfg = NavConfig.from_yaml(str(f))
    assert cfg.follower.back_off is True and cfg.sampler.goal_disc is False


def test_nav_config_refuses_a_stride_beyond_the_block(root, nav_config_over):
    assert NavConfig.from_yaml(root / "config" / "nav.yaml").classifier.stride_px == 20
    bad = nav_config_over("nav.yaml", "classifier: {stride_px: 60}\n")
    with pytest.raises(NavConfigError, match=r"classifier.stride_px: must be in \(0, block_px = 40\], got 60"):
        NavConfig.from_yaml(bad)


def test_the_ground_margin_key_is_checked_and_zero_in_nav_yaml(nav_config_over):
    assert NavConfig.from_yaml().classifier.ground_margin == 0.0           # the committed: the SVM's class
    f = nav_config_over("nav.yaml", "classifier:\n  ground_margin: .nan\n")
    with pytest.raises(NavConfigError, match="classifier.ground_margin: must be a finite number, got nan"):
        NavConfig.from_yaml(f)
    f = nav_config_over("nav.yaml", "classifier:\n  ground_margin: .inf\n")
    with pytest.raises(NavConfigError, match="classifier.ground_margin: must be a finite number, got inf"):
        NavConfig.from_yaml(f)
    f = nav_config_over("nav.yaml", "classifier:\n  ground_margin: 0.25\n")
    assert NavConfig.from_yaml(f).classifier.ground_margin == 0.25


def test_the_ground_fraction_key_is_checked_and_half_in_nav_yaml(nav_config_over):
    f = nav_config_over("nav.yaml", "classifier:\n  ground_fraction: 0.0\n")
    with pytest.raises(NavConfigError, match=r"ground_fraction: must be in \(0, 1\], got 0.0"):
        NavConfig.from_yaml(f)
    f = nav_config_over("nav.yaml", "classifier:\n  ground_fraction: 1.0\n")
    assert NavConfig.from_yaml(f).classifier.ground_fraction == 1.0
    assert NavConfig.from_yaml().classifier.ground_fraction == 0.5        # committed: half the block


def test_the_gaits_and_the_steering_law_are_nav_config_keys():
    base = NavConfig.from_yaml()
    assert (base.gaits.forward, base.gaits.reverse, base.gaits.stop) == ("rectilinear", "rectilinear_reverse",
                                                                         "hold_curve")
    assert base.gaits.steering == "uniform"
    assert [base.gaits.command(hold, back) for hold, back in ((False, False), (False, True), (True, True))] == [
        "rectilinear", "rectilinear_reverse", "hold_curve"]                # a stop wins over backing off
    ftl = NavConfig.from_dict({"gaits": {"steering": "follow_the_leader"}})
    assert ftl.gaits.steering == "follow_the_leader" and ftl.gaits.forward == base.gaits.forward
    with pytest.raises(NavConfigError,
                       match=r"gaits.steering: expected one of uniform, follow_the_leader, got 'snake'"):
        NavConfig.from_dict({"gaits": {"steering": "snake"}})
    with pytest.raises(NavConfigError, match=r"gaits.stop: expected a gait name of config/gaits.yaml, got 3"):
        NavConfig.from_dict({"gaits": {"stop": 3}})


def test_blocked_wins_is_a_boolean_nav_config_key_on_in_nav_yaml():
    assert NavConfig.from_yaml().sampler.blocked_wins is True
    with pytest.raises(NavConfigError, match=r"blocked_wins: must be true or false, got 'yes'"):
        NavConfig.from_dict({"sampler": {"blocked_wins": "yes"}})


def test_swing_guard_keys_are_checked_and_on_in_nav_yaml():
    sp = NavConfig.from_yaml().sampler
    assert sp.swing_guard_m == pytest.approx(0.2) and sp.swing_obstacle_depth_m == pytest.approx(0.1)
    with pytest.raises(NavConfigError, match=r"swing_guard_m: must be >= 0, got -0.1"):
        NavConfig.from_dict({"sampler": {"swing_guard_m": -0.1}})
    with pytest.raises(NavConfigError, match=r"swing_obstacle_depth_m: must be > 0, got 0"):
        NavConfig.from_dict({"sampler": {"swing_obstacle_depth_m": 0}})


def test_turn_free_m_is_checked_and_on_in_nav_yaml():
    assert NavConfig.from_yaml().sampler.turn_free_m == pytest.approx(0.05)
    with pytest.raises(NavConfigError, match=r"turn_free_m: must be >= 0, got -0.05"):
        NavConfig.from_dict({"sampler": {"turn_free_m": -0.05}})


def test_the_map_section_is_checked_and_named():
    base = {"map": {"source": "walls", "prior_radius_m": -0.1, "edge_px": 2.5, "route": 1}}
    with pytest.raises(NavConfigError) as e:
        NavConfig.from_dict(base)
    text = str(e.value)
    for part in ("map.source: expected one of none, faces, truth, got 'walls'", "map.prior_radius_m: must be > 0",
                 "map.edge_px: must be an integer", "map.route: must be true or false, got 1"):
        assert part in text, text
    with pytest.raises(NavConfigError, match="route: true needs a map"):
        NavConfig.from_dict({"map": {"source": "none"}})              # route's default: nav.yaml's true
    assert NavConfig.from_dict({"map": {"source": "none", "route": False}}).map.source == "none"
    assert MapParams().validate() == []


def test_nav_yaml_keeps_the_side_and_aims_at_the_disc_and_both_are_checked():
    """goal_disc on (the tie-break measured alone on seven of the eight experiments, the eighth
    with the near-field fix)."""
    sp = NavConfig.from_yaml().sampler
    assert sp.turn_keeps_side is True and sp.goal_disc is True
    with pytest.raises(NavConfigError, match=r"sampler.goal_disc: must be true or false, got 'yes'"):
        NavConfig.from_dict({"sampler": {"goal_disc": "yes"}})
    with pytest.raises(NavConfigError, match=r"sampler.turn_keeps_side: must be true or false, got 1"):
        NavConfig.from_dict({"sampler": {"turn_keeps_side": 1}})


def test_priors_off_own_floor_is_validated():
    with pytest.raises(NavConfigError, match=r"map.priors_off_own_floor: must be true or false, got 'yes'"):
        NavConfig.from_dict({"map": {"priors_off_own_floor": "yes"}})


def test_back_off_check_m_is_validated():
    with pytest.raises(NavConfigError, match=r"sampler.back_off_check_m: must be >= 0, got -0.1"):
        NavConfig.from_dict({"sampler": {"back_off_check_m": -0.1}})


def test_the_shipped_nav_configs_check_the_tail_track_and_keep_priors_off_their_floor():
    """nav.yaml (COBRA) and nav_chang_rectilinear.yaml: measured at 20 worlds x 5 seeds x both seed sets."""
    cobra, chang = NavConfig.from_yaml(), NavConfig.from_yaml(nav_config_path("chang_rectilinear"))
    assert cobra.map.priors_off_own_floor and chang.map.priors_off_own_floor
    assert cobra.sampler.blocked_wins_depth_m == chang.sampler.blocked_wins_depth_m == pytest.approx(0.1)
    assert cobra.sampler.back_off_check_m == pytest.approx(0.1)
    assert chang.sampler.back_off_check_m == pytest.approx(0.15)
    assert cobra.sampler.turn_free_m == pytest.approx(0.05) and chang.sampler.turn_free_m == pytest.approx(0.1)
    assert chang.sampler.swing_guard_tail_m == pytest.approx(0.2)   # COBRA's too: the next test


@pytest.mark.parametrize("key", ["crawl_guard_m", "crawl_dead_band_per_m", "crawl_margin_m"])
def test_the_crawl_guards_keys_are_validated(key):
    with pytest.raises(NavConfigError, match=rf"sampler.{key}: must be >= 0, got -0.1"):
        NavConfig.from_dict({"sampler": {key: -0.1}})


def test_reshape_keeps_centroid_is_validated():
    with pytest.raises(NavConfigError, match=r"sampler.reshape_keeps_centroid: must be true or false, got 'yes'"):
        NavConfig.from_dict({"sampler": {"reshape_keeps_centroid": "yes"}})
    with pytest.raises(NavConfigError, match=r"body_sweep.reshape_while_crawling: must be true or false, got 1"):
        NavConfig.from_dict({"body_sweep": {"reshape_while_crawling": 1}})
    assert not NavConfig.from_yaml(nav_config_path("chang_rectilinear")).body_sweep.reshape_while_crawling


def test_cobras_nav_config_turns_on_the_tail_body_and_crawl_guards():
    """nav.yaml (COBRA): the tail guard on (the 12-link robot's setting), reshaping about the
    centroid with the body guard, the crawl guard and backing off a blocked crawl, measured at 20
    worlds x 5 seeds. The 12-link robot keeps the guards off (not measured with them)."""
    cobra, chang = NavConfig.from_yaml(), NavConfig.from_yaml(nav_config_path("chang_rectilinear"))
    assert cobra.sampler.swing_guard_tail_m == chang.sampler.swing_guard_tail_m == pytest.approx(0.2)
    assert cobra.sampler.reshape_keeps_centroid and cobra.sampler.swing_guard_body
    assert cobra.sampler.crawl_guard_m == pytest.approx(0.2) and cobra.sampler.crawl_blocked_backs_off
    assert cobra.sampler.crawl_dead_band_per_m == pytest.approx(0.35)
    s = chang.sampler
    assert not (s.reshape_keeps_centroid or s.swing_guard_body or s.crawl_blocked_backs_off)
    assert s.crawl_guard_m == 0.0


def test_the_crawl_toward_arc_key_is_validated():
    with pytest.raises(NavConfigError, match=r"sampler.crawl_forces_toward_arc: must be true or false, got 1"):
        NavConfig.from_dict({"sampler": {"crawl_forces_toward_arc": 1}})


def test_cobra_crawls_toward_the_arc():
    """COBRA (config/nav.yaml): the crawl guard forces towards the arc. The 12-link robot's config
    does not use the crawl guard."""
    assert NavConfig.from_yaml().sampler.crawl_forces_toward_arc
    assert NavConfig.from_yaml(nav_config_path("chang_rectilinear")).sampler.crawl_guard_m == 0.0


@pytest.mark.parametrize("section, key, value", [
    ("sampler", "near_field_max_m", 0.5), ("sampler", "view_obstacle_range_m", 0.8),
    ("sampler", "crawl_guard_forces", True), ("map", "prior_normal_window_m", 0.04),
    ("map", "prior_shape", "shadow"), ("map", "prior_pad_m", 0.01)])
def test_options_measured_and_dropped_are_refused_as_unknown(section, key, value):
    """Options off in every shipped config were removed with their code: a config naming one is
    refused, not silently ignored."""
    with pytest.raises(NavConfigError, match=rf"{section}\.{key}: unknown key"):
        NavConfig.from_dict({section: {key: value}})


def test_depth_traversability_keys_are_validated():
    """Every problem named with its value (the whole section at once)."""
    with pytest.raises(NavConfigError) as e:
        NavConfig.from_dict({"depth_traversability": {"refine_iterations": -1, "depth_tolerance": 0.0,
                                                      "refine_floor_m": -0.001, "min_fraction": 1.5}})
    text = str(e.value)
    for want in ("depth_traversability.refine_iterations: must be an integer >= 0, got -1",
                 "depth_traversability.depth_tolerance: must be > 0, got 0.0",
                 "depth_traversability.refine_floor_m: must be > 0, got -0.001",
                 "depth_traversability.min_fraction: must be in (0, 1], got 1.5"):
        assert want in text, text
    assert NavConfig.from_yaml().depth.validate() == []


def test_every_robots_depth_plane_is_refined():
    """config/nav.yaml: three refits; the other robots' configs inherit them."""
    for robot in ("cobra", "chang_rectilinear"):
        d = NavConfig.from_yaml(nav_config_path(robot)).depth
        assert d.refine_iterations == 3 and d.refine_floor_m == pytest.approx(0.0005), robot


def test_the_code_defaults_are_the_shipped_nav_yaml(root):
    """NavConfig() with no file is config/nav.yaml, and a config that omits a key (or a section)
    plans as nav.yaml does; the dataclasses of this package's sections default to its values too."""
    shipped = NavConfig.from_yaml(root / "config" / "nav.yaml")
    assert NavConfig() == shipped
    assert NavConfig.from_dict({}) == shipped
    for section in ("sampler", "map", "classifier", "gait", "plant", "gaits", "planner", "local_map", "body_sweep",
                    "critics", "recovery"):
        assert type(getattr(shipped, section))() == getattr(shipped, section), section


def test_one_schema_names_every_bad_key_with_its_value_at_once():
    """Checked where the file is loaded: each key's type (its default's; numbers finite unless .inf
    means off) and range, named section.key with the value, every problem in one error."""
    bad = {
        "camera": {"lens": "wide", "mount": {"translation_m": [0.05, 0.0]},
                   "intrinsics": {"width": 640.5, "height": 480, "fx": 615.0, "fy": 615.0, "cx": 320.0, "cy": 240.0}},
        "depth_traversability": {"stride_px": 2.5, "inlier_m": -1},
        "sampler": {"num_arcs": 4, "margin_m": -0.1, "horizon_m": float("inf"), "known_free_m": float("inf"),
                    "goal_disc": "yes"},
        "follower": {"k_heading": float("nan"), "back_off_replans": -1, "replan_period_s": 0},
        "classifier": {"stride_px": 60},
        "plant": {"flat_belly_fraction": 1.5},
        "map": {"source": "walls", "cell_m": 0, "column_step_px": 0},
    }
    expected = [
        "camera.lens: unknown key (value 'wide'); known: intrinsics, mount",
        "camera.intrinsics.width: must be an integer, got 640.5",
        "camera.mount.translation_m: expected 3 numbers, got [0.05, 0.0]",
        "depth_traversability.stride_px: must be an integer, got 2.5",
        "depth_traversability.inlier_m: must be > 0, got -1.0",
        "sampler.num_arcs: must be an odd integer >= 1, got 4",
        "sampler.margin_m: must be >= 0, got -0.1",
        "sampler.horizon_m: must be a finite number, got inf",
        "sampler.goal_disc: must be true or false, got 'yes'",
        "follower.k_heading: must be a finite number, got nan",
        "follower.back_off_replans: must be an integer >= 0, got -1",
        "follower.replan_period_s: must be a number > 0, got 0",
        "classifier.stride_px: must be in (0, block_px = 40], got 60",
        "plant.flat_belly_fraction: must be in [0, 1], got 1.5",
        "map.source: expected one of none, faces, truth, got 'walls'",
        "map.cell_m: must be > 0, got 0.0",
        "map.column_step_px: must be an integer >= 1, got 0",
    ]
    with pytest.raises(NavConfigError) as e:
        NavConfig.from_dict(bad, "bad.yaml")
    assert sorted(e.value.problems) == sorted(expected)
    assert str(e.value).startswith(f"bad.yaml: {len(expected)} problem(s):")


def test_a_config_that_is_no_mapping_is_refused_by_name():
    with pytest.raises(NavConfigError, match=r"expected a mapping of sections, got \['sampler'\]"):
        NavConfig.from_dict(["sampler"])
    with pytest.raises(NavConfigError, match=r"camera.mount: expected a mapping, got 5"):
        NavConfig.from_dict({"camera": {"mount": 5}})
    with pytest.raises(NavConfigError, match=r"sampler: expected a mapping, got 'all'"):
        NavConfig.from_dict({"sampler": "all"})
