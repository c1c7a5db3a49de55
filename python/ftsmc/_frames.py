"""runs.csv's columns as a pandas DataFrame, one way for every function
that returns rows (``ftsmc.montecarlo``, ``ftsmc.compare``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

if TYPE_CHECKING:
    import pandas


def frame(names: Sequence[str], columns: Sequence[Any]) -> "pandas.DataFrame":
    """Numbers as the native module's numpy arrays; text as object columns
    with None for an empty cell (``margin_binds`` where no envelope limits
    the flight), as an empty number is NaN."""
    import pandas

    return pandas.DataFrame(
        {n: c if isinstance(c, np.ndarray) else pandas.Series(list(c), dtype=object) for n, c in zip(names, columns)}
    )
