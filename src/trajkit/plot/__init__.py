"""Figures (matplotlib), imported lazily: ``import trajkit.plot.profiles`` etc.

Nothing in the math layers imports this package. Every function takes planned
objects and returns a :class:`matplotlib.figure.Figure` (and writes it when
given a path); matplotlib is an optional dependency (``pip install trajkit[plot]``).
"""


def require_matplotlib():
    """Import matplotlib with the Agg backend, or raise a clear ImportError."""
    try:
        import matplotlib
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ImportError(
            "plotting needs matplotlib: pip install 'trajkit[plot]'"
        ) from exc
    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg", "ps", "cairo"):
        try:
            matplotlib.use("Agg")
        except Exception:  # pragma: no cover
            pass
    import matplotlib.pyplot as plt

    return plt


def set_equal_3d(ax, points) -> None:
    """Equal scales on the x, y and z axes of a 3-D ``ax`` around ``points`` (n, 3).

    A circle looks round and a straight line keeps its true slope: the three
    axes span the same range about the centre of the points' bounding box.
    """
    import numpy as np

    p = np.asarray(points, dtype=float).reshape(-1, 3)
    p = p[np.isfinite(p).all(axis=1)]
    if p.size == 0:
        return
    lo, hi = p.min(axis=0), p.max(axis=0)
    mid = 0.5 * (lo + hi)
    half = 0.5 * float((hi - lo).max()) or 1.0
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1.0, 1.0, 1.0))


def line_colors(n: int) -> list:
    """``n`` distinct line colours: matplotlib's cycle up to 10, tab20 up to 20, then a colormap."""
    if n <= 10:
        return [f"C{i}" for i in range(n)]
    import matplotlib

    if n <= 20:
        cmap = matplotlib.colormaps["tab20"]
        return [cmap(i) for i in range(n)]
    cmap = matplotlib.colormaps["turbo"]
    return [cmap(i / (n - 1)) for i in range(n)]


#: Resolution of written raster figures [dots per inch].
FIGURE_DPI = 110


def save_figure(fig, path, dpi: int = FIGURE_DPI) -> None:
    """Write ``fig`` to ``path`` atomically (see :func:`trajkit._atomicio.write_file`).

    The format follows the extension (``.png`` when there is none); a failed
    write leaves neither a half-written image nor the temporary file behind.
    ``path=None`` writes nothing.

    Raises
    ------
    ValueError
        An extension matplotlib cannot write (the message lists the ones it can).
    OSError
        The folder does not exist or is not writable.
    """
    import os

    from .._atomicio import write_file
    from ..errors import InvalidInputError

    if path is None:
        return
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower().lstrip(".") or "png"
    formats = fig.canvas.get_supported_filetypes()
    if ext not in formats:
        raise InvalidInputError(
            f"cannot write {path}: figures can be {', '.join(sorted(formats))}, not .{ext}")
    write_file(path, lambda tmp: fig.savefig(tmp, format=ext, dpi=dpi))
