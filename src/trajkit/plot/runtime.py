"""Runtime figures: following error of a servo simulation, a recorded setpoint stream."""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from . import require_matplotlib, save_figure

__all__ = ["plot_following_error", "plot_stream"]


def _save(fig, path) -> None:
    save_figure(fig, path)


def plot_following_error(report: Any, path: str | os.PathLike | None = None,
                         scale: Sequence[float] | None = None, unit: str = "unit"):
    """Following error per axis against time, with the motion ends marked.

    Parameters
    ----------
    report : SimulationReport
        From :func:`trajkit.runtime.simulate` with ``record=True``
        (``InvalidInputError`` otherwise).
    path : str or PathLike, optional
        Write the figure there (by extension), atomically.
    scale : sequence of float, optional
        Factor per axis for display (e.g. 1000 for m -> mm).
    unit : str
        Label of the displayed unit.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if report.t is None or report.following_error is None:
        raise InvalidInputError("plot_following_error needs a report simulated with record=True "
                                "(this one keeps no time series)")
    plt = require_matplotlib()
    n = len(report.names)
    sc = np.ones(n) if scale is None else np.asarray(scale, dtype=float)
    fig, axes = plt.subplots(n, 1, figsize=(9, 1.8 * n + 1), sharex=True, squeeze=False)
    ends = np.cumsum([m.simulated_s for m in report.motions])
    for k in range(n):
        ax = axes[k, 0]
        ax.plot(report.t, report.following_error[:, k] * sc[k], lw=0.8)
        w = report.servo[k].in_position * sc[k]
        ax.axhspan(-w, w, color="tab:green", alpha=0.15, lw=0)
        for e in ends[:60]:
            ax.axvline(e, color="0.7", lw=0.5)
        ax.set_ylabel(f"{report.names[k]} [{unit}]")
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(f"following error: planned {report.planned_s:.3f} s, "
                 f"simulated {report.simulated_s:.3f} s (in-position window shaded)")
    fig.tight_layout()
    if path is not None:
        _save(fig, path)
    return fig


def plot_stream(setpoints: Sequence[Any], names: Sequence[str],
                path: str | os.PathLike | None = None):
    """Commanded velocity per axis and the override of a recorded stream.

    Parameters
    ----------
    setpoints : sequence of Setpoint
    names : sequence of str
        Axis names.
    path : str or PathLike, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = require_matplotlib()
    t = np.array([s.t for s in setpoints])
    v = np.array([s.velocity for s in setpoints])
    ov = np.array([s.override for s in setpoints])
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    for k, nm in enumerate(names):
        a1.plot(t, v[:, k], lw=0.9, label=nm)
    a1.set_ylabel("velocity [unit/s]")
    a1.legend(loc="upper right")
    a2.plot(t, 100 * ov, color="k", lw=0.9)
    a2.set_ylabel("override [%]")
    a2.set_xlabel("time [s]")
    faults = [s for s in setpoints if s.fault is not None]
    for s in faults:
        for ax in (a1, a2):
            ax.axvline(s.t, color="tab:red", lw=1)
    fig.tight_layout()
    if path is not None:
        _save(fig, path)
    return fig
