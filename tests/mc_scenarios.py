"""Module-level Monte Carlo scenarios for tests (importable by worker processes)."""

from __future__ import annotations

import numpy as np


def random_walk_kf(rng: np.random.Generator, n_steps: int = 200, q: float = 0.01, r: float = 1.0):
    """Scalar random walk tracked by its (optimal) Kalman filter: NEES ~ chi2(1)."""
    x = np.cumsum(rng.normal(0.0, np.sqrt(q), n_steps))
    z = x + rng.normal(0.0, np.sqrt(r), n_steps)
    xh, P = 0.0, 10.0
    x0 = rng.normal(0.0, np.sqrt(10.0))
    x = x + x0
    z = z + x0
    nees = np.empty(n_steps)
    for k in range(n_steps):
        P = P + q
        K = P / (P + r)
        xh = xh + K * (z[k] - xh)
        P = (1 - K) * P
        nees[k] = (x[k] - xh) ** 2 / P
    return {"rmse": float(np.sqrt(np.mean((x - xh) ** 2))), "final_P": P, "nees": nees}


def batched_mean(rngs, n: int = 1000):
    return [{"mean": float(g.normal(size=n).mean())} for g in rngs]


def failing(item):
    if item == 2:
        raise ValueError("unit 2 is broken")
    return {"x": item * 2}
