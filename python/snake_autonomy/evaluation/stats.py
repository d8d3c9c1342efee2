"""Summary statistics of an error array, evo's own (the same keys and values as evo_ape/evo_rpe)."""
from typing import Dict

import numpy as np

STAT_KEYS = ("max", "mean", "median", "min", "rmse", "sse", "std")


def statistics(errors: np.ndarray) -> Dict[str, float]:
    """evo's statistics (its own PE.get_all_statistics) of any error array."""
    from evo.core import metrics as evo_metrics  # lazy: evo is heavy and only this path needs it

    errors = np.asarray(errors, dtype=float)
    if errors.size == 0:
        return {k: float("nan") for k in STAT_KEYS}
    m = evo_metrics.APE()
    m.error = errors
    return {k: float(v) for k, v in m.get_all_statistics().items()}
