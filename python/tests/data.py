"""Data the tests share."""

import numpy as np


def nile(sm):
    """The Nile's annual flow 1871–1970 (statsmodels' copy), years 1890–1892 unknown:
    ``(years, flow)``."""
    data = sm.datasets.nile.load_pandas().data
    years = data["year"].to_numpy(dtype=float)
    flow = data["volume"].to_numpy(dtype=float).copy()
    flow[(years >= 1890) & (years <= 1892)] = np.nan
    return years, flow
