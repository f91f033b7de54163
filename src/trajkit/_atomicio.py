"""The one place below the shells that touches files: atomic writes, all or none.

Every file trajkit writes (``Trajectory.to_csv(path)``, figures, the CLI's
``--csv``/``--json``/``--plot`` outputs) goes through :func:`write_file`:

- the content is written to a hidden temporary file in the target folder and
  renamed onto the target, so a failed write never leaves a half-written file;
- inside :func:`output_group` (the command line wraps every command in one),
  the renames wait until the group ends without an error: when one requested
  output fails, none of the others appears either;
- messages name the target, never the temporary file;
- nothing creates folders: a target in a missing folder is refused.
"""

from __future__ import annotations

import contextlib
import contextvars
import itertools
import os
from collections.abc import Callable, Iterator

__all__ = ["atomic_write", "write_file", "check_target", "output_group", "OutputGroup", "output_folder", "TEMP_GLOB"]


class OutputGroup:
    """Files staged under temporary names, renamed onto their targets together by :meth:`commit`."""

    def __init__(self) -> None:
        self._staged: list[tuple[str, str]] = []

    def add(self, tmp: str, path: str) -> None:
        # a later write to the same target replaces the earlier one
        for i, (old_tmp, old_path) in enumerate(self._staged):
            if old_path == path:
                _remove(old_tmp)
                self._staged[i] = (tmp, path)
                return
        self._staged.append((tmp, path))

    @property
    def targets(self) -> list[str]:
        """Target paths staged so far."""
        return [p for _, p in self._staged]

    def commit(self) -> None:
        """Rename every staged file onto its target."""
        staged, self._staged = self._staged, []
        try:
            for tmp, path in staged:
                try:
                    os.replace(tmp, path)
                except OSError as exc:
                    raise OSError(exc.errno, f"cannot write {path}: {exc.strerror}") from None
        finally:
            for tmp, _ in staged:
                _remove(tmp)

    def abort(self) -> None:
        """Remove every staged temporary file; no target is touched."""
        staged, self._staged = self._staged, []
        for tmp, _ in staged:
            _remove(tmp)


_GROUP: contextvars.ContextVar[OutputGroup | None] = contextvars.ContextVar("trajkit_output_group",
                                                                            default=None)


@contextlib.contextmanager
def output_group() -> Iterator[OutputGroup]:
    """Collect every :func:`write_file` inside the block; rename all at its end, or none on error."""
    group = OutputGroup()
    token = _GROUP.set(group)
    try:
        yield group
    except BaseException:
        group.abort()
        raise
    else:
        group.commit()
    finally:
        _GROUP.reset(token)


def check_target(path: str | os.PathLike, what: str = "output") -> str:
    """Check that ``path`` can be a new or replaced file; return it as a string.

    Raises
    ------
    OSError
        The folder does not exist, or ``path`` is a folder. Nothing is created.
    """
    p = os.fspath(path)
    if not p:
        raise FileNotFoundError(f"{what}: empty file name")
    folder = os.path.dirname(os.path.abspath(p))
    if not os.path.isdir(folder):
        raise FileNotFoundError(f"cannot write {p}: folder {folder} does not exist")
    if os.path.isdir(p):
        raise IsADirectoryError(f"cannot write {p}: it is a folder")
    return p


_SERIAL = itertools.count()

#: Glob pattern of the temporary files (hidden, next to their target).
TEMP_GLOB = ".*.trajkit-*.tmp"


def _tmp_name(path: str) -> str:
    folder, base = os.path.split(os.path.abspath(path))
    return os.path.join(folder, f".{base}.trajkit-{os.getpid()}-{next(_SERIAL)}.tmp")


def _remove(tmp: str) -> None:
    with contextlib.suppress(OSError):
        os.remove(tmp)


def write_file(path: str | os.PathLike, writer: Callable[[str], None]) -> None:
    """Write a file through ``writer(tmp_path)`` and an atomic rename onto ``path``.

    Inside :func:`output_group` the rename waits for the end of the group.

    Raises
    ------
    OSError
        The folder does not exist or is not writable, ``path`` is a folder,
        or ``writer`` failed to write; the message names ``path``. No partial
        file and no temporary file is left behind.
    """
    p = check_target(path)
    tmp = _tmp_name(p)
    try:
        writer(tmp)
    except OSError as exc:
        _remove(tmp)
        raise OSError(exc.errno, f"cannot write {p}: {exc.strerror or exc}") from None
    except BaseException:
        _remove(tmp)
        raise
    group = _GROUP.get()
    if group is not None:
        group.add(tmp, p)
        return
    try:
        os.replace(tmp, p)
    except OSError as exc:
        raise OSError(exc.errno, f"cannot write {p}: {exc.strerror}") from None
    finally:
        _remove(tmp)


def atomic_write(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically; see :func:`write_file`."""

    def _write(tmp: str) -> None:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)

    write_file(path, _write)


@contextlib.contextmanager
def output_folder(path: str | os.PathLike) -> Iterator[str]:
    """A folder for several outputs: created if missing (its parent must exist), and
    removed again when the block fails and the folder is still empty.

    The files are written all or none (the block is an :func:`output_group`).

    Raises
    ------
    OSError
        The parent folder does not exist, or ``path`` is a file.
    """
    p = os.fspath(path)
    created = False
    if not os.path.isdir(p):
        if os.path.exists(p):
            raise FileExistsError(f"cannot write into {p}: it is a file, not a folder")
        parent = os.path.dirname(os.path.abspath(p))
        if not os.path.isdir(parent):
            raise FileNotFoundError(f"cannot create folder {p}: folder {parent} does not exist")
        os.mkdir(p)
        created = True
    try:
        with output_group():
            yield p
    except BaseException:
        if created:
            with contextlib.suppress(OSError):
                os.rmdir(p)
        raise
