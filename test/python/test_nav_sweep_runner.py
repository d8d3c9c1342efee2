"""The sweep runner (runs/sweep_runner.py): the same tasks give identical results, in task order,
on the serial, thread-pool and Dask LocalCluster engines; a gait-map point is deterministic."""
import math

import pytest

from snake_autonomy.runs.gait_map import GaitPoint, fit_gait_map, simulate_point
from snake_autonomy.runs.sweep_runner import SerialExecutor, open_executor, run_tasks


def _square_plus_seed(task):
    k, seed = task
    return k * k + seed


def test_serial_executor_hands_exceptions_to_the_future():
    f = SerialExecutor().submit(lambda: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        f.result()


def test_open_executor_refuses_unknown_engines_and_zero_workers():
    with pytest.raises(ValueError, match="engine: expected one of dask, threads, serial, got 'mpi'"):
        with open_executor("mpi"):
            pass
    with pytest.raises(ValueError, match="n_workers: must be >= 1, got 0"):
        with open_executor("threads", n_workers=0):
            pass


def test_results_come_back_in_task_order_on_every_engine():
    tasks = [(k, 100) for k in range(7, 0, -1)]
    expected = [k * k + 100 for k in range(7, 0, -1)]
    for engine in ("serial", "threads"):
        with open_executor(engine, n_workers=3) as ex:
            assert run_tasks(ex, _square_plus_seed, tasks, progress=False) == expected


# Short points: 1 settle cycle + 1 measured cycle at 1 Hz after a 0.5 s ramp (about 3 s of physics).
POINTS = [GaitPoint("cobra", "rectilinear", 0.02, kappa_per_m=k, frequency_hz=1.0, ramp_s=0.5,
                    measure_cycles=1) for k in (-0.5, 0.5)]


def test_a_gait_map_sweep_is_identical_on_serial_threads_and_a_dask_local_cluster():
    with open_executor("serial") as ex:
        serial = run_tasks(ex, simulate_point, POINTS, progress=False)
    with open_executor("threads", n_workers=2) as ex:
        threads = run_tasks(ex, simulate_point, POINTS, progress=False)
    with open_executor("dask", n_workers=1) as ex:
        dask = run_tasks(ex, simulate_point, POINTS, progress=True)
    assert serial == threads == dask
    for r in serial:
        assert all(math.isfinite(r[k]) for k in ("xi_x_m_s", "xi_y_m_s", "xi_w_rad_s"))
    # opposite curvatures turn opposite ways (kappa > 0: left, CCW)
    assert serial[0]["xi_w_rad_s"] < 0 < serial[1]["xi_w_rad_s"]


def test_fit_gait_map_gives_the_follower_keys_from_a_linear_fit():
    rows = [{"gait": "rectilinear", "amplitude": 0.02, "kappa_per_m": k, "delta_deg": 0.0,
             "xi_x_m_s": 0.006, "xi_y_m_s": 0.0, "xi_w_rad_s": 0.013 * k + 0.001, "rolled_over": False}
            for k in (-1.0, 0.0, 1.0)]
    rows.append({**rows[0], "kappa_per_m": 2.0, "xi_w_rad_s": 9.0, "rolled_over": True})   # excluded
    s = fit_gait_map(rows)
    f = s["follower"]
    assert f["omega_per_kappa"] == pytest.approx(0.013)
    assert f["omega_offset_rad_s"] == pytest.approx(0.001)
    assert f["speed_m_s"] == pytest.approx(0.006)
    assert f["kappa_max_per_m"] == pytest.approx(1.0)
    assert s["fits"][0]["r2"] == pytest.approx(1.0)
