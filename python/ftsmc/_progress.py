"""A progress bar for long batches: tqdm when it is installed and the session
is interactive (a terminal or a notebook), nothing otherwise.

In a notebook the bar is ``tqdm.auto``'s widget, which needs ipywidgets;
without ipywidgets there is no bar (tqdm's text fallback would store a line
per update and a ``TqdmWarning`` in the notebook's outputs)."""

from __future__ import annotations

import sys
from typing import Any, Callable, Optional, Union

ProgressArg = Union[bool, None, Callable[[int, int], Any]]
"""``None``: a bar when interactive; ``True``: a bar; ``False``: none; or a
callable ``progress(done, total)`` (control steps flown and planned)."""


def interactive() -> bool:
    """True in a terminal (stderr is a TTY) or an IPython/Jupyter session."""
    try:
        if sys.stderr is not None and sys.stderr.isatty():
            return True
    except (AttributeError, ValueError):
        pass
    shell = sys.modules.get("IPython")
    get_ipython = getattr(shell, "get_ipython", None)
    return get_ipython is not None and get_ipython() is not None


def _notebook_without_widgets() -> bool:
    """True in a Jupyter kernel where ipywidgets cannot be imported."""
    shell = sys.modules.get("IPython")
    get_ipython = getattr(shell, "get_ipython", None)
    ip = get_ipython() if get_ipython is not None else None
    if ip is None or type(ip).__name__ != "ZMQInteractiveShell":
        return False
    try:
        import ipywidgets  # noqa: F401
    except ImportError:
        return True
    return False


class _Bar:
    """A tqdm bar fed with ``(done, total)`` in control steps, shown as flights."""

    def __init__(self, flights: int, description: str) -> None:
        from tqdm.auto import tqdm

        # delay: short batches never show a bar.
        self._bar = tqdm(total=flights, desc=description, unit="flight", delay=1.0, leave=False)
        self._flights = flights
        self._shown = 0

    def __call__(self, done: int, total: int) -> None:
        now = self._flights if total == 0 else min(self._flights, int(self._flights * done / total))
        if now > self._shown:
            self._bar.update(now - self._shown)
            self._shown = now

    def close(self) -> None:
        self._bar.close()


def callback(progress: ProgressArg, flights: int, description: str) -> Optional[Callable[[int, int], Any]]:
    """The callable to hand to the native batch for ``progress`` (see :data:`ProgressArg`)."""
    if callable(progress) and not isinstance(progress, bool):
        return progress
    if progress is False or (progress is None and (not interactive() or _notebook_without_widgets())):
        return None
    try:
        return _Bar(flights, description)
    except ImportError:
        if progress is True:
            raise
        return None


def close(cb: Optional[Callable[[int, int], Any]]) -> None:
    """Close a bar made by :func:`callback` (no-op for user callables and None)."""
    if isinstance(cb, _Bar):
        cb.close()
