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
